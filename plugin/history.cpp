#include "history.h"

#include <cctype>

namespace mcr::plugin {

FrameName split_frame_number(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const std::size_t name_start = slash == std::string::npos ? 0 : slash + 1;
  std::size_t end = path.size();
  while (end > name_start && !std::isdigit(static_cast<unsigned char>(path[end - 1]))) --end;
  if (end == name_start) return {path, std::nullopt};
  std::size_t begin = end;
  while (begin > name_start && std::isdigit(static_cast<unsigned char>(path[begin - 1]))) --begin;
  FrameName f;
  f.pattern = path.substr(0, begin) + std::string(end - begin, '#') + path.substr(end);
  const std::string digits = path.substr(begin, end - begin);
  if (digits.size() <= 18) f.number = std::stoll(digits);  // longer runs are not frame numbers
  else f.pattern = path;
  return f;
}

StreamHistory::Lease StreamHistory::acquire(const std::string& settings_key, const std::string& path,
                                            const Factory& make) {
  const FrameName fn = split_frame_number(path);
  const std::string key = settings_key + '\n' + fn.pattern;
  auto it = streams_.begin();
  while (it != streams_.end() && it->key != key) ++it;
  if (it == streams_.end()) {
    streams_.push_front(Stream{key, make(), std::nullopt});
    if (streams_.size() > max_streams_) streams_.pop_back();
  } else {
    streams_.splice(streams_.begin(), streams_, it);  // most recently used first
  }
  Stream& s = streams_.front();
  current_ = &s;
  current_number_ = fn.number;
  Lease lease;
  lease.reconstruction = s.reconstruction.get();
  lease.continued = s.reconstruction->temporal() && fn.number && s.last && *s.last + 1 == *fn.number;
  if (!lease.continued) {
    s.last.reset();
    s.reconstruction->reset();
  }
  return lease;
}

void StreamHistory::done() {
  if (current_) current_->last = current_number_;
  current_ = nullptr;
}

void StreamHistory::failed() {
  if (current_) current_->last.reset();
  current_ = nullptr;
}

}  // namespace mcr::plugin

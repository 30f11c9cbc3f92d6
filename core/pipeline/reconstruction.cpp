#include "pipeline/reconstruction.h"

#include "pipeline/filter_catalog.h"
#include "util/error.h"

namespace mcr {

std::unique_ptr<Filter> make_committed_filter(const std::string& filter,
                                              const std::vector<std::pair<std::string, std::string>>& params) {
  std::unique_ptr<Filter> f = make_catalog_filter(filter);
  for (const auto& kv : params) f->set_text(kv.first, kv.second);
  f->commit();
  return f;
}

std::string parameters_text(const Filter& filter) {
  std::string params;
  for (const auto& kv : filter.params().values())
    params += (params.empty() ? "" : " ") + kv.first + "=" + param_value_text(kv.second);
  return params;
}

Reconstruction::Reconstruction(std::unique_ptr<Filter> filter, bool accumulate)
    : filter_(std::move(filter)), accumulate_(accumulate) {
  if (!filter_) throw Error(Errc::Internal, "Reconstruction without a filter");
}

PassNeeds Reconstruction::needs() const {
  PassNeeds n = filter_->needs();
  if (accumulate_) {
    n.require(Role::Position, "accumulate");
    n.require(Role::Normal, "accumulate");
    n.use(Role::Motion);
  }
  return n;
}

Image Reconstruction::run(const Frame& frame, const ExecOptions& options) {
  if (!accumulate_) {
    const std::lock_guard<std::mutex> lock(mutex_);
    notes_.clear();
    return filter_->execute(frame, options);
  }
  Frame copy = frame;  // the accumulated colour replaces the copy's, not the caller's
  return run_in_place(copy, options);
}

Image Reconstruction::run_in_place(Frame& frame, const ExecOptions& options) {
  const std::lock_guard<std::mutex> lock(mutex_);
  notes_.clear();
  if (!accumulate_) return filter_->execute(frame, options);
  // Accumulation's passes first: nothing is accumulated for a frame the filter refuses.
  check_passes(needs(), frame, "filter '" + filter_->info().name + "' with accumulation");
  Image& colour = frame.passes[std::size_t(&frame.get(Role::Colour) - frame.passes.data())].image;
  const Image& acc =
      accumulator_.accumulate(frame, colour.channels() == 3 ? colour : colour.channel_range(0, 3), options.nthreads);
  const std::size_t ch = std::size_t(colour.channels());
  for (std::size_t i = 0; i < acc.pixel_count(); ++i)
    for (std::size_t c = 0; c < 3; ++c) colour.data()[i * ch + c] = acc.data()[i * 3 + c];
  if (accumulator_.last_reprojection().cut) notes_.push_back("accumulation: camera cut, history restarted");
  return filter_->execute(frame, options);
}

void Reconstruction::reset() {
  const std::lock_guard<std::mutex> lock(mutex_);
  accumulator_.reset();
  filter_->reset();
}

std::vector<std::string> Reconstruction::notes() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::string> all = filter_->unused_settings();
  all.insert(all.end(), filter_->notes().begin(), filter_->notes().end());
  all.insert(all.end(), notes_.begin(), notes_.end());
  return all;
}

std::string Reconstruction::parameters_text() const {
  const std::string own = mcr::parameters_text(*filter_);
  return accumulate_ ? "accumulate=true " + own : own;
}

}  // namespace mcr

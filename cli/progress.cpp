#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace mcr::cli {

Progress::Progress(std::string what, int total)
    : what_(std::move(what)), total_(total), tty_(::isatty(2)), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() {
  if (open_line_) std::fputc('\n', stderr);
}

void Progress::step(int done, const std::string& detail) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double eta = done > 0 ? s / done * (total_ - done) : 0.0;
  std::fprintf(stderr, "%s[%d/%d] %s %3.0f%% %.1fs elapsed, %.1fs left  %s%s", tty_ ? "\r\033[K" : "", done, total_,
               what_.c_str(), total_ ? 100.0 * done / total_ : 100.0, s, eta, detail.c_str(), tty_ ? "" : "\n");
  open_line_ = tty_;
  std::fflush(stderr);
}

void Progress::finish(const std::string& detail) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: done in %.2fs %s\n", tty_ ? "\r\033[K" : "", what_.c_str(), s, detail.c_str());
  open_line_ = false;
}

}  // namespace mcr::cli

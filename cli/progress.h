#pragma once
// Progress display for long operations (sequences, benchmarks, the demo) on stderr:
// one updating line on a terminal, one line per step otherwise (logs, CI).
#include <chrono>
#include <string>

namespace mcr::cli {

class Progress {
 public:
  Progress(std::string what, int total);
  ~Progress();
  // Step `done` of total finished; detail is shown after the counter.
  void step(int done, const std::string& detail);
  void finish(const std::string& detail = "");

 private:
  std::string what_;
  int total_;
  bool tty_;
  bool open_line_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace mcr::cli

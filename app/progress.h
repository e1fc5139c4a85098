#pragma once
// A progress bar on stderr for long runs: drawn only when stderr is a terminal, not asked to be quiet,
// and the run has already lasted more than a second; redrawn at most ten times a second.
#include <chrono>
#include <cstdint>
#include <string>

namespace btr_app {

class ProgressBar {
 public:
  ProgressBar(std::string label, bool quiet);
  ~ProgressBar();  // ends the line if anything was drawn
  void update(std::int64_t done, std::int64_t total);

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  Clock::time_point start_, last_;
};

}  // namespace btr_app

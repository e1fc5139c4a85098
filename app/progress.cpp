#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace btr_app {

ProgressBar::ProgressBar(std::string label, bool quiet)
    : label_(std::move(label)), enabled_(!quiet && ::isatty(STDERR_FILENO) == 1), start_(Clock::now()), last_(start_) {}

ProgressBar::~ProgressBar() {
  if (drawn_) std::fputs("\n", stderr);
}

void ProgressBar::update(std::int64_t done, std::int64_t total) {
  if (!enabled_ || total <= 0) return;
  const Clock::time_point now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const bool final = done >= total;
  if (elapsed < 1.0 || (!final && now - last_ < std::chrono::milliseconds(100)) || (final && !drawn_)) return;
  last_ = now;
  constexpr int kWidth = 30;
  const double f = double(done) / double(total);
  const int filled = static_cast<int>(f * kWidth);
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
  bar[kWidth] = '\0';
  const double eta = done > 0 ? elapsed * (1.0 - f) / f : 0.0;
  std::fprintf(stderr, "\r%s [%s] %3d%% %lld/%lld  %.1f s, %.0f s left ", label_.c_str(), bar,
               static_cast<int>(100.0 * f), static_cast<long long>(done), static_cast<long long>(total), elapsed, eta);
  std::fflush(stderr);
  drawn_ = true;
}

}  // namespace btr_app

// Shared by the table-printing benchmarks.
#pragma once

#include <algorithm>
#include <chrono>
#include <functional>

namespace mvtm::bench {

// Wall-clock seconds of the fastest of `repeat` runs of f (the least disturbed by other load).
inline double BestOf(int repeat, const std::function<void()>& f) {
  double best = 1e300;
  for (int i = 0; i < repeat; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    f();
    best = std::min(best,
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace mvtm::bench

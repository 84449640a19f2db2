// Shared by the table-printing benchmarks.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

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

// One row of the benchmark report (`make -f Makefile.examples bench`, examples/bench_report.py):
// appended to the CSV file named by $MVTM_BENCH_CSV when it is set, else nothing. `value` and
// `anchor_value` are in `unit`, measured in the same run; for times the report's ratio is
// anchor / value (above 1: mvtm is faster than its anchor). An empty anchor: a figure without
// one (a miss rate).
//   bench,figure,value,unit,anchor,anchor_value
inline void Report(const std::string& bench, const std::string& figure, double value,
                   const std::string& unit, const std::string& anchor, double anchor_value) {
  const char* path = std::getenv("MVTM_BENCH_CSV");
  if (!path || !*path) return;
  std::FILE* f = std::fopen(path, "a");
  if (!f) return;
  auto quoted = [](const std::string& t) {  // CSV: figures may hold commas
    std::string q = "\"";
    for (char c : t) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  std::fprintf(f, "%s,%s,%.6g,%s,%s,%.6g\n", quoted(bench).c_str(), quoted(figure).c_str(), value,
               quoted(unit).c_str(), quoted(anchor).c_str(), anchor_value);
  std::fclose(f);
}

}  // namespace mvtm::bench

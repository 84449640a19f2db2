// The up-to-date check of a large output folder: 10^4 outputs recorded by one run (run/ledger.h),
// then a rerun's check — reading the record, a stat per output and per input, the options
// compared — against the check it replaces in the same run: IsUpToDate's two stats per output
// against a mesh and a model (file times only, which kept outputs made with other options).
// The target: under 1 s for 10^4 outputs.
// usage: bench_ledger [--outputs N] [--repeat R] [--short]
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "bench_util.h"
#include "run/ledger.h"

using namespace mvtm;

namespace {

struct Opts {
  double lateral = 0.5;
  int projectors = 4;
};

OptionTable Declare(Opts& o) {
  OptionTable t("bench");
  t.Real("--lateral", &o.lateral, "Lateral");
  t.Integer("--projectors", &o.projectors, "K");
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  size_t n = 10000;
  int repeat = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--outputs" && i + 1 < argc)
      n = std::stoul(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::stoi(argv[++i]);
    else if (a == "--short")
      n = 1000, repeat = 1;
  }
  const fs::path dir =
      fs::temp_directory_path() / ("mvtm-bench-ledger-" + std::to_string(getpid()));
  fs::create_directories(dir / "ws/images");
  fs::create_directories(dir / "out");
  std::ofstream(dir / "ws/mesh.ply") << std::string(1 << 20, 'm');
  std::ofstream(dir / "ws/images.txt") << std::string(1 << 16, 'i');
  const std::vector<fs::path> inputs = {dir / "ws/mesh.ply", dir / "ws/images.txt"};
  std::vector<fs::path> outs(n), items(n);
  Opts o;
  OptionTable table = Declare(o);
  {
    Ledger made(dir / "out", "bench", table, inputs, dir / "ws");
    for (size_t i = 0; i < n; ++i) {
      outs[i] = dir / "out" / ("frame_" + std::to_string(i) + ".png");
      items[i] = dir / "ws/images" / ("img_" + std::to_string(i % 500) + ".png");
      if (i < 500) std::ofstream(items[i]) << "image " << i;
      std::ofstream(outs[i]) << std::string(2000, static_cast<char>('a' + i % 26));
      made.Done(outs[i], {items[i]});
    }
    made.Write();
  }
  size_t stale = 0;
  const double t_ledger = bench::BestOf(repeat, [&] {
    Ledger check(dir / "out", "bench", table, inputs, dir / "ws");
    for (size_t i = 0; i < n; ++i) stale += !check.Stale(outs[i], {items[i]}).empty();
  });
  size_t old_stale = 0;
  const double t_mtime = bench::BestOf(repeat, [&] {
    for (size_t i = 0; i < n; ++i) old_stale += !IsUpToDate(outs[i], inputs);
  });
  const auto record_bytes = fs::file_size(dir / "out/provenance/bench.json");
  fs::remove_all(dir);
  std::printf("ledger benchmark: up-to-date check of %zu outputs (record %.1f MB), best of %d\n", n,
              double(record_bytes) / 1e6, repeat);
  std::printf("%-48s %10.1f ms  (%zu stale)\n", "ledger: record read + stat + options (ours)",
              t_ledger * 1e3, stale);
  std::printf("%-48s %10.1f ms  (%zu stale)\n", "  baseline: file times only (IsUpToDate)",
              t_mtime * 1e3, old_stale);
  std::printf("target: under 1 s for 10^4 outputs: %s\n",
              n < 10000 ? "not measured (--short)" : (t_ledger < 1.0 ? "met" : "MISSED"));
  bench::Report("ledger", "up-to-date check, " + std::to_string(n) + " outputs", t_ledger * 1e3,
                "ms", "file times only (IsUpToDate)", t_mtime * 1e3);
  return stale == 0 ? 0 : 1;
}

#include "ssim_tool.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "base/atomic_file.h"
#include "base/error.h"
#include "image/folder.h"
#include "image/image.h"
#include "radiometry/exposure.h"
#include "run/ledger.h"

namespace mvtm {

namespace fs = std::filesystem;

namespace {

struct PairJob {
  std::string name;  // file name of A
  fs::path a, b, mask, map;
  bool make_map = false;  // the map is to be (re)made (else none, or up to date)

  // The files its map is made from.
  std::vector<fs::path> Inputs() const {
    std::vector<fs::path> in = {a, b};
    if (!mask.empty()) in.push_back(mask);
    return in;
  }
};

struct Row {
  std::string name;
  Similarity sim;
};

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::vector<fs::path> ListImages(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& name : ListImageFiles(dir)) files.push_back(dir / name);
  if (files.empty()) throw Error(dir.string(), 0, "no image files in folder");
  return files;
}

// The mask of image `name` in folder `dir`: the same file name, else the same stem with .png.
fs::path MaskIn(const fs::path& dir, const fs::path& name) {
  fs::path p = dir / name;
  if (fs::exists(p)) return p;
  fs::path png = dir / name.stem();
  png += ".png";
  if (fs::exists(png)) return png;
  throw Error(p.string(), 0, "missing mask (masks are matched by file name, or stem + .png)");
}

bool MapIsExr(const fs::path& p) { return Lower(p.extension().string()) == ".exr"; }

std::vector<PairJob> PlanPairs(const SsimToolOptions& o) {
  const fs::path a = o.a, b = o.b, mask = o.mask;
  if (!fs::exists(a)) throw Error(o.a, 0, "no such file or folder");
  if (!fs::exists(b)) throw Error(o.b, 0, "no such file or folder");
  const bool dir_a = fs::is_directory(a), dir_b = fs::is_directory(b);
  if (dir_a != dir_b) throw UsageError("A and B must both be images or both be folders");
  if (!o.mask.empty() && !fs::exists(mask)) throw Error(o.mask, 0, "no such file or folder");
  const bool dir_mask = !o.mask.empty() && fs::is_directory(mask);
  std::vector<PairJob> jobs;
  if (!dir_a) {
    if (dir_mask) throw UsageError("--mask must be an image when A and B are images");
    if (!o.map.empty()) {
      const std::string ext = Lower(fs::path(o.map).extension().string());
      if (ext != ".exr" && ext != ".png")
        throw UsageError("--map " + o.map + ": the extension must be .exr (float) or .png");
    }
    jobs.push_back({a.filename().string(), a, b, mask, o.map});
    return jobs;
  }
  for (const fs::path& fa : ListImages(a)) {
    PairJob job;
    job.name = fa.filename().string();
    job.a = fa;
    job.b = b / fa.filename();
    if (!fs::exists(job.b))
      throw Error(job.b.string(), 0, "missing (pairs are matched by file name)");
    if (!o.mask.empty()) job.mask = dir_mask ? MaskIn(mask, fa.filename()) : mask;
    if (!o.map.empty()) {
      job.map = fs::path(o.map) / fa.filename().stem();
      job.map += ".exr";
    }
    jobs.push_back(std::move(job));
  }
  return jobs;
}

std::string DimsOf(const Image& img) {
  return std::to_string(img.width) + "x" + std::to_string(img.height) + "x" +
         std::to_string(img.channels);
}

// SSIM, NCC and PSNR are undefined over NaN or inf samples (a float image from a failed render).
Image ReadFiniteImage(const fs::path& path) {
  Image img = ReadImage(path.string());
  for (float v : img.data)
    if (!std::isfinite(v))
      throw Error(path.string(), 0,
                  "image has non-finite samples (NaN or inf): nothing to compare");
  return img;
}

// Compares one pair; writes its map when it is to be made, and records it in `ledger`.
Row ComparePair(const PairJob& job, const SsimToolOptions& o, Ledger* ledger) {
  Image a = ReadFiniteImage(job.a);
  Image b = ReadFiniteImage(job.b);
  if (o.channels == ChannelMode::kGrey) {
    a = ToGrey(a);
    b = ToGrey(b);
  }
  if (a.width != b.width || a.height != b.height || a.channels != b.channels)
    throw SizeMismatchError(
        job.b.string(), 0,
        "size " + DimsOf(b) + " differs from " + job.a.string() + " (" + DimsOf(a) + ")");
  if (a.bits != b.bits)
    throw Error(job.b.string(), 0,
                std::to_string(b.bits) + "-bit samples but " + job.a.string() + " has " +
                    std::to_string(a.bits) + "-bit (samples are compared in file scale)");
  std::optional<Image> mask;
  if (!job.mask.empty()) {
    mask = ReadImage(job.mask.string());
    if (mask->width != a.width || mask->height != a.height)
      throw SizeMismatchError(job.mask.string(), 0,
                              "mask size " + std::to_string(mask->width) + "x" +
                                  std::to_string(mask->height) + " differs from " + job.a.string() +
                                  " (" + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                  ")");
  }
  if (o.fit_exposure) a = ApplyExposure(a, FitImageExposure(a, b, mask ? &*mask : nullptr));
  Image map;
  Row row;
  row.name = job.name;
  try {
    row.sim = Compare(a, b, o.ssim, mask ? &*mask : nullptr, job.make_map ? &map : nullptr);
  } catch (const SizeMismatchError&) {
    throw;
  } catch (const UsageError&) {
    throw;
  } catch (const Error& e) {
    throw Error(job.a.string(), 0, e.what());  // name the pair in data errors
  }
  if (job.make_map) {
    if (!MapIsExr(job.map)) {  // 8-bit: 255·clamp(S, 0, 1)
      map.bits = 8;
      for (float& v : map.data) v = 255.f * std::clamp(v, 0.f, 1.f);
    }
    WriteImage(job.map.string(), map);
    ledger->Done(job.map, job.Inputs());
  }
  return row;
}

// Every pair. One pair: SSIM's row threads. Several (a folder): one pair per thread, each pair
// on one thread, which keeps every core busy through decoding too and does not stall when
// another process takes a core. Rows come back in job order; the first failing pair in that
// order is the error reported (no new pair is started once one has failed).
std::vector<Row> CompareAll(const std::vector<PairJob>& jobs, const SsimToolOptions& options,
                            Ledger* ledger) {
  std::vector<Row> rows(jobs.size());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const size_t workers = std::min<size_t>(
      jobs.size(), options.ssim.threads > 0 ? size_t(options.ssim.threads) : cores);
  if (workers <= 1) {
    for (size_t i = 0; i < jobs.size(); ++i) rows[i] = ComparePair(jobs[i], options, ledger);
    return rows;
  }
  SsimToolOptions per_pair = options;
  per_pair.ssim.threads = 1;
  std::vector<std::exception_ptr> errors(jobs.size());
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  auto work = [&] {
    for (size_t i; !failed && (i = next.fetch_add(1)) < jobs.size();) {
      try {
        rows[i] = ComparePair(jobs[i], per_pair, ledger);
      } catch (...) {
        errors[i] = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (size_t k = 1; k < workers; ++k) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  return rows;
}

// Statistics over the non-NaN values (NaN when there are none); std is the population one.
struct Stats {
  double mean, std, min;
};
Stats StatsOf(const std::vector<double>& v) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> x;
  for (double d : v)
    if (!std::isnan(d)) x.push_back(d);
  if (x.empty()) return {nan, nan, nan};
  double sum = 0;
  for (double d : x) sum += d;
  const double mean = sum / x.size();
  double ss = 0;
  for (double d : x) ss += (d - mean) * (d - mean);
  // A set holding inf (identical images: PSNR inf) has an infinite mean and no defined spread:
  // nan, spelled "nan" (inf − inf would print as "-nan").
  const double sd = std::isfinite(mean) ? std::sqrt(ss / x.size()) : nan;
  return {mean, sd, *std::min_element(x.begin(), x.end())};
}

std::string Fixed(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);  // "nan", "inf" for non-finite values
  return buf;
}

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; }

// Where the maps' record goes: the --map folder, or the folder the map file is in.
fs::path MapRoot(const SsimToolOptions& o, bool folders) {
  if (folders) return o.map;
  const fs::path dir = fs::path(o.map).parent_path();
  return dir.empty() ? fs::path(".") : dir;
}

std::string ChannelModeName(ChannelMode m) {
  for (const auto& [mode, name] : kChannelModes)
    if (mode == m) return name;
  return "";
}

// The summary statistics of each metric over the pairs.
struct Summary {
  Stats ssim, ncc, psnr;
};
Summary SummaryOf(const std::vector<Row>& rows) {
  std::vector<double> ssim, ncc, psnr;
  for (const Row& r : rows) {
    ssim.push_back(r.sim.ssim);
    ncc.push_back(r.sim.ncc);
    psnr.push_back(r.sim.psnr);
  }
  return {StatsOf(ssim), StatsOf(ncc), StatsOf(psnr)};
}

void PrintJson(const SsimToolOptions& options, const std::vector<Row>& rows, bool folders,
               std::ostream& out) {
  nlohmann::json j;
  j["a"] = options.a;
  j["b"] = options.b;
  if (!options.mask.empty()) j["mask"] = options.mask;
  j["options"] = {{"sigma", options.ssim.sigma},
                  {"k1", options.ssim.k1},
                  {"k2", options.ssim.k2},
                  {"truncate", options.ssim.truncate},
                  {"window", 2 * options.ssim.Radius() + 1},
                  {"channels", ChannelModeName(options.channels)}};
  nlohmann::json pairs = nlohmann::json::array();
  for (const Row& r : rows) {
    pairs.push_back({{"name", r.name},
                     {"ssim", Number(r.sim.ssim)},
                     {"ncc", Number(r.sim.ncc)},
                     {"psnr", Number(r.sim.psnr)},
                     {"data_range", r.sim.data_range},
                     {"pixels", r.sim.pixels},
                     {"ssim_pixels", r.sim.ssim_pixels}});
  }
  j["pairs"] = pairs;
  if (folders) {
    const Summary s = SummaryOf(rows);
    auto stat = [&](double Stats::*field) {
      return nlohmann::json{{"ssim", Number(s.ssim.*field)},
                            {"ncc", Number(s.ncc.*field)},
                            {"psnr", Number(s.psnr.*field)}};
    };
    j["summary"] = {{"count", rows.size()},
                    {"mean", stat(&Stats::mean)},
                    {"std", stat(&Stats::std)},
                    {"min", stat(&Stats::min)}};
  }
  out << j.dump(2) << "\n";
}

void PrintTsv(const std::vector<Row>& rows, bool folders, std::ostream& out) {
  out << "name\tssim\tncc\tpsnr\n";
  for (const Row& r : rows)
    out << r.name << "\t" << Fixed(r.sim.ssim) << "\t" << Fixed(r.sim.ncc) << "\t"
        << Fixed(r.sim.psnr) << "\n";
  if (!folders) return;
  const Summary s = SummaryOf(rows);
  for (auto [label, field] : {std::pair{"mean", &Stats::mean}, std::pair{"std", &Stats::std},
                              std::pair{"min", &Stats::min}})
    out << label << "\t" << Fixed(s.ssim.*field) << "\t" << Fixed(s.ncc.*field) << "\t"
        << Fixed(s.psnr.*field) << "\n";
}

// The verdict on standard output: JSON or TSV.
void PrintTable(const SsimToolOptions& options, const std::vector<Row>& rows, bool folders,
                std::ostream& out) {
  if (options.json)
    PrintJson(options, rows, folders, out);
  else
    PrintTsv(rows, folders, out);
}

}  // namespace

OptionTable DeclareOptions(SsimToolOptions& o) {
  OptionTable t("ssim");
  t.Positional("A", &o.a, "First image, or folder of images").File();
  t.Positional("B", &o.b, "Second image, or folder (pairs matched by file name)").File();
  t.Text("--mask", &o.mask,
         "Evaluate only where this mask (image, or folder for folders) is nonzero")
      .File();
  // Where the maps go; what they hold does not depend on it.
  t.Text("--map", &o.map,
         "Write the SSIM map: .exr (float) or .png (8-bit); for folders a folder of NAME.exr")
      .Cosmetic();
  // The table on standard output only: recomputed on every run, no file depends on it.
  t.Flag("--json", &o.json, "Write JSON instead of TSV").Cosmetic();
  t.Flag("--fit-exposure", &o.fit_exposure,
         "First bring A to the exposure of B: gain and offset fitted by least squares (inside "
         "the mask)");
  t.Real("--sigma", &o.ssim.sigma, "Gaussian window standard deviation in pixels").Above(0);
  t.Real("--k1", &o.ssim.k1, "Luminance constant, C1 = (K1*R)^2").AtLeast(0);
  t.Real("--k2", &o.ssim.k2, "Contrast constant, C2 = (K2*R)^2").AtLeast(0);
  t.Real("--data-range", &o.ssim.data_range,
         "Data range R (default: from the bit depth: 255, 65535, 1 for float)")
      .AtLeast(0);  // 0: from the bit depth
  t.Choice("--channels", &o.channels, kChannelModes,
           "Colour: mean = per channel, averaged (scikit-image); grey = compare the grey images");
  t.Flag("--force", &o.force, "Rewrite the maps even when they are up to date").Cosmetic();
  return t;
}

void SsimToolOptions::Check() const {
  CheckDeclared(*this);
  if (a.empty() || b.empty()) throw UsageError("two images or two folders are required");
  ssim.Check();  // the window's size (truncate * sigma)
}

int RunSsim(const SsimToolOptions& options, std::ostream& out) {
  options.Check();
  std::vector<PairJob> jobs = PlanPairs(options);
  const bool folders = fs::is_directory(options.a);
  if (folders && !options.map.empty()) CreateFolder(options.map);
  SsimToolOptions resolved = options;
  const OptionTable table = DeclareOptions(resolved);
  std::optional<Ledger> ledger;
  size_t maps = 0;
  if (!options.map.empty()) {
    ledger.emplace(MapRoot(options, folders), "ssim", table, std::vector<fs::path>{}, fs::path());
    for (PairJob& job : jobs) {
      job.make_map = !ledger->Stale(job.map, job.Inputs(), options.force).empty();
      maps += job.make_map;
    }
  }

  const std::vector<Row> rows = CompareAll(jobs, options, ledger ? &*ledger : nullptr);
  if (maps) ledger->Write();

  PrintTable(options, rows, folders, out);
  out.flush();
  if (!out) throw Error("cannot write the table to standard output");
  return 0;
}

}  // namespace mvtm

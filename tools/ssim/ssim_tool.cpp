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

namespace mvtm {

namespace fs = std::filesystem;

namespace {

struct PairJob {
  std::string name;  // file name of A
  fs::path a, b, mask, map;
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

Row ComparePair(const PairJob& job, const SsimToolOptions& o) {
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
    row.sim = Compare(a, b, o.ssim, mask ? &*mask : nullptr, job.map.empty() ? nullptr : &map);
  } catch (const SizeMismatchError&) {
    throw;
  } catch (const UsageError&) {
    throw;
  } catch (const Error& e) {
    throw Error(job.a.string(), 0, e.what());  // name the pair in data errors
  }
  if (!job.map.empty()) {
    if (!MapIsExr(job.map)) {  // 8-bit: 255·clamp(S, 0, 1)
      map.bits = 8;
      for (float& v : map.data) v = 255.f * std::clamp(v, 0.f, 1.f);
    }
    WriteImage(job.map.string(), map);
  }
  return row;
}

// Every pair. One pair: SSIM's row threads. Several (a folder): one pair per thread, each pair
// on one thread, which keeps every core busy through decoding too and does not stall when
// another process takes a core. Rows come back in job order; the first failing pair in that
// order is the error reported (no new pair is started once one has failed).
std::vector<Row> CompareAll(const std::vector<PairJob>& jobs, const SsimToolOptions& options) {
  std::vector<Row> rows(jobs.size());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const size_t workers = std::min<size_t>(
      jobs.size(), options.ssim.threads > 0 ? size_t(options.ssim.threads) : cores);
  if (workers <= 1) {
    for (size_t i = 0; i < jobs.size(); ++i) rows[i] = ComparePair(jobs[i], options);
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
        rows[i] = ComparePair(jobs[i], per_pair);
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

}  // namespace

void SsimToolOptions::Check() const {
  if (a.empty() || b.empty()) throw UsageError("two images or two folders are required");
  ssim.Check();
}

int RunSsim(const SsimToolOptions& options, std::ostream& out) {
  options.Check();
  const std::vector<PairJob> jobs = PlanPairs(options);
  const bool folders = fs::is_directory(options.a);
  if (folders && !options.map.empty()) CreateFolder(options.map);

  const std::vector<Row> rows = CompareAll(jobs, options);

  std::vector<double> ssim, ncc, psnr;
  for (const Row& r : rows) {
    ssim.push_back(r.sim.ssim);
    ncc.push_back(r.sim.ncc);
    psnr.push_back(r.sim.psnr);
  }
  const Stats s_ssim = StatsOf(ssim), s_ncc = StatsOf(ncc), s_psnr = StatsOf(psnr);

  if (options.json) {
    nlohmann::json j;
    j["a"] = options.a;
    j["b"] = options.b;
    if (!options.mask.empty()) j["mask"] = options.mask;
    j["options"] = {{"sigma", options.ssim.sigma},
                    {"k1", options.ssim.k1},
                    {"k2", options.ssim.k2},
                    {"truncate", options.ssim.truncate},
                    {"window", 2 * options.ssim.Radius() + 1},
                    {"channels", ChannelModeNames()[static_cast<size_t>(options.channels)]}};
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
      auto stat = [&](double Stats::*field) {
        return nlohmann::json{{"ssim", Number(s_ssim.*field)},
                              {"ncc", Number(s_ncc.*field)},
                              {"psnr", Number(s_psnr.*field)}};
      };
      j["summary"] = {{"count", rows.size()},
                      {"mean", stat(&Stats::mean)},
                      {"std", stat(&Stats::std)},
                      {"min", stat(&Stats::min)}};
    }
    out << j.dump(2) << "\n";
  } else {
    out << "name\tssim\tncc\tpsnr\n";
    for (const Row& r : rows)
      out << r.name << "\t" << Fixed(r.sim.ssim) << "\t" << Fixed(r.sim.ncc) << "\t"
          << Fixed(r.sim.psnr) << "\n";
    if (folders) {
      out << "mean\t" << Fixed(s_ssim.mean) << "\t" << Fixed(s_ncc.mean) << "\t"
          << Fixed(s_psnr.mean) << "\n";
      out << "std\t" << Fixed(s_ssim.std) << "\t" << Fixed(s_ncc.std) << "\t" << Fixed(s_psnr.std)
          << "\n";
      out << "min\t" << Fixed(s_ssim.min) << "\t" << Fixed(s_ncc.min) << "\t" << Fixed(s_psnr.min)
          << "\n";
    }
  }
  out.flush();
  if (!out) throw Error("cannot write the table to standard output");
  return 0;
}

}  // namespace mvtm

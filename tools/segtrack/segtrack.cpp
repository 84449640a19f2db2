#include "segtrack.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <opencv2/core.hpp>
#include <utility>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "image/folder.h"
#include "image/image.h"
#include "io/tracks.h"
#include "track/labels.h"
#include "workspace/workspace.h"

namespace mvtm {

namespace {

LabelDecoder MakeDecoder(const SegtrackOptions& o) {
  if (o.binary) return LabelDecoder::Binary();
  const std::vector<int> classes = LabelDecoder::ParseClasses(o.classes);
  if (!o.palette.empty()) return LabelDecoder::Palette(ReadImage(o.palette), o.palette, classes);
  return LabelDecoder::ClassIds(classes);
}

std::string SizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// Frames read and decoded in parallel between two in-order hand-overs: enough to keep every
// core busy, few enough that a bad file is reported soon and the progress bar moves.
constexpr size_t kBatch = 32;

// Work for cv::parallel_for_ in a few stripes per thread, so that each stripe's buffers serve
// several frames and a thread slowed by other load does not hold up the rest for long.
double Stripes() { return 4.0 * cv::getNumThreads(); }

// Reads the label images of `files` and decodes their vehicle masks on all cores (OpenCV's
// thread pool), a batch at a time; per_frame(vehicle, width, height, finder) runs on the worker
// threads, and its result goes to use(index, result) on this thread in file order, after the
// size check. Errors are thrown in file order too, as a one-by-one loop would throw them.
template <class PerFrame, class Use>
void ForEachLabel(const std::vector<fs::path>& files, const LabelDecoder& decoder,
                  Progress* progress, PerFrame&& per_frame, Use&& use) {
  using Value = decltype(per_frame(std::vector<uint8_t>(), 0, 0, std::declval<BlobFinder&>()));
  struct Frame {
    int width = 0, height = 0;
    Value value{};
    std::exception_ptr error;
  };
  std::vector<Frame> batch;
  int w0 = 0, h0 = 0;
  for (size_t b0 = 0; b0 < files.size(); b0 += kBatch) {
    batch.assign(std::min(kBatch, files.size() - b0), Frame());
    cv::parallel_for_(
        cv::Range(0, static_cast<int>(batch.size())),
        [&](const cv::Range& range) {
          BlobFinder finder;
          std::vector<uint8_t> vehicle;
          for (int k = range.start; k < range.end; ++k) {
            Frame& f = batch[static_cast<size_t>(k)];
            try {
              const std::string name = files[b0 + static_cast<size_t>(k)].string();
              const Image label = ReadImage(name);
              f.width = label.width, f.height = label.height;
              decoder.Decode(label, name, vehicle);
              f.value = per_frame(vehicle, f.width, f.height, finder);
            } catch (...) {
              f.error = std::current_exception();
            }
          }
        },
        Stripes());
    for (size_t k = 0; k < batch.size(); ++k) {
      const size_t i = b0 + k;
      Frame& f = batch[k];
      if (f.error) std::rethrow_exception(f.error);
      if (i == 0) {
        w0 = f.width, h0 = f.height;
      } else if (f.width != w0 || f.height != h0) {
        throw Error(files[i].string() + ": size " + SizeText(f.width, f.height) + " differs from " +
                    files[0].string() + " (" + SizeText(w0, h0) + ")");
      }
      use(i, std::move(f.value), w0, h0);
      if (progress) progress->Step();
    }
  }
}

// Renders and writes every frame's mask on all cores. Each write is atomic; the error of the
// first frame (in file order) that failed is thrown, and no new write starts after a failure.
void WriteMasks(const TrackResult& res, const std::vector<fs::path>& files, const Workspace& ws,
                int dilate) {
  std::vector<std::exception_ptr> errors(files.size());
  std::atomic<bool> failed{false};
  cv::parallel_for_(
      cv::Range(0, static_cast<int>(files.size())),
      [&](const cv::Range& range) {
        std::vector<uint8_t> mask;
        Image out(res.width, res.height, 1, 8);
        for (int i = range.start; i < range.end && !failed; ++i) {
          try {
            res.RenderMask(i, dilate, mask);
            std::copy(mask.begin(), mask.end(), out.data.begin());
            // Masks are long runs of 0 and 255: the fast PNG settings encode them 4-5x faster
            // at about the same size (same pixels).
            WriteImage(ws.MaskPath(files[static_cast<size_t>(i)].filename().string()).string(), out,
                       PngCompression::kFast);
          } catch (...) {
            errors[static_cast<size_t>(i)] = std::current_exception();
            failed = true;
          }
        }
      },
      Stripes());
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace

void SegtrackOptions::Check() const {
  if (rank) {
    if (paths.empty()) throw UsageError("--rank needs at least one LABELDIR");
  } else if (paths.size() != 2) {
    throw UsageError("expected LABELDIR WS, got " + std::to_string(paths.size()) + " path" +
                     (paths.size() == 1 ? "" : "s") + " (or --rank LABELDIR...)");
  }
  if (binary && !palette.empty()) throw UsageError("--binary and --palette exclude each other");
  if (!binary) LabelDecoder::ParseClasses(classes);
  track.Check();
}

std::vector<fs::path> ListLabelImages(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(dir.string() + ": not a folder");
  std::vector<fs::path> files;
  for (const auto& name : ListImageFiles(dir, {".png"}))
    files.push_back(dir / name);  // labels are lossless
  if (files.empty()) throw Error(dir.string() + ": no label images (*.png)");
  return files;
}

SegtrackReport RunSegtrack(const SegtrackOptions& o) {
  o.Check();
  const LabelDecoder decoder = MakeDecoder(o);
  const fs::path labeldir = o.paths[0];
  const Workspace ws(o.paths[1]);
  const std::vector<fs::path> files = ListLabelImages(labeldir);

  std::unique_ptr<Tracker> tracker;
  {
    Progress progress("segtrack", files.size(), o.quiet);
    ForEachLabel(
        files, decoder, &progress,
        [](const std::vector<uint8_t>& vehicle, int w, int h, BlobFinder& finder) {
          return finder.Find(vehicle.data(), w, h);
        },
        [&](size_t, std::vector<Blob>&& blobs, int w, int h) {
          if (!tracker) tracker = std::make_unique<Tracker>(w, h, o.track);
          tracker->AddBlobs(std::move(blobs));
        });
  }
  const TrackResult res = tracker->Finish();
  RemoveStaleTemporaries(ws.MasksDir());  // a killed run's leftovers
  WriteMasks(res, files, ws, o.track.dilate);

  std::vector<TracksTsvRow> table;
  table.reserve(res.rows.size());
  for (const TrackRow& r : res.rows)
    table.push_back({files[static_cast<size_t>(r.frame)].filename().string(), r});
  WriteTracksTsv(ws.TracksPath().string(), table);

  nlohmann::json opts = {{"labeldir", labeldir.string()}, {"classes", o.binary ? "" : o.classes},
                         {"palette", o.palette},          {"binary", o.binary},
                         {"max_jump", o.track.max_jump},  {"max_missed", o.track.max_missed},
                         {"max_gap", o.track.max_gap},    {"smooth", o.track.smooth},
                         {"min_life", o.track.min_life},  {"min_ratio", o.track.min_ratio},
                         {"dilate", o.track.dilate}};
  std::vector<fs::path> inputs = files;
  if (!o.palette.empty()) inputs.insert(inputs.begin(), o.palette);
  ws.WriteProvenance("segtrack", opts, inputs);

  SegtrackReport rep;
  rep.summary = res.summary;
  rep.masks_dir = ws.MasksDir();
  rep.tracks = ws.TracksPath();
  return rep;
}

std::vector<RankRow> RankSequences(const SegtrackOptions& o) {
  o.Check();
  const LabelDecoder decoder = MakeDecoder(o);
  std::vector<RankRow> rows;
  for (const std::string& dir : o.paths) {
    const std::vector<fs::path> files = ListLabelImages(dir);
    RankRow row;
    row.labeldir = dir;
    double pixels = 0;
    ForEachLabel(
        files, decoder, nullptr,
        [](const std::vector<uint8_t>& vehicle, int, int, BlobFinder&) {
          size_t n = 0;
          for (uint8_t v : vehicle) n += v;
          return n;
        },
        [&](size_t, size_t n, int w, int h) {
          row.area += static_cast<double>(n);
          pixels += static_cast<double>(w) * h;
          ++row.frames;
        });
    row.fraction = pixels > 0 ? row.area / pixels : 0;
    rows.push_back(row);
  }
  std::stable_sort(rows.begin(), rows.end(), [](const RankRow& a, const RankRow& b) {
    return a.area != b.area ? a.area < b.area : a.labeldir < b.labeldir;
  });
  return rows;
}

}  // namespace mvtm

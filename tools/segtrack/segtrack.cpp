#include "segtrack.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <opencv2/core.hpp>
#include <utility>

#include "base/atomic_file.h"
#include "base/error.h"
#include "cli/progress.h"
#include "cli/work.h"
#include "image/folder.h"
#include "image/image.h"
#include "io/tracks.h"
#include "run/ledger.h"
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

// Renders and writes the masks of the frames `todo` on all cores, each recorded in the ledger
// when it is in place. Each write is atomic; the error of the first frame (in file order) that
// failed is thrown, and no new write starts after a failure.
void WriteMasks(const TrackResult& res, const std::vector<fs::path>& files,
                const std::vector<size_t>& todo, const Workspace& ws, int dilate, Ledger& ledger) {
  std::vector<std::exception_ptr> errors(todo.size());
  std::atomic<bool> failed{false};
  cv::parallel_for_(
      cv::Range(0, static_cast<int>(todo.size())),
      [&](const cv::Range& range) {
        std::vector<uint8_t> mask;
        Image out(res.width, res.height, 1, 8);
        for (int k = range.start; k < range.end && !failed; ++k) {
          const size_t i = todo[static_cast<size_t>(k)];
          try {
            res.RenderMask(static_cast<int>(i), dilate, mask);
            std::copy(mask.begin(), mask.end(), out.data.begin());
            // Masks are long runs of 0 and 255: the fast PNG settings encode them 4-5x faster
            // at about the same size (same pixels).
            const fs::path path = ws.MaskPath(files[i].filename().string());
            WriteImage(path.string(), out, PngCompression::kFast);
            ledger.Done(path);
          } catch (...) {
            errors[static_cast<size_t>(k)] = std::current_exception();
            failed = true;
          }
        }
      },
      Stripes());
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

// Reads, decodes and tracks every label image (the tracking couples all frames).
TrackResult TrackLabels(const std::vector<fs::path>& files, const LabelDecoder& decoder,
                        const SegtrackOptions& o) {
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
  return tracker->Finish();
}

}  // namespace

OptionTable DeclareOptions(SegtrackOptions& o) {
  OptionTable t("segtrack");
  t.PositionalList("PATHS", &o.paths,
                   "LABELDIR WS: label images (*.png, name order) and the workspace written to; "
                   "with --rank: LABELDIR...");
  t.Text("--classes", &o.classes, "Vehicle class ids, comma-separated (class-id or palette labels)")
      .Alternative("8,5")
      .Check([&o] {
        if (!o.binary) LabelDecoder::ParseClasses(o.classes);
      });
  t.Text("--palette", &o.palette,
         "Labels are RGB: FILE's pixels, in row-major order, are the colours of class 0, 1, ...")
      .File();
  t.Flag("--binary", &o.binary, "Labels are masks: first channel non-zero = vehicle")
      .Excludes("--classes")
      .Excludes("--palette");
  t.Real("--max-jump", &o.track.max_jump,
         "Largest distance from a track's predicted centroid to its blob")
      .Above(0)
      .Alternative("2");
  DeclareTrackOptions(t, o.track);
  t.Flag("--rank", &o.rank,
         "Print the LABELDIRs ordered by total vehicle area (fewest first) on stdout")
      .Cosmetic();
  t.Flag("--force", &o.force, "Rewrite masks and tracks.tsv even when they are up to date")
      .Cosmetic();
  DeclareQuietOption(t, o.quiet);
  return t;
}

void SegtrackOptions::Check() const {
  CheckDeclared(*this);
  if (rank) {
    if (paths.empty()) throw UsageError("--rank needs at least one LABELDIR");
  } else if (paths.size() != 2) {
    throw UsageError("expected LABELDIR WS, got " + std::to_string(paths.size()) + " path" +
                     (paths.size() == 1 ? "" : "s") + " (or --rank LABELDIR...)");
  }
  if (binary && !palette.empty()) throw UsageError("--binary and --palette exclude each other");
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
  SegtrackReport rep;
  rep.frames = files.size();
  rep.masks_dir = ws.MasksDir();
  rep.tracks = ws.TracksPath();

  // Tracking couples the frames: every label image (and the palette) is an input of every
  // output, so any changed label makes every mask and tracks.tsv stale.
  std::vector<fs::path> inputs = files;
  if (!o.palette.empty()) inputs.push_back(o.palette);
  SegtrackOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(ws.root(), "segtrack", table, inputs, ws.root());
  std::vector<size_t> todo;
  for (size_t i = 0; i < files.size(); ++i)
    if (!ledger.Stale(ws.MaskPath(files[i].filename().string()), {}, o.force).empty())
      todo.push_back(i);
  const bool tracks_stale = !ledger.Stale(rep.tracks, {}, o.force).empty();
  rep.why = ledger.Summary();
  rep.skipped = files.size() - todo.size() + (tracks_stale ? 0 : 1);
  RemoveStaleTemporaries(ws.MasksDir());  // a killed run's leftovers, even when all is up to date
  if (todo.empty() && !tracks_stale) return rep;

  const TrackResult res = TrackLabels(files, decoder, o);
  rep.tracked = true;
  rep.summary = res.summary;
  WriteMasks(res, files, todo, ws, o.track.dilate, ledger);
  rep.written = todo.size();
  if (tracks_stale) {
    std::vector<TracksTsvRow> rows;
    rows.reserve(res.rows.size());
    for (const TrackRow& r : res.rows)
      rows.push_back({files[static_cast<size_t>(r.frame)].filename().string(), r});
    WriteTracksTsv(rep.tracks.string(), rows);
    ledger.Done(rep.tracks);
    ++rep.written;
  }
  ledger.Write({{"labeldir", labeldir.generic_string()}});
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

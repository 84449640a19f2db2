#include "segtrack.h"

#include <algorithm>

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

// Reads the label images of `files` in order, all of one size, and hands each decoded vehicle
// mask to `use(index, mask, width, height)`.
template <class Use>
void ForEachLabel(const std::vector<fs::path>& files, const LabelDecoder& decoder,
                  Progress* progress, Use&& use) {
  int w0 = 0, h0 = 0;
  std::vector<uint8_t> vehicle;
  for (size_t i = 0; i < files.size(); ++i) {
    const Image label = ReadImage(files[i].string());
    if (i == 0) {
      w0 = label.width, h0 = label.height;
    } else if (label.width != w0 || label.height != h0) {
      throw Error(files[i].string() + ": size " + SizeText(label.width, label.height) +
                  " differs from " + files[0].string() + " (" + SizeText(w0, h0) + ")");
    }
    decoder.Decode(label, files[i].string(), vehicle);
    use(i, vehicle, w0, h0);
    if (progress) progress->Step();
  }
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
    ForEachLabel(files, decoder, &progress,
                 [&](size_t, const std::vector<uint8_t>& vehicle, int w, int h) {
                   if (!tracker) tracker = std::make_unique<Tracker>(w, h, o.track);
                   tracker->AddFrame(vehicle.data());
                 });
  }
  const TrackResult res = tracker->Finish();
  RemoveStaleTemporaries(ws.MasksDir());  // a killed run's leftovers

  std::vector<uint8_t> mask;
  Image out(res.width, res.height, 1, 8);
  for (size_t i = 0; i < files.size(); ++i) {
    res.RenderMask(static_cast<int>(i), o.track.dilate, mask);
    std::copy(mask.begin(), mask.end(), out.data.begin());
    WriteImage(ws.MaskPath(files[i].filename().string()).string(), out);
  }

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
    ForEachLabel(files, decoder, nullptr,
                 [&](size_t, const std::vector<uint8_t>& vehicle, int w, int h) {
                   size_t n = 0;
                   for (uint8_t v : vehicle) n += v;
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

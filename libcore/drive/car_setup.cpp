#include "drive/car_setup.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/stats.h"
#include "base/text.h"

namespace mvtm {

RecordedDrive SelectRecordedDrive(std::vector<const ImageRecord*> images, const std::string& pass,
                                  const std::string& start, const std::string& file,
                                  const std::string& held) {
  std::sort(images.begin(), images.end(),
            [](const ImageRecord* a, const ImageRecord* b) { return a->name < b->name; });
  RecordedDrive r;
  for (const ImageRecord* im : images)
    if (im->name.compare(0, pass.size(), pass) == 0) {
      r.images.push_back(im);
      r.w2c.emplace_back(NormalizedQuaternion(im->world_to_camera.q), im->world_to_camera.t);
    }
  if (r.images.empty())
    throw Error(file, 0,
                pass.empty() ? "the model has no images"
                             : "no image name starts with '" + pass + "' (--pass)");
  if (!start.empty()) {
    size_t i = 0;
    while (i < r.images.size() && r.images[i]->name != start) ++i;
    if (i == r.images.size())
      throw UsageError("--start: no image '" + start + "' " + held +
                       (pass.empty() ? "" : " whose name starts with '" + pass + "'"));
    r.start = i;
  }
  return r;
}

RecordedDrive LoadRecordedDrive(const Workspace& ws, const std::string& pass,
                                const std::string& start) {
  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  RecordedDrive r = SelectRecordedDrive(rec.ImagesByName(), pass, start, ws.SparseDir().string(),
                                        "in the workspace");
  r.rec = std::move(rec);  // (a moved std::map keeps its nodes: r.images stay valid)
  return r;
}

double ResolveScale(double scale, bool metric, const Workspace& ws,
                    const std::vector<double>& heights, const std::string& tool,
                    std::string& source) {
  if (scale > 0) {
    source = "--scale";
    return scale;
  }
  const fs::path record = ws.MetricRecord(tool);
  if (metric || !record.empty()) {
    source = metric ? "--metric" : record.string();
    return 1.0;
  }
  std::string hint;
  if (!heights.empty()) {
    const double h = Median(heights);
    hint = "; its cameras are " + FormatDouble(std::round(h * 1e4) / 1e4) +
           " model units above the mesh, i.e. --scale " +
           FormatDouble(std::round(h / 1.65 * 1e4) / 1e4) + " for a camera 1.65 m high";
  }
  throw UsageError(ws.root().string() +
                   " is not known to be metric: give --scale S (model units per metre) or "
                   "--metric" +
                   hint);
}

Eigen::Vector3d ParseCameraOffset(const std::string& text, const std::string& option) {
  const auto f = SplitChar(text, ',');
  if (f.size() != 3)
    throw UsageError(option + ": expected X,Y,Z in metres (forward, left, up), got '" + text + "'");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v[k] = ParseDoubleArg(f[k], option);
  if (!(v.z() > 0)) throw UsageError(option + ": the height Z must be > 0 metres");
  return v;
}

CarGeometry MakeCar(double wheelbase, double track, const std::string& camera_offset,
                    const Workspace& ws, const std::vector<double>& heights, double scale,
                    bool* from_workspace) {
  CarGeometry car{wheelbase, track, Eigen::Vector3d::Zero()};
  if (from_workspace) *from_workspace = false;
  if (!camera_offset.empty()) {
    car.camera_offset = ParseCameraOffset(camera_offset, "--camera-offset");
    return car;
  }
  if (heights.empty())
    throw Error(ws.MeshPath().string(), 0,
                "no recorded camera is above the mesh: give --camera-offset X,Y,Z");
  car.camera_offset = Eigen::Vector3d(0, 0, Median(heights) / scale);
  if (from_workspace) *from_workspace = true;
  return car;
}

CarOnRoad SetUpCar(const Workspace& ws, const MeshRaycaster& mesh, const CarOptions& o,
                   const std::string& tool) {
  CarOnRoad c;
  c.rec = LoadRecordedDrive(ws, o.pass, o.start);
  const Eigen::Vector3d up = RecordedUp(c.rec.w2c);
  const std::vector<double> heights = CameraHeights(mesh, c.rec.w2c, up);
  c.height_cameras = heights.size();
  c.scale = ResolveScale(o.scale, o.metric, ws, heights, tool, c.scale_source);
  c.car = MakeCar(o.wheelbase, o.track, o.camera_offset, ws, heights, c.scale,
                  &c.height_from_workspace);
  c.frame = FrameAtCamera(c.rec.w2c[c.rec.start], up, c.scale);
  return c;
}

}  // namespace mvtm

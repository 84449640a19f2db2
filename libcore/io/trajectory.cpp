#include "io/trajectory.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <streambuf>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "io/colmap_model.h"
#include "io/text_file.h"

namespace mvtm {

namespace fs = std::filesystem;

namespace {

Eigen::Quaterniond NormalisedOrFail(double w, double x, double y, double z, const std::string& name,
                                    long line) {
  double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!std::isfinite(n)) {  // components near 1e308: rescale first, the rotation is the same
    double m = std::max({std::abs(w), std::abs(x), std::abs(y), std::abs(z)});
    w /= m, x /= m, y /= m, z /= m;
    n = std::sqrt(w * w + x * x + y * y + z * z);
  }
  if (!(n > 1e-12)) throw Error(name, line, "quaternion has zero norm");
  Eigen::Quaterniond q(w / n, x / n, y / n, z / n);
  return q;
}

// Reads lines up to and including the first data line and tells the format from them. Appends
// every line read to `seen` (when given), so the caller can hand them to the reader again.
TrajectoryFormat DetectFormat(LineReader& in, std::string* seen) {
  std::string raw;
  bool colmap_header = false;
  while (in.NextRaw(raw)) {
    if (seen) seen->append(raw).push_back('\n');
    std::string_view t = Trim(raw);
    if (t.empty()) continue;
    if (t.front() == '#') {
      if (t.find("IMAGE_ID, QW") != std::string_view::npos) colmap_header = true;
      continue;
    }
    if (colmap_header) return TrajectoryFormat::kColmap;
    size_t n = SplitBlank(t).size();
    if (n == 8) return TrajectoryFormat::kTum;
    if (n == 12) return TrajectoryFormat::kKitti;
    if (n == 10) return TrajectoryFormat::kColmap;
    in.Fail("cannot tell the trajectory format: " + std::to_string(n) +
            " fields (TUM has 8, KITTI 12, COLMAP images.txt 10)");
  }
  throw Error(in.name(), 0, "cannot tell the trajectory format: the file has no poses");
}

// A stream buffer that gives `prefix` and then the rest of `rest`: the lines that format
// detection has read, followed by what it has not, without seeking (stdin, pipes).
class PrefixedBuf : public std::streambuf {
 public:
  PrefixedBuf(std::string prefix, std::streambuf* rest) : prefix_(std::move(prefix)), rest_(rest) {
    setg(prefix_.data(), prefix_.data(), prefix_.data() + prefix_.size());
  }

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    const std::streamsize n = rest_->sgetn(chunk_, sizeof chunk_);
    if (n <= 0) return traits_type::eof();
    setg(chunk_, chunk_, chunk_ + n);
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::string prefix_;
  std::streambuf* rest_;
  char chunk_[4096];
};

Trajectory ReadColmapImagesTrajectory(std::istream& stream, const std::string& name) {
  Trajectory tr;
  ForEachColmapImageText(stream, name, [&](ImageRecord&& im, long line) {
    const Eigen::Quaterniond& q = im.world_to_camera.q;
    Rigid3d w2c(NormalisedOrFail(q.w(), q.x(), q.y(), q.z(), name, line), im.world_to_camera.t);
    StampedPose p;
    p.time = static_cast<double>(im.id);
    p.line = line;
    p.pose = w2c.Inverse();
    tr.poses.push_back(p);
    tr.names.push_back(std::move(im.name));
  });
  if (tr.poses.empty()) throw Error(name, 0, "trajectory file has no poses");
  return tr;
}

Trajectory ReadTrajectoryAs(std::istream& in, const std::string& name, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return ReadTum(in, name);
    case TrajectoryFormat::kKitti:
      return ReadKittiPoses(in, name);
    case TrajectoryFormat::kColmap:
      return ReadColmapImagesTrajectory(in, name);
    default:
      break;
  }
  throw Error(name, 0, "unknown trajectory format");
}

}  // namespace

TrajectoryFormat DetectTrajectoryFormat(const std::string& path) {
  LineReader in(path);
  return DetectFormat(in, nullptr);
}

Trajectory ReadTum(std::istream& stream, const std::string& name) {
  LineReader in(stream, name);
  Trajectory tr;
  std::string line;
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.size() != 8)
      in.Fail("TUM pose needs 8 fields (timestamp tx ty tz qx qy qz qw), found " +
              std::to_string(tok.size()));
    static const char* names[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = ParseDouble(tok[i], in, names[i]);
    StampedPose p;
    p.time = v[0];
    p.line = in.line();
    p.pose = Rigid3d(NormalisedOrFail(v[7], v[4], v[5], v[6], name, in.line()),
                     Eigen::Vector3d(v[1], v[2], v[3]));
    tr.poses.push_back(p);
  }
  if (tr.poses.empty()) throw Error(name, 0, "trajectory file has no poses");
  return tr;
}

Trajectory ReadTum(const std::string& path) {
  std::ifstream in = OpenTextFile(path);
  return ReadTum(in, path);
}

Trajectory ReadKittiPoses(std::istream& stream, const std::string& name) {
  LineReader in(stream, name);
  Trajectory tr;
  std::string line;
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.size() != 12)
      in.Fail("KITTI pose needs 12 numbers (row-major 3x4), found " + std::to_string(tok.size()));
    Eigen::Matrix<double, 3, 4> m;
    for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = ParseDouble(tok[i], in, "matrix entry");
    double det = m.leftCols<3>().determinant();
    if (!(std::abs(det - 1) < 1e-3))
      in.Fail("rotation part is not a rotation (det " + FormatDouble(det) + ")");
    StampedPose p;
    p.time = static_cast<double>(tr.poses.size());
    p.line = in.line();
    p.pose = Rigid3d::FromMatrix(m);
    tr.poses.push_back(p);
  }
  if (tr.poses.empty()) throw Error(name, 0, "trajectory file has no poses");
  return tr;
}

Trajectory ReadKittiPoses(const std::string& path, const std::string& times_path) {
  std::ifstream in = OpenTextFile(path);
  Trajectory tr = ReadKittiPoses(in, path);
  if (!times_path.empty()) {
    auto times = ReadTimestamps(times_path);
    if (times.size() != tr.poses.size())
      throw Error(times_path, 0,
                  std::to_string(times.size()) + " timestamps for " +
                      std::to_string(tr.poses.size()) + " poses in " + path);
    for (size_t i = 0; i < times.size(); ++i) tr.poses[i].time = times[i].time;
  }
  return tr;
}

Trajectory ReadTrajectory(std::istream& in, const std::string& name, TrajectoryFormat format) {
  if (format != TrajectoryFormat::kAuto) return ReadTrajectoryAs(in, name, format);
  std::string seen;
  {
    LineReader lines(in, name);
    format = DetectFormat(lines, &seen);
  }
  PrefixedBuf buf(std::move(seen), in.rdbuf());
  std::istream joined(&buf);
  return ReadTrajectoryAs(joined, name, format);
}

std::string PoseName(const Trajectory& trajectory, size_t i) {
  if (i < trajectory.names.size()) return trajectory.names[i];
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06zu", i);
  return buf;
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format) {
  std::ifstream in = OpenTextFile(path);
  return ReadTrajectory(in, path, format);
}

std::string TumRow(double time, const Rigid3d& c2w) {
  std::string row = FormatDouble(time);
  for (double v : {c2w.t.x(), c2w.t.y(), c2w.t.z(), c2w.q.x(), c2w.q.y(), c2w.q.z(), c2w.q.w()})
    row += ' ' + FormatDouble(v);
  return row;
}

void WriteTum(const std::string& path, const std::vector<StampedPose>& c2w) {
  WriteTextAtomic(path, [&](std::ostream& f) {
    f << "# timestamp tx ty tz qx qy qz qw (camera-to-world)\n";
    for (const auto& p : c2w) f << TumRow(p.time, p.pose) << '\n';
  });
}

void WriteKittiPoses(const std::string& path, const std::vector<StampedPose>& c2w) {
  WriteTextAtomic(path, [&](std::ostream& f) {
    for (const auto& p : c2w) {
      auto m = p.pose.Matrix3x4();
      for (int i = 0; i < 12; ++i) f << (i ? " " : "") << FormatDouble(m(i / 4, i % 4));
      f << '\n';
    }
  });
}

std::vector<TimedName> ReadTimestamps(std::istream& stream, const std::string& name) {
  LineReader in(stream, name);
  std::vector<TimedName> out;
  std::string line;
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.size() > 2)
      in.Fail("timestamp line needs 'timestamp [name]', found " + std::to_string(tok.size()) +
              " fields");
    TimedName t;
    t.time = ParseDouble(tok[0], in, "timestamp");
    if (tok.size() == 2) t.name = std::string(tok[1]);
    t.line = in.line();
    out.push_back(t);
  }
  if (out.empty()) throw Error(name, 0, "no timestamps");
  return out;
}

std::vector<TimedName> ReadTimestamps(const std::string& path) {
  std::ifstream in = OpenTextFile(path);
  return ReadTimestamps(in, path);
}

namespace {

// The line "Pn: p0 .. p11" of a KITTI calib.txt (row-major, positive focal lengths), with its
// line number and key for messages.
struct KittiProjection {
  std::array<double, 12> p;
  long line;
  std::string key;
};

KittiProjection ReadKittiProjection(const std::string& path, int cam_index) {
  LineReader in(path);
  std::string line, key = "P" + std::to_string(cam_index) + ":";
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.empty() || tok[0] != key) continue;
    if (tok.size() != 13)
      in.Fail(key + " needs 12 numbers, found " + std::to_string(tok.size() - 1));
    std::array<double, 12> p;
    for (int i = 0; i < 12; ++i) p[i] = ParseDouble(tok[1 + i], in, "projection entry");
    if (!(p[0] > 0) || !(p[5] > 0)) in.Fail(key + " focal lengths must be positive");
    return {p, in.line(), key};
  }
  throw Error(path, 0, "no line '" + key + "'");
}

}  // namespace

Camera ReadKittiCalib(const std::string& path, int cam_index, uint64_t width, uint64_t height) {
  const KittiProjection kp = ReadKittiProjection(path, cam_index);
  const auto& p = kp.p;
  Camera c;
  c.model = CameraModel::kPinhole;
  c.width = width;
  c.height = height;
  c.params = {p[0], p[5], p[2], p[6]};
  std::string problem = CameraProblem(c);
  if (!problem.empty()) throw Error(path, kp.line, kp.key + " " + problem);
  return c;
}

Eigen::Vector3d ReadKittiCameraOffset(const std::string& path, int cam_index) {
  const KittiProjection kp = ReadKittiProjection(path, cam_index);
  const auto& p = kp.p;
  // A rectified camera: K upper triangular with K[2][2] = 1 (KITTI writes it so).
  if (p[4] != 0 || p[8] != 0 || p[9] != 0 || !(std::abs(p[10] - 1) < 1e-9))
    throw Error(path, kp.line,
                kp.key +
                    " is not a rectified camera's K [I | t] (row 2 must begin 0 fy cy, "
                    "row 3 0 0 1)");
  Eigen::Matrix3d k;
  k << p[0], p[1], p[2], 0, p[5], p[6], 0, 0, 1;
  return k.triangularView<Eigen::Upper>().solve(Eigen::Vector3d(p[3], p[7], p[11]));
}

Camera ReadOrbSettings(const std::string& path, uint64_t width, uint64_t height) {
  if (!fs::exists(path)) throw Error(path, 0, "cannot open");
  cv::FileStorage fsr;
  try {
    fsr.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception&) {  // OpenCV's text names its own source lines: not for users
    throw Error(path, 0, "not a readable ORB-SLAM2 settings file (YAML)");
  }
  if (!fsr.isOpened()) throw Error(path, 0, "not a readable ORB-SLAM2 settings file");
  auto get = [&](const char* key, bool required, double def) {
    cv::FileNode n = fsr[key];
    if (n.empty()) {
      if (required) throw Error(path, 0, std::string("missing key ") + key);
      return def;
    }
    if (!n.isReal() && !n.isInt()) throw Error(path, 0, std::string(key) + " is not a number");
    double v = n.real();
    if (!std::isfinite(v)) throw Error(path, 0, std::string(key) + " is not finite");
    return v;
  };
  double fx = get("Camera.fx", true, 0), fy = get("Camera.fy", true, 0);
  double cx = get("Camera.cx", true, 0), cy = get("Camera.cy", true, 0);
  double k1 = get("Camera.k1", false, 0), k2 = get("Camera.k2", false, 0);
  double p1 = get("Camera.p1", false, 0), p2 = get("Camera.p2", false, 0);
  double k3 = get("Camera.k3", false, 0);
  double w = get("Camera.width", false, 0), h = get("Camera.height", false, 0);
  if (width) w = static_cast<double>(width);
  if (height) h = static_cast<double>(height);
  if (!(w > 0) || !(h > 0))
    throw Error(path, 0, "no Camera.width/Camera.height: give the image size (--size)");
  if (!(w <= double(kMaxCameraSide)) || !(h <= double(kMaxCameraSide)))
    throw Error(path, 0, "Camera.width/Camera.height beyond " + std::to_string(kMaxCameraSide));
  if (!(fx > 0) || !(fy > 0)) throw Error(path, 0, "focal lengths must be positive");
  Camera c;
  c.width = static_cast<uint64_t>(w);
  c.height = static_cast<uint64_t>(h);
  if (k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0) {
    c.model = CameraModel::kPinhole;
    c.params = {fx, fy, cx, cy};
  } else if (k3 == 0) {
    c.model = CameraModel::kOpenCV;
    c.params = {fx, fy, cx, cy, k1, k2, p1, p2};
  } else {
    c.model = CameraModel::kFullOpenCV;
    c.params = {fx, fy, cx, cy, k1, k2, p1, p2, k3, 0, 0, 0};
  }
  std::string problem = CameraProblem(c);
  if (!problem.empty()) throw Error(path, 0, problem);
  return c;
}

NerfScene ReadNerfTransforms(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw Error(path, 0, "cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {  // parse_error, out_of_range (number overflow)
    throw Error(path, 0, std::string("invalid JSON: ") + e.what());
  }
  auto num = [&](const nlohmann::json& obj, const char* key, const std::string& where) {
    if (!obj.contains(key)) throw Error(path, 0, where + key + " is missing");
    if (!obj[key].is_number()) throw Error(path, 0, where + key + " is not a number");
    double v = obj[key].get<double>();
    if (!std::isfinite(v)) throw Error(path, 0, where + key + " is not finite");
    return v;
  };
  NerfScene s;
  double w = num(j, "w", "/"), h = num(j, "h", "/");
  double fx = num(j, "fl_x", "/");
  double fy = j.contains("fl_y") ? num(j, "fl_y", "/") : fx;
  double cx = j.contains("cx") ? num(j, "cx", "/") : w / 2,
         cy = j.contains("cy") ? num(j, "cy", "/") : h / 2;
  double k1 = j.contains("k1") ? num(j, "k1", "/") : 0,
         k2 = j.contains("k2") ? num(j, "k2", "/") : 0;
  double p1 = j.contains("p1") ? num(j, "p1", "/") : 0,
         p2 = j.contains("p2") ? num(j, "p2", "/") : 0;
  if (!(w >= 1 && w <= double(kMaxCameraSide)) || !(h >= 1 && h <= double(kMaxCameraSide)))
    throw Error(path, 0, "/w and /h must be in 1.." + std::to_string(kMaxCameraSide));
  s.camera.width = static_cast<uint64_t>(w);
  s.camera.height = static_cast<uint64_t>(h);
  if (k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0) {
    s.camera.model = CameraModel::kPinhole;
    s.camera.params = {fx, fy, cx, cy};
  } else {
    s.camera.model = CameraModel::kOpenCV;
    s.camera.params = {fx, fy, cx, cy, k1, k2, p1, p2};
  }
  std::string problem = CameraProblem(s.camera);
  if (!problem.empty()) throw Error(path, 0, problem);
  if (!j.contains("frames") || !j["frames"].is_array()) throw Error(path, 0, "/frames is missing");
  size_t i = 0;
  for (const auto& fr : j["frames"]) {
    std::string where = "/frames/" + std::to_string(i) + "/";
    if (!fr.contains("file_path") || !fr["file_path"].is_string())
      throw Error(path, 0, where + "file_path is missing");
    const auto& m = fr.value("transform_matrix", nlohmann::json());
    if (!m.is_array() || m.size() < 3) throw Error(path, 0, where + "transform_matrix is not 4x4");
    Eigen::Matrix<double, 3, 4> c2w;
    for (int r = 0; r < 3; ++r) {
      if (!m[r].is_array() || m[r].size() != 4)
        throw Error(path, 0, where + "transform_matrix is not 4x4");
      for (int c = 0; c < 4; ++c) {
        if (!m[r][c].is_number()) throw Error(path, 0, where + "transform_matrix has a non-number");
        c2w(r, c) = m[r][c].get<double>();
        if (!std::isfinite(c2w(r, c)))
          throw Error(path, 0, where + "transform_matrix is not finite");
      }
    }
    // OpenGL camera axes (y up, z backward) → camera axes (y down, z forward).
    c2w.col(1) = -c2w.col(1);
    c2w.col(2) = -c2w.col(2);
    StampedPose p;
    p.time = static_cast<double>(i);
    p.pose = Rigid3d::FromMatrix(c2w);
    s.frames.poses.push_back(p);
    s.frames.names.push_back(fr["file_path"].get<std::string>());
    ++i;
  }
  return s;
}

}  // namespace mvtm

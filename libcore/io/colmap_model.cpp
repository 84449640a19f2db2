#include "io/colmap_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/text.h"
#include "io/text_file.h"

namespace mvtm {

namespace fs = std::filesystem;

std::vector<std::string> ColmapModelFileNames(bool binary) {
  const char* ext = binary ? ".bin" : ".txt";
  std::vector<std::string> names;
  for (const char* f : {"cameras", "images", "points3D"}) names.push_back(std::string(f) + ext);
  return names;
}

namespace {

bool AllExist(const std::string& dir, bool binary) {
  bool all = true;
  for (const auto& f : ColmapModelFileNames(binary)) all = all && fs::exists(fs::path(dir) / f);
  return all;
}

// The readers' work under the lock their public callers hold (LockForReading: never taken twice).
Reconstruction ReadTextLocked(const std::string& dir);
Reconstruction ReadBinaryLocked(const std::string& dir);
std::map<uint32_t, ImageRecord> ReadImagesBinary(const std::string& path);

}  // namespace

bool HasColmapModel(const std::string& dir) {
  const FolderLock lock = LockForReading(dir);
  return AllExist(dir, false) || AllExist(dir, true);
}

std::vector<std::string> ColmapModelFiles(const std::string& dir) {
  const FolderLock lock = LockForReading(dir);
  std::vector<std::string> files;
  for (bool binary : {false, true})
    for (const auto& f : ColmapModelFileNames(binary))
      if (fs::exists(fs::path(dir) / f)) files.push_back((fs::path(dir) / f).string());
  return files;
}

bool IsColmapBinaryModel(const std::string& dir) {
  const FolderLock lock = LockForReading(dir);
  return AllExist(dir, true);
}

Reconstruction ReadColmapModel(const std::string& dir) {
  // One lock for the choice of format and the read: a live commit from text to binary (the text
  // files already removed) is waited for, not taken for a folder without a model.
  const FolderLock lock = LockForReading(dir);
  if (AllExist(dir, true)) return ReadBinaryLocked(dir);
  if (!fs::exists(fs::path(dir) / "images.txt"))
    throw Error(dir, 0, "no COLMAP model here (need cameras, images, points3D as .txt or .bin)");
  return ReadTextLocked(dir);
}

std::vector<std::string> ReadColmapImageNames(const std::string& dir) {
  const FolderLock lock = LockForReading(dir);  // the format's choice and the read: one lock
  std::vector<std::string> names;
  if (AllExist(dir, true)) {
    for (const auto& [id, im] : ReadImagesBinary((fs::path(dir) / "images.bin").string()))
      names.push_back(im.name);
    return names;
  }
  const fs::path text = fs::path(dir) / "images.txt";
  if (!fs::exists(text))
    throw Error(dir, 0, "no COLMAP model here (need cameras, images, points3D as .txt or .bin)");
  std::ifstream in(text, std::ios::binary);
  if (!in) throw Error(text.string(), 0, std::string("cannot open: ") + strerror(errno));
  ForEachColmapImageText(in, text.string(),
                         [&](ImageRecord&& r, long) { names.push_back(std::move(r.name)); });
  return names;
}

// ---------------------------------------------------------------------------------------------
// Checks shared by the text and binary readers.
namespace {

void CheckReferences(const Reconstruction& r, const std::string& images_file,
                     const std::string& points_file) {
  for (const auto& [id, im] : r.images) {
    if (!r.cameras.count(im.camera_id))
      throw Error(images_file, 0,
                  "image " + std::to_string(id) + " names camera " + std::to_string(im.camera_id) +
                      " which does not exist");
    for (const auto& p : im.points2D)
      if (p.point3D_id != kInvalidPoint3DId && !r.points3D.count(p.point3D_id))
        throw Error(images_file, 0,
                    "image " + std::to_string(id) + " observes 3-D point " +
                        std::to_string(p.point3D_id) + " which does not exist");
  }
  for (const auto& [id, pt] : r.points3D)
    for (const auto& el : pt.track) {
      auto it = r.images.find(el.image_id);
      if (it == r.images.end())
        throw Error(points_file, 0,
                    "point " + std::to_string(id) + " has a track element in image " +
                        std::to_string(el.image_id) + " which does not exist");
      if (el.point2D_idx >= it->second.points2D.size())
        throw Error(points_file, 0,
                    "point " + std::to_string(id) + " names 2-D point " +
                        std::to_string(el.point2D_idx) + " of image " +
                        std::to_string(el.image_id) + " which has only " +
                        std::to_string(it->second.points2D.size()));
    }
}

Eigen::Quaterniond CheckedQuaternion(double w, double x, double y, double z,
                                     const std::string& file, long line) {
  double n2 = w * w + x * x + y * y + z * z;
  if (!(n2 > 0)) throw Error(file, line, "quaternion has zero norm");
  if (!std::isfinite(n2) || n2 < 1e-280) {
    // Components near the double range (1e308) or tiny: rescale by the largest one so a later
    // normalisation neither overflows nor underflows (the rotation is the same).
    double m = std::max({std::abs(w), std::abs(x), std::abs(y), std::abs(z)});
    return Eigen::Quaterniond(w / m, x / m, y / m, z / m);
  }
  return Eigen::Quaterniond(w, x, y, z);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Text

std::map<uint32_t, Camera> ReadColmapCamerasText(std::istream& stream, const std::string& name) {
  std::map<uint32_t, Camera> cameras;
  LineReader in(stream, name);
  std::string line;
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.size() < 4) in.Fail("camera line needs CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    Camera c;
    int64_t id = ParseInt(tok[0], in, "CAMERA_ID");
    if (id < 0 || id > UINT32_MAX) in.Fail("CAMERA_ID out of range");
    c.id = static_cast<uint32_t>(id);
    try {
      c.model = CameraModelFromName(std::string(tok[1]));
    } catch (const Error& e) {
      in.Fail(e.what());
    }
    int64_t w = ParseInt(tok[2], in, "WIDTH"), h = ParseInt(tok[3], in, "HEIGHT");
    if (w <= 0 || h <= 0) in.Fail("WIDTH and HEIGHT must be positive");
    c.width = static_cast<uint64_t>(w);
    c.height = static_cast<uint64_t>(h);
    size_t np = static_cast<size_t>(CameraModelNumParams(c.model));
    if (tok.size() != 4 + np)
      in.Fail(std::string(tok[1]) + " takes " + std::to_string(np) + " parameters, found " +
              std::to_string(tok.size() - 4));
    for (size_t i = 4; i < tok.size(); ++i) c.params.push_back(ParseDouble(tok[i], in, "PARAMS"));
    std::string problem = CameraProblem(c);
    if (!problem.empty()) in.Fail("camera " + std::to_string(c.id) + ": " + problem);
    if (!cameras.emplace(c.id, c).second) in.Fail("duplicate CAMERA_ID " + std::to_string(c.id));
  }
  return cameras;
}

namespace {

// The POINTS2D line of an image: triples X Y POINT3D_ID (-1: none).
std::vector<Point2D> ParsePoints2D(std::string_view text, const LineReader& in) {
  auto pt = SplitBlank(Trim(text));
  if (pt.size() % 3 != 0) in.Fail("POINTS2D needs triples X Y POINT3D_ID");
  std::vector<Point2D> points;
  for (size_t i = 0; i < pt.size(); i += 3) {
    Point2D p;
    p.xy = {ParseDouble(pt[i], in, "X"), ParseDouble(pt[i + 1], in, "Y")};
    int64_t pid = ParseInt(pt[i + 2], in, "POINT3D_ID");
    p.point3D_id = pid < 0 ? kInvalidPoint3DId : static_cast<uint64_t>(pid);
    points.push_back(p);
  }
  return points;
}

// The pose line of an image: IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME.
ImageRecord ParseImageLine(const std::string& line, const LineReader& in) {
  auto tok = SplitBlank(line);
  if (tok.size() != 10)
    in.Fail("image line needs 10 fields (IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME), found " +
            std::to_string(tok.size()));
  ImageRecord im;
  int64_t id = ParseInt(tok[0], in, "IMAGE_ID");
  if (id < 0 || id > UINT32_MAX) in.Fail("IMAGE_ID out of range");
  im.id = static_cast<uint32_t>(id);
  double q[4], t[3];
  const char* qn[4] = {"QW", "QX", "QY", "QZ"};
  const char* tn[3] = {"TX", "TY", "TZ"};
  for (int i = 0; i < 4; ++i) q[i] = ParseDouble(tok[1 + i], in, qn[i]);
  for (int i = 0; i < 3; ++i) t[i] = ParseDouble(tok[5 + i], in, tn[i]);
  im.world_to_camera.q = CheckedQuaternion(q[0], q[1], q[2], q[3], in.name(), in.line());
  im.world_to_camera.t = Eigen::Vector3d(t[0], t[1], t[2]);
  int64_t cid = ParseInt(tok[8], in, "CAMERA_ID");
  if (cid < 0 || cid > UINT32_MAX) in.Fail("CAMERA_ID out of range");
  im.camera_id = static_cast<uint32_t>(cid);
  im.name = std::string(tok[9]);
  return im;
}

}  // namespace

void ForEachColmapImageText(std::istream& stream, const std::string& name,
                            const std::function<void(ImageRecord&&, long line)>& each) {
  LineReader in(stream, name);
  std::string line, pts;
  while (in.Next(line)) {
    ImageRecord im = ParseImageLine(line, in);
    const long image_line = in.line();
    if (!in.NextRaw(pts)) in.Fail("image " + std::to_string(im.id) + " has no POINTS2D line");
    im.points2D = ParsePoints2D(pts, in);
    each(std::move(im), image_line);
  }
}

std::map<uint32_t, ImageRecord> ReadColmapImagesText(std::istream& stream,
                                                     const std::string& name) {
  std::map<uint32_t, ImageRecord> images;
  std::set<std::string> names;
  ForEachColmapImageText(stream, name, [&](ImageRecord&& im, long line) {
    const uint32_t id = im.id;
    if (!names.insert(im.name).second) throw Error(name, line, "duplicate image NAME " + im.name);
    if (!images.emplace(id, std::move(im)).second)
      throw Error(name, line, "duplicate IMAGE_ID " + std::to_string(id));
  });
  return images;
}

std::map<uint64_t, Point3D> ReadColmapPoints3DText(std::istream& stream, const std::string& name) {
  std::map<uint64_t, Point3D> points;
  LineReader in(stream, name);
  std::string line;
  while (in.Next(line)) {
    auto tok = SplitBlank(line);
    if (tok.size() < 8 || (tok.size() - 8) % 2 != 0)
      in.Fail("point line needs POINT3D_ID X Y Z R G B ERROR TRACK[] (pairs)");
    Point3D p;
    int64_t id = ParseInt(tok[0], in, "POINT3D_ID");
    if (id < 0) in.Fail("POINT3D_ID must not be negative");
    p.id = static_cast<uint64_t>(id);
    p.xyz = {ParseDouble(tok[1], in, "X"), ParseDouble(tok[2], in, "Y"),
             ParseDouble(tok[3], in, "Z")};
    for (int c = 0; c < 3; ++c) {
      int64_t v = ParseInt(tok[4 + c], in, "RGB");
      if (v < 0 || v > 255) in.Fail("colour component out of 0..255");
      p.rgb[c] = static_cast<uint8_t>(v);
    }
    p.error = ParseDouble(tok[7], in, "ERROR");
    for (size_t i = 8; i < tok.size(); i += 2) {
      int64_t iid = ParseInt(tok[i], in, "IMAGE_ID"), idx = ParseInt(tok[i + 1], in, "POINT2D_IDX");
      if (iid < 0 || iid > UINT32_MAX || idx < 0 || idx > UINT32_MAX)
        in.Fail("track element out of range");
      p.track.push_back({static_cast<uint32_t>(iid), static_cast<uint32_t>(idx)});
    }
    if (!points.emplace(p.id, std::move(p)).second)
      in.Fail("duplicate POINT3D_ID " + std::to_string(id));
  }
  return points;
}

Reconstruction ReadColmapText(const std::string& dir) {
  // A writer killed between its renames: its model, whole; a live one's renames waited for.
  const FolderLock lock = LockForReading(dir);
  return ReadTextLocked(dir);
}

namespace {

Reconstruction ReadTextLocked(const std::string& dir) {
  Reconstruction r;
  const std::string cam_file = (fs::path(dir) / "cameras.txt").string();
  const std::string img_file = (fs::path(dir) / "images.txt").string();
  const std::string pts_file = (fs::path(dir) / "points3D.txt").string();
  {
    std::ifstream in = OpenTextFile(cam_file);
    r.cameras = ReadColmapCamerasText(in, cam_file);
  }
  {
    std::ifstream in = OpenTextFile(img_file);
    r.images = ReadColmapImagesText(in, img_file);
  }
  {
    std::ifstream in = OpenTextFile(pts_file);
    r.points3D = ReadColmapPoints3DText(in, pts_file);
  }
  CheckReferences(r, img_file, pts_file);
  return r;
}

}  // namespace

namespace {
// COLMAP normalises quaternions (v / v.norm()) every time it reads or writes them, and that
// division can move the last bit, so a model would not survive `colmap model_converter` bit for
// bit. We write a unit quaternion whose norm rounds to exactly 1.0 under both summation orders
// Eigen may use (scalar and SSE pairs): normalising it is then the identity. It is found by
// stepping two of the three largest components by at most 16 ulps (a rotation change of ~1e-16).
bool ExactlyUnit(const Eigen::Vector4d& v) {
  double a = v[0] * v[0], b = v[1] * v[1], c = v[2] * v[2], d = v[3] * v[3];
  return std::sqrt(((a + b) + c) + d) == 1.0 && std::sqrt((a + c) + (b + d)) == 1.0;
}

Eigen::Vector4d NormalizedWxyz(const Eigen::Quaterniond& q) {
  // "+ 0.0" turns −0 into +0 (conjugates and negations make −0s that would print as "-0").
  Eigen::Vector4d v(q.w() + 0.0, q.x() + 0.0, q.y() + 0.0, q.z() + 0.0);
  double n = v.norm();
  if (!(n > 0)) return Eigen::Vector4d(1, 0, 0, 0);
  v /= n;
  if (ExactlyUnit(v)) return v;
  // Components by decreasing magnitude; perturbing the larger ones moves the sums most finely.
  int order[4] = {0, 1, 2, 3};
  std::sort(order, order + 4, [&](int x, int y) { return std::abs(v[x]) > std::abs(v[y]); });
  auto step = [](double x, int k) {
    for (; k > 0; --k) x = std::nextafter(x, HUGE_VAL);
    for (; k < 0; ++k) x = std::nextafter(x, -HUGE_VAL);
    return x;
  };
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int r = 1; r <= 16; ++r)
    for (const auto& pr : pairs) {
      int i0 = order[pr[0]], i1 = order[pr[1]];
      for (int da = -r; da <= r; ++da)
        for (int db = -r; db <= r; ++db) {
          if (std::max(std::abs(da), std::abs(db)) != r) continue;
          Eigen::Vector4d c = v;
          c[i0] = step(v[i0], da);
          c[i1] = step(v[i1], db);
          if (ExactlyUnit(c)) return c;
        }
    }
  return v;
}

template <typename T>
void Join(std::ostream& os, const T& x, bool& first) {
  if (!first) os << ' ';
  first = false;
  os << x;
}

// The other format's files in DIR: a commit removes them (ReadColmapModel prefers binary, so a
// stale binary model beside a new text one would be the one read).
std::vector<fs::path> OtherFormat(const fs::path& dir, bool writing_binary) {
  std::vector<fs::path> out;
  for (const std::string& f : ColmapModelFileNames(!writing_binary)) out.push_back(dir / f);
  return out;
}

}  // namespace

static void WriteCamerasText(std::ostream& f, const std::map<uint32_t, Camera>& cameras) {
  f << "# Camera list with one line of data per camera:\n"
    << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
    << "# Number of cameras: " << cameras.size() << "\n";
  for (const auto& [id, c] : cameras) {
    f << id << ' ' << CameraModelName(c.model) << ' ' << c.width << ' ' << c.height;
    for (double p : c.params) f << ' ' << p;
    f << '\n';
  }
}

void WriteColmapCamerasText(const std::map<uint32_t, Camera>& cameras, const std::string& file) {
  WriteTextAtomic(file, [&](std::ostream& f) { WriteCamerasText(f, cameras); });
}

void WriteColmapImagesHeader(std::ostream& f, size_t images, size_t observations) {
  const double mean = images == 0 ? 0.0 : double(observations) / double(images);
  f << "# Image list with two lines of data per image:\n"
    << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
    << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
    << "# Number of images: " << images << ", mean observations per image: " << mean << "\n";
}

void WriteColmapImageText(std::ostream& f, uint32_t id, const ImageRecord& im) {
  Eigen::Vector4d q = NormalizedWxyz(im.world_to_camera.q);
  const Eigen::Vector3d t = im.world_to_camera.t.array() + 0.0;  // no "-0"
  f << id << ' ' << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << ' ' << t.x() << ' '
    << t.y() << ' ' << t.z() << ' ' << im.camera_id << ' ' << im.name << '\n';
  bool first = true;
  for (const auto& p : im.points2D) {
    Join(f, p.xy.x(), first);
    Join(f, p.xy.y(), first);
    if (p.point3D_id == kInvalidPoint3DId)
      Join(f, -1, first);
    else
      Join(f, p.point3D_id, first);
  }
  f << '\n';
}

void WriteColmapPointsHeader(std::ostream& f, size_t points, size_t track_sum) {
  const double mean = points == 0 ? 0.0 : double(track_sum) / double(points);
  f << "# 3D point list with one line of data per point:\n"
    << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
    << "# Number of points: " << points << ", mean track length: " << mean << "\n";
}

void WriteColmapPointText(std::ostream& f, uint64_t id, const Point3D& p) {
  f << id << ' ' << p.xyz.x() << ' ' << p.xyz.y() << ' ' << p.xyz.z() << ' ' << int(p.rgb[0]) << ' '
    << int(p.rgb[1]) << ' ' << int(p.rgb[2]) << ' ' << p.error;
  for (const auto& el : p.track) f << ' ' << el.image_id << ' ' << el.point2D_idx;
  f << '\n';
}

// The three files are renamed into place together (one journalled step), and the other format's
// are removed only then: a failed write (a full disk) leaves the model that was there whole.
void WriteColmapText(const Reconstruction& r, const std::string& dir) {
  fs::path d(dir);
  size_t observations = 0;
  for (const auto& [id, im] : r.images)
    for (const auto& p : im.points2D) observations += p.point3D_id != kInvalidPoint3DId;
  const auto cameras = [&](std::ostream& f) { WriteCamerasText(f, r.cameras); };
  const auto images = [&](std::ostream& f) {
    WriteColmapImagesHeader(f, r.images.size(), observations);
    for (const auto& [id, im] : r.images) WriteColmapImageText(f, id, im);
  };
  const auto points = [&](std::ostream& f) {
    size_t track_sum = 0;
    for (const auto& [id, p] : r.points3D) track_sum += p.track.size();
    WriteColmapPointsHeader(f, r.points3D.size(), track_sum);
    for (const auto& [id, p] : r.points3D) WriteColmapPointText(f, id, p);
  };
  WriteTogetherAtomic(
      {{d / "cameras.txt", cameras}, {d / "images.txt", images}, {d / "points3D.txt", points}},
      false, OtherFormat(d, false));
}

// ---------------------------------------------------------------------------------------------
// Binary (little-endian, as COLMAP writes on x86).

namespace {

class BinReader {
 public:
  explicit BinReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw Error(path, 0, "cannot open");
  }
  template <typename T>
  T Get(const char* what) {
    T v;
    in_.read(reinterpret_cast<char*>(&v), sizeof v);
    if (!in_) Fail(std::string("truncated file while reading ") + what);
    pos_ += sizeof v;
    return v;
  }
  std::string GetString() {
    std::string s;
    char c;
    while (in_.get(c)) {
      ++pos_;
      if (c == '\0') return s;
      s.push_back(c);
      if (s.size() > 4096) Fail("image name longer than 4096 bytes (corrupt file?)");
    }
    Fail("truncated file while reading an image name");
  }
  void CheckCount(uint64_t n, size_t min_bytes_each, const char* what) {
    // Reject counts that cannot fit in the rest of the file before allocating for them.
    auto here = in_.tellg();
    in_.seekg(0, std::ios::end);
    auto end = in_.tellg();
    in_.seekg(here);
    if (min_bytes_each > 0 && n > static_cast<uint64_t>(end - here) / min_bytes_each)
      Fail(std::string(what) + " count " + std::to_string(n) + " exceeds the file size");
  }
  void ExpectEnd() {
    char c;
    if (in_.get(c)) Fail("unexpected data after the last record");
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(path_, 0, "byte " + std::to_string(pos_) + ": " + what);
  }

 private:
  std::string path_;
  std::ifstream in_;
  uint64_t pos_ = 0;
};

template <typename T>
void Put(std::ostream& o, T v) {
  o.write(reinterpret_cast<const char*>(&v), sizeof v);
}

}  // namespace

namespace {

std::map<uint32_t, Camera> ReadCamerasBinary(const std::string& path) {
  std::map<uint32_t, Camera> out;
  BinReader in(path);
  uint64_t n = in.Get<uint64_t>("camera count");
  in.CheckCount(n, 24, "camera");
  for (uint64_t i = 0; i < n; ++i) {
    Camera c;
    c.id = in.Get<uint32_t>("CAMERA_ID");
    int32_t model = in.Get<int32_t>("MODEL_ID");
    try {
      c.model = CameraModelFromId(model);
    } catch (const Error& e) {
      in.Fail(e.what());
    }
    c.width = in.Get<uint64_t>("WIDTH");
    c.height = in.Get<uint64_t>("HEIGHT");
    for (int k = 0; k < CameraModelNumParams(c.model); ++k)
      c.params.push_back(in.Get<double>("PARAMS"));
    std::string problem = CameraProblem(c);
    if (!problem.empty()) in.Fail("camera " + std::to_string(c.id) + ": " + problem);
    if (!out.emplace(c.id, c).second) in.Fail("duplicate CAMERA_ID " + std::to_string(c.id));
  }
  in.ExpectEnd();
  return out;
}

std::map<uint32_t, ImageRecord> ReadImagesBinary(const std::string& path) {
  std::map<uint32_t, ImageRecord> out;
  std::set<std::string> names;
  BinReader in(path);
  uint64_t n = in.Get<uint64_t>("image count");
  in.CheckCount(n, 73, "image");
  for (uint64_t i = 0; i < n; ++i) {
    ImageRecord im;
    im.id = in.Get<uint32_t>("IMAGE_ID");
    double q[4], t[3];
    for (double& v : q) v = in.Get<double>("QVEC");
    for (double& v : t) v = in.Get<double>("TVEC");
    if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 0))
      in.Fail("image " + std::to_string(im.id) + ": quaternion has zero norm");
    im.world_to_camera = Rigid3d(Eigen::Quaterniond(q[0], q[1], q[2], q[3]), {t[0], t[1], t[2]});
    im.camera_id = in.Get<uint32_t>("CAMERA_ID");
    im.name = in.GetString();
    uint64_t np = in.Get<uint64_t>("points2D count");
    in.CheckCount(np, 24, "points2D");
    im.points2D.resize(np);
    for (auto& p : im.points2D) {
      p.xy.x() = in.Get<double>("X");
      p.xy.y() = in.Get<double>("Y");
      p.point3D_id = in.Get<uint64_t>("POINT3D_ID");
    }
    uint32_t id = im.id;
    if (!names.insert(im.name).second) in.Fail("duplicate image NAME " + im.name);
    if (!out.emplace(id, std::move(im)).second) in.Fail("duplicate IMAGE_ID " + std::to_string(id));
  }
  in.ExpectEnd();
  return out;
}

std::map<uint64_t, Point3D> ReadPoints3DBinary(const std::string& path) {
  std::map<uint64_t, Point3D> out;
  BinReader in(path);
  uint64_t n = in.Get<uint64_t>("point count");
  in.CheckCount(n, 43, "point");
  for (uint64_t i = 0; i < n; ++i) {
    Point3D p;
    p.id = in.Get<uint64_t>("POINT3D_ID");
    for (int k = 0; k < 3; ++k) p.xyz[k] = in.Get<double>("XYZ");
    for (auto& c : p.rgb) c = in.Get<uint8_t>("RGB");
    p.error = in.Get<double>("ERROR");
    uint64_t tl = in.Get<uint64_t>("track length");
    in.CheckCount(tl, 8, "track");
    p.track.resize(tl);
    for (auto& el : p.track) {
      el.image_id = in.Get<uint32_t>("IMAGE_ID");
      el.point2D_idx = in.Get<uint32_t>("POINT2D_IDX");
    }
    uint64_t id = p.id;
    if (!out.emplace(id, std::move(p)).second)
      in.Fail("duplicate POINT3D_ID " + std::to_string(id));
  }
  in.ExpectEnd();
  return out;
}

}  // namespace

Reconstruction ReadColmapBinary(const std::string& dir) {
  const FolderLock lock = LockForReading(dir);
  return ReadBinaryLocked(dir);
}

namespace {

Reconstruction ReadBinaryLocked(const std::string& dir) {
  Reconstruction r;
  const std::string img_file = (fs::path(dir) / "images.bin").string();
  const std::string pts_file = (fs::path(dir) / "points3D.bin").string();
  r.cameras = ReadCamerasBinary((fs::path(dir) / "cameras.bin").string());
  r.images = ReadImagesBinary(img_file);
  r.points3D = ReadPoints3DBinary(pts_file);
  CheckReferences(r, img_file, pts_file);
  return r;
}

}  // namespace

// As WriteColmapText: the three files renamed into place together.
void WriteColmapBinary(const Reconstruction& r, const std::string& dir) {
  fs::path d(dir);
  const auto cameras = [&](std::ostream& o) {
    Put<uint64_t>(o, r.cameras.size());
    for (const auto& [id, c] : r.cameras) {
      Put<uint32_t>(o, id);
      Put<int32_t>(o, static_cast<int32_t>(c.model));
      Put<uint64_t>(o, c.width);
      Put<uint64_t>(o, c.height);
      for (double p : c.params) Put<double>(o, p);
    }
  };
  const auto images = [&](std::ostream& o) {
    Put<uint64_t>(o, r.images.size());
    for (const auto& [id, im] : r.images) {
      Put<uint32_t>(o, id);
      Eigen::Vector4d q = NormalizedWxyz(im.world_to_camera.q);
      for (int k = 0; k < 4; ++k) Put<double>(o, q[k]);
      for (int k = 0; k < 3; ++k) Put<double>(o, im.world_to_camera.t[k]);
      Put<uint32_t>(o, im.camera_id);
      o.write(im.name.c_str(), static_cast<std::streamsize>(im.name.size() + 1));
      Put<uint64_t>(o, im.points2D.size());
      for (const auto& p : im.points2D) {
        Put<double>(o, p.xy.x());
        Put<double>(o, p.xy.y());
        Put<uint64_t>(o, p.point3D_id);
      }
    }
  };
  const auto points = [&](std::ostream& o) {
    Put<uint64_t>(o, r.points3D.size());
    for (const auto& [id, p] : r.points3D) {
      Put<uint64_t>(o, id);
      for (int k = 0; k < 3; ++k) Put<double>(o, p.xyz[k]);
      for (uint8_t c : p.rgb) Put<uint8_t>(o, c);
      Put<double>(o, p.error);
      Put<uint64_t>(o, p.track.size());
      for (const auto& el : p.track) {
        Put<uint32_t>(o, el.image_id);
        Put<uint32_t>(o, el.point2D_idx);
      }
    }
  };
  WriteTogetherAtomic(
      {{d / "cameras.bin", cameras}, {d / "images.bin", images}, {d / "points3D.bin", points}},
      true, OtherFormat(d, true));
}

}  // namespace mvtm

// densify's plane sweep two ways, on the same inputs, in the same run (issue #10):
//   CPU  SweepDepth of libcore/stereo, what densify runs: per plane and neighbour OpenCV
//        warpPerspective of the neighbour and box-filtered ZNCC, best-k over the neighbours,
//        planes in parallel on OpenCV's pool;
//   GL   the same sweep on the headless GL context of libcore/render (llvmpipe here): the
//        reference and the neighbours as float textures; per plane one pass samples every
//        neighbour through the plane homography (a bilinear texture lookup) into float targets
//        (J, J², I·J, seen), a horizontal and a vertical box pass give the window sums, and the
//        vertical pass also takes the ZNCC, the best k of the neighbours and a running best plane
//        (with the scores beside it for the parabola, and the sum and count for the margin) per
//        pixel; one read-back at the end, then the parabola and the trust test on the CPU.
// The GL sweep computes what the CPU one does: the bench prints the share of textured pixels
// (reference window sd >= 2) on which both pick the same plane, and fails below 95 %.
//
// Inputs: a synthetic road (ground, two facades, an end wall, three car backs; value-noise
// textures, a flat sky) seen by a KITTI-like camera at 640x192 and 1241x376 from a reference
// and 4 neighbours 0.8 and 1.6 m behind and ahead of it (forward baseline, a few cm sideways);
// one fronto-parallel family of --planes planes (48) from 4 to 160 m, window 7, best 2 of 4.
// Times are the best of --repeat runs (the least disturbed by other load on a shared machine);
// the GL time counts the reference's window statistics (OpenCV, as the CPU variant), the uploads
// of the 5 images, every pass, the read-back (also printed apart) and the parabola and trust test
// after it, not the one-off context creation and shader compilation (printed apart), nor the
// first run (printed apart: llvmpipe compiles its shader variants there). Per plane-neighbour
// times are the sweep's time over planes x neighbours. Also the CPU time of all the process's
// threads per sweep (OpenCV's pool, llvmpipe's threads), less disturbed by other load. Run with
// MESA_SHADER_CACHE_DISABLE=true (as bench_report.py does).
// usage: bench_planesweep [--short] [--planes P] [--repeat R]
#include <glad/gl.h>
#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_util.h"
#include "render/context.h"
#include "render/gl_program.h"
#include "stereo/plane_sweep.h"

using namespace mvtm;
using Clock = std::chrono::steady_clock;

namespace {

constexpr float kNoScore = -2.f;  // as in plane_sweep.cpp: "this neighbour / plane says nothing"

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// CPU time of all the process's threads (OpenCV's pool and llvmpipe's included), ms: less
// disturbed by other processes on the machine than wall time.
double CpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

// Wall and CPU ms of the fastest of `repeat` runs of f (each the least disturbed of its runs).
struct Times {
  double wall = 1e300, cpu = 1e300;
};
template <typename F>
Times Best(int repeat, F&& f) {
  Times best;
  for (int i = 0; i < repeat; ++i) {
    const double c0 = CpuMs();
    const auto t0 = Clock::now();
    f();
    best.wall = std::min(best.wall, Ms(t0, Clock::now()));
    best.cpu = std::min(best.cpu, CpuMs() - c0);
  }
  return best;
}

// ---- The scene -------------------------------------------------------------------------------

// Value noise (bilinear between pseudo-random lattice values), two octaves: asphalt-like.
double Lattice(long i, long j) {
  uint64_t h = uint64_t(i) * 0x9E3779B97F4A7C15ull ^ uint64_t(j) * 0xC2B2AE3D27D4EB4Full;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return double(h % 1000) / 999.0;
}
double Noise(double a, double b, double cell) {
  const double u = a / cell, v = b / cell;
  const long i = long(std::floor(u)), j = long(std::floor(v));
  const double fu = u - double(i), fv = v - double(j);
  return (1 - fu) * ((1 - fv) * Lattice(i, j) + fv * Lattice(i, j + 1)) +
         fu * ((1 - fv) * Lattice(i + 1, j) + fv * Lattice(i + 1, j + 1));
}

// An axis-aligned rectangle: coordinate `axis` equals `at`, the other two (in x, y, z order)
// within [lo, hi].
struct Rect {
  int axis;
  double at;
  Eigen::Vector2d lo, hi;
};

// Reference camera coordinates = world (x right, y down, z forward); the camera 1.65 m above the
// ground on a 14 m wide street.
const std::vector<Rect>& Street() {
  static const std::vector<Rect> s = {
      {1, 1.65, {-7, -10}, {7, 200}},      // ground (x, z)
      {0, -7, {-12, -10}, {1.65, 200}},    // left facade (y, z)
      {0, 7, {-12, -10}, {1.65, 200}},     // right facade
      {2, 150, {-7, -12}, {7, 1.65}},      // end wall (x, y)
      {2, 10, {-4.6, 0.2}, {-2.8, 1.65}},  // car backs
      {2, 18, {1.2, 0.3}, {3.0, 1.65}},   {2, 30, {-1.0, 0.2}, {1.0, 1.65}},
  };
  return s;
}

// Grey image (CV_32F, 0..255) the camera centred at C (identity rotation) sees.
cv::Mat See(const Camera& cam, const Eigen::Vector3d& C) {
  cv::Mat im(int(cam.height), int(cam.width), CV_32F);
  const Eigen::Matrix3d Ki = cam.K().inverse();
  for (int y = 0; y < im.rows; ++y)
    for (int x = 0; x < im.cols; ++x) {
      const Eigen::Vector3d r = Ki * Eigen::Vector3d(x + 0.5, y + 0.5, 1);
      double best = 1e300, value = 180;  // sky: flat
      for (size_t k = 0; k < Street().size(); ++k) {
        const Rect& q = Street()[k];
        if (r[q.axis] == 0) continue;
        const double t = (q.at - C[q.axis]) / r[q.axis];
        if (!(t > 0) || t >= best) continue;
        const Eigen::Vector3d X = C + t * r;
        const int a = (q.axis + 1) % 3, b = (q.axis + 2) % 3;
        const double ua = X[std::min(a, b)], ub = X[std::max(a, b)];
        if (ua < q.lo.x() || ua > q.hi.x() || ub < q.lo.y() || ub > q.hi.y()) continue;
        best = t;
        value =
            30 + 150 * Noise(ua, ub, 0.3) + 60 * Noise(ua + 7.1, ub - 3.3, 0.07) + 10 * double(k);
      }
      im.at<float>(y, x) = float(value);
    }
  return im;
}

Rigid3d At(const Eigen::Vector3d& c) { return Rigid3d(Eigen::Quaterniond::Identity(), -c); }

struct Inputs {
  StereoView ref;
  std::vector<StereoView> nbs;
};

Inputs MakeInputs(int w, int h) {
  const Camera cam =
      ParseCameraSpec("PINHOLE 1241 376 718.856 718.856 607.1928 185.2157").Scaled(w, h);
  Inputs in{{cam, At({0, 0, 0}), See(cam, {0, 0, 0})}, {}};
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(0.04, 0, -1.6), Eigen::Vector3d(-0.03, 0, -0.8),
                                   Eigen::Vector3d(0.03, 0, 0.8), Eigen::Vector3d(-0.04, 0, 1.6)})
    in.nbs.push_back({cam, At(c), See(cam, c)});
  return in;
}

// ---- The GL sweep ----------------------------------------------------------------------------

// The shaders' per-neighbour lines: `text` once per neighbour j with every '$' replaced by j
// (GLSL 3.30 indexes sampler arrays only with constants).
std::string PerNeighbour(const std::string& text, int n) {
  std::string out;
  for (int j = 0; j < n; ++j)
    for (char c : text) out += c == '$' ? std::to_string(j) : std::string(1, c);
  return out;
}

const char* kVertex = R"(
void main() {  // one triangle over the whole target
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

// Reference pixel -> (J, J², I·J, seen) of every neighbour, J sampled through the homography.
std::string WarpShader(int n) {
  return "uniform sampler2D ref;\n" +
         PerNeighbour(
             "uniform sampler2D nb$;\nuniform mat3 H$;\nuniform vec2 size$;\n"
             "uniform float on$;\nlayout(location = $) out vec4 o$;\n",
             n) +
         "void main() {\n"
         "  float I = texelFetch(ref, ivec2(gl_FragCoord.xy), 0).r;\n" +
         PerNeighbour(
             "  {\n"
             "    vec3 p = H$ * vec3(gl_FragCoord.xy, 1.0);\n"
             "    vec2 u = p.xy / p.z;\n"
             "    bool seen = on$ > 0.5 && p.z > 0.0 && all(greaterThanEqual(u, vec2(0.0))) &&\n"
             "                all(lessThan(u, size$));\n"
             "    float J = seen ? texture(nb$, u / size$).r : 0.0;\n"
             "    o$ = vec4(J, J * J, I * J, seen ? 1.0 : 0.0);\n"
             "  }\n",
             n) +
         "}\n";
}

// Horizontal window sums of the warp targets.
std::string HBoxShader(int n, int radius) {
  return PerNeighbour("uniform sampler2D w$;\nlayout(location = $) out vec4 o$;\n", n) +
         "void main() {\n"
         "  ivec2 q = ivec2(gl_FragCoord.xy);\n"
         "  int xmax = textureSize(w0, 0).x - 1;\n" +
         PerNeighbour("  vec4 s$ = vec4(0.0);\n", n) + "  for (int dx = -" +
         std::to_string(radius) + "; dx <= " + std::to_string(radius) +
         "; ++dx) {\n"
         "    ivec2 t = ivec2(clamp(q.x + dx, 0, xmax), q.y);\n" +
         PerNeighbour("    s$ += texelFetch(w$, t, 0);\n", n) + "  }\n" +
         PerNeighbour("  o$ = s$;\n", n) + "}\n";
}

// Sorts the floats v0..v(n-1) in descending order: n rounds of compare-exchange of neighbours
// (odd-even transposition), max and min without branches or indexed arrays (which llvmpipe
// would keep in memory).
std::string SortDescending(int n) {
  std::string out;
  for (int round = 0; round < n; ++round)
    for (int i = round % 2; i + 1 < n; i += 2) {
      const std::string a = "v" + std::to_string(i), b = "v" + std::to_string(i + 1);
      out += "  { float hi = max(" + a + ", " + b + "), lo = min(" + a + ", " + b + "); " + a +
             " = hi; " + b + " = lo; }\n";
    }
  return out;
}

std::string Sum(int k) {
  std::string out;
  for (int i = 0; i < k; ++i) out += "  sum += v" + std::to_string(i) + ";\n";
  return out;
}

// Vertical window sums, ZNCC per neighbour, mean of the best k, and the running best plane:
//   A = (best score, best plane, score of the plane before it, score of the plane after it)
//   B = (score of the previous plane, sum of the scores that exist, their count, 0)
std::string ScoreShader(int n, int radius, int k) {
  const std::string r = std::to_string(radius);
  return PerNeighbour("uniform sampler2D h$;\n", n) +
         "uniform sampler2D stats;  // reference window mean, sd\n"
         "uniform sampler2D stateA;\nuniform sampler2D stateB;\n"
         "uniform float plane;\nuniform float offset;\nuniform vec3 ray_dot;\n"
         "layout(location = 0) out vec4 oA;\nlayout(location = 1) out vec4 oB;\n"
         "const float kNo = -2.0;\n"
         "float Zncc(vec4 s, vec2 st, bool inside) {\n"
         "  vec4 m = s * (1.0 / float(" +
         std::to_string((2 * radius + 1) * (2 * radius + 1)) +
         "));  // mean J, JJ, IJ, cover\n"
         "  float var_b = m.y - m.x * m.x;\n"
         "  if (!inside || m.w < 0.999 || var_b <= 1e-6 || st.y <= 1e-3) return kNo;\n"
         "  return clamp((m.z - st.x * m.x) / (st.y * sqrt(var_b)), -1.0, 1.0);\n"
         "}\n"
         "void main() {\n"
         "  ivec2 q = ivec2(gl_FragCoord.xy);\n"
         "  ivec2 size = textureSize(stats, 0);\n" +
         PerNeighbour("  vec4 s$ = vec4(0.0);\n", n) + "  for (int dy = -" + r + "; dy <= " + r +
         "; ++dy) {\n"
         "    ivec2 t = ivec2(q.x, clamp(q.y + dy, 0, size.y - 1));\n" +
         PerNeighbour("    s$ += texelFetch(h$, t, 0);\n", n) +
         "  }\n"
         "  bool inside = all(greaterThanEqual(q, ivec2(" +
         r + "))) && all(lessThan(q, size - " + r +
         "));\n"
         "  vec2 st = texelFetch(stats, q, 0).rg;\n" +
         PerNeighbour("  float v$ = Zncc(s$, st, inside);\n", n) + SortDescending(n) +
         "  float sum = 0.0;\n" + Sum(k) + "  float score = v" + std::to_string(k - 1) +
         " > kNo ? sum / float(" + std::to_string(k) +
         ") : kNo;\n"
         "  if (!(offset / dot(ray_dot, vec3(gl_FragCoord.xy, 1.0)) > 0.0)) score = kNo;\n"
         "  vec4 A = texelFetch(stateA, q, 0), B = texelFetch(stateB, q, 0);\n"
         "  if (A.y == plane - 1.0) A.w = score;\n"
         "  if (score > kNo) B.yz += vec2(score, 1.0);\n"
         "  if (score > A.x) A = vec4(score, plane, B.x, kNo);\n"
         "  B.x = score;\n"
         "  oA = A;\n"
         "  oB = B;\n"
         "}\n";
}

GLuint Texture(int w, int h, GLenum internal, GLenum format, bool linear) {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexImage2D(GL_TEXTURE_2D, 0, GLint(internal), w, h, 0, format, GL_FLOAT, nullptr);
  const GLint filter = linear ? GL_LINEAR : GL_NEAREST;
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
  // Outside the image: 0, as OpenCV's BORDER_CONSTANT (such pixels are not `seen` anyway).
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
  return t;
}

GLuint Framebuffer(const std::vector<GLuint>& targets) {
  GLuint f = 0;
  glGenFramebuffers(1, &f);
  glBindFramebuffer(GL_FRAMEBUFFER, f);
  std::vector<GLenum> bufs;
  for (size_t i = 0; i < targets.size(); ++i) {
    glFramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D,
                           targets[i], 0);
    bufs.push_back(GLenum(GL_COLOR_ATTACHMENT0 + i));
  }
  glDrawBuffers(GLsizei(bufs.size()), bufs.data());
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("incomplete framebuffer");
  return f;
}

struct GlResult {
  DepthMap map;
  std::vector<float> A, B;  // the final state per pixel (see ScoreShader)
  double upload_ms = 0, sweep_ms = 0, readback_ms = 0, finish_ms = 0;
};

// Textures, targets and programs for one image size and neighbour count (made once; densify would
// keep them for every image of a size).
class GlSweep {
 public:
  GlSweep(int w, int h, int n, int window, int k) : w_(w), h_(h), n_(n) {
    if (n < 1 || n > 4) throw std::runtime_error("GL sweep: 1..4 neighbours");
    const int r = window / 2;
    warp_ = BuildProgramFromText("planesweep_warp", kVertex, WarpShader(n));
    hbox_ = BuildProgramFromText("planesweep_hbox", kVertex, HBoxShader(n, r));
    score_ = BuildProgramFromText("planesweep_score", kVertex, ScoreShader(n, r, k));
    glGenVertexArrays(1, &vao_);
    ref_ = Texture(w, h, GL_R32F, GL_RED, false);
    stats_ = Texture(w, h, GL_RG32F, GL_RG, false);
    std::vector<GLuint> warped, hsum;
    for (int j = 0; j < n; ++j) {
      nb_.push_back(Texture(w, h, GL_R32F, GL_RED, true));
      warped.push_back(Texture(w, h, GL_RGBA32F, GL_RGBA, false));
      hsum.push_back(Texture(w, h, GL_RGBA32F, GL_RGBA, false));
    }
    fb_warp_ = Framebuffer(warped);
    fb_hbox_ = Framebuffer(hsum);
    for (int s = 0; s < 2; ++s) {
      stateA_[s] = Texture(w, h, GL_RGBA32F, GL_RGBA, false);
      stateB_[s] = Texture(w, h, GL_RGBA32F, GL_RGBA, false);
      fb_state_[s] = Framebuffer({stateA_[s], stateB_[s]});
    }
    // Texture units: ref 0, stats 1, neighbours / warped / h-sums 2.., state 8, 9.
    glUseProgram(warp_);
    glUniform1i(glGetUniformLocation(warp_, "ref"), 0);
    for (int j = 0; j < n; ++j) {
      glUniform1i(Loc(warp_, "nb", j), 2 + j);
      glUniform2f(Loc(warp_, "size", j), float(w), float(h));
    }
    glUseProgram(hbox_);
    for (int j = 0; j < n; ++j) glUniform1i(Loc(hbox_, "w", j), 2 + j);
    glUseProgram(score_);
    glUniform1i(glGetUniformLocation(score_, "stats"), 1);
    for (int j = 0; j < n; ++j) glUniform1i(Loc(score_, "h", j), 2 + j);
    glUniform1i(glGetUniformLocation(score_, "stateA"), 8);
    glUniform1i(glGetUniformLocation(score_, "stateB"), 9);
    warped_ = warped;
    hsum_ = hsum;
  }

  GlResult Run(const StereoView& ref, const std::vector<StereoView>& nbs, const SweepFamily& f,
               const PlaneSweepOptions& o) {
    GlResult res;
    const auto t0 = Clock::now();
    // The reference's window statistics, as plane_sweep.cpp's WindowStats.
    cv::Mat mean, sq, sd;
    cv::boxFilter(ref.grey, mean, CV_32F, {o.window, o.window}, {-1, -1}, true, cv::BORDER_REFLECT);
    cv::boxFilter(ref.grey.mul(ref.grey), sq, CV_32F, {o.window, o.window}, {-1, -1}, true,
                  cv::BORDER_REFLECT);
    cv::Mat var = sq - mean.mul(mean);
    cv::max(var, 0.0, var);
    cv::sqrt(var, sd);
    cv::Mat stats;
    cv::merge(std::vector<cv::Mat>{mean, sd}, stats);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    Upload(ref_, ref.grey, GL_RED);
    Upload(stats_, stats, GL_RG);
    for (int j = 0; j < n_; ++j) Upload(nb_[size_t(j)], nbs[size_t(j)].grey, GL_RED);
    const auto t1 = Clock::now();

    glViewport(0, 0, w_, h_);
    glBindVertexArray(vao_);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    const float initA[4] = {kNoScore, -1, kNoScore, kNoScore}, initB[4] = {kNoScore, 0, 0, 0};
    glBindFramebuffer(GL_FRAMEBUFFER, fb_state_[0]);
    glClearBufferfv(GL_COLOR, 0, initA);
    glClearBufferfv(GL_COLOR, 1, initB);
    const Eigen::Matrix3d Ki = ref.camera.K().inverse();
    const Eigen::Vector3d rd = Ki.transpose() * f.normal;  // n·K⁻¹(x, y, 1)
    int cur = 0;
    for (size_t p = 0; p < f.offsets.size(); ++p) {
      const double d = f.offsets[p];
      glUseProgram(warp_);
      for (int j = 0; j < n_; ++j) {
        const Eigen::Matrix3d H = PlaneHomography(ref, nbs[size_t(j)], f.normal, d);
        const double scale = H.norm();
        const bool on = d != 0 && std::isfinite(scale) && scale != 0 &&
                        std::abs(H.determinant()) >= 1e-12 * scale * scale * scale;
        float m[9];
        for (int a = 0; a < 9; ++a) m[a] = on ? float(H(a / 3, a % 3)) : 0.f;
        glUniformMatrix3fv(Loc(warp_, "H", j), 1, GL_TRUE, m);
        glUniform1f(Loc(warp_, "on", j), on ? 1.f : 0.f);
      }
      Bind(0, ref_);
      for (int j = 0; j < n_; ++j) Bind(2 + j, nb_[size_t(j)]);
      Draw(fb_warp_);
      glUseProgram(hbox_);
      for (int j = 0; j < n_; ++j) Bind(2 + j, warped_[size_t(j)]);
      Draw(fb_hbox_);
      glUseProgram(score_);
      glUniform1f(glGetUniformLocation(score_, "plane"), float(p));
      glUniform1f(glGetUniformLocation(score_, "offset"), float(d));
      glUniform3f(glGetUniformLocation(score_, "ray_dot"), float(rd.x()), float(rd.y()),
                  float(rd.z()));
      Bind(1, stats_);
      for (int j = 0; j < n_; ++j) Bind(2 + j, hsum_[size_t(j)]);
      Bind(8, stateA_[cur]);
      Bind(9, stateB_[cur]);
      Draw(fb_state_[1 - cur]);
      cur = 1 - cur;
    }
    glFinish();
    const auto t2 = Clock::now();
    res.A.resize(size_t(w_) * size_t(h_) * 4);
    res.B.resize(res.A.size());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fb_state_[cur]);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w_, h_, GL_RGBA, GL_FLOAT, res.A.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w_, h_, GL_RGBA, GL_FLOAT, res.B.data());
    const auto t3 = Clock::now();
    res.map = Finish(res, f, ref.camera, sd, o);
    const auto t4 = Clock::now();
    res.upload_ms = Ms(t0, t1);
    res.sweep_ms = Ms(t1, t2);
    res.readback_ms = Ms(t2, t3);
    res.finish_ms = Ms(t3, t4);
    return res;
  }

 private:
  static GLint Loc(GLuint prog, const std::string& name, int j) {
    return glGetUniformLocation(prog, (name + std::to_string(j)).c_str());
  }
  static void Bind(int unit, GLuint tex) {
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, tex);
  }
  void Draw(GLuint fb) {
    glBindFramebuffer(GL_FRAMEBUFFER, fb);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  void Upload(GLuint tex, const cv::Mat& m, GLenum format) {
    if (!m.isContinuous()) throw std::runtime_error("upload: not continuous");
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w_, h_, format, GL_FLOAT, m.data);
  }

  // plane_sweep.cpp's TakeBest (the parabola through the best plane's neighbours) and trust test
  // on the read-back state.
  DepthMap Finish(const GlResult& r, const SweepFamily& f, const Camera& cam, const cv::Mat& sd,
                  const PlaneSweepOptions& o) const {
    DepthMap out{Image(w_, h_, 1, 32, std::numeric_limits<float>::infinity()),
                 Image(w_, h_, 1, 32, 0.f)};
    const int P = int(f.offsets.size());
    auto param = [&](int p) {
      return f.inverse_spacing ? 1.0 / f.offsets[size_t(p)] : f.offsets[size_t(p)];
    };
    const Eigen::Vector3d rd = cam.K().inverse().transpose() * f.normal;
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const float* A = &r.A[(size_t(y) * size_t(w_) + size_t(x)) * 4];
        const float* B = &r.B[(size_t(y) * size_t(w_) + size_t(x)) * 4];
        const float bs = A[0];
        const int bp = int(A[1]);
        if (bp < 0) continue;
        double s = param(bp);
        if (bp > 0 && bp + 1 < P) {
          const double a = A[2], c = A[3], den = a - 2.0 * bs + c;
          if (a > kNoScore && c > kNoScore && den < 0) {
            const double delta = std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
            s += delta * (delta > 0 ? param(bp + 1) - s : s - param(bp - 1));
          }
        }
        const double d = f.inverse_spacing ? 1.0 / s : s;
        const double z = d / float(rd.x() * (x + 0.5) + rd.y() * (y + 0.5) + rd.z());
        if (!(z > 0) || !std::isfinite(z)) continue;
        const float margin = float(bs - B[1] / B[2]);
        if (bs < o.min_score || margin < o.min_margin || sd.at<float>(y, x) < o.min_texture)
          continue;
        out.depth.at(x, y) = float(z);
        out.confidence.at(x, y) = std::clamp(std::min(bs, margin), 0.f, 1.f);
      }
    return out;
  }

  int w_, h_, n_;
  GLuint warp_ = 0, hbox_ = 0, score_ = 0, vao_ = 0, ref_ = 0, stats_ = 0;
  std::vector<GLuint> nb_, warped_, hsum_;
  GLuint fb_warp_ = 0, fb_hbox_ = 0;
  GLuint stateA_[2] = {}, stateB_[2] = {}, fb_state_[2] = {};
};

// The sweep alone: a per-pixel refinement after it (a `refine` option of PlaneSweepOptions, where
// there is one) is switched off, so that both variants do the same work.
template <typename T>
auto NoRefinement(T& o, int) -> decltype(o.refine = 0, void()) {
  o.refine = 0;
}
template <typename T>
void NoRefinement(T&, long) {}

// The plane a depth came from (fronto family, inverse spacing): the nearest plane in 1/z.
int PlaneOf(float z, const SweepFamily& f) {
  const double p0 = 1.0 / f.offsets.front(), step = 1.0 / f.offsets[1] - p0;
  return int(std::lround((1.0 / z - p0) / step));
}

struct Row {
  int w, h, planes, nbs;
  Times cpu, gl;
  double gl_cold_ms, readback_ms, agree_textured, agree_kept;
  size_t textured, kept;
};

Row Measure(int w, int h, int planes, int repeat, GlSweep& gl) {
  const Inputs in = MakeInputs(w, h);
  const SweepFamily f = MakeFrontoSweep(4, 160, planes);
  PlaneSweepOptions keep;  // densify's defaults: window 7, best 2, the trust test
  NoRefinement(keep, 0);
  PlaneSweepOptions all = keep;  // no trust test: a best plane wherever one has a score
  all.min_score = -1, all.min_margin = 0, all.min_texture = 0;
  Row row{w, h, planes, int(in.nbs.size()), {}, {}, 0, 1e300, 0, 0, 0, 0};

  DepthMap cpu, cpu_all;
  row.cpu = Best(repeat, [&] { cpu = SweepDepth(in.ref, in.nbs, {f}, keep); });
  cpu_all = SweepDepth(in.ref, in.nbs, {f}, all);

  GlResult g;
  const auto t = Clock::now();
  g = gl.Run(in.ref, in.nbs, f, keep);  // the first run compiles llvmpipe's shader variants
  row.gl_cold_ms = Ms(t, Clock::now());
  row.gl = Best(repeat, [&] {
    g = gl.Run(in.ref, in.nbs, f, keep);
    row.readback_ms = std::min(row.readback_ms, g.readback_ms);
  });

  // Agreement of the best plane. Textured: the reference window's sd >= 2 (densify's
  // --min-texture) and the CPU has a plane there; kept: the pixels densify keeps (CPU).
  cv::Mat mean, sq;
  cv::boxFilter(in.ref.grey, mean, CV_32F, {keep.window, keep.window}, {-1, -1}, true,
                cv::BORDER_REFLECT);
  cv::boxFilter(in.ref.grey.mul(in.ref.grey), sq, CV_32F, {keep.window, keep.window}, {-1, -1},
                true, cv::BORDER_REFLECT);
  size_t same_t = 0, same_k = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float z = cpu_all.depth.at(x, y);
      const float m = mean.at<float>(y, x), var = sq.at<float>(y, x) - m * m;
      if (!std::isfinite(z) || !(var >= keep.min_texture * keep.min_texture)) continue;
      const int gp = int(g.A[(size_t(y) * size_t(w) + size_t(x)) * 4 + 1]);
      const bool same = gp == PlaneOf(z, f);
      ++row.textured;
      same_t += same;
      if (std::isfinite(cpu.depth.at(x, y))) ++row.kept, same_k += same;
    }
  row.agree_textured = row.textured ? double(same_t) / double(row.textured) : 0;
  row.agree_kept = row.kept ? double(same_k) / double(row.kept) : 0;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int planes = 48, repeat = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--short")
      quick = true, planes = 8, repeat = 1;
    else if (a == "--planes" && i + 1 < argc)
      planes = std::stoi(argv[++i]);
    else if (a == "--repeat" && i + 1 < argc)
      repeat = std::max(1, std::stoi(argv[++i]));
    else {
      std::fprintf(stderr, "usage: bench_planesweep [--short] [--planes P] [--repeat R]\n");
      return 2;
    }
  }
  const PlaneSweepOptions o;
  auto t = Clock::now();
  auto ctx = GlContext::Create();
  const double ctx_ms = Ms(t, Clock::now());
  const char* lp = std::getenv("LP_NUM_THREADS");
  std::printf("plane sweep, CPU (OpenCV, %d threads) against GL (%s, LP_NUM_THREADS=%s)\n",
              cv::getNumThreads(), ctx->Describe().c_str(), lp ? lp : "unset");
  std::printf("fronto family 4..160 m, window %d, best %d of 4 neighbours; best of %d runs\n",
              o.window, o.best_k, repeat);
  std::vector<std::pair<int, int>> sizes = {{640, 192}, {1241, 376}};
  if (quick) sizes = {{320, 96}};
  std::vector<Row> rows;
  for (auto [w, h] : sizes) {
    t = Clock::now();
    GlSweep gl(w, h, 4, o.window, o.best_k);
    const double setup_ms = Ms(t, Clock::now());
    std::printf("%dx%d: GL context %.0f ms (once), programs and targets %.0f ms (once per size)\n",
                w, h, ctx_ms, setup_ms);
    rows.push_back(Measure(w, h, planes, repeat, gl));
  }
  std::printf("\n%-9s %3s %3s %9s %9s %6s %9s %9s %6s %8s %8s %8s %8s %7s %7s\n", "size", "P", "N",
              "CPU ms", "GL ms", "CPU/GL", "CPU cpu", "GL cpu", "ratio", "CPU/pn", "GL/pn",
              "readback", "GL cold", "agree", "kept");
  bool ok = true;
  for (const Row& r : rows) {
    const double pn = double(r.planes) * r.nbs;
    char size[32];
    std::snprintf(size, sizeof size, "%dx%d", r.w, r.h);
    std::printf(
        "%-9s %3d %3d %9.1f %9.1f %6.2f %9.1f %9.1f %6.2f %8.3f %8.3f %8.2f %8.1f %6.2f%% "
        "%6.2f%%\n",
        size, r.planes, r.nbs, r.cpu.wall, r.gl.wall, r.cpu.wall / r.gl.wall, r.cpu.cpu, r.gl.cpu,
        r.cpu.cpu / r.gl.cpu, r.cpu.wall / pn, r.gl.wall / pn, r.readback_ms, r.gl_cold_ms,
        100 * r.agree_textured, 100 * r.agree_kept);
    const std::string what = std::string(size) + ", " + std::to_string(r.planes) + " planes x " +
                             std::to_string(r.nbs) + " neighbours";
    bench::Report("densify", "plane sweep on GL (llvmpipe) incl. read-back, " + what, r.gl.wall,
                  "ms", "CPU plane sweep (OpenCV), densify's", r.cpu.wall);
    bench::Report("densify", "GL sweep: best plane as the CPU's, textured pixels, " + what,
                  100 * r.agree_textured, "%", "", 0);
    if (r.agree_textured < 0.95) ok = false;
  }
  std::printf(
      "ms: wall time of one sweep (GL: uploads, passes and read-back); cpu: CPU time of all the\n"
      "process's threads for it; CPU/GL and ratio above 1: GL faster; /pn: wall ms per plane and\n"
      "neighbour (the sweep over P x N); agree: best plane as the CPU's on the textured pixels\n"
      "(window sd >= 2); kept: on the pixels densify keeps.\n");
  if (!ok) {
    std::fprintf(stderr,
                 "bench_planesweep: the GL sweep picks another plane than the CPU on "
                 "more than 5 %% of textured pixels: the times compare different work\n");
    return 1;
  }
  return 0;
}

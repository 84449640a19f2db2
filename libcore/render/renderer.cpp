#include "render/renderer.h"

#include <glad/gl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "base/error.h"
#include "image/push_pull.h"
#include "render/gl_program.h"

namespace mvtm {

namespace {

using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct Chunk {
  Eigen::Vector3d origin, lo, hi;  // world, double
  GLint base_vertex = 0;
  size_t vertex_count = 0;
  size_t first_index = 0, index_count = 0;
};

// A chunk's simplified triangles at one cell size (SetDetail), a tier per doubling of the
// distance, each with its own compacted vertices (a software rasteriser shades every vertex of
// the index range it is given).
struct ChunkLod {
  std::array<size_t, 4> first{}, count{};
  std::array<GLint, 4> base{};
};

void CheckGlError(const char* where) {
  GLenum e = glGetError();
  if (e != GL_NO_ERROR)
    throw Error(std::string("OpenGL error ") + std::to_string(e) + " in " + where);
}

// Camera coordinates (x right, y down, z forward) → clip: the GL projection of K applied to
// OpenGL eye coordinates (x, −y, −z). The one place the axis flip happens.
Eigen::Matrix4f ClipFromCamera(const Camera& c, double n, double f) {
  Eigen::Matrix4d flip = Eigen::Vector4d(1, -1, -1, 1).asDiagonal();
  return (c.GlProjection(n, f) * flip).cast<float>();
}

// Throws a one-line Error when this OpenGL cannot hold a w×h texture or framebuffer (Mesa
// crashes instead of failing cleanly on oversized allocations).
void RequireGlSize(int w, int h, const std::string& what) {
  GLint max_tex = 0, max_rb = 0, dims[2] = {0, 0};
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, dims);
  int limit = std::min({max_tex, max_rb, dims[0], dims[1]});
  if (w <= 0 || h <= 0 || w > limit || h > limit)
    throw Error(what + " of " + std::to_string(w) + "x" + std::to_string(h) +
                " pixels is beyond this OpenGL's limit of " + std::to_string(limit) +
                " pixels a side");
}

// A framebuffer of same-sized texture attachments (colour attachments 0, 1, ...), optionally
// with a depth buffer.
struct Target {
  struct Format {
    GLenum internal, format, type;
  };
  GLuint fbo = 0, depth_rb = 0;
  std::vector<GLuint> tex;
  int w = 0, h = 0;
  void Release() {
    if (fbo) glDeleteFramebuffers(1, &fbo);
    if (!tex.empty()) glDeleteTextures(static_cast<GLsizei>(tex.size()), tex.data());
    if (depth_rb) glDeleteRenderbuffers(1, &depth_rb);
    *this = Target();
  }
};

const Target::Format kLinearDepth{GL_R32F, GL_RED, GL_FLOAT};
const Target::Format kRgba8{GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE};
const Target::Format kSource{GL_R8UI, GL_RED_INTEGER, GL_UNSIGNED_BYTE};

// Linear depth from the red channel of colour attachment 0 of the bound framebuffer.
Image ReadLinearDepth(int w, int h) {
  Image out(w, h, 1, 32);
  std::vector<float> buf(static_cast<size_t>(w) * h);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, w, h, GL_RED, GL_FLOAT, buf.data());
  for (int y = 0; y < h; ++y)  // GL rows are bottom-up
    std::copy_n(buf.data() + size_t(h - 1 - y) * w, w, out.data.data() + size_t(y) * w);
  return out;
}

}  // namespace

struct Renderer::Impl {
  GLuint vao = 0, vbo = 0, ebo = 0;
  std::vector<Chunk> chunks;
  size_t triangles = 0;
  // Level of detail (SetDetail): the vertices (x y z r g b, chunk-relative), the full-detail
  // indices and which vertices lie on a chunk border (never moved, so chunks meet at any level).
  std::vector<float> verts;
  std::vector<uint32_t> indices;
  std::vector<uint8_t> border;
  double lod_distance = 0;
  bool lod_allowed = false;  // Render's surface pass only, never RenderDepth
  // Every cell size built so far (kept: a live renderer moves between levels), and what the
  // GPU buffers hold: the full mesh, then each built cell size's tiers.
  std::map<double, std::vector<ChunkLod>> lods;
  const std::vector<ChunkLod>* lod = nullptr;  // the cell size in use
  std::vector<float> gpu_verts;
  std::vector<uint32_t> gpu_indices;

  // Vertex clustering (Rossignac & Borrel 1993) of each chunk on grids of `cell` · 2^tier model
  // units: every vertex off the border moves to the first vertex of its cell, degenerate
  // triangles go, and the vertices still used are copied into the tier's own compact range.
  void BuildLod(double cell) {
    if (gpu_verts.empty()) {
      gpu_verts = verts;
      gpu_indices = indices;
    }
    std::vector<ChunkLod> out(chunks.size());
    for (size_t ci = 0; ci < chunks.size(); ++ci)
      for (size_t tier = 0; tier < 4; ++tier)
        Simplify(chunks[ci], cell * double(1 << tier), tier, out[ci]);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(gpu_verts.size() * sizeof(float)),
                 gpu_verts.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(gpu_indices.size() * sizeof(uint32_t)), gpu_indices.data(),
                 GL_STATIC_DRAW);
    glBindVertexArray(0);
    CheckGlError("level of detail");
    lods[cell] = std::move(out);
  }

  // One tier of a chunk clustered on cells of `c`, appended to the GPU arrays.
  void Simplify(const Chunk& ch, double c, size_t tier, ChunkLod& out) {
    std::unordered_map<uint64_t, uint32_t> first;
    std::vector<uint32_t> rep(ch.vertex_count);
    for (uint32_t v = 0; v < ch.vertex_count; ++v) {
      const size_t g = size_t(ch.base_vertex) + v;
      rep[v] = v;
      if (border[g]) continue;
      uint64_t key = 0;  // 21 bits per axis: a chunk spans far fewer cells
      for (int k = 0; k < 3; ++k)
        key =
            (key << 21) |
            (uint64_t(int64_t(std::floor((double(verts[6 * g + size_t(k)]) + ch.origin[k]) / c))) &
             0x1FFFFF);
      rep[v] = first.emplace(key, v).first->second;
    }
    out.base[tier] = GLint(gpu_verts.size() / 6);
    std::vector<uint32_t> compact(ch.vertex_count, UINT32_MAX);
    auto local = [&](uint32_t v) {  // the tier's index of chunk vertex v, copied on first use
      if (compact[v] == UINT32_MAX) {
        compact[v] = uint32_t(gpu_verts.size() / 6) - uint32_t(out.base[tier]);
        const size_t g = 6 * (size_t(ch.base_vertex) + v);
        gpu_verts.insert(gpu_verts.end(), verts.begin() + long(g), verts.begin() + long(g + 6));
      }
      return compact[v];
    };
    out.first[tier] = gpu_indices.size();
    for (size_t i = ch.first_index; i + 2 < ch.first_index + ch.index_count; i += 3) {
      const uint32_t a = rep[indices[i]], b = rep[indices[i + 1]], d = rep[indices[i + 2]];
      if (a != b && b != d && a != d)
        gpu_indices.insert(gpu_indices.end(), {local(a), local(b), local(d)});
    }
    out.count[tier] = gpu_indices.size() - out.first[tier];
  }

  // The detail tier of a chunk `d` model units away: -1 full, else 0..3 (one per doubling).
  int Tier(double d) const {
    if (!lod_allowed || lod_distance <= 0 || !lod || d <= lod_distance) return -1;
    return std::min(3, int(std::floor(std::log2(d / lod_distance))));
  }

  // Distance (model units) from `c` to the chunk's box.
  static double BoxDistance(const Chunk& ch, const Eigen::Vector3d& c) {
    return (c - c.cwiseMax(ch.lo).cwiseMin(ch.hi)).norm();
  }
  Eigen::Vector3d lo, hi;
  std::map<std::string, GLuint> programs;  // by defines + stage
  // Depth renders; the two passes of a colour render: surface (gbuffer.frag), then per pixel
  // (ptm.frag) into colour + source.
  Target depth_target, surface_target, colour_target;
  GLuint images = 0, depths = 0, masks = 0, seens = 0, screen_vao = 0;
  // Projector textures live in layers of four texture arrays (colour, depth, mask, seen depth)
  // that are reused across frames: a projector whose key is already in a layer is not uploaded
  // again. The seen array is allocated on first use only.
  int layer_w = 0, layer_h = 0, layer_count = 0;
  struct Layer {
    int64_t key = -1;
    bool depth = false, mask = false, seen = false;  // whether those slices are valid
    uint64_t last_used = 0;
  };
  std::vector<Layer> layers;
  uint64_t tick = 0;

  ~Impl() {
    for (auto& [k, p] : programs) glDeleteProgram(p);
    colour_target.Release();
    surface_target.Release();
    depth_target.Release();
    GLuint tex[4] = {images, depths, masks, seens};
    glDeleteTextures(4, tex);
    glDeleteBuffers(1, &vbo);
    glDeleteBuffers(1, &ebo);
    glDeleteVertexArrays(1, &vao);
    glDeleteVertexArrays(1, &screen_vao);
  }

  GLuint Program(const std::string& vert, const std::string& frag,
                 const std::vector<std::string>& defines,
                 const std::vector<std::string>& includes) {
    std::string key = vert + "|" + frag;
    for (const auto& d : defines) key += "|" + d;
    auto it = programs.find(key);
    if (it != programs.end()) return it->second;
    GLuint p = BuildProgram(vert, frag, defines, includes);
    programs[key] = p;
    return p;
  }

  void EnsureTarget(Target& t, int w, int h, const std::vector<Target::Format>& formats,
                    bool with_depth) {
    if (t.fbo && t.w == w && t.h == h) return;
    RequireGlSize(w, h, "a render");
    t.Release();
    t.w = w;
    t.h = h;
    glGenFramebuffers(1, &t.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    std::vector<GLenum> bufs;
    for (const Target::Format& f : formats) {
      GLuint id = 0;
      glGenTextures(1, &id);
      glBindTexture(GL_TEXTURE_2D, id);
      glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(f.internal), w, h, 0, f.format, f.type,
                   nullptr);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      bufs.push_back(GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(t.tex.size()));
      glFramebufferTexture2D(GL_FRAMEBUFFER, bufs.back(), GL_TEXTURE_2D, id, 0);
      t.tex.push_back(id);
    }
    glDrawBuffers(static_cast<GLsizei>(bufs.size()), bufs.data());
    if (with_depth) {
      glGenRenderbuffers(1, &t.depth_rb);
      glBindRenderbuffer(GL_RENDERBUFFER, t.depth_rb);
      glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t.depth_rb);
    }
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("OpenGL: incomplete framebuffer " + std::to_string(w) + "x" + std::to_string(h));
  }

  // Near/far planes enclosing the mesh as seen from `c` (double).
  void Planes(const Eigen::Vector3d& centre, double& n, double& f) const {
    double far = 0;
    for (int i = 0; i < 8; ++i) {
      Eigen::Vector3d corner((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                             (i & 4) ? hi.z() : lo.z());
      far = std::max(far, (corner - centre).norm());
    }
    f = std::max(1.0, far * 1.01);
    n = std::clamp(f * 1e-5, 0.01, 0.1);
  }

  // Frustum culling: a chunk is skipped when all 8 corners of its box are outside one plane of
  // the view frustum (camera coordinates, double).
  bool Visible(const Chunk& ch, const View& v, double f) const {
    const Camera& c = v.camera;
    double W = double(c.width), H = double(c.height);
    int out[5] = {0, 0, 0, 0, 0};
    for (int i = 0; i < 8; ++i) {
      Eigen::Vector3d corner((i & 1) ? ch.hi.x() : ch.lo.x(), (i & 2) ? ch.hi.y() : ch.lo.y(),
                             (i & 4) ? ch.hi.z() : ch.lo.z());
      Eigen::Vector3d x = v.world_to_camera * corner;
      double z = x.z();
      out[0] += x.x() < (0 - c.cx()) / c.fx() * z;
      out[1] += x.x() > (W - c.cx()) / c.fx() * z;
      out[2] += x.y() < (0 - c.cy()) / c.fy() * z;
      out[3] += x.y() > (H - c.cy()) / c.fy() * z;
      out[4] += z <= 0 || z > f;
    }
    for (int k : out)
      if (k == 8) return false;
    return true;
  }

  void Draw(GLuint prog, const View& v, RenderStats* stats) {
    auto t0 = Clock::now();
    double n, f;
    Eigen::Vector3d C = v.world_to_camera.Centre();
    Planes(C, n, f);
    std::vector<const Chunk*> visible;
    for (const auto& ch : chunks)
      if (Visible(ch, v, f)) visible.push_back(&ch);
    // Near chunks first: hidden fragments then fail the early depth test instead of running the
    // texturing shader (overdraw is most of the cost on a software rasteriser).
    std::sort(visible.begin(), visible.end(), [&](const Chunk* a, const Chunk* b) {
      return (a->origin - C).squaredNorm() < (b->origin - C).squaredNorm();
    });
    auto t1 = Clock::now();
    glUseProgram(prog);
    Eigen::Matrix3f R = v.world_to_camera.R().cast<float>();
    Eigen::Matrix4f P = ClipFromCamera(v.camera, n, f);
    glUniformMatrix3fv(glGetUniformLocation(prog, "u_R"), 1, GL_FALSE, R.data());
    glUniformMatrix4fv(glGetUniformLocation(prog, "u_P"), 1, GL_FALSE, P.data());
    GLint off = glGetUniformLocation(prog, "u_offset");
    glBindVertexArray(vao);
    size_t tris = 0;
    for (const Chunk* ch : visible) {
      Eigen::Vector3f o = (ch->origin - C).cast<float>();
      glUniform3fv(off, 1, o.data());
      const int tier = Tier(BoxDistance(*ch, C));
      const size_t t = size_t(std::max(tier, 0));
      const ChunkLod* l = tier < 0 ? nullptr : &(*lod)[size_t(ch - chunks.data())];
      const size_t first = l ? l->first[t] : ch->first_index;
      const size_t count = l ? l->count[t] : ch->index_count;
      const GLint base = l ? l->base[t] : ch->base_vertex;
      glDrawElementsBaseVertex(GL_TRIANGLES, static_cast<GLsizei>(count), GL_UNSIGNED_INT,
                               reinterpret_cast<void*>(first * sizeof(uint32_t)), base);
      tris += count / 3;
    }
    glFinish();
    auto t2 = Clock::now();
    if (stats) {
      stats->chunks_total = chunks.size();
      stats->chunks_drawn = visible.size();
      stats->triangles_drawn = tris;
      stats->cull_ms += Ms(t0, t1);
      stats->draw_ms += Ms(t1, t2);
    }
  }

  // (Re)allocates the texture arrays for `count` layers of w×h texels (the seen array only with
  // `seen` or when it exists); forgets all layers.
  void AllocateLayers(int w, int h, int count, bool seen) {
    RequireGlSize(w, h, "a projector image");
    auto alloc = [&](GLuint& tex, GLenum unit, GLint internal, GLenum format, GLenum type,
                     GLint filter) {
      if (!tex) glGenTextures(1, &tex);
      glActiveTexture(unit);
      glBindTexture(GL_TEXTURE_2D_ARRAY, tex);
      glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, internal, w, h, count, 0, format, type, nullptr);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, filter);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, filter);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    };
    alloc(images, GL_TEXTURE0, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR);
    alloc(depths, GL_TEXTURE1, GL_R32F, GL_RED, GL_FLOAT, GL_NEAREST);
    alloc(masks, GL_TEXTURE2, GL_R8, GL_RED, GL_UNSIGNED_BYTE, GL_NEAREST);
    if (seen || seens) alloc(seens, GL_TEXTURE5, GL_RG32F, GL_RG, GL_FLOAT, GL_NEAREST);
    layer_w = w, layer_h = h, layer_count = count;
    layers.assign(static_cast<size_t>(count), Layer());
  }

  // RGBA8 (alpha unused), the layout a software GL stores texels in: the upload is a copy.
  void UploadColour(int layer, const Image& im) {
    std::vector<uint8_t> buf(static_cast<size_t>(layer_w) * layer_h * 4, 255);
    const bool wide = im.bits == 16;
    auto to8 = [wide](float v) {  // rounded half away from zero (lround) for v ≥ 0
      return static_cast<uint8_t>(std::clamp(wide ? v / 257.f : v, 0.f, 255.f) + 0.5f);
    };
    for (size_t p = 0; p < im.pixels(); ++p)
      for (int c = 0; c < 3; ++c)
        buf[p * 4 + c] = to8(im.data[p * im.channels + (im.channels >= 3 ? c : 0)]);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, images);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, layer_w, layer_h, 1, GL_RGBA,
                    GL_UNSIGNED_BYTE, buf.data());
  }

  void UploadDepth(int layer, const Image& d) {
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, depths);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, layer_w, layer_h, 1, GL_RED, GL_FLOAT,
                    d.data.data());
  }

  // Depth and confidence (a map read by ReadSeenDepthAtCamera is uploaded as it is); a projector
  // without a seen map saw nothing (+inf everywhere), a map without a confidence channel is
  // sure (1).
  void UploadSeen(int layer, const Image* d) {
    std::vector<float> buf;
    if (!d || d->channels != 2) {
      buf.assign(static_cast<size_t>(layer_w) * layer_h * 2, 1.f);
      for (size_t p = 0; p < buf.size() / 2; ++p)
        buf[2 * p] = d ? d->data[p * d->channels] : INFINITY;
    }
    glActiveTexture(GL_TEXTURE5);  // 3 and 4 hold the surface pass's targets while shading
    glBindTexture(GL_TEXTURE_2D_ARRAY, seens);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, layer_w, layer_h, 1, GL_RG, GL_FLOAT,
                    buf.empty() ? d->data.data() : buf.data());
  }

  void UploadMask(int layer, const Image* m) {
    std::vector<uint8_t> buf(static_cast<size_t>(layer_w) * layer_h, 0);
    if (m)
      for (size_t p = 0; p < buf.size(); ++p) buf[p] = m->data[p * m->channels] > 0 ? 255 : 0;
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D_ARRAY, masks);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, layer, layer_w, layer_h, 1, GL_RED,
                    GL_UNSIGNED_BYTE, buf.data());
  }

  // Puts the frame's projectors into layers (reusing those whose key is already resident) and
  // returns the layer of each, in rank order. Seen maps: only the first `seen` projectors' (the
  // ones the shader searches; one without a map gets +inf).
  std::vector<int> PlaceProjectors(const std::vector<Projector>& ps, int n, bool need_depth,
                                   bool need_mask, int seen) {
    int w = ps[0].image->width, h = ps[0].image->height;
    for (int k = 0; k < n; ++k) {
      const Image* im = ps[k].image;
      if (im->width != w || im->height != h)
        throw Error("projector images differ in size (" + std::to_string(w) + "x" +
                    std::to_string(h) + " and " + std::to_string(im->width) + "x" +
                    std::to_string(im->height) + ")");
      for (const Image* other : {ps[k].depth, ps[k].mask, ps[k].seen})
        if (other && (other->width != w || other->height != h))
          throw Error("projector depth maps and masks must match the image size (" +
                      std::to_string(w) + "x" + std::to_string(h) + ", got " +
                      std::to_string(other->width) + "x" + std::to_string(other->height) + ")");
    }
    if (w != layer_w || h != layer_h || layer_count < 2 * n || (seen > 0 && !seens))
      AllocateLayers(w, h, std::max(8, 2 * n), seen > 0);
    ++tick;
    std::vector<int> out(static_cast<size_t>(n), -1);
    std::vector<bool> taken(layers.size(), false);
    for (int k = 0; k < n; ++k) {  // resident first, so they are not evicted by this frame
      if (ps[k].key < 0) continue;
      for (size_t l = 0; l < layers.size(); ++l)
        if (!taken[l] && layers[l].key == ps[k].key) {
          out[k] = static_cast<int>(l);
          taken[l] = true;
          break;
        }
    }
    for (int k = 0; k < n; ++k) {
      if (out[k] < 0) {  // least recently used free layer
        size_t best = layers.size();
        for (size_t l = 0; l < layers.size(); ++l)
          if (!taken[l] && (best == layers.size() || layers[l].last_used < layers[best].last_used))
            best = l;
        taken[best] = true;
        out[k] = static_cast<int>(best);
        layers[best] = Layer();
        layers[best].key = ps[k].key;
        UploadColour(out[k], *ps[k].image);
      }
      Layer& L = layers[static_cast<size_t>(out[k])];
      if (need_depth && !L.depth) {
        UploadDepth(out[k], *ps[k].depth);
        L.depth = ps[k].key >= 0;
      }
      if (need_mask && !L.mask) {
        UploadMask(out[k], ps[k].mask);
        L.mask = ps[k].key >= 0;
      }
      if (k < seen && !L.seen) {
        UploadSeen(out[k], ps[k].seen);
        L.seen = ps[k].key >= 0;
      }
      L.last_used = tick;
    }
    return out;
  }

  // Projector uniforms relative to the render camera centre, in double.
  void DrawSurface(Target& t, const std::vector<Target::Format>& formats, const char* frag,
                   const View& view, RenderStats* stats);
  void Shade(const View& view, const std::vector<Projector>& projectors, const EffectsPlan& plan,
             const std::vector<int>& layer_of, CameraExposure exposure);
  void SetProjectors(GLuint prog, const View& v, const std::vector<Projector>& ps,
                     const EffectsPlan& plan, const std::vector<int>& layer_of) {
    int n = std::min<int>(plan.projectors, static_cast<int>(ps.size()));
    glUniform1i(glGetUniformLocation(prog, "u_num_projectors"), n);
    Eigen::Vector3d C = v.world_to_camera.Centre();
    for (int k = 0; k < n; ++k) {
      const View& pv = ps[k].view;
      Eigen::Matrix3d Rk = pv.world_to_camera.R();
      Eigen::Matrix3f Rf = Rk.cast<float>();
      Eigen::Vector3f t = (Rk * (C - pv.world_to_camera.Centre())).cast<float>();
      Eigen::Vector4f K(float(pv.camera.fx()), float(pv.camera.fy()), float(pv.camera.cx()),
                        float(pv.camera.cy()));
      std::string i = "[" + std::to_string(k) + "]";
      glUniformMatrix3fv(glGetUniformLocation(prog, ("u_proj_R" + i).c_str()), 1, GL_FALSE,
                         Rf.data());
      glUniform3fv(glGetUniformLocation(prog, ("u_proj_t" + i).c_str()), 1, t.data());
      glUniform4fv(glGetUniformLocation(prog, ("u_proj_K" + i).c_str()), 1, K.data());
      glUniform1i(glGetUniformLocation(prog, ("u_proj_layer" + i).c_str()),
                  layer_of[static_cast<size_t>(k)]);
      if (plan.exposure)
        glUniform2f(glGetUniformLocation(prog, ("u_proj_exposure" + i).c_str()),
                    ps[k].exposure.gain, ps[k].exposure.offset / 255.f);
    }
    if (n > 0) {
      glUniform2f(glGetUniformLocation(prog, "u_proj_size"), float(ps[0].image->width),
                  float(ps[0].image->height));
    }
    glUniform1i(glGetUniformLocation(prog, "u_images"), 0);
    glUniform1i(glGetUniformLocation(prog, "u_depths"), 1);
    glUniform1i(glGetUniformLocation(prog, "u_masks"), 2);
    glUniform1f(glGetUniformLocation(prog, "u_bias"), float(plan.bias));
    glUniform1f(glGetUniformLocation(prog, "u_blend_power"), float(plan.weights.power));
    glUniform1f(glGetUniformLocation(prog, "u_feather"),
                float(std::max(plan.weights.feather, 1e-3)));
    glUniform1f(glGetUniformLocation(prog, "u_res_weight"), float(plan.weights.res_weight));
    glUniform1f(glGetUniformLocation(prog, "u_soft"), float(std::max(plan.weights.soft, 1e-6)));
    glUniform1i(glGetUniformLocation(prog, "u_seens"), 5);
    glUniform1f(glGetUniformLocation(prog, "u_seen_front"), float(plan.seen_surfaces.front));
    glUniform1f(glGetUniformLocation(prog, "u_seen_jump"), float(plan.seen_surfaces.jump));
    glUniform1f(glGetUniformLocation(prog, "u_seen_reach"),
                float(std::max(plan.seen_surfaces.reach, 1e-3)));
    glUniform1i(glGetUniformLocation(prog, "u_seen_projectors"), plan.SeenProjectors());
    glUniform1f(glGetUniformLocation(prog, "u_seen_ground_conf"),
                float(plan.seen_surfaces.ground_confidence));
  }
};

// Whether each mesh vertex is used by the triangles of two chunks (a border, kept at every level
// of detail).
std::vector<uint8_t> ChunkBorders(
    const Mesh& mesh, const std::map<std::array<int64_t, 3>, std::vector<uint32_t>>& bins) {
  std::vector<int64_t> chunk_of(mesh.vertices.size(), -1);
  std::vector<uint8_t> shared(mesh.vertices.size(), 0);
  int64_t bin_id = 0;
  for (const auto& [key, faces] : bins) {
    for (uint32_t f : faces)
      for (uint32_t vi : mesh.faces[f]) {
        if (chunk_of[vi] >= 0 && chunk_of[vi] != bin_id) shared[vi] = 1;
        chunk_of[vi] = bin_id;
      }
    ++bin_id;
  }
  return shared;
}

Renderer::Renderer(const Mesh& mesh, double chunk_size) : impl_(std::make_unique<Impl>()) {
  if (mesh.faces.empty() || mesh.vertices.empty()) throw Error("the mesh has no triangles");
  Impl& m = *impl_;
  mesh.Bounds(m.lo, m.hi);
  // Bin triangles by centroid into the cubes of chunk_size metres of a grid fixed in the world.
  std::map<std::array<int64_t, 3>, std::vector<uint32_t>> bins;
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    Eigen::Vector3d c = (mesh.vertices[mesh.faces[f][0]] + mesh.vertices[mesh.faces[f][1]] +
                         mesh.vertices[mesh.faces[f][2]]) /
                        3;
    std::array<int64_t, 3> key;
    for (int k = 0; k < 3; ++k) key[k] = static_cast<int64_t>(std::floor(c[k] / chunk_size));
    bins[key].push_back(f);
  }
  std::vector<float>& verts = m.verts;  // x y z r g b
  std::vector<uint32_t>& indices = m.indices;
  const bool colours = mesh.has_colors();
  const std::vector<uint8_t> shared = ChunkBorders(mesh, bins);
  for (const auto& [key, faces] : bins) {
    Chunk ch;
    std::unordered_map<uint32_t, uint32_t> local;
    std::vector<uint32_t> order;
    ch.lo.setConstant(std::numeric_limits<double>::infinity());
    ch.hi = -ch.lo;
    for (uint32_t f : faces)
      for (uint32_t vi : mesh.faces[f]) {
        if (local.emplace(vi, static_cast<uint32_t>(order.size())).second) order.push_back(vi);
        ch.lo = ch.lo.cwiseMin(mesh.vertices[vi]);
        ch.hi = ch.hi.cwiseMax(mesh.vertices[vi]);
      }
    // The cell's centre: a triangle's float vertices then depend only on where it is, not on
    // which other triangles share the mesh (a road's fragments render alike alone or together).
    for (int k = 0; k < 3; ++k) ch.origin[k] = (static_cast<double>(key[k]) + 0.5) * chunk_size;
    ch.base_vertex = static_cast<GLint>(verts.size() / 6);
    ch.vertex_count = order.size();
    for (uint32_t vi : order) {
      m.border.push_back(shared[vi]);
      Eigen::Vector3d p = mesh.vertices[vi] - ch.origin;
      verts.insert(verts.end(), {float(p.x()), float(p.y()), float(p.z())});
      if (colours)
        verts.insert(verts.end(), {mesh.colors[vi][0] / 255.f, mesh.colors[vi][1] / 255.f,
                                   mesh.colors[vi][2] / 255.f});
      else
        verts.insert(verts.end(), {0.5f, 0.5f, 0.5f});
    }
    ch.first_index = indices.size();
    for (uint32_t f : faces)
      for (uint32_t vi : mesh.faces[f]) indices.push_back(local[vi]);
    ch.index_count = indices.size() - ch.first_index;
    m.chunks.push_back(ch);
  }
  m.triangles = mesh.faces.size();
  glGenVertexArrays(1, &m.vao);
  glBindVertexArray(m.vao);
  glGenBuffers(1, &m.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(verts.size() * sizeof(float)), verts.data(),
               GL_STATIC_DRAW);
  glGenBuffers(1, &m.ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, m.ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(uint32_t)),
               indices.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glBindVertexArray(0);
  glGenVertexArrays(1, &m.screen_vao);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  CheckGlError("mesh upload");
}

Renderer::~Renderer() = default;
size_t Renderer::triangles() const { return impl_->triangles; }
size_t Renderer::chunks() const { return impl_->chunks.size(); }

// The mesh seen from `view` into target t (colour attachment 0 cleared to +inf: no surface), the
// nearest fragment of each pixel kept.
void Renderer::Impl::DrawSurface(Target& t, const std::vector<Target::Format>& formats,
                                 const char* frag, const View& view, RenderStats* stats) {
  int w = static_cast<int>(view.camera.width), h = static_cast<int>(view.camera.height);
  EnsureTarget(t, w, h, formats, true);
  glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
  glViewport(0, 0, w, h);
  const float inf = std::numeric_limits<float>::infinity();
  const float none[4] = {inf, 0, 0, 0};
  glClearBufferfv(GL_COLOR, 0, none);
  glClear(GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  Draw(Program("mesh.vert", frag, {}, {}), view, stats);
}

void Renderer::SetDetail(double distance, double cell) {
  Impl& m = *impl_;
  if (!(distance >= 0) || (distance > 0 && !(cell > 0)))
    throw Error("level of detail: the distance must be >= 0 and the cell > 0");
  if (distance > 0 && !m.lods.count(cell)) m.BuildLod(cell);
  m.lod = distance > 0 ? &m.lods.at(cell) : nullptr;
  m.lod_distance = distance;
}

Image Renderer::RenderDepth(const View& view, RenderStats* stats) {
  view.camera.RequireUndistorted();
  Impl& m = *impl_;
  m.DrawSurface(m.depth_target, {kLinearDepth}, "depth.frag", view, stats);
  auto t0 = Clock::now();
  Image out = ReadLinearDepth(m.depth_target.w, m.depth_target.h);
  if (stats) stats->readback_ms += Ms(t0, Clock::now());
  CheckGlError("RenderDepth");
  return out;
}

namespace {

// Every projector the plan uses has an image of its camera's size, and depth when needed.
void CheckProjectors(const std::vector<Projector>& projectors, const EffectsPlan& plan) {
  for (int k = 0; k < plan.projectors; ++k) {
    const Projector& p = projectors[k];
    p.view.camera.RequireUndistorted();
    if (!p.image) throw Error("projector " + std::to_string(k) + " has no image");
    if (p.image->width != static_cast<int>(p.view.camera.width) ||
        p.image->height != static_cast<int>(p.view.camera.height))
      throw Error("projector image is " + std::to_string(p.image->width) + "x" +
                  std::to_string(p.image->height) + " but its camera is " +
                  std::to_string(p.view.camera.width) + "x" + std::to_string(p.view.camera.height));
    if ((plan.occlusion || plan.skybox) && !p.depth)
      throw Error("projector " + std::to_string(k) + " has no depth map");
  }
}

// Reads the colour and source attachments of the bound framebuffer (GL rows are bottom-up).
Renderer::Frame ReadFrame(int w, int h) {
  Renderer::Frame out;
  out.colour = Image(w, h, 3, 8);
  out.source = Image(w, h, 1, 8);
  std::vector<uint8_t> rgba(static_cast<size_t>(w) * h * 4), src(static_cast<size_t>(w) * h);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, w, h, GL_RED_INTEGER, GL_UNSIGNED_BYTE, src.data());
  for (int y = 0; y < h; ++y) {
    size_t gy = size_t(h - 1 - y);
    for (int x = 0; x < w; ++x) {
      size_t g = gy * w + x, o = size_t(y) * w + x;
      for (int c = 0; c < 3; ++c) out.colour.data[o * 3 + c] = rgba[g * 4 + c];
      out.source.data[o] = src[g];
    }
  }
  return out;
}

// plan.fill: the background pixels (no surface, no sky) take the colour of the rest around them.
void FillBackground(Image& colour, Image& source) {
  std::vector<uint8_t> known(source.pixels());
  size_t unknown = 0;
  for (size_t p = 0; p < known.size(); ++p) {
    known[p] = source.data[p] != kSourceBackground;
    unknown += !known[p];
  }
  if (unknown == 0 || !PushPullFill(colour, known)) return;
  for (size_t p = 0; p < known.size(); ++p) {
    if (known[p]) continue;
    source.data[p] = kSourceFilled;
    for (int c = 0; c < colour.channels; ++c) {  // 8-bit frames, as ReadFrame gives
      float& v = colour.data[p * colour.channels + c];
      v = std::nearbyint(std::clamp(v, 0.f, 255.f));
    }
  }
}

}  // namespace

// The second pass: ptm.frag once per pixel over the surface pass, into colour and source.
void Renderer::Impl::Shade(const View& view, const std::vector<Projector>& projectors,
                           const EffectsPlan& plan, const std::vector<int>& layer_of,
                           CameraExposure exposure) {
  std::vector<std::string> inc;
  if (plan.ptm || plan.skybox) inc.push_back("ptm_common.glsl");
  GLuint prog = Program("screen.vert", "ptm.frag", plan.Defines(), inc);
  glUseProgram(prog);
  glDisable(GL_DEPTH_TEST);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, surface_target.tex[0]);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, surface_target.tex[1]);
  glUniform1i(glGetUniformLocation(prog, "u_depth"), 3);
  glUniform1i(glGetUniformLocation(prog, "u_vertex_colour"), 4);
  glUniform3f(glGetUniformLocation(prog, "u_background"), plan.background[0] / 255.f,
              plan.background[1] / 255.f, plan.background[2] / 255.f);
  Eigen::Matrix3f Rt = view.world_to_camera.R().transpose().cast<float>();
  glUniformMatrix3fv(glGetUniformLocation(prog, "u_Rt"), 1, GL_FALSE, Rt.data());
  glUniform4f(glGetUniformLocation(prog, "u_K"), float(view.camera.fx()), float(view.camera.fy()),
              float(view.camera.cx()), float(view.camera.cy()));
  glUniform2f(glGetUniformLocation(prog, "u_size"), float(view.camera.width),
              float(view.camera.height));
  if (plan.skybox)
    glUniform1f(glGetUniformLocation(prog, "u_sky_distance"), float(plan.sky_distance));
  if (plan.ptm || plan.skybox) SetProjectors(prog, view, projectors, plan, layer_of);
  glUniform2f(glGetUniformLocation(prog, "u_render_exposure"), exposure.gain,
              exposure.offset / 255.f);
  glBindVertexArray(screen_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glEnable(GL_DEPTH_TEST);
}

Renderer::Frame Renderer::Render(const View& view, const std::vector<Projector>& projectors,
                                 const EffectsPlan& plan_in, RenderStats* stats, bool with_depth,
                                 CameraExposure exposure) {
  view.camera.RequireUndistorted();
  Impl& m = *impl_;
  EffectsPlan plan = plan_in;
  if (projectors.empty()) plan.ptm = plan.skybox = false;
  plan.projectors =
      std::max(1, std::min<int>(plan.projectors, static_cast<int>(projectors.size())));
  const int w = static_cast<int>(view.camera.width), h = static_cast<int>(view.camera.height);
  std::vector<int> layer_of;
  if (plan.ptm || plan.skybox) {
    CheckProjectors(projectors, plan);
    layer_of = m.PlaceProjectors(projectors, plan.projectors, plan.occlusion || plan.skybox,
                                 plan.masks, plan.SeenProjectors());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, m.images);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, m.depths);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D_ARRAY, m.masks);
    if (m.seens) {
      glActiveTexture(GL_TEXTURE5);
      glBindTexture(GL_TEXTURE_2D_ARRAY, m.seens);
    }
  }
  // Two passes: the surface each pixel sees, then texturing once per pixel (a fragment hidden by
  // a nearer one costs no texturing, and a software rasteriser shades tiny triangles wastefully).
  m.lod_allowed = true;  // the frame's own surface may be simplified far away; depth maps never
  m.DrawSurface(m.surface_target, {kLinearDepth, kRgba8}, "gbuffer.frag", view, stats);
  m.lod_allowed = false;
  auto t_shade = Clock::now();
  m.EnsureTarget(m.colour_target, w, h, {kRgba8, kSource}, false);
  glBindFramebuffer(GL_FRAMEBUFFER, m.colour_target.fbo);
  glViewport(0, 0, w, h);
  m.Shade(view, projectors, plan, layer_of, exposure);
  glFinish();
  auto t0 = Clock::now();
  Frame out = ReadFrame(w, h);
  if (with_depth) {
    glBindFramebuffer(GL_FRAMEBUFFER, m.surface_target.fbo);
    out.depth = ReadLinearDepth(w, h);
  }
  auto t_read = Clock::now();
  if (plan.fill) FillBackground(out.colour, out.source);
  if (stats) {
    stats->shade_ms += Ms(t_shade, t0);
    stats->readback_ms += Ms(t0, t_read);
    stats->fill_ms += Ms(t_read, Clock::now());
  }
  CheckGlError("Render");
  return out;
}

}  // namespace mvtm

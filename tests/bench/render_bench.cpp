// ptmrender's renderer at 1241×376 on this machine's GL (llvmpipe here).
//
// First ptmrender itself, end to end, on the mkroad --full road (255k triangles, 48 images, depth
// baked by bakedepth): its frame rate with 4 projectors against bakedepth's depth pass in the same
// run, and where its time goes per frame (load, depth, render, readback, write). The workspace is
// generated once into the temporary folder (or --workspace DIR) and kept for later runs.
//
// Then the renderer alone: frames/s per configuration and where the time goes (cull, draw = the
// mesh pass, shade = the texturing pass, readback, PNG encode), for the road mesh at the --full
// density (~255k triangles) and at ~1M; then the fastest frame's texturing pass and whole time
// and that against the fastest depth render, and the process's CPU time per frame (all threads)
// against the depth render's: the two least disturbed by other load.
//
// Every figure is also given as a ratio to a baseline measured in the same run: a plain depth
// render of the same frames (one rasterisation of the mesh, no texturing), so the table holds on
// a noisy shared machine. Projector images of the second part are synthetic (speed does not
// depend on content). Run with MESA_SHADER_CACHE_DISABLE=true for repeatable timings.
// usage: bench_render [--frames N] [--short] [--workspace DIR] [--renderer-only]
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>

#include "bakedepth.h"
#include "bench_util.h"
#include "image/image.h"
#include "mkroad/mkroad.h"
#include "mkroad/road_scene.h"
#include "ptmrender.h"
#include "render/context.h"
#include "render/renderer.h"

using namespace mvtm;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

static double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// CPU time of all the process's threads (llvmpipe's included), ms: less disturbed by other
// processes on the machine than wall time.
static double CpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

// ptmrender --at-images --exclude-self (4 projectors, baked depth) on an mkroad --full workspace
// against bakedepth's depth pass over the same workspace, in the same run.
static void PipelineBench(bool quick, fs::path ws) {
  if (ws.empty())
    ws = fs::temp_directory_path() / (quick ? "mvtm-bench-road-short" : "mvtm-bench-road-full");
  if (!fs::exists(ws / "mesh.ply")) {
    fixture::MkroadOptions mo;
    mo.out_dir = ws.string();
    mo.full = !quick;
    mo.frames = quick ? 4 : 24;  // per pass: 48 images
    mo.ApplyFull(true, false, false, false);
    mo.supersample = 1;  // content does not change the speed
    mo.offpath_every = mo.fullsize_frames = 0;
    mo.quiet = true;
    std::fprintf(stderr, "bench_render: generating the workspace %s\n", ws.c_str());
    fixture::RunMkroad(mo);
  }
  // The baseline before and after ptmrender (their mean), so that a change of load on the machine
  // during the run shows.
  auto bake = [&ws] {
    BakeDepthOptions bo;
    bo.workspace = ws.string();
    bo.force = bo.quiet = true;
    const BakeDepthReport br = RunBakeDepth(bo);
    return br.render_ms / double(br.written);
  };
  const double depth_before = bake();
  fs::remove_all(ws / "stereo");  // a run killed between the seen-surface frames left them

  PtmRenderOptions po;
  po.workspace = ws.string();
  po.outdir = (ws / "bench-frames").string();
  po.at_images = po.exclude_self = po.force = po.quiet = true;
  std::ostringstream sink;
  const PtmRenderReport r = RunPtmRender(po, sink);
  fs::remove_all(po.outdir);
  // The same frames without the effects issue 19 added (blending, fill): what they cost.
  PtmRenderOptions first = po;
  first.no_blend = first.no_fill = true;
  const PtmRenderReport r0 = RunPtmRender(first, sink);
  fs::remove_all(po.outdir);
  // With seen surfaces: densify's maps stood in for by the mesh's own depth (copies of the baked
  // maps), so no ray finds a surface in front of the mesh and every sample is read: their worst
  // case (a hit ends a ray's march early).
  fs::create_directories(ws / "stereo");
  for (const auto& e : fs::directory_iterator(ws / "depth"))
    fs::copy_file(e.path(), ws / "stereo" / e.path().filename());
  const PtmRenderReport rs = RunPtmRender(po, sink);
  fs::remove_all(po.outdir);
  fs::remove_all(ws / "stereo");
  const double depth_after = bake(), depth_ms = (depth_before + depth_after) / 2;
  const double n = double(r.rendered), frame_ms = r.frames_ms / n;
  const double unwritten_ms = (r.frames_ms - r.write_ms) / n;
  std::printf(
      "ptmrender --at-images --exclude-self, %d projectors, baked depth: %zu frames on %s\n",
      po.projectors, r.rendered, ws.c_str());
  std::printf(
      "  depth only (bakedepth's pass)   %8.2f ms  %6.1f fps  (baseline: %.2f ms before, "
      "%.2f ms after)\n",
      depth_ms, 1000 / depth_ms, depth_before, depth_after);
  std::printf("  ptmrender, whole frame          %8.2f ms  %6.1f fps  %5.2fx the depth-only rate\n",
              frame_ms, 1000 / frame_ms, depth_ms / frame_ms);
  std::printf("  ptmrender without write waits   %8.2f ms  %6.1f fps  %5.2fx the depth-only rate\n",
              unwritten_ms, 1000 / unwritten_ms, depth_ms / unwritten_ms);
  mvtm::bench::Report("ptmrender",
                      std::to_string(po.projectors) + " projectors, baked depth, whole frame, " +
                          std::to_string(r.rendered) + " frames of mkroad --full",
                      1000 / frame_ms, "fps", "depth only (bakedepth's pass)", 1000 / depth_ms);
  const double first_ms = r0.frames_ms / double(r0.rendered);
  std::printf(
      "  ptmrender, first projector, no fill %8.2f ms  %6.1f fps (blend + fill: %.2fx its "
      "rate; texturing %.2f against %.2f ms, fill %.2f ms per frame)\n",
      first_ms, 1000 / first_ms, first_ms / frame_ms, r.shade_ms / n,
      r0.shade_ms / double(r0.rendered), r.fill_ms / n);
  mvtm::bench::Report(
      "ptmrender",
      "blending + fill, whole frame, " + std::to_string(r.rendered) + " frames of mkroad --full",
      1000 / frame_ms, "fps", "first projector, no fill (--no-blend --no-fill)", 1000 / first_ms);
  const double seen_ms = rs.frames_ms / double(rs.rendered);
  std::printf(
      "  ptmrender with seen surfaces    %8.2f ms  %6.1f fps  (%.2fx the rate without; "
      "texturing %.2f against %.2f ms per frame)\n",
      seen_ms, 1000 / seen_ms, frame_ms / seen_ms, rs.shade_ms / double(rs.rendered),
      r.shade_ms / n);
  mvtm::bench::Report("ptmrender",
                      "seen surfaces (worst case: every sample read), whole frame, " +
                          std::to_string(rs.rendered) + " frames of mkroad --full",
                      1000 / seen_ms, "fps", "without seen surfaces (no stereo/)", 1000 / frame_ms);
  const double other = r.frames_ms - r.load_ms - r.survey_ms - r.render_ms - r.write_ms;
  std::printf(
      "  ptmrender per frame: load %.2f (depth maps %.2f), survey %.2f, render %.2f = "
      "mesh pass %.2f + texturing %.2f + readback %.2f + uploads etc. %.2f, write wait "
      "%.2f, other %.2f ms\n",
      r.load_ms / n, (r.depth_ms - r.survey_ms) / n, r.survey_ms / n, r.render_ms / n,
      r.draw_ms / n, r.shade_ms / n, r.readback_ms / n,
      (r.render_ms - r.draw_ms - r.shade_ms - r.readback_ms) / n, r.write_ms / n, other / n);
}

int main(int argc, char** argv) {
  int frames = 20;
  bool quick = false;
  fs::path ws;
  bool pipeline = true;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--frames" && i + 1 < argc) frames = std::stoi(argv[++i]);
    if (a == "--short") quick = true, frames = 2;
    if (a == "--workspace" && i + 1 < argc) ws = argv[++i];
    if (a == "--renderer-only") pipeline = false;
  }
  if (pipeline) PipelineBench(quick, ws);
  const int W = quick ? 320 : fixture::kKittiWidth, H = quick ? 96 : fixture::kKittiHeight;
  Camera cam = ParseCameraSpec("PINHOLE 1241 376 718.856 718.856 607.1928 185.2157").Scaled(W, H);
  auto ctx = GlContext::Create();
  std::printf("render benchmark, %dx%d, %d frames per row, %s\n", W, H, frames,
              ctx->Describe().c_str());
  std::vector<double> cells = quick ? std::vector<double>{0.75} : std::vector<double>{0.28, 0.14};
  for (double cell : cells) {
    fixture::RoadScene scene = fixture::BuildRoadScene(1, cell);
    Mesh mesh;
    mesh.vertices = scene.mesh.vertices;
    mesh.faces = scene.mesh.faces;
    for (const auto& a : scene.VertexAlbedo())
      mesh.colors.push_back({uint8_t(255 * a.x()), uint8_t(255 * a.y()), uint8_t(255 * a.z())});
    Renderer r(mesh);
    // Render poses along pass A; projectors: the nearest recorded poses of pass B.
    auto pa = fixture::PassFrames('A', frames, 1), pb = fixture::PassFrames('B', frames + 4, 1);
    Image img(W, H, 3, 8);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = float((i * 2654435761u) % 251);
    std::vector<Image> depth(pb.size());
    std::vector<View> pviews;
    for (size_t k = 0; k < pb.size(); ++k) pviews.push_back(View{cam, pb[k].pose.WorldToCamera()});
    auto t_bake = Clock::now();
    for (size_t k = 0; k < pb.size(); ++k) depth[k] = r.RenderDepth(pviews[k]);
    double bake_ms = Ms(t_bake, Clock::now()) / double(pb.size());

    std::printf(
        "\nmesh: %zu triangles in %zu chunks (cell %.2f m); baking one depth map: %.1f ms\n",
        r.triangles(), r.chunks(), cell, bake_ms);
    std::printf("%-30s %8s %8s %8s %8s %8s %8s %8s %8s %9s %8s %8s %9s %8s %9s\n", "configuration",
                "cull", "draw", "shade", "readback", "fill", "depth", "total", "fps", "x depth",
                "min shd", "min tot", "x depth", "cpu", "x depth");
    double base_ms = 0, base_best = 0, base_cpu = 0;
    struct Cfg {
      const char* name;
      bool ptm;
      int k;
      bool occlusion, baked;
      bool blend = false, fill = false;
    };
    std::vector<Cfg> cfgs = {{"depth only (baseline)", false, 0, false, false},
                             {"vertex colours", false, 0, false, false},
                             {"PTM 1 projector", true, 1, false, false},
                             {"PTM 1 proj + occlusion, baked", true, 1, true, true},
                             {"PTM 4 proj + occlusion, baked", true, 4, true, true},
                             {"PTM 4 proj + occl. + blend", true, 4, true, true, true, false},
                             {"PTM 4 + occl. + blend + fill", true, 4, true, true, true, true},
                             {"PTM 4 proj + occl., on the fly", true, 4, true, false}};
    double encode_ms = 0;
    for (size_t c = 0; c < cfgs.size(); ++c) {
      const Cfg& cfg = cfgs[c];
      RenderStats st;
      double depth_ms = 0, best = 1e300, best_shade = 1e300;
      const double cpu0 = CpuMs();
      auto t0 = Clock::now();
      for (int f = 0; f < frames; ++f) {
        View v{cam, pa[f].pose.WorldToCamera()};
        auto tf = Clock::now();
        const double shade0 = st.shade_ms;
        if (c == 0) {
          r.RenderDepth(v, &st);
          best = std::min(best, Ms(tf, Clock::now()));
          continue;
        }
        std::vector<Projector> ps;
        for (int k = 0; k < cfg.k; ++k) {
          size_t idx = std::min(pb.size() - 1, size_t(f + k));
          Projector p{pviews[idx], &img, nullptr, nullptr, cfg.baked ? int64_t(idx) : -1};
          if (cfg.occlusion) {
            if (cfg.baked) {
              p.depth = &depth[idx];
            } else {
              auto td = Clock::now();
              depth[idx] = r.RenderDepth(pviews[idx]);
              depth_ms += Ms(td, Clock::now());
              p.depth = &depth[idx];
            }
          }
          ps.push_back(p);
        }
        EffectsPlan plan;
        plan.ptm = cfg.ptm;
        plan.projectors = std::max(1, cfg.k);
        plan.occlusion = cfg.occlusion;
        plan.skybox = cfg.ptm && cfg.occlusion;  // the skybox needs the projectors' depth maps
        plan.blend = cfg.blend;
        plan.fill = cfg.fill;
        Renderer::Frame fr = r.Render(v, ps, plan, &st);
        best = std::min(best, Ms(tf, Clock::now()));
        best_shade = std::min(best_shade, st.shade_ms - shade0);
        if (c == cfgs.size() - 1 && f < 3) {  // PNG encoding, measured on a few frames
          fs::path p =
              fs::temp_directory_path() / ("mvtm-bench-" + std::to_string(getpid()) + ".png");
          auto te = Clock::now();
          WriteImage(p.string(), fr.colour, PngCompression::kFast);  // as ptmrender writes
          encode_ms += Ms(te, Clock::now()) / 3;
          fs::remove(p);
        }
      }
      double total = Ms(t0, Clock::now()) / frames, cpu = (CpuMs() - cpu0) / frames;
      if (c == 0) base_ms = total, base_best = best, base_cpu = cpu;
      std::printf(
          "%-30s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.1f %8.2fx %8.2f %8.2f %8.2fx %8.2f "
          "%8.2fx\n",
          cfg.name, st.cull_ms / frames, st.draw_ms / frames, st.shade_ms / frames,
          st.readback_ms / frames, st.fill_ms / frames, depth_ms / frames, total, 1000 / total,
          total / base_ms, c == 0 ? 0.0 : best_shade, best, best / base_best, cpu, cpu / base_cpu);
    }
    std::printf(
        "PNG encoding of one %dx%d frame: %.1f ms (overlapped with rendering by ptmrender's writer "
        "thread)\n",
        W, H, encode_ms);
  }
  return 0;
}

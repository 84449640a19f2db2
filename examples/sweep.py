#!/usr/bin/env python3
"""What accuracy costs, for every tool: sweep each program's accuracy knobs on the mkroad fixture.

usage: /usr/bin/python3 examples/sweep.py [--bin build/bin] [--out out/sweep] [--frames N]
                                          [--only TOOL,...] [--repeat N] [--short]

For each tool, every setting below runs on an mkroad road and is scored against the fixture's
ray-traced truth; writes OUT/TOOL.csv and OUT/TOOL.png (accuracy against time, matplotlib) per
tool and OUT/index.html, the page to read before choosing settings. Work folders: OUT/work/.

  pickview   --method kdtree|brute|flann|grid9, flann --checks: misses against the exact
             kdtree's picks, against pickview's own microseconds per query (index + search)
  segtrack   --smooth, --max-gap, --min-life on damaged labels: mask IoU against truth/masks,
             against whole-process milliseconds per frame
  dynmask    --threshold, --no-colour, --colour-threshold, --flow-threshold, --no-flow,
             --neighbours, --partners, --min-baseline,
             --partners-ahead, --ahead-veto, --partners-veto, --ahead and --ahead-min-share
             (with --partners 0),
             --passes, --segments,
             --region-depth,
             --probability, --grounded, --min-height,
             --occludes, --occlusion-gap, --min-ratio, --max-gap, --gap-support,
             --max-width, --window, --slack, --quantile, --texture, --depth-tolerance, --open,
             --close, --min-area
             (no labels; the fixture's true mesh, no densify maps), and --max-fill,
             --complete, --driven, --driven-agree, --no-driven-grow and --seen-tolerance on a mesh densify + roadmesh
             --dense make of the same photos (with their
             densify maps): mask IoU against truth/masks and
             the share of drive B masked, against whole-process milliseconds per image
  inpaint3d  --method 3d|telea|ns|patch2d, --partners, --dilate: SSIM inside the vehicle masks
             against truth/background, against whole-process milliseconds per inpainted image
  bakedepth  --scale: share of the truth's surface pixels whose looked-up depth is within 1 %,
             against bakedepth's own milliseconds per map (render + write)
  ptmrender  --projectors, --bias, baked depth scale or a depth pre-pass, effects off, blending
             weights (--blend-power, --feather, --res-weight, --soft), --sky-distance,
             --max-heading, --ahead-weight, seen
             surfaces on densify's maps (--seen-reach, --seen-projectors, --seen-front,
             --seen-ground-conf): SSIM
             against the ray-traced off-path truth, against ptmrender's own ms per frame
  densify    (examples/sweep_densify.py) depth within 2 % against densify's ms per image
  exposure   --iterations, --outlier-mads, --min-points, --offsets on the road's photos with a
             known gain applied to each: RMS error of the fitted gains, against whole-process ms
  boresight  --conditioning, --max-error, --min-angle, --min-track, --min-gain on the road's model turned
             into a record with a known mount rotation: degrees from it, against whole-process ms

Cheap runs are repeated (--repeat, default 3) and the fastest kept, to damp the noise of other
load. --short (the ctest sweep_short) runs a few settings of every tool on a small road. Either
way the sweep checks what must hold (the exact pickview methods agree, the page shows every plot,
...) and exits 1 when a check fails. Needs /usr/bin/python3 with python3-matplotlib, -numpy,
-scipy, -imageio and -openimageio.
"""
import argparse
import json
import os
import re
import shutil
import sys
import types

import imageio
import numpy as np
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "unit", "track"))
import sweep_densify  # noqa: E402
import sweeplib as sl  # noqa: E402
from segtrack_recovery import CAR, damage, iou  # noqa: E402  (the recovery test's damage)


def pickview_cloud(road, folder, n_index, n_query, seed=7):
    """An index workspace of n_index poses scattered around the road's two drives (centres moved
    by N(0, 2 m), turned by N(0, 15 deg), one in five turned round: the set-up of bench_pickview),
    and n_query render-like queries along drive A (N(0, 1.5 m) sideways, N(0, 10 deg) of yaw)."""
    rng = np.random.default_rng(seed)
    drives = [np.loadtxt(os.path.join(road, "truth", f"trajectory_{p}.txt")) for p in "AB"]

    def along(traj, n):
        i = rng.integers(0, len(traj) - 1, n)
        f = rng.random(n)[:, None]
        pos = traj[i, 1:4] * (1 - f) + traj[i + 1, 1:4] * f
        return pos, Rotation.from_quat(traj[i, 4:8])  # c2w, TUM order x y z w

    pos, rot = zip(*(along(d, n_index // 2) for d in drives))
    pos, rot = np.vstack(pos), Rotation.concatenate(rot)
    pos[:, :2] += rng.normal(0, 2.0, (len(pos), 2))
    yaw = rng.normal(0, 15, len(pos)) + 180 * (rng.random(len(pos)) < 0.2)
    c2w = Rotation.from_euler("z", yaw, degrees=True) * rot  # world z is up
    w2c = c2w.inv()
    t = -w2c.apply(pos)
    q = w2c.as_quat()  # x y z w
    sparse = os.path.join(folder, "sparse")
    os.makedirs(sparse, exist_ok=True)
    shutil.copy(os.path.join(road, "sparse", "cameras.txt"), sparse)
    with open(os.path.join(sparse, "points3D.txt"), "w") as f:
        f.write("# 3D point list with one line of data per point:\n")
    with open(os.path.join(sparse, "images.txt"), "w") as f:
        for k in range(len(pos)):
            f.write(f"{k + 1} {q[k, 3]:.17g} {q[k, 0]:.17g} {q[k, 1]:.17g} {q[k, 2]:.17g} "
                    f"{t[k, 0]:.17g} {t[k, 1]:.17g} {t[k, 2]:.17g} 1 P_{k:05d}.png\n\n")
    qpos, qrot = along(drives[0], n_query)
    qrot = Rotation.from_euler("z", rng.normal(0, 10, n_query), degrees=True) * qrot
    qpos += qrot.apply(np.array([1.0, 0, 0]) * rng.normal(0, 1.5, (n_query, 1)))  # camera x
    queries = os.path.join(folder, "queries.txt")
    qq = qrot.as_quat()
    np.savetxt(queries, np.column_stack([np.arange(n_query) * 0.1, qpos, qq]), fmt="%.17g")
    return queries


def picks(tsv):
    """query -> set of picked images, from pickview's table."""
    out = {}
    for line in tsv.splitlines()[1:]:
        query, _, image = line.split("\t")[:3]
        out.setdefault(query, set()).add(image)
    return out


def sweep_pickview(c):
    folder = os.path.join(c.work, "pickview")
    n_index, n_query = (2000, 1000) if c.short else (10000, 5000)
    queries = pickview_cloud(c.road, folder, n_index, n_query)
    settings = [("exact", "kdtree", []), ("exact", "brute", []), ("grid9", "grid9", [])]
    checks = (1, 8, 32, 128) if c.short else (1, 2, 4, 8, 16, 32, 64, 128, 256)
    settings += [("flann", f"flann checks={n}", ["--checks", n]) for n in checks]
    rows, exact, exact_table = [], None, None
    for group, name, extra in settings:
        method = name.split()[0]
        # flann builds different trees on every run (std::random_device): average the misses.
        misses, slots, times = [], 0, []
        for _ in range(c.repeat):
            out, err, _ = c.tools.run("pickview", "--method", method, *extra, folder, queries)
            got = picks(out)
            if exact is None:  # kdtree runs first
                exact, exact_table = got, out
            if group == "exact":
                c.checks(out == exact_table,
                         f"pickview {name}: the same table as kdtree's first run")
            slots = sum(len(v) for v in exact.values())
            missed = sum(len(v - got.get(q, set())) for q, v in exact.items())
            misses.append(missed)
            times.append(float(re.search(r"([\d.]+) us/query", err).group(1)))
            m = re.search(r"miss rate [\d.]+ \((\d+) of (\d+)\)", err)
            if m:  # pickview's own comparison must count what we count from its table
                c.checks(int(m.group(1)) == missed and int(m.group(2)) == slots,
                         f"pickview {name}: its reported misses ({m.group(1)} of {m.group(2)}) "
                         f"= misses counted from its table ({missed} of {slots})")
        rows.append({"group": group, "setting": name, "default": name == "kdtree",
                     "miss_percent": round(100 * float(np.mean(misses)) / slots, 4),
                     "misses": round(float(np.mean(misses)), 1), "slots": slots,
                     "us_per_query": round(float(np.median(times)), 3), "runs": len(misses)})
        sl.log("pickview", name, f"misses {rows[-1]['miss_percent']:.3f} %  "
               f"{rows[-1]['us_per_query']:8.2f} us/query")
    kd = rows[0]
    fast = min((r for r in rows if r["group"] != "exact"), key=lambda r: r["us_per_query"])
    s = sl.Section(
        "pickview", "pickview: view selection, misses against microseconds per query", rows,
        ["group", "setting", "default", "miss_percent", "misses", "slots", "us_per_query",
         "runs"],
        f"<b>Knob:</b> <code>--method</code> (kdtree, brute: exact; flann, grid9: approximate) "
        f"and, for flann, <code>--checks</code> (leaves visited per query). "
        f"{n_index} projector poses scattered around the road's two drives (centres moved by "
        f"N(0, 2 m), turned by N(0, 15&deg;), one in five turned round), {n_query} render-like "
        f"query poses along drive A, K = 4, &plusmn;45&deg; gate. <b>Accuracy:</b> the share "
        f"of the exact picks (kdtree's table) missing from the method's table, in percent "
        f"(symmetric-log axis: 0 is exact). <b>Time:</b> pickview's own microseconds per query, "
        f"index build included, the median of {c.repeat} runs. flann's trees differ on every "
        f"run, so its misses are the mean of those runs. <b>Read:</b> lower left is better; "
        f"the default (kdtree) is ringed. In this run it took {kd['us_per_query']} &micro;s "
        f"per query; the fastest approximate setting, {fast['setting']}, took "
        f"{fast['us_per_query']} &micro;s and "
        f"missed {fast['miss_percent']} % of the exact picks.")
    return sl.emit(c.out, s, "us_per_query", "miss_percent", xlabel="microseconds per query "
                   "(pickview's own timing: index build + search)", ylabel="missed picks (%)",
                   logx=True, yscale=("symlog", {"linthresh": 0.01}), ylim=(0, 300))


def sweep_segtrack(c):
    folder = os.path.join(c.work, "segtrack")
    names = sorted(n for n in os.listdir(os.path.join(c.road, "truth", "masks")))
    labels = [imageio.imread(os.path.join(c.road, "labels", n)) for n in names]
    truths = [imageio.imread(os.path.join(c.road, "truth", "masks", n)) > 0 for n in names]
    k = 4
    damaged = damage(labels, k, np.random.default_rng(5))
    ldir = os.path.join(folder, "labels")
    shutil.rmtree(ldir, ignore_errors=True)
    os.makedirs(ldir)
    for n, lab in zip(names, damaged):
        imageio.imwrite(os.path.join(ldir, n), lab)
    input_iou = iou([d == CAR for d in damaged], truths)
    clean_iou = iou([lab == CAR for lab in labels], truths)
    if c.short:
        knobs = [("smooth", "--smooth", (0, 1, 4)), ("max-gap", "--max-gap", (0, 10)),
                 ("min-life", "--min-life", (1, 3))]
    else:
        knobs = [("smooth", "--smooth", (0, 0.5, 1, 2, 4, 8)),
                 ("max-gap", "--max-gap", (0, 1, 2, 5, 10, 20)),
                 ("min-life", "--min-life", (1, 2, 3, 5, 8))]
    defaults = {"--smooth": 1, "--max-gap": 10, "--min-life": 3}
    rows = []
    ws = os.path.join(folder, "ws")
    for group, opt, values in knobs:
        for v in values:
            (_, _, wall), slow = c.tools.best_wall(c.repeat, "segtrack", "-q", opt, v, ldir, ws)
            masks = [imageio.imread(os.path.join(ws, "masks", n)) > 0 for n in names]
            rows.append({"group": group, "setting": f"{group}={v}", "default": v == defaults[opt],
                         "iou": round(iou(masks, truths), 4),
                         "ms_per_frame": round(1000 * wall / len(names), 3),
                         "slowest_ms_per_frame": round(1000 * slow / len(names), 3)})
            sl.log("segtrack", rows[-1]["setting"], f"IoU {rows[-1]['iou']:.4f}  "
                   f"{rows[-1]['ms_per_frame']:7.2f} ms/frame")
    best_default = max(r["iou"] for r in rows if r["default"])
    c.checks(best_default > input_iou,
             f"segtrack defaults: IoU {best_default:.4f} beats the damaged labels' {input_iou:.4f}")
    s = sl.Section(
        "segtrack", "segtrack: vehicle masks, IoU against milliseconds per frame", rows,
        ["group", "setting", "default", "iou", "ms_per_frame", "slowest_ms_per_frame"],
        f"<b>Knobs:</b> <code>--smooth</code> (Gaussian sigma in frames for centroid and size), "
        f"<code>--max-gap</code> (longest run of missed frames filled by interpolation), "
        f"<code>--min-life</code> (shortest track kept). Each knob is varied alone, the others "
        f"at their defaults. Input: the {len(names)} label images of drive A, damaged as in the "
        f"test track.segtrack_recovery_mkroad (every {k}th frame loses its cars, a third of the "
        f"frames gain a spurious blob). <b>Accuracy:</b> IoU of the masks against the "
        f"ray-traced truth/masks, pooled over frames (dashed: the damaged labels as they are, "
        f"and the clean labels). <b>Time:</b> whole-process wall time per frame (PNG decoding "
        f"and writing included), fastest of {c.repeat} runs (the bar reaches the slowest: the "
        f"spread is other load). <b>Read:</b> higher is better; "
        f"the default settings are ringed (one per knob: the same setting run again).",
        note="The settings cost the same to within noise: choose by IoU alone.")
    return sl.emit(c.out, s, "ms_per_frame", "iou", xmax="slowest_ms_per_frame",
                   xlabel="milliseconds per frame "
                   "(whole-process wall time)", ylabel="mask IoU against the truth (pooled)",
                   lines=[(input_iou, "damaged labels, no segtrack"),
                          (clean_iou, "undamaged labels")])


def sweep_inpaint3d(c):
    folder = os.path.join(c.work, "inpaint3d")
    ws = sl.copy_workspace(c.road, os.path.join(folder, "ws"))
    truth = os.path.join(c.road, "truth")
    names = sorted(os.listdir(os.path.join(truth, "masks")))
    shutil.copytree(os.path.join(truth, "masks"), os.path.join(ws, "masks"), dirs_exist_ok=True)
    c.tools.run("pickview", "-q", "--partners", ws)
    c.tools.run("bakedepth", "-q", ws)
    bg = sl.link_subset(os.path.join(truth, "background"), names, os.path.join(folder, "truth"))
    score = lambda d: c.tools.ssim_mean(bg, d, "--mask", os.path.join(truth, "masks"))  # noqa
    recorded = score(os.path.join(ws, "images"))
    if c.short:
        settings = [("3d partners", "3d partners=1", ["--partners", 1]),
                    ("3d partners", "3d (defaults)", []), ("2-D", "telea", ["--method", "telea"])]
    else:
        settings = [("3d partners", f"3d partners={n}", ["--partners", n]) for n in (1, 2)]
        settings += [("3d partners", "3d (defaults)", [])]
        settings += [("3d partners", f"3d partners={n}", ["--partners", n]) for n in (8, 16)]
        settings += [("3d dilate", f"3d dilate={d}", ["--dilate", d]) for d in (0, 3, 6)]
        settings += [("2-D", m, ["--method", m]) for m in ("telea", "ns", "patch2d")]
        settings += [("2-D", "telea radius=9", ["--method", "telea", "--radius", 9])]
    rows = []
    for group, name, extra in settings:
        (_, _, wall), slow = c.tools.best_wall(c.repeat, "inpaint3d", "--force", "-q", *extra,
                                               ws)
        rows.append({"group": group, "setting": name, "default": not extra,
                     "in_mask_ssim": round(score(os.path.join(ws, "textures")), 4),
                     "ms_per_image": round(1000 * wall / len(names), 2),
                     "slowest_ms_per_image": round(1000 * slow / len(names), 2)})
        sl.log("inpaint3d", name, f"in-mask SSIM {rows[-1]['in_mask_ssim']:.4f}  "
               f"{rows[-1]['ms_per_image']:7.1f} ms/image")
    best = {r["setting"]: r["in_mask_ssim"] for r in rows}
    c.checks(best["3d (defaults)"] > max(best["telea"], recorded),
             f"inpaint3d: 3d ({best['3d (defaults)']:.4f}) beats telea ({best['telea']:.4f}) "
             f"and the recorded image ({recorded:.4f}) inside the masks")
    s = sl.Section(
        "inpaint3d", "inpaint3d: vehicle removal, in-mask SSIM against milliseconds per image",
        rows, ["group", "setting", "default", "in_mask_ssim", "ms_per_image",
               "slowest_ms_per_image"],
        f"<b>Knobs:</b> <code>--method</code> (3d: partner images of the other drive through the "
        f"mesh; telea, ns: OpenCV 2-D inpainting; patch2d: the thesis's 2-D templates), for 3d "
        f"<code>--partners</code> (partners tried per image) and <code>--dilate</code> (pixels "
        f"the mask grows by first). Masks: the fixture's truth masks; partners from "
        f"<code>pickview --partners</code>; baked depth. <b>Accuracy:</b> mean SSIM inside the "
        f"truth vehicle masks of the {len(names)} images of drive A against the ray-traced "
        f"background without vehicles (dashed: the recorded image, vehicles still in). "
        f"<b>Time:</b> whole-process wall time (GL start-up, reading, writing all "
        f"{2 * len(names)} textures) divided by the images with a vehicle, fastest of "
        f"{c.repeat} runs (the bar reaches the slowest: the spread is other load). "
        f"<b>Read:</b> higher is better; the default (3d, 4 partners, dilate 1) is ringed.")
    return sl.emit(c.out, s, "ms_per_image", "in_mask_ssim", xmax="slowest_ms_per_image",
                   xlabel="milliseconds per inpainted "
                   "image (whole-process wall time)", ylabel="SSIM inside the vehicle masks",
                   lines=[(recorded, "recorded image (no inpainting)")])


def depth_scores(maps, truths, via=None):
    """Each map looked up (nearest texel, as the occlusion test samples it) at the pixel centres
    of its truth, after resizing it to the shape `via` first (nearest, as ptmrender and inpaint3d
    load maps: libcore/workspace/projector_sources.cpp) when given: (% of the truth's surface
    pixels within 1 %, % that ptmrender's default bias 0.005 would wrongly call occluded, % of all
    pixels where map and truth disagree about there being a surface)."""
    good = surface = occluded = disagree = pixels = 0
    for n, t in truths.items():
        d = sl.read_float(os.path.join(maps, n))
        d = sl.resample_nearest(sl.resample_nearest(d, via) if via else d, t.shape)
        s = np.isfinite(t)
        with np.errstate(invalid="ignore", divide="ignore"):
            good += int((s & (np.abs(d / t - 1) <= 0.01)).sum())
            occluded += int((s & (t > d * 1.005)).sum())
        surface += int(s.sum())
        disagree += int((np.isfinite(d) != s).sum())
        pixels += s.size
    return (round(100 * good / surface, 3), round(100 * occluded / surface, 3),
            round(100 * disagree / pixels, 3))


def sweep_bakedepth(c):
    ws = sl.copy_workspace(c.road, os.path.join(c.work, "bakedepth", "ws"))

    def truth(*sub):
        d = os.path.join(c.road, "truth", *sub, "depth")
        return {n: sl.read_float(os.path.join(d, n)) for n in sorted(os.listdir(d))}

    own, fine = truth(), truth("fullsize")
    w, h = fine[next(iter(fine))].shape[::-1]
    image = own[next(iter(own))].shape
    maps = os.path.join(ws, "depth")
    rows = []
    for scale in ((0.25, 1) if c.short else (0.125, 0.25, 0.5, 1, 2, 4)):
        (_, err, _), _ = c.tools.best_wall(c.repeat, "bakedepth", "--force", "--scale", scale,
                                           ws)
        m = re.search(r"\(([\d.]+) ms render, ([\d.]+) ms write per map", err)
        shape = sl.read_float(os.path.join(maps, next(iter(own)))).shape
        for group, via in (("map as written", None), ("as ptmrender loads it", image)):
            within1, false_occ, disagree = depth_scores(maps, fine, via)
            rows.append({"group": group, "setting": f"scale={scale}",
                         "default": scale == 1 and via is None,
                         "within1_percent": within1, "false_occlusion_percent": false_occ,
                         "surface_disagrees_percent": disagree,
                         "own_centres_within1_percent": depth_scores(maps, own, via)[0],
                         "ms_per_map": round(float(m.group(1)) + float(m.group(2)), 2),
                         "map_size": f"{shape[1]}x{shape[0]}"})
            sl.log("bakedepth", f"{rows[-1]['setting']} {group}", f"within 1 % {within1:.2f} %"
                   f"  {rows[-1]['ms_per_map']:6.2f} ms/map")
    by = {(r["group"], r["setting"]): r for r in rows}
    one = by[("map as written", "scale=1")]
    c.checks(one["own_centres_within1_percent"] > 99,
             f"bakedepth --scale 1: {one['own_centres_within1_percent']} % of the truth's surface "
             f"pixels within 1 % at the image's own pixel centres (the mesh is the traced "
             f"geometry)")
    c.checks(one["within1_percent"] > by[("map as written", "scale=0.25")]["within1_percent"],
             "bakedepth: scale 1 maps are more accurate than scale 0.25 maps")
    s = sl.Section(
        "bakedepth", "bakedepth: depth maps, depth accuracy against milliseconds per map", rows,
        ["group", "setting", "default", "within1_percent", "false_occlusion_percent",
         "surface_disagrees_percent", "own_centres_within1_percent", "ms_per_map", "map_size"],
        f"<b>Knob:</b> <code>--scale</code>, the depth map's size relative to the image "
        f"({image[1]}x{image[0]} here). "
        f"<b>Accuracy:</b> the maps of the {len(fine)} images that mkroad also ray-traced at "
        f"{w}x{h} (truth/fullsize), looked up (nearest texel, as ptmrender's occlusion test "
        f"samples them) at those finer pixel centres, which fall anywhere inside a texel as "
        f"projected points do: the share of the truth's surface pixels within 1 % of the true "
        f"depth. Two groups: the map as bakedepth wrote it, and the map as ptmrender and "
        f"inpaint3d load it: resized to the image's size (nearest), which throws away what a "
        f"scale above 1 adds and shifts its samples by a quarter pixel. The CSV also gives the "
        f"share the occlusion test at ptmrender's default bias 0.005 would wrongly call "
        f"occluded, the share of all pixels where map and truth disagree about there being a "
        f"surface, and the score at the images' own pixel centres "
        f"(all {len(own)} images; exact at scale 1, since the mesh is the traced geometry). "
        f"<b>Time:</b> bakedepth's own milliseconds per map (render + EXR write), fastest of "
        f"{c.repeat} runs (both groups share it). <b>Read:</b> higher is better; the default "
        f"(scale 1) is ringed. "
        f"What the scale does to the rendered frames is in the ptmrender plot (group "
        f"&ldquo;depth&rdquo;).")
    return sl.emit(c.out, s, "ms_per_map", "within1_percent", xlabel="milliseconds per map "
                   "(bakedepth's own timing: render + write)",
                   ylabel="truth surface pixels within 1 % (%)")


def sweep_ptmrender(c):
    ws = sl.copy_workspace(c.road, os.path.join(c.work, "ptmrender", "ws"))
    shutil.copytree(os.path.join(ws, "truth", "masks"), os.path.join(ws, "masks"))
    variants = ["lane_left", "lane_right", "yaw_left", "yaw_right"]
    offpath = os.path.join(ws, "truth", "offpath")

    def bake(scale):
        shutil.rmtree(os.path.join(ws, "depth"), ignore_errors=True)
        if scale is not None:
            c.tools.run("bakedepth", "--quiet", "--scale", scale, ws)

    def score(name, extra):
        """Mean SSIM over the variants and ptmrender's ms per frame for one setting (each
        variant's fastest of c.repeat runs; the frames are the same every run)."""
        ssims, ms, frames = [], 0.0, 0
        for v in variants:
            dst = os.path.join(c.work, "ptmrender", "renders", name.replace(" ", "_"), v)
            best = None
            for _ in range(c.repeat):
                _, err, _ = c.tools.run("ptmrender", "--force", "--poses",
                                        os.path.join(offpath, v, "sparse", "images.txt"),
                                        *extra, ws, dst)
                m = re.search(r"(\d+) frames rendered.*\(([\d.]+) ms render, ([\d.]+) ms "
                              r"depth, ([\d.]+) ms load", err)
                t = float(m.group(2)) + float(m.group(3)) + float(m.group(4))
                best = t if best is None else min(best, t)
            n = int(m.group(1))
            ms += n * best
            frames += n
            ssims.append(c.tools.ssim_mean(dst, os.path.join(offpath, v, "images")))
        return sum(ssims) / len(ssims), ms / frames

    if c.short:
        settings = [("baseline", "vertex colours", ["--mode", "vertex"], 1),
                    ("projectors", "K=1", ["--projectors", 1], 1),
                    ("projectors", "K=4", [], 1),
                    ("depth", "depth pre-pass (not baked)", [], None)]
    else:
        settings = [("baseline", "vertex colours", ["--mode", "vertex"], 1)]
        settings += [("projectors", f"K={k}", ["--projectors", k] if k != 4 else [], 1)
                     for k in (1, 2, 4, 8)]
        settings += [("bias", f"bias={b}", ["--bias", b], 1) for b in (0, 0.001, 0.02, 0.1)]
        settings += [("depth", f"baked depth scale {s}", [], s) for s in (0.25, 0.5, 2)]
        settings += [("depth", "depth pre-pass (not baked)", [], None)]
        settings += [("effects", f"no {e}", [f"--no-{e}"], 1)
                     for e in ("occlusion", "skybox", "masks", "blend", "fill")]
        settings += [("blend", f"blend power {p}", ["--blend-power", p], 1) for p in (0, 1, 4, 8)]
        settings += [("blend", f"feather {f} px", ["--feather", f], 1) for f in (0, 48)]
        settings += [("blend", f"res weight {r}", ["--res-weight", r], 1) for r in (0, 1)]
        settings += [("blend", f"soft occlusion {x}", ["--soft", x], 1) for x in (0, 0.05)]
        settings += [("sky", f"sky distance {d}", ["--sky-distance", d], 1)
                     for d in (0, 20, 200)]
        settings += [("choice", f"max heading {h}", ["--max-heading", h], 1) for h in (30, 90)]
        settings += [("choice", f"ahead weight {w}", ["--ahead-weight", w], 1) for w in (0, 3)]
        # Seen surfaces need densify's maps: made once before these rows (the rows above have
        # none, as the fixture's workspace has none).
        settings += [("seen", "seen surfaces (densify's maps)", [], 1),
                     ("seen", "seen surfaces, none", ["--no-seen-surfaces"], 1)]
        settings += [("seen", f"seen reach {r} px", ["--seen-reach", r], 1) for r in (8, 96)]
        settings += [("seen", "seen projectors 2", ["--seen-projectors", 2], 1),
                     ("seen", "seen front 0.02", ["--seen-front", 0.02], 1),
                     ("seen", "seen ground confidence 0", ["--seen-ground-conf", 0], 1),
                     ("seen", "seen ground confidence 1", ["--seen-ground-conf", 1], 1)]
    rows, baked = [], "unset"
    for group, name, extra, scale in settings:
        if group == "seen" and not os.path.isdir(os.path.join(ws, "stereo")):
            c.tools.run("densify", "--quiet", ws)
        if scale != baked:
            bake(scale)
            baked = scale
        s, ms = score(name, extra)
        rows.append({"group": group, "setting": name, "default": name == "K=4",
                     "ssim": round(s, 5), "ms_per_frame": round(ms, 2)})
        sl.log("ptmrender", name, f"SSIM {s:.4f}  {ms:7.1f} ms/frame")
    by = {r["setting"]: r["ssim"] for r in rows}
    c.checks(by["K=4"] > by["vertex colours"],
             f"ptmrender: projecting photographs ({by['K=4']:.4f}) beats vertex colours "
             f"({by['vertex colours']:.4f})")
    s = sl.Section(
        "ptmrender", "ptmrender (and bakedepth's scale): SSIM against milliseconds per frame",
        rows, ["group", "setting", "default", "ssim", "ms_per_frame"],
        "<b>Knobs:</b> <code>--projectors</code> K (projectors tried per pixel), "
        "<code>--bias</code> (relative occlusion bias), the baked depth maps' scale "
        "(<code>bakedepth --scale</code>) or no baked maps (a depth pre-pass per frame), the "
        "effects turned off (<code>--no-occlusion</code>, <code>--no-skybox</code>, "
        "<code>--no-masks</code>, <code>--no-blend</code>, <code>--no-fill</code>), the blending "
        "weights (<code>--blend-power</code>, <code>--feather</code>, <code>--res-weight</code>, "
        "<code>--soft</code>), the skybox's distance (<code>--sky-distance</code>: 0 at "
        "infinity; by default the scene's far end, the 98th percentile of the sparse points' "
        "distances), the projectors' choice (<code>--max-heading</code>, the heading gate; "
        "<code>--ahead-weight</code>, the cost per metre ahead of the pose), the seen surfaces on densify's maps (group &ldquo;seen&rdquo;, after "
        "<code>densify</code>: <code>--seen-reach</code>, <code>--seen-projectors</code>, "
        "<code>--seen-front</code>, <code>--seen-ground-conf</code>, "
        "<code>--no-seen-surfaces</code>; on this true mesh they "
        "can only lose what wrong depths in the maps cost), and vertex colours only (<code>--mode vertex</code>) as the "
        "baseline. Each knob is varied alone; masks: the fixture's truth masks. Poses: the "
        "fixture's off-path truth poses (1.5 m lane changes and 15&deg; turns of drive A), "
        "projected from the recorded photographs of both drives. <b>Accuracy:</b> mean SSIM "
        "against the ray-traced truth at those poses. <b>Time:</b> ptmrender's own "
        f"milliseconds per frame (render + depth + load; PNG encoding excluded, it overlaps "
        f"rendering), fastest of {c.repeat} runs. <b>Read:</b> "
        "higher is better, left is faster; the default (K=4, bias 0.005, baked depth at scale 1, "
        "blend power 2, feather 16 px, res weight 0.1, soft 0.01, max heading 45, ahead weight 1, "
        "every effect the scene needs) "
        "is ringed. This road renders on its exact mesh, where blending costs a little; on meshes "
        "built from photos it gains (ptmrender(1), EFFECTS PLAN).")
    return sl.emit(c.out, s, "ms_per_frame", "ssim", xlabel="milliseconds per frame "
                   "(ptmrender's own timing: render + depth + load)",
                   ylabel="mean SSIM against the ray-traced truth")


def sweep_exposure(c):
    """exposure's knobs on the road's photos with a known gain applied to each (log-normal,
    sigma 0.15, within 0.7..1.4; a pixel pushed over 255 clips, as a real sensor's does): the
    RMS (percent) of the fitted gains' ratio to the applied ones, the common scale taken out,
    against whole-process milliseconds per image."""
    ws = sl.copy_workspace(c.road, os.path.join(c.work, "exposure", "ws"))
    rng = np.random.default_rng(11)
    names = sorted(os.listdir(os.path.join(ws, "images")))
    applied = {}
    for n in names:
        p = os.path.join(ws, "images", n)
        g = float(np.clip(np.exp(rng.normal(0, 0.15)), 0.7, 1.4))
        img = imageio.imread(p).astype(np.float64)
        rgb = img[..., :3] if img.ndim == 3 else img
        rgb[...] = np.clip(np.rint(rgb * g), 0, 255)
        imageio.imwrite(p, img.astype(np.uint8))
        applied[n] = g
    spread = 100 * float(np.std(np.log(list(applied.values()))))
    if c.short:
        knobs = [("iterations", "--iterations", (3, 30))]
    else:
        knobs = [("iterations", "--iterations", (1, 3, 10, 30, 100)),
                 ("outlier-mads", "--outlier-mads", (1.5, 3, 6, 1000)),
                 ("min-points", "--min-points", (5, 20, 80)),
                 ("offsets", "--offsets", (False, True))]
    defaults = {"--iterations": 30, "--outlier-mads": 3, "--min-points": 20, "--offsets": False}
    rows = []
    for group, opt, values in knobs:
        for v in values:
            args = ([opt] if v else []) if opt == "--offsets" else [opt, v]
            (_, _, wall), _ = c.tools.best_wall(c.repeat, "exposure", "-q", "--force", *args, ws)
            fit = {}
            with open(os.path.join(ws, "exposure.tsv")) as f:
                for line in f.read().splitlines()[1:]:
                    name, gain = line.split("\t")[:2]
                    fit[name] = float(gain)
            e = np.array([np.log(fit[n] / applied[n]) for n in names])
            rms = 100 * float(np.sqrt(np.mean((e - e.mean()) ** 2)))
            rows.append({"group": group, "setting": f"{group}={v}", "default": v == defaults[opt],
                         "gain_error_percent": round(rms, 3),
                         "ms_per_image": round(1000 * wall / len(names), 2)})
            sl.log("exposure", rows[-1]["setting"], f"gain error {rms:.3f} %  "
                   f"{rows[-1]['ms_per_image']:7.2f} ms/image")
    best = min(r["gain_error_percent"] for r in rows if r["default"])
    c.checks(best < 0.25 * spread, f"exposure defaults: gains within {best:.3f} % of the applied "
             f"ones (applied spread {spread:.1f} %)")
    sec = sl.Section(
        "exposure", "exposure: error of the fitted gains against milliseconds per image", rows,
        ["group", "setting", "default", "gain_error_percent", "ms_per_image"],
        f"<b>Knobs:</b> <code>--iterations</code> (alternating least-squares rounds), "
        f"<code>--outlier-mads</code> (observations that far from the fit dropped), "
        f"<code>--min-points</code> (observations an image needs to be fitted), "
        f"<code>--offsets</code> (fit a black level too). The road's {len(names)} photos, each "
        f"with a known gain applied (log-normal, {spread:.1f} % spread; pixels pushed over 255 "
        f"clip). <b>Accuracy:</b> RMS of the fitted gain's ratio to the applied one, percent, "
        f"the common scale (a fit's choice) taken out; it is mostly a slow drift along each "
        f"drive (measured 7 Dec 2026 on 16 photos a drive at the defaults: +2 % at its start to "
        f"-3 % at its end). It is there with no gain applied (the photos as mkroad made them, "
        f"gains fitted 1.03 to 0.95: 1.9 % RMS), and half of it is the fixture's wet road, whose "
        f"reflection of the sky grows towards grazing views (Fresnel), so a road point darkens "
        f"as the camera nears it (mkroad built with that reflection off: 0.9 % RMS; leaving out "
        f"clipped samples or sampling a blurred image does not remove it). "
        f"<b>Time:</b> whole process per image, "
        f"fastest of {c.repeat} runs. <b>Read:</b> lower is better.")
    return sl.emit(c.out, sec, "ms_per_image", "gain_error_percent",
                   xlabel="milliseconds per image (whole process)",
                   ylabel="gain error against the applied gains (RMS, %)")


def sweep_dynmask(c):
    """dynmask's knobs on a 640x192 road of the same drives (its defaults are tuned at the
    working width of 640): pooled IoU of drive A's masks against truth/masks, and the share of
    drive B (no vehicles) masked, against whole-process milliseconds per image."""
    folder = os.path.join(c.work, "dynmask")
    ws = c.tools.mkroad(os.path.join(folder, "ws"), "--frames", 12 if c.short else 30,
                        "--size", "640x192", "--offpath-every", 0, "--fullsize-frames", 0)
    names = sorted(os.listdir(os.path.join(ws, "images")))
    a_names = [n for n in names if n.startswith("A_")]
    truths = [imageio.imread(os.path.join(ws, "truth", "masks", n)) > 0 for n in a_names]
    if c.short:
        knobs = [("passes", "--passes", (1, 2))]
    else:
        knobs = [("threshold", "--threshold", (0.03, 0.04, 0.05, 0.065, 0.08, 0.1)),
                 ("flow-threshold", "--flow-threshold", (1.5, 2, 2.5, 3.5, 5)),
                 ("colour", "--no-colour", (False, True)),
                 ("colour-threshold", "--colour-threshold", (0.05, 0.065, 0.08)),
                 ("flow", "--no-flow", (False, True)),
                 ("flow-relative", "--flow-relative", (0, 0.05, 0.1, 0.2)),
                 ("neighbours", "--neighbours", (2, 4, 6, 8)),
                 ("partners", "--partners", (0, 1, 2, 4)),
                 ("partners-ahead", "--partners-ahead", (0, 2, 4, 6)),
                 ("ahead-veto", "--ahead-veto", (0, 0.5, 1)),
                 ("partners-veto", "--partners-veto", (0, 0.5, 1, 2)),
                 # photos of the same drive farther along are a cue only without partners (with
                 # them, a veto: --ahead-veto above): drive A as a road of one drive
                 ("ahead (--partners 0)", "--ahead", (0, 2, 4), ["--partners", 0]),
                 ("ahead-min-share (--partners 0)", "--ahead-min-share", (0.1, 0.25, 0.5),
                  ["--partners", 0]),
                 ("min-baseline", "--min-baseline", (0.25, 1.5, 2.5)),
                 ("passes", "--passes", (1, 2)),
                 ("segments", "--segments", (0, 100, 300, 1000)),
                 ("region-depth", "--region-depth", (0.25, 0.5, 1)),
                 ("probability", "--probability", (0.3, 0.4, 0.5, 0.6)),
                 ("grounded", "--grounded", (0, 0.25, 0.5)),
                 ("min-height", "--min-height", (0, 0.3, 0.5, 0.7)),
                 ("occludes", "--occludes", (0, 0.1, 0.2, 0.35)),
                 ("occlusion-gap", "--occlusion-gap", (0.1, 0.25, 0.5)),
                 ("min-ratio", "--min-ratio", (0.3, 0.4, 0.5)),
                 ("max-gap", "--max-gap", (1, 3, 10)),
                 ("gap-support", "--gap-support", (0, 0.05, 0.1)),
                 ("max-width", "--max-width", (320, 480, 640)),
                 ("window", "--window", (3, 5, 9)),
                 ("slack", "--slack", (0, 1, 2)),
                 ("quantile", "--quantile", (0, 0.5)),
                 ("texture", "--texture", (0.01, 0.02, 0.05)),
                 ("depth-tolerance", "--depth-tolerance", (0.02, 0.05, 0.1)),
                 ("open", "--open", (0, 1, 2)),
                 ("close", "--close", (0, 0.02, 0.05)),
                 ("min-area", "--min-area", (1e-4, 2e-4, 1e-3))]
    defaults = {"--threshold": 0.05, "--flow-threshold": 2.5, "--no-flow": False,
                "--no-colour": False, "--colour-threshold": 0.065,
                "--flow-relative": 0,
                "--neighbours": 4, "--partners": 2, "--partners-ahead": 4, "--ahead": 2,
                "--ahead-veto": 0.5, "--partners-veto": 1, "--ahead-min-share": 0.1,
                "--region-depth": 0.5,
                "--min-baseline": 0.25, "--passes": 2, "--occludes": 0.2, "--occlusion-gap": 0.25,
                "--segments": 300,
                "--probability": 0.4, "--grounded": 0.25, "--min-height": 0.5,
                "--min-ratio": 0.5, "--max-gap": 3, "--gap-support": 0.05, "--max-fill": 0.5, "--complete": 3,
                "--driven": 1, "--driven-agree": 0.1, "--no-driven-grow": False,
                "--max-width": 640, "--window": 5, "--slack": 1, "--quantile": 0, "--texture": 0.02,
                "--depth-tolerance": 0.05, "--open": 1, "--close": 0.02, "--min-area": 2e-4,
                "--seen-tolerance": 0.05}
    rows = []

    def measure(group, opt, v, args, where):
        (_, _, wall), slow = c.tools.best_wall(c.repeat, "dynmask", "-q", "--force", *args, where)
        masks = [imageio.imread(os.path.join(where, "masks", n)) > 0 for n in a_names]
        b_share = np.mean([(imageio.imread(os.path.join(where, "masks", n)) > 0).mean()
                           for n in names if n.startswith("B_")])
        rows.append({"group": group, "setting": f"{group}={v}", "default": v == defaults[opt],
                     "iou": round(iou(masks, truths), 4), "pass_b_masked": round(b_share, 4),
                     "ms_per_image": round(1000 * wall / len(names), 1),
                     "slowest_ms_per_image": round(1000 * slow / len(names), 1)})
        sl.log("dynmask", rows[-1]["setting"], f"IoU {rows[-1]['iou']:.4f}  pass B "
               f"{100 * b_share:.2f} %  {rows[-1]['ms_per_image']:7.1f} ms/image")

    for group, opt, values, *extra in knobs:
        for v in values:
            args = ([opt] if v is True else []) if opt.startswith("--no-") else [opt, v]
            measure(group, opt, v, args + (extra[0] if extra else []), ws)
    # --max-fill judges blobs on the corridor walls of a mesh built from the photos (densify,
    # roadmesh --dense: the walls close the fused facades' holes); the true mesh has none.
    photo = sl.copy_workspace(ws, os.path.join(folder, "photo"),
                              leave_out=("mesh.ply", "dynmask-mesh.ply", "masks", "dynamic",
                                         "tracks.tsv"))
    c.tools.run("densify", "--quiet", photo)
    c.tools.run("roadmesh", "--quiet", "--dense", "--metric", "--no-colours", photo)
    for v in (0.5, 1) if c.short else (0.3, 0.5, 1):
        measure("max-fill (photo-built mesh)", "--max-fill", v, ["--max-fill", v], photo)
    # --complete needs what each photo saw (densify's maps) beside the mesh: the same workspace.
    for v in (0, 3) if c.short else (0, 1, 3, 10):
        measure("complete (photo-built mesh)", "--complete", v, ["--complete", v], photo)
    # --driven also needs densify's maps and the mesh. The fixture has no vehicle standing where
    # a drive passed (its vehicles move): these rows measure its time and that it marks nothing
    # of the road (IoU and drive B as at 0); CamVid 0016E5 is where it finds something.
    if not c.short:
        for v in (0, 0.5, 1, 2):
            measure("driven (photo-built mesh)", "--driven", v, ["--driven", v], photo)
        for v in (0.05, 0.1, 0.2):
            measure("driven-agree (photo-built mesh)", "--driven-agree", v,
                    ["--driven-agree", v], photo)
        for v in (False, True):
            measure("no-driven-grow (photo-built mesh)", "--no-driven-grow", v,
                    ["--no-driven-grow"] if v else [], photo)
        # --seen-tolerance compares densify's map of each photo with the static depth: only
        # this workspace has the maps.
        for v in (0, 0.05, 0.1):
            measure("seen-tolerance (photo-built mesh)", "--seen-tolerance", v,
                    ["--seen-tolerance", v], photo)
    best_default = max(r["iou"] for r in rows if r["default"])
    c.checks(best_default > 0.2, f"dynmask defaults: IoU {best_default:.4f} above 0.2")
    s = sl.Section(
        "dynmask", "dynmask: label-free vehicle masks, IoU against milliseconds per image", rows,
        ["group", "setting", "default", "iou", "pass_b_masked", "ms_per_image",
         "slowest_ms_per_image"],
        f"<b>Knobs:</b> <code>--threshold</code> (photometric residual at p = 0.5), "
        f"<code>--no-colour</code>, <code>--colour-threshold</code> (a colour channel's), "
        f"<code>--flow-threshold</code> (flow residual in pixels), <code>--no-flow</code>, "
        f"<code>--neighbours</code>, <code>--partners</code> (photos of the other drive), "
        f"<code>--partners-ahead</code> (photos of the other drive farther along the road), "
        f"<code>--ahead-veto</code> (this drive's photos farther along veto the other drive's "
        f"evidence where they saw the road as the photo does), "
        f"<code>--ahead</code> (photos of the same drive farther along; only without partners, "
        f"so measured with <code>--partners 0</code>; <code>--ahead-min-share</code>: how near "
        f"a photo farther along may be to stand for its depth, towards a drive's end), "
        f"<code>--region-depth</code>, "
        f"<code>--min-baseline</code>, <code>--passes</code>, "
        f"<code>--segments</code> (Felzenszwalb's k; 0 = no regions), "
        f"<code>--probability</code>, <code>--grounded</code>, <code>--min-height</code> "
        f"(blobs must stand that share of the camera's height), <code>--occludes</code>, "
        f"<code>--occlusion-gap</code> (blobs must hide something behind them; on this true "
        f"mesh there are no facade errors for them to remove), <code>--max-fill</code> (blobs "
        f"mostly on the corridor walls that close the holes of a mesh fused from the photos; "
        f"measured on such a mesh, densify + roadmesh --dense of the same photos), "
        f"<code>--complete</code> (blobs grown by GrabCut into what the photo's own depth does "
        f"not explain, at most that many times their area; on the same photo-built workspace: "
        f"it needs densify's maps), "
        f"<code>--driven</code>, <code>--driven-agree</code> (surfaces the photo and the mesh "
        f"agree on, standing where a drive's car passed; <code>--no-driven-grow</code>: not "
        f"the rest of their surface in the mesh; on the same photo-built workspace; "
        f"the fixture's vehicles all move, so these rows show the time and that the road is "
        f"left alone; CamVid 0016E5 is where it finds parked and waiting vehicles), "
        f"<code>--min-ratio</code>, "
        f"<code>--max-gap</code> (tracking), <code>--gap-support</code> (a gap fill kept only "
        f"where the probability supports it), <code>--max-width</code> (the working "
        f"resolution: the images scaled down to that width), <code>--window</code> (the box "
        f"averaging the photometric residual), <code>--slack</code> (misalignment forgiven), "
        f"<code>--quantile</code> (of the residuals over the neighbours), <code>--texture</code> "
        f"(the gradient at which a pixel's own evidence counts fully), "
        f"<code>--depth-tolerance</code> (hides a point in a neighbour), <code>--open</code>, "
        f"<code>--close</code>, <code>--min-area</code> (the blobs' morphology), "
        f"<code>--seen-tolerance</code> (pixels densify's map puts on the static surface are "
        f"static; on the photo-built workspace, which has the maps). Each varied alone on the "
        f"fixture's photos and true mesh ({len(a_names)} frames per drive, 640x192). "
        f"<b>Accuracy:</b> IoU of drive A's masks against truth/masks, pooled (the column "
        f"pass_b_masked: the share of drive B, which has no vehicle, masked: lower is better). "
        f"<b>Time:</b> whole-process wall time per image, fastest of {c.repeat} runs.",
        note="Flow and the second pass cost time; the thresholds cost nothing: choose them by IoU "
             "and drive B's false share.")
    return sl.emit(c.out, s, "ms_per_image", "iou", xmax="slowest_ms_per_image",
                   xlabel="milliseconds per image (whole-process wall time)",
                   ylabel="mask IoU against the truth (pooled)")


def sweep_simulate(c):
    """simulate's quality levels (render scale, projectors, mesh detail): the frames as shown
    against ptmrender's full-quality frames at the same poses, and simulate's render time per
    frame."""
    folder = os.path.join(c.work, "simulate")
    ws = sl.copy_workspace(c.road, os.path.join(folder, "ws"))
    c.tools.run("bakedepth", "--quiet", ws)
    log = os.path.join(folder, "log.tsv")
    with open(log, "w") as f:  # a gentle left curve at 6 m/s, then straight
        f.write(f"time steer speed\n0 0 6\n1 20 6\n2 0 6\n{3 if c.short else 6} 0 6\n")
    levels = (0, 3, 7) if c.short else range(8)
    common = ["-q", "--metric", "--replay", log, "--as-fast", "--fps", 10, "--no-window",
              "--no-adapt", "--record-frames"]
    rows, ref = [], os.path.join(folder, "ptmrender")
    for q in levels:
        rec = os.path.join(folder, f"level{q}")
        best = None
        for _ in range(c.repeat):
            c.tools.run("simulate", *common, "--quality", q, "--record", rec, ws)
            ms = json.load(open(os.path.join(rec, "summary.json")))["frames"]["render_ms"]
            best = ms if best is None else min(best, ms)
        if q == 0:  # the same poses at every level (--as-fast): the reference once
            c.tools.run("ptmrender", "--quiet", "--force", "--poses",
                        os.path.join(rec, "poses.tum"), ws, ref)
        s = c.tools.ssim_mean(os.path.join(rec, "frames"), ref)
        rows.append({"group": "quality", "setting": f"level {q}", "default": q == 0,
                     "ssim": round(s, 5), "ms_per_frame": round(best, 2)})
        sl.log("simulate", f"level {q}", f"SSIM {s:.4f}  {best:7.1f} ms/frame")
    c.checks(rows[0]["ssim"] > 0.999, f"simulate level 0 equals ptmrender ({rows[0]['ssim']:.4f})")
    sec = sl.Section(
        "simulate", "simulate's quality levels: SSIM against milliseconds per frame", rows,
        ["group", "setting", "default", "ssim", "ms_per_frame"],
        "<b>Knob:</b> <code>--quality</code> (with <code>--no-adapt</code>): the levels adaptive "
        "quality steps through, (render scale, projectors, mesh detail) from (1, 4, full) to "
        "(0.5, 1, simplified beyond 6 m). <b>Accuracy:</b> mean SSIM of the frames as shown (scaled "
        "up to the screen as the window does) against ptmrender's full-quality frames at the same "
        "poses (a replayed log on the sweep's road, baked depth). <b>Time:</b> simulate's own "
        f"render milliseconds per frame (choosing and reading projectors included), fastest of "
        f"{c.repeat} runs. <b>Read:</b> adaptive quality moves left along this curve when frames "
        "take longer than 90 % of the budget.")
    return sl.emit(c.out, sec, "ms_per_frame", "ssim", xlabel="milliseconds per frame "
                   "(simulate's render time)", ylabel="mean SSIM against ptmrender's full quality")


def record_like_model(sparse, dst, mount_deg, noise_px, seed=3):
    """The road's true model as a navigation record would give it: the true centres, every
    attitude off by one mount rotation (camera-axis rotation vector, degrees), each 2-D point
    moved by N(0, noise_px) so that the tracks are not exact. Text model in dst."""
    rng = np.random.default_rng(seed)
    M = Rotation.from_rotvec(np.radians(mount_deg))
    os.makedirs(dst, exist_ok=True)
    shutil.copy(os.path.join(sparse, "cameras.txt"), os.path.join(dst, "cameras.txt"))
    shutil.copy(os.path.join(sparse, "points3D.txt"), os.path.join(dst, "points3D.txt"))
    lines = open(os.path.join(sparse, "images.txt")).read().split("\n")
    out, i = [], 0
    while i < len(lines):
        if lines[i].startswith("#") or not lines[i].strip():
            out.append(lines[i])
            i += 1
            continue
        f = lines[i].split()
        q = np.array(list(map(float, f[1:5])))
        t = np.array(list(map(float, f[5:8])))
        R = Rotation.from_quat([q[1], q[2], q[3], q[0]])
        C = -R.inv().apply(t)
        Rr = M.inv() * R
        qq = Rr.as_quat()
        out.append(" ".join([f[0]] + [f"{v:.17g}" for v in (qq[3], qq[0], qq[1], qq[2])]
                            + [f"{v:.17g}" for v in -Rr.apply(C)] + f[8:]))
        pts = lines[i + 1].split()
        for k in range(0, len(pts) - 2, 3):
            pts[k] = f"{float(pts[k]) + rng.normal(0, noise_px):.6f}"
            pts[k + 1] = f"{float(pts[k + 1]) + rng.normal(0, noise_px):.6f}"
        out.append(" ".join(pts))
        i += 2
    with open(os.path.join(dst, "images.txt"), "w") as f:
        f.write("\n".join(out))
    return dst


def sweep_boresight(c):
    """boresight's knobs on the road's true model turned into a record with a known mount
    rotation (pitch 0.3, yaw -0.5, roll 0.2 degrees) and 0.5 px of noise on the 2-D points: the
    angle between the fitted and the true mount rotation, against whole-process milliseconds."""
    folder = os.path.join(c.work, "boresight")
    shutil.rmtree(folder, ignore_errors=True)
    mount = np.array([0.3, -0.5, 0.2])
    rec = record_like_model(os.path.join(c.road, "sparse"), os.path.join(folder, "rec"), mount, 0.5)
    defaults = {"--conditioning": 0.01, "--max-error": 4, "--min-angle": 1, "--min-track": 3,
                "--min-gain": 0.05}
    knobs = [("conditioning", "--conditioning", (0, 0.01, 0.1) if c.short else (0, 0.001, 0.01, 0.1, 0.5)),
             ("max-error", "--max-error", (1, 4) if c.short else (1, 2, 4, 16)),
             ("min-angle", "--min-angle", (0, 1) if c.short else (0, 1, 3, 10)),
             ("min-track", "--min-track", (3,) if c.short else (2, 3, 5)),
             ("min-gain", "--min-gain", (0.05,) if c.short else (0, 0.05, 0.2, 0.5))]
    want = Rotation.from_rotvec(np.radians(mount))
    rows = []
    for group, opt, values in knobs:
        for v in values:
            o = os.path.join(folder, f"{group}-{v}")
            (_, _, wall), _ = c.tools.best_wall(c.repeat, "boresight", "-q", "--force", opt, v, rec, o)
            j = json.load(open(os.path.join(o, "boresight.json")))
            err = np.degrees((Rotation.from_matrix(np.array(j["R"])) * want.inv()).magnitude())  # R: as applied
            rows.append({"group": group, "setting": f"{group}={v}", "default": v == defaults[opt],
                         "error_deg": round(float(err), 5), "frozen": len(j["frozen_directions"]),
                         "ms": round(wall * 1000, 1)})
            sl.log("boresight", rows[-1]["setting"], f"error {err:.4f} deg  {wall * 1000:7.1f} ms")
    base = [r for r in rows if r["default"]]
    c.checks(all(r["error_deg"] < 0.05 for r in base),
             f"boresight default finds the mount within 0.05 deg ({base[0]['error_deg']:.4f})")
    sec = sl.Section(
        "boresight", "boresight's knobs: error of the fitted mount rotation against milliseconds",
        rows, ["group", "setting", "default", "error_deg", "frozen", "ms"],
        "<b>Knobs:</b> <code>--conditioning</code>, <code>--max-error</code>, "
        "<code>--min-angle</code>, <code>--min-track</code>, <code>--min-gain</code> (a fit under it is not applied: its error is then the whole mount). <b>Accuracy:</b> the angle (degrees) "
        "between the fitted rotation and the mount rotation the record was made with (the road's "
        "true model, every attitude off by pitch 0.3, yaw -0.5, roll 0.2 degrees, 0.5 px of noise "
        "on the 2-D points); a frozen direction keeps its share of the mount as error. "
        f"<b>Time:</b> whole process, fastest of {c.repeat} runs. <b>Read:</b> lower is better.")
    return sl.emit(c.out, sec, "ms", "error_deg", xlabel="milliseconds (whole process)",
                   ylabel="degrees from the true mount rotation")


SWEEPS = {"pickview": sweep_pickview, "segtrack": sweep_segtrack, "inpaint3d": sweep_inpaint3d,
          "dynmask": sweep_dynmask,
          "bakedepth": sweep_bakedepth, "ptmrender": sweep_ptmrender,
          "densify": sweep_densify.sweep, "simulate": sweep_simulate,
          "boresight": sweep_boresight, "exposure": sweep_exposure}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build", "bin"))
    ap.add_argument("--out", default=os.path.join(HERE, "..", "out", "sweep"))
    ap.add_argument("--frames", type=int, help="mkroad frames per pass (default 40; short 16)")
    ap.add_argument("--only", help="comma-separated tools (default: all): " + ",".join(SWEEPS)
                    + "; the page then shows only these, and other tools' files in OUT go")
    ap.add_argument("--repeat", type=int, help="runs of each cheap setting (default 3; short 1)")
    ap.add_argument("--short", action="store_true", help="a few settings per tool, small roads")
    a = ap.parse_args()
    only = a.only.split(",") if a.only else list(SWEEPS)
    unknown = [t for t in only if t not in SWEEPS]
    if unknown:
        ap.error(f"--only: unknown tool {unknown[0]} (choose from {', '.join(SWEEPS)})")
    out = os.path.abspath(a.out)
    os.makedirs(os.path.join(out, "work"), exist_ok=True)
    c = types.SimpleNamespace(tools=sl.Tools(a.bin), out=out, work=os.path.join(out, "work"),
                              short=a.short, checks=sl.Checks(),
                              repeat=a.repeat or (1 if a.short else 3))
    frames = a.frames or (16 if a.short else 40)
    c.road = c.tools.mkroad(os.path.join(c.work, "road"), "--frames", frames,
                            "--fullsize-frames", 1 if a.short else 4)
    for f in os.listdir(out):  # plots of tools not swept this time would be stale
        if f.endswith((".png", ".csv")) and f[:-4] not in only:
            os.remove(os.path.join(out, f))
    sections = [SWEEPS[t](c) for t in only]
    page = sl.write_page(
        out, sections, "mvtm: what accuracy costs, for every tool",
        f"Each plot is one tool's accuracy knobs, swept on the synthetic mkroad road "
        f"({frames} frames per drive{', short mode' if a.short else ''}) and scored against its "
        f"ray-traced truth. Read it before choosing settings: up is more accurate (down, for "
        f"pickview's misses), left is faster; the ringed point is the tool's default. Made by "
        f"<code>make -f Makefile.examples sweep</code> (<code>examples/sweep.py</code>); "
        f"times are from one shared machine, so compare them within a plot, not across runs.")
    c.checks.page(out, sections)
    print(page)
    if c.checks.failed:
        print(f"sweep: {len(c.checks.failed)} check(s) failed", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

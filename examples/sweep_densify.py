"""Accuracy against time for densify's knobs (and the fused mesh): the densify part of the sweep.

Run through examples/sweep.py (`sweep.py --only densify [--short]`), which writes
OUT/densify.csv and OUT/densify.png and the section of OUT/index.html.

Builds a static mkroad road (no vehicles: stereo has no answer for moving objects; 640x192,
12 frames per drive; --short: 320x96, 4 frames), runs densify with every setting below, and scores
each depth map against the fixture's CPU ray-traced depth (truth/depth/NAME.exr, sampled at the
map's pixel centres when the maps are smaller than the image): the share of depths within 2 % of the truth, and the share
of the truth's surface pixels that get such a depth ("good coverage"). Time is densify's own
milliseconds per image. --short runs three settings.

Knobs: --planes (16, 32, 48, 96), --window (5, 7, 11), --neighbours (2, 4, 6), --best-k (1, 2, 3),
--scale (0.25, 0.5, 1; the default is 0: from --map-focal), --map-focal (180, 360, 720),
--min-score (0.3, 0.5, 0.7), --refine (0, 2, 4, 8), sweep directions
(fronto only, no facade), and the fused mesh of the default setting (roadmesh --dense, baked
back with bakedepth; also with --strict-agree, --agree-tolerance 0.02, --walls-gap 1, --no-seen-walls,
--walls-reach 8, --voxel 0.05 and 0.2, --min-agree 1 and 3, --max-depth 20 and 80, --walls-behind -1)
beside the corridor proxy alone (in the CSV and the page's table, their time roadmesh's
whole-process wall time per image; not in the plot, whose time is densify's).
"""
import os
import re

import numpy as np

import sweeplib as sl


def score(ws, folder):
    """(share of depths within 2 %, share of truth surface pixels with such a depth)."""
    good = have = surface = 0
    for f in sorted(os.listdir(os.path.join(ws, "truth", "depth"))):
        p = os.path.join(folder, f)
        if not os.path.exists(p):
            continue
        d = sl.read_float(p)
        t = sl.resample_nearest(sl.read_float(os.path.join(ws, "truth", "depth", f)), d.shape)
        s = np.isfinite(t)
        h = s & np.isfinite(d)
        rel = np.abs(d[h] / t[h] - 1)
        good += int((rel <= 0.02).sum())
        have += int(h.sum())
        surface += int(s.sum())
    return good / max(have, 1), good / max(surface, 1)


def sweep(c):
    frames, size = (4, "320x96") if c.short else (12, "640x192")
    ws = c.tools.mkroad(os.path.join(c.work, "densify", "road"), "--vehicles", 0, "--frames",
                        frames, "--size", size, "--fullsize-frames", 0, "--offpath-every", 0)
    rows = []

    def add(group, name, extra):
        _, err, _ = c.tools.run("densify", "--force", *extra, ws)
        ms = float(re.search(r"\(([\d.]+) ms per image", err).group(1))
        within2, coverage = score(ws, os.path.join(ws, "stereo"))
        rows.append({"group": group, "setting": name, "default": not extra,
                     "within2": round(within2, 4), "good_coverage": round(coverage, 4),
                     "ms_per_image": ms})
        sl.log("densify", name, f"within 2 % {within2:.3f}  good coverage {coverage:.3f}  "
               f"{ms:7.0f} ms/image")

    add("default", "defaults", [])
    if c.short:
        add("planes", "planes=16", ["--planes", "16"])
        add("scale", "scale=0.25", ["--scale", "0.25"])
    else:
        for p in (16, 32, 96):
            add("planes", f"planes={p}", ["--planes", p])
        for w in (5, 11):
            add("window", f"window={w}", ["--window", w])
        for n in (2, 6):
            add("neighbours", f"neighbours={n}", ["--neighbours", n])
        for k in (1, 3):
            add("best-k", f"best-k={k}", ["--best-k", k])
        for s in (0.25, 0.5, 1.0):
            add("scale", f"scale={s}", ["--scale", s])
        for f in (180, 720):  # the default, 360, is the defaults row (scale 0.971 here)
            add("map-focal", f"map-focal={f}", ["--map-focal", f])
        for s in (0.3, 0.7):
            add("min-score", f"min-score={s}", ["--min-score", s])
        for r in (0, 2, 8):
            add("refine", f"refine={r}", ["--refine", r])
        add("sweeps", "fronto only", ["--no-ground", "--no-facade"])
        add("sweeps", "no facade", ["--no-facade"])
        # The meshes, baked back at the images' size: fused (default densify) against the corridor.
        add("default", "defaults (for fusion)", [])
        for name, extra in (("corridor proxy", []), ("fused (roadmesh --dense)", ["--dense"]),
                            ("fused, --strict-agree", ["--dense", "--strict-agree"]),
                            ("fused, --agree-tolerance 0.02", ["--dense", "--agree-tolerance", 0.02]),
                            ("fused, --walls-gap 1", ["--dense", "--walls-gap", 1]),
                            ("fused, --no-seen-walls", ["--dense", "--no-seen-walls"]),
                            ("fused, --walls-reach 8", ["--dense", "--walls-reach", 8]),
                            ("fused, --voxel 0.05", ["--dense", "--voxel", 0.05]),
                            ("fused, --voxel 0.2", ["--dense", "--voxel", 0.2]),
                            ("fused, --min-agree 1", ["--dense", "--min-agree", 1]),
                            ("fused, --min-agree 3", ["--dense", "--min-agree", 3]),
                            ("fused, --max-depth 20", ["--dense", "--max-depth", 20]),
                            ("fused, --max-depth 80", ["--dense", "--max-depth", 80]),
                            ("fused, --walls-behind -1 (no walls)",
                             ["--dense", "--walls-behind", -1])):
            _, _, wall = c.tools.run("roadmesh", "--force", "--no-colours", *extra, ws)
            c.tools.run("bakedepth", "--force", ws)
            within2, coverage = score(ws, os.path.join(ws, "depth"))
            ms = round(1000 * wall / len(os.listdir(os.path.join(ws, "images"))), 1)
            rows.append({"group": "mesh", "setting": name, "default": False,
                         "within2": round(within2, 4), "good_coverage": round(coverage, 4),
                         "ms_per_image": ms})
            sl.log("densify", name, f"within 2 % {within2:.3f}  good coverage {coverage:.3f}  "
                   f"{ms:7.0f} ms/image (roadmesh, whole process)")
    s = sl.Section(
        "densify", "densify: dense depth, good coverage against milliseconds per image", rows,
        ["group", "setting", "default", "within2", "good_coverage", "ms_per_image"],
        f"<b>Knobs:</b> <code>--planes</code> (planes per sweep family), <code>--window</code> "
        f"(ZNCC window), <code>--neighbours</code>, <code>--best-k</code>, <code>--scale</code> "
        f"(depth map size; by default from <code>--map-focal</code>, the maps' focal length in "
        f"pixels), <code>--map-focal</code>, <code>--min-score</code> (confidence cut), <code>--refine</code> "
        f"(per-pixel refinement sub-steps), the sweep families "
        f"(<code>--no-ground</code>, <code>--no-facade</code>); each varied alone. A static "
        f"mkroad road ({frames} frames per drive at {size}, no vehicles). <b>Accuracy:</b> "
        f"&ldquo;good coverage&rdquo;, the share of the ray-traced truth's surface pixels that "
        f"get a depth within 2 % of the truth (the CSV also gives the share of the depths "
        f"written that are within 2 %, and, in full mode, the corridor proxy and the mesh fused "
        f"from the default maps, baked back with bakedepth, with roadmesh's knobs <code>--voxel</code>, "
        f"<code>--min-agree</code>, <code>--max-depth</code>, <code>--strict-agree</code>, "
        f"<code>--agree-tolerance</code>, the walls' <code>--walls-gap</code>, "
        f"<code>--walls-reach</code>, <code>--walls-behind</code>, <code>--no-seen-walls</code>; "
        f"their time: roadmesh's whole-process milliseconds per image). <b>Time:</b> densify's own "
        f"milliseconds per image. <b>Read:</b> higher is better; the default is ringed.")
    return sl.emit(c.out, s, "ms_per_image", "good_coverage",
                   plot_rows=[r for r in rows if r["group"] != "mesh"],
                   xlabel="milliseconds per image (densify's own timing)",
                   ylabel="truth surface pixels with a depth within 2 %")

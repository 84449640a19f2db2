#!/usr/bin/env python3
"""Accuracy against time for densify's knobs (and the fused mesh) on the mkroad fixture.

usage: examples/sweep_densify.py [--bin build/bin] [--out out/sweep_densify] [--frames N]
                                 [--size WxH] [--short]

Builds a static mkroad road (no vehicles: stereo has no answer for moving objects), runs densify
with every setting below, and scores each depth map against the fixture's CPU ray-traced depth
(truth/depth/NAME.exr, sampled at the map's pixel centres when --scale < 1): the share of depths
within 2 % of the truth, and the share of the truth's surface pixels that get such a depth
("good coverage"). Time is densify's own milliseconds per image. Writes OUT/densify.csv and
OUT/densify.svg (good coverage against ms per image). --short runs three settings (CI).

Knobs: --planes (16, 32, 48, 96), --window (5, 7, 11), --neighbours (2, 4, 6), --best-k (1, 2, 3),
--scale (0.5, 1), --min-score (0.3, 0.5, 0.7), sweep directions (fronto only, no facade), and the
fused mesh of the default setting (roadmesh --dense, baked back with bakedepth) beside the
corridor proxy alone. Needs Debian's python3-openimageio and python3-numpy.
"""
import argparse
import csv
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

ap = argparse.ArgumentParser()
ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin"))
ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "out", "sweep_densify"))
ap.add_argument("--frames", type=int, default=12, help="mkroad frames per pass")
ap.add_argument("--size", default="640x192", help="mkroad image size")
ap.add_argument("--short", action="store_true", help="three settings only (keeps CI short)")
args = ap.parse_args()
B = os.path.abspath(args.bin)
out = os.path.abspath(args.out)
ws = os.path.join(out, "road")
os.makedirs(out, exist_ok=True)


def run(*cmd):
    r = subprocess.run([os.path.join(B, cmd[0]), *cmd[1:]], check=True, text=True,
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    return r.stderr


def read(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise SystemExit(f"sweep_densify: error: {path}: {buf.geterror()}")
    return buf.get_pixels(oiio.FLOAT)[:, :, 0]


if not os.path.exists(os.path.join(ws, "truth", "mkroad.txt")):
    run("mkroad", "--quiet", "--vehicles", "0", "--frames", str(args.frames), "--size", args.size,
        "--fullsize-frames", "0", "--offpath-every", "0", ws)


def score(folder, suffix=".exr"):
    """(share of depths within 2 %, share of truth surface pixels with such a depth)."""
    good = have = surface = 0
    for f in sorted(os.listdir(os.path.join(ws, "truth", "depth"))):
        p = os.path.join(folder, f)
        if not os.path.exists(p):
            continue
        d, t = read(p), read(os.path.join(ws, "truth", "depth", f))
        ys = np.minimum(((np.arange(d.shape[0]) + 0.5) * t.shape[0] / d.shape[0]).astype(int), t.shape[0] - 1)
        xs = np.minimum(((np.arange(d.shape[1]) + 0.5) * t.shape[1] / d.shape[1]).astype(int), t.shape[1] - 1)
        t = t[np.ix_(ys, xs)]
        s = np.isfinite(t)
        h = s & np.isfinite(d)
        rel = np.abs(d[h] / t[h] - 1)
        good += int((rel <= 0.02).sum())
        have += int(h.sum())
        surface += int(s.sum())
    return good / max(have, 1), good / max(surface, 1)


rows = []


def add(group, name, extra):
    err = run("densify", "--force", *extra, ws)
    m = re.search(r"\(([\d.]+) ms per image", err)
    within2, coverage = score(os.path.join(ws, "stereo"))
    rows.append({"group": group, "setting": name, "within2": round(within2, 4),
                 "good_coverage": round(coverage, 4), "ms_per_image": float(m.group(1))})
    print(f"{group:10s} {name:26s} within 2 % {within2:.3f}  good coverage {coverage:.3f}  "
          f"{float(m.group(1)):7.0f} ms/image", file=sys.stderr)


add("default", "defaults", [])
if args.short:
    add("planes", "planes=16", ["--planes", "16"])
    add("scale", "scale=0.25", ["--scale", "0.25"])
else:
    for p in (16, 32, 96):
        add("planes", f"planes={p}", ["--planes", str(p)])
    for w in (5, 11):
        add("window", f"window={w}", ["--window", str(w)])
    for n in (2, 6):
        add("neighbours", f"neighbours={n}", ["--neighbours", str(n)])
    for k in (1, 3):
        add("best-k", f"best-k={k}", ["--best-k", str(k)])
    for s in (0.25, 1.0):
        add("scale", f"scale={s}", ["--scale", str(s)])
    for s in (0.3, 0.7):
        add("min-score", f"min-score={s}", ["--min-score", str(s)])
    add("sweeps", "fronto only", ["--no-ground", "--no-facade"])
    add("sweeps", "no facade", ["--no-facade"])
    # The meshes, baked back at the images' size: fused (default densify) against the corridor.
    add("default", "defaults (for fusion)", [])
    for name, extra in (("corridor proxy", []), ("fused (roadmesh --dense)", ["--dense"])):
        run("roadmesh", "--force", "--no-colours", *extra, ws)
        run("bakedepth", "--force", ws)
        within2, coverage = score(os.path.join(ws, "depth"))
        rows.append({"group": "mesh", "setting": name, "within2": round(within2, 4),
                     "good_coverage": round(coverage, 4), "ms_per_image": 0})
        print(f"{'mesh':10s} {name:26s} within 2 % {within2:.3f}  good coverage {coverage:.3f}", file=sys.stderr)

with open(os.path.join(out, "densify.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=["group", "setting", "within2", "good_coverage", "ms_per_image"])
    w.writeheader()
    w.writerows(rows)

pts = [r for r in rows if r["group"] != "mesh"]
W, H, M = 760, 460, 60
x1 = max(r["ms_per_image"] for r in pts) * 1.1
y0 = min(r["good_coverage"] for r in pts) - 0.02
y1 = max(r["good_coverage"] for r in pts) + 0.02
X = lambda v: M + v / x1 * (W - 2 * M)
Y = lambda v: H - M - (v - y0) / (y1 - y0) * (H - 2 * M)
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<line x1="{M}" y1="{H-M}" x2="{W-M}" y2="{H-M}" stroke="#000"/><line x1="{M}" y1="{M}" x2="{M}" y2="{H-M}" stroke="#000"/>',
       f'<text x="{W/2}" y="{H-20}" text-anchor="middle">densify ms per image</text>',
       f'<text x="15" y="{H/2}" transform="rotate(-90 15 {H/2})" text-anchor="middle">truth pixels with a depth within 2 %</text>']
for i in range(6):
    svg.append(f'<text x="{X(x1 * i / 5):.1f}" y="{H-M+15}" text-anchor="middle">{x1 * i / 5:.0f}</text>')
    yv = y0 + (y1 - y0) * i / 5
    svg.append(f'<text x="{M-5}" y="{Y(yv)+4:.1f}" text-anchor="end">{yv:.3f}</text>')
for r in pts:
    svg.append(f'<circle cx="{X(r["ms_per_image"]):.1f}" cy="{Y(r["good_coverage"]):.1f}" r="4" fill="#36c"/>')
    svg.append(f'<text x="{X(r["ms_per_image"])+6:.1f}" y="{Y(r["good_coverage"])-4:.1f}">{r["setting"]}</text>')
svg.append("</svg>")
with open(os.path.join(out, "densify.svg"), "w") as f:
    f.write("\n".join(svg))
print(os.path.join(out, "densify.csv"))

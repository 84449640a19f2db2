#!/usr/bin/env python3
"""Accuracy against time: sweep ptmrender's and bakedepth's knobs on the mkroad fixture.

usage: examples/sweep.py [--bin build/bin] [--out out/sweep] [--frames N]

Renders the fixture's off-path truth poses (1.5 m lane changes and 15 degree turns, pass A) with
every setting below, scores each against the ray-traced truth with `ssim`, and takes the
milliseconds per frame that ptmrender reports (render + depth + load; PNG encoding excluded,
it overlaps rendering). Writes OUT/sweep.csv and OUT/sweep.svg (SSIM against ms per frame).

Knobs: --projectors K (1, 2, 4, 8), --bias B (0, 0.001, 0.005, 0.02, 0.1),
baked depth at --scale 0.25 / 0.5 / 1 against a depth pre-pass (no baked maps), and the
effects (occlusion, skybox) on and off. Only the standard library and the mvtm tools are used.
"""
import argparse
import csv
import os
import re
import shutil
import subprocess
import sys

ap = argparse.ArgumentParser()
ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin"))
ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "out", "sweep"))
ap.add_argument("--frames", type=int, default=20, help="mkroad frames per pass")
args = ap.parse_args()
B = os.path.abspath(args.bin)
out = os.path.abspath(args.out)
ws = os.path.join(out, "road")
os.makedirs(out, exist_ok=True)


def run(*cmd, capture=False):
    r = subprocess.run([os.path.join(B, cmd[0]), *cmd[1:]], check=True, text=True,
                       stdout=subprocess.PIPE if capture else None, stderr=subprocess.PIPE)
    return r.stdout if capture else r.stderr


if not os.path.exists(os.path.join(ws, "truth", "mkroad.txt")):
    run("mkroad", "--quiet", "--frames", str(args.frames), "--fullsize-frames", "0", ws)
# Vehicle masks: the fixture's truth, where segtrack would put them.
os.makedirs(os.path.join(ws, "masks"), exist_ok=True)
for f in os.listdir(os.path.join(ws, "truth", "masks")):
    shutil.copy(os.path.join(ws, "truth", "masks", f), os.path.join(ws, "masks", f))

variants = ["lane_left", "lane_right", "yaw_left", "yaw_right"]


def bake(scale):
    d = os.path.join(ws, "depth")
    shutil.rmtree(d, ignore_errors=True)
    if scale is not None:
        run("bakedepth", "--quiet", "--scale", str(scale), ws)


def score(name, extra):
    """Mean SSIM over all variants and ms per frame for one setting."""
    ssims, ms, frames = [], 0.0, 0
    for v in variants:
        dst = os.path.join(out, "renders", name, v)
        err = run("ptmrender", "--force", "--poses", os.path.join(ws, "truth", "offpath", v, "sparse", "images.txt"),
                  *extra, ws, dst)
        m = re.search(r"(\d+) frames rendered.*\(([\d.]+) ms render, ([\d.]+) ms depth, ([\d.]+) ms load", err)
        n = int(m.group(1))
        ms += n * (float(m.group(2)) + float(m.group(3)) + float(m.group(4)))
        frames += n
        table = run("ssim", dst, os.path.join(ws, "truth", "offpath", v, "images"), capture=True)
        ssims.append(float([l for l in table.splitlines() if l.startswith("mean\t")][0].split("\t")[1]))
    return sum(ssims) / len(ssims), ms / frames


rows = []
def add(group, name, extra, depth_scale):
    bake(depth_scale)
    s, ms = score(name, extra)
    rows.append({"group": group, "setting": name, "ssim": round(s, 5), "ms_per_frame": round(ms, 2)})
    print(f"{group:12s} {name:28s} SSIM {s:.4f}  {ms:7.1f} ms/frame", file=sys.stderr)

add("baseline", "vertex colours", ["--mode", "vertex"], 1.0)
for k in (1, 2, 4, 8):
    add("projectors", f"K={k}", ["--projectors", str(k)], 1.0)
for b in (0, 0.001, 0.005, 0.02, 0.1):
    add("bias", f"bias={b}", ["--bias", str(b)], 1.0)
for sc in (0.25, 0.5, 1.0):
    add("depth", f"baked depth scale {sc}", [], sc)
add("depth", "depth pre-pass (not baked)", [], None)
add("effects", "no occlusion", ["--no-occlusion"], 1.0)
add("effects", "no skybox", ["--no-skybox"], 1.0)
add("effects", "no masks", ["--no-masks"], 1.0)

with open(os.path.join(out, "sweep.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=["group", "setting", "ssim", "ms_per_frame"])
    w.writeheader()
    w.writerows(rows)

# A plain SVG scatter plot: SSIM (y) against ms per frame (x), one colour per group.
W, H, M = 760, 460, 60
xs = [r["ms_per_frame"] for r in rows]
ys = [r["ssim"] for r in rows]
x0, x1 = 0, max(xs) * 1.1
y0, y1 = min(ys) - 0.02, max(ys) + 0.02
X = lambda v: M + (v - x0) / (x1 - x0) * (W - 2 * M)
Y = lambda v: H - M - (v - y0) / (y1 - y0) * (H - 2 * M)
colours = {"baseline": "#000", "projectors": "#c33", "bias": "#36c", "depth": "#393", "effects": "#c90"}
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<line x1="{M}" y1="{H-M}" x2="{W-M}" y2="{H-M}" stroke="#000"/><line x1="{M}" y1="{M}" x2="{M}" y2="{H-M}" stroke="#000"/>',
       f'<text x="{W/2}" y="{H-20}" text-anchor="middle">ms per frame (render + depth + load)</text>',
       f'<text x="15" y="{H/2}" transform="rotate(-90 15 {H/2})" text-anchor="middle">mean SSIM vs ray-traced truth</text>']
for i in range(6):
    xv = x0 + (x1 - x0) * i / 5
    yv = y0 + (y1 - y0) * i / 5
    svg.append(f'<text x="{X(xv)}" y="{H-M+15}" text-anchor="middle">{xv:.0f}</text>')
    svg.append(f'<text x="{M-5}" y="{Y(yv)+4}" text-anchor="end">{yv:.3f}</text>')
for r in rows:
    c = colours[r["group"]]
    svg.append(f'<circle cx="{X(r["ms_per_frame"]):.1f}" cy="{Y(r["ssim"]):.1f}" r="4" fill="{c}"/>')
    svg.append(f'<text x="{X(r["ms_per_frame"])+6:.1f}" y="{Y(r["ssim"])-4:.1f}" fill="{c}">{r["setting"]}</text>')
svg.append("</svg>")
with open(os.path.join(out, "sweep.svg"), "w") as f:
    f.write("\n".join(svg))
print(os.path.join(out, "sweep.csv"))

#!/usr/bin/env python3
"""Side by side: the same lane-change frame rendered on two meshes (e.g. the corridor proxy and
the fused dense mesh), full frame and an enlarged crop, as one PNG.

usage: examples/compare_lanes.py A_LANE_DIR B_LANE_DIR FRAME OUT.png [--crop X,Y,W,H] [--zoom 2]

Rows: A's frame, B's frame, then A's crop beside B's crop enlarged (nearest neighbour). Needs
Debian's python3-openimageio and python3-numpy.
"""
import argparse

import numpy as np
import OpenImageIO as oiio

ap = argparse.ArgumentParser()
ap.add_argument("a")
ap.add_argument("b")
ap.add_argument("frame")
ap.add_argument("out")
ap.add_argument("--crop", default="0,0,400,370", help="X,Y,W,H in pixels")
ap.add_argument("--zoom", type=int, default=1)
args = ap.parse_args()


def read(path):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise SystemExit(f"compare_lanes: error: {path}: {buf.geterror()}")
    px = buf.get_pixels(oiio.UINT8)
    return px if px.shape[2] != 1 else np.repeat(px, 3, axis=2)


a, b = read(f"{args.a}/{args.frame}"), read(f"{args.b}/{args.frame}")
if a.shape != b.shape:
    raise SystemExit("compare_lanes: error: the two frames differ in size")
x, y, w, h = (int(v) for v in args.crop.split(","))
ca = a[y:y + h, x:x + w].repeat(args.zoom, 0).repeat(args.zoom, 1)
cb = b[y:y + h, x:x + w].repeat(args.zoom, 0).repeat(args.zoom, 1)
crops = np.concatenate([ca, np.full((ca.shape[0], 8, 3), 255, np.uint8), cb], axis=1)
width = max(a.shape[1], crops.shape[1])
pad = lambda im: np.pad(im, ((0, 8), (0, width - im.shape[1]), (0, 0)), constant_values=255)
img = np.concatenate([pad(a), pad(b), pad(crops)], axis=0)
out = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
out.set_pixels(oiio.ROI(), np.ascontiguousarray(img))
if not out.write(args.out):
    raise SystemExit(f"compare_lanes: error: {args.out}: {out.geterror()}")
print(args.out)

#!/usr/bin/python3
"""Views of a chessboard through a known camera, for calibrate's tests: each pixel's ray is found
by inverting the OPENCV distortion (fixed-point iteration) and intersected with the board plane;
3x3 samples per pixel. The truth is the camera given here, nothing calibrate computes.

usage: make_board_views.py OUTDIR [--camera "fx fy cx cy k1 k2 p1 p2"] [--size 640x480]
         [--pattern 9x6] [--square 0.03] [--views 12] [--seed 1] [--noise 2] [--blank 0]
--blank N adds N views without the board (a wall), which calibrate must leave out.
"""
import argparse
import os

import imageio
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("out")
ap.add_argument("--camera", default="520 515 322 238 -0.28 0.09 0.001 -0.0008")
ap.add_argument("--size", default="640x480")
ap.add_argument("--pattern", default="9x6")
ap.add_argument("--square", type=float, default=0.03)
ap.add_argument("--views", type=int, default=12)
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--noise", type=float, default=2.0)
ap.add_argument("--blank", type=int, default=0)
a = ap.parse_args()
fx, fy, cx, cy, k1, k2, p1, p2 = map(float, a.camera.split())
W, H = map(int, a.size.split("x"))
C, R_ = map(int, a.pattern.split("x"))
sq = a.square
rng = np.random.default_rng(a.seed)
os.makedirs(a.out, exist_ok=True)

ss = 3
u = (np.arange(W * ss) + 0.5) / ss - 0.5
v = (np.arange(H * ss) + 0.5) / ss - 0.5
U, V = np.meshgrid(u, v)
xd, yd = (U - cx) / fx, (V - cy) / fy
x, y = xd.copy(), yd.copy()
for _ in range(30):
    r2 = x * x + y * y
    rad = 1 + k1 * r2 + k2 * r2 * r2
    dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    x, y = (xd - dx) / rad, (yd - dy) / rad
d = np.stack([x, y, np.ones_like(x)], axis=-1)


def rot(rx, ry, rz):
    cx_, sx = np.cos(rx), np.sin(rx)
    cy_, sy = np.cos(ry), np.sin(ry)
    cz, sz = np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx_, -sx], [0, sx, cx_]])
    Ry = np.array([[cy_, 0, sy], [0, 1, 0], [-sy, 0, cy_]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


for k in range(a.views + a.blank):
    if k < a.views:
        R = rot(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3))
        centre = np.array([(C - 1) * sq / 2, (R_ - 1) * sq / 2, 0])
        dist = rng.uniform(0.35, 0.6)
        off = np.array([rng.uniform(-0.08, 0.08), rng.uniform(-0.06, 0.06), dist])
        t = off - R @ centre
        n = R[:, 2]
        s = (n @ t) / (d @ n)
        P = d * s[..., None]
        B = (P - t) @ R  # board coordinates
        bx, by = B[..., 0], B[..., 1]
        inside = (bx > -sq) & (bx < C * sq) & (by > -sq) & (by < R_ * sq) & (s > 0)
        border = (bx > -2 * sq) & (bx < (C + 1) * sq) & (by > -2 * sq) & (by < (R_ + 1) * sq) & (s > 0)
        parity = (np.floor(bx / sq) + np.floor(by / sq)) % 2 == 0
        img = np.full(U.shape, 90.0)
        img[border] = 235.0
        img[inside & parity] = 20.0
    else:
        img = 90 + 40 * np.sin(U / 17.0) * np.cos(V / 23.0)
    img = img.reshape(H, ss, W, ss).mean(axis=(1, 3))
    img += rng.normal(0, a.noise, img.shape)
    imageio.imwrite(os.path.join(a.out, "view_%02d.png" % k), np.clip(img, 0, 255).astype(np.uint8))

#!/usr/bin/env python3
"""Damage real and synthetic vehicle labels, let segtrack recover them, and compare IoUs.

usage: segtrack_recovery.py --segtrack BIN --case camvid --data MVTM_DATA
       segtrack_recovery.py --segtrack BIN --case mkroad --mkroad BIN

For each k, the labels are damaged in two ways: the vehicle pixels of every k-th frame (frames
k-1, 2k-1, ... counting from 0) are relabelled as another class, and spurious vehicle blobs
(filled ellipses, 20..120 pixels) are added to a third of the frames, away from the real
vehicles. The table gives the IoU against the truth, pooled over all frames
(sum of intersections / sum of unions), of the damaged input and of segtrack's masks. The test
fails unless segtrack's masks beat the damaged input for every k.
  camvid: the truth is the real labels themselves (class 8, car), MVTM_DATA/camvid_0016E5_seg.
  mkroad: the truth is mkroad's ray-traced truth/masks (pass A), the labels its labels/ (car = 8).
Exit 77 (skipped) when the real data or a binary is missing.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

import imageio
import numpy as np

CAR, OTHER = 8, 11  # CamVid ids: car, unlabelled


def dilate(mask, r):
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def damage(labels, k, rng):
    out = []
    h, w = labels[0].shape
    yy, xx = np.mgrid[0:h, 0:w]
    for i, lab in enumerate(labels):
        d = lab.copy()
        if i % k == k - 1:
            d[d == CAR] = OTHER
        if rng.random() < 1 / 3:
            near = dilate(lab == CAR, 12)
            for _ in range(50):  # a place away from every real vehicle
                ry, rx = rng.uniform(2.5, 6.5, 2)
                cy, cx = rng.uniform(ry, h - ry), rng.uniform(rx, w - rx)
                blob = ((yy - cy) / ry) ** 2 + ((xx - cx) / rx) ** 2 <= 1
                if not (blob & near).any():
                    d[blob] = CAR
                    break
        out.append(d)
    return out


def iou(masks, truths):
    inter = sum(int((m & t).sum()) for m, t in zip(masks, truths))
    union = sum(int((m | t).sum()) for m, t in zip(masks, truths))
    return inter / union if union else 1.0


def run_segtrack(binary, names, labels, work, tag, extra):
    ldir, ws = os.path.join(work, tag, "labels"), os.path.join(work, tag, "ws")
    os.makedirs(ldir)
    for n, lab in zip(names, labels):
        imageio.imwrite(os.path.join(ldir, n), lab)
    subprocess.run([binary, "-q", *extra, ldir, ws], check=True)
    return [imageio.imread(os.path.join(ws, "masks", n)) > 0 for n in names]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--segtrack", required=True)
    ap.add_argument("--case", choices=["camvid", "mkroad"], required=True)
    ap.add_argument("--data", default=os.environ.get("MVTM_DATA", "/work/shared/data"))
    ap.add_argument("--mkroad")
    ap.add_argument("--ks", default="2,3,4,5,10")
    ap.add_argument("--seed", type=int, default=5)
    a = ap.parse_args()
    ks = [int(k) for k in a.ks.split(",")]
    work = tempfile.mkdtemp(prefix="segtrack-recovery-")
    try:
        if a.case == "camvid":
            src = os.path.join(a.data, "camvid_0016E5_seg", "labels")
            if not os.path.isdir(src):
                print(f"skipped: {src} not found (set MVTM_DATA)")
                return 77
            names = sorted(n for n in os.listdir(src) if n.endswith(".png"))
            labels = [imageio.imread(os.path.join(src, n)) for n in names]
            truths = [lab == CAR for lab in labels]
        else:
            if not a.mkroad or not os.path.exists(a.mkroad):
                print("skipped: no mkroad binary")
                return 77
            ws = os.path.join(work, "road")
            subprocess.run([a.mkroad, "-q", "--frames", "60", "--fullsize-frames", "0",
                            "--offpath-every", "0", ws], check=True)
            names = sorted(n for n in os.listdir(os.path.join(ws, "truth", "masks")) if n.endswith(".png"))
            labels = [imageio.imread(os.path.join(ws, "labels", n)) for n in names]
            truths = [imageio.imread(os.path.join(ws, "truth", "masks", n)) > 0 for n in names]
        rng = np.random.default_rng(a.seed)
        clean = run_segtrack(a.segtrack, names, labels, work, "clean", [])
        h, w = labels[0].shape
        print(f"{a.case}: {len(names)} frames of {w}x{h}; IoU against the truth, pooled over frames")
        print(f"{'damage':<42}{'input IoU':>10}{'segtrack IoU':>14}")
        print(f"{'none':<42}{iou([l == CAR for l in labels], truths):>10.4f}{iou(clean, truths):>14.4f}")
        failed = []
        for k in ks:
            dam = damage(labels, k, rng)
            rec = run_segtrack(a.segtrack, names, dam, work, f"k{k}", [])
            i_in, i_out = iou([d == CAR for d in dam], truths), iou(rec, truths)
            print(f"{'k=%d: every %s frame dropped + spurious' % (k, ordinal(k)):<42}"
                  f"{i_in:>10.4f}{i_out:>14.4f}{'' if i_out > i_in else '   FAIL'}")
            if not i_out > i_in:
                failed.append(k)
        if failed:
            print(f"recovery did not beat the damaged input for k = {failed}")
            return 1
        return 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


def ordinal(k):
    return {2: "2nd", 3: "3rd"}.get(k, f"{k}th")


if __name__ == "__main__":
    sys.exit(main())

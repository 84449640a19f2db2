#!/usr/bin/python3
"""Scores masks (WS/masks/NAME.png, non-zero = masked) against truth masks, per frame.

  score_masks.py --masks DIR --truth DIR [--camera CAMERAS_TXT --height 1.65 --near 30]
                 [--min-share 0.005]
                 [--labels DIR --classes 8,9,10] [--names A_] [--empty B_] [--json]

Truth: either a folder of masks (mkroad's truth/masks: 255 = vehicle) or, with --labels, label
images whose --classes are the truth (CamVid: 8 car, 9 pedestrian, 10 bicyclist). Nothing the
masks were made from reads them.
  * IoU per frame over the frames where the truth covers at least --min-share of the image
    (mean and median printed), and the pixel precision and recall over those frames.
  * --camera (a COLMAP cameras.txt, PINHOLE) and --height (the camera's height above a level
    road, mkroad's 1.65 m): a truth blob's distance is the ground-plane depth h·fy/(v − cy) of
    the row v just below it (where it stands on the road); recall of the pixels of blobs nearer
    than --near.
  * --empty PREFIX: frames whose names start with it have no vehicle (mkroad's pass B): the
    share of each such frame that is masked (max and mean).
Exit status 0; the numbers are for the caller (a CLI case, or the closing note).
"""
import argparse
import glob
import json
import os
import sys

import numpy as np
import imageio


def read_mask(path):
    a = np.asarray(imageio.imread(path))
    return (a.reshape(a.shape[0], a.shape[1], -1) != 0).any(axis=2)


def blob_distances(truth, fy, cy, height):
    """Per-pixel distance of each truth blob: the ground-plane depth of the row below it."""
    from scipy import ndimage
    lab, _ = ndimage.label(truth, structure=np.ones((3, 3)))
    dist = np.full(truth.shape, np.inf)
    for k, sl in enumerate(ndimage.find_objects(lab), start=1):
        v = sl[0].stop + 0.5  # centre of the row below the blob
        dist[lab == k] = height * fy / (v - cy) if v > cy else np.inf
    return dist


def read_camera(path, shape):
    """fy, cy of the first camera of a COLMAP cameras.txt, scaled to the mask's height."""
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        f = line.split()
        h, fy, cy = float(f[3]), float(f[5]), float(f[7])
        s = shape[0] / h
        return fy * s, cy * s
    sys.exit(f"{path}: no camera")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--masks", required=True)
    ap.add_argument("--truth", help="folder of truth masks")
    ap.add_argument("--labels", help="folder of label images (with --classes)")
    ap.add_argument("--classes", default="8,9,10")
    ap.add_argument("--camera", help="COLMAP cameras.txt (PINHOLE fx fy cx cy)")
    ap.add_argument("--height", type=float, default=1.65)
    ap.add_argument("--near", type=float, default=30)
    ap.add_argument("--min-share", type=float, default=0.005)
    ap.add_argument("--names", default="", help="only frames whose names start with this")
    ap.add_argument("--empty", help="frames with this name prefix have no vehicle")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    classes = [int(c) for c in a.classes.split(",")]
    names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(a.masks, "*.png")))
    ious, tp, fp, fn, near_hit, near_all, empty = [], 0, 0, 0, 0, 0, []
    for n in names:
        pred = read_mask(os.path.join(a.masks, n))
        if a.empty and n.startswith(a.empty):
            empty.append(pred.mean())
            continue
        if not n.startswith(a.names):
            continue
        if a.labels:
            lab = np.asarray(imageio.imread(os.path.join(a.labels, n)))
            truth = np.isin(lab, classes)
        else:
            p = os.path.join(a.truth, n)
            if not os.path.exists(p):
                continue
            truth = read_mask(p)
        if truth.shape != pred.shape:
            sys.exit(f"{n}: size {pred.shape} differs from the truth's {truth.shape}")
        if a.camera:
            fy, cy = read_camera(a.camera, truth.shape)
            dist = blob_distances(truth, fy, cy, a.height)
            near = truth & (dist < a.near)
            near_all += near.sum()
            near_hit += (near & pred).sum()
        if truth.mean() < a.min_share:
            continue
        inter, union = (truth & pred).sum(), (truth | pred).sum()
        ious.append(inter / union)
        tp += inter
        fp += (pred & ~truth).sum()
        fn += (truth & ~pred).sum()
    out = {
        "frames": len(ious),
        "mean_iou": float(np.mean(ious)) if ious else float("nan"),
        "median_iou": float(np.median(ious)) if ious else float("nan"),
        "precision": float(tp / max(1, tp + fp)),
        "recall": float(tp / max(1, tp + fn)),
    }
    if a.camera:
        out["near_recall"] = float(near_hit / max(1, near_all))
        out["near_pixels"] = int(near_all)
    if a.empty:
        out["empty_frames"] = len(empty)
        out["empty_max_share"] = float(max(empty)) if empty else 0.0
        out["empty_mean_share"] = float(np.mean(empty)) if empty else 0.0
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k}\t{v:.4f}" if isinstance(v, float) else f"{k}\t{v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Black pixels of renders where the real photo has none (issue 19's "no black, ever").

usage: black_pixels.py RENDERS [TRUTH] [--level 2]

A pixel is black when every channel is <= LEVEL (8-bit). Counted per frame are the render's black
pixels where the photo of the same name (TRUTH/NAME, same size) is not black; without TRUTH (a
lane change has no photo), every black pixel. Prints a TSV: frame,
black pixels, share of the frame; then mean and max rows. Exit 1 when a pair is missing or differs
in size.
"""
import argparse
import os
import sys

import numpy as np
from skimage import io


def black(img, level):
    a = np.asarray(img)
    if a.ndim == 2:
        return a <= level
    return np.all(a[..., :3] <= level, axis=-1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("renders")
    ap.add_argument("truth", nargs="?")
    ap.add_argument("--level", type=int, default=2)
    a = ap.parse_args()
    names = sorted(n for n in os.listdir(a.renders) if n.lower().endswith((".png", ".jpg", ".exr")))
    if not names:
        print(f"black_pixels.py: error: {a.renders}: no images", file=sys.stderr)
        return 1
    counts = []
    print("frame\tblack\tshare")
    for n in names:
        r = io.imread(os.path.join(a.renders, n))
        bad = black(r, a.level)
        if a.truth:
            t = os.path.join(a.truth, n)
            if not os.path.exists(t):
                print(f"black_pixels.py: error: {t}: missing (pairs are matched by name)",
                      file=sys.stderr)
                return 1
            p = io.imread(t)
            if r.shape[:2] != p.shape[:2]:
                print(f"black_pixels.py: error: {t}: size differs from the render", file=sys.stderr)
                return 1
            bad &= ~black(p, a.level)
        c = int(np.count_nonzero(bad))
        counts.append(c)
        print(f"{n}\t{c}\t{c / (r.shape[0] * r.shape[1]):.6f}")
    print(f"mean\t{np.mean(counts):.1f}\t")
    print(f"max\t{max(counts)}\t")
    return 0


if __name__ == "__main__":
    sys.exit(main())

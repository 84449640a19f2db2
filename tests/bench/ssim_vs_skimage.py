#!/usr/bin/python3
"""Speed of mean SSIM in one run: mvtm vs the OpenCV Gaussian-blur recipe vs scikit-image.

  ssim_vs_skimage.py --bench BUILD/bench/bench_ssim [--data DIR] [--repetitions N]

Runs bench_ssim (Google Benchmark: mvtm::Ssim with all cores and with one thread, the OpenCV
tutorial recipe) and then times skimage.metrics.structural_similarity(gaussian_weights=True,
sigma=1.5, use_sample_covariance=False, data_range=255) on the same pairs (KITTI 01 frames 0/1,
1241x376 grey; CamVid 07959/07961, 480x360 colour; seeded random images of those sizes when
$MVTM_DATA is missing). Tables: wall-clock time, best of the repetitions (least disturbed by
other processes on a shared machine) and median, each with the ratios; then the CPU time of
single-threaded runs (mvtm and OpenCV on one thread, scikit-image), which other load on the
machine disturbs much less.
"""
import argparse
import csv
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np
from skimage import io
from skimage.metrics import structural_similarity

PAIRS = {
    0: ("kitti_odom01_f000-050/image_0/000000.png", "kitti_odom01_f000-050/image_0/000001.png",
        (376, 1241)),
    1: ("camvid_0016E5_seg/images/0016E5_07959.png", "camvid_0016E5_seg/images/0016E5_07961.png",
        (360, 480, 3)),
}


def load(data, colour):
    fa, fb, shape = PAIRS[colour]
    pa, pb = os.path.join(data, fa), os.path.join(data, fb)
    if os.path.exists(pa) and os.path.exists(pb):
        return io.imread(pa), io.imread(pb), "real"
    rng = np.random.default_rng(1)
    return (rng.integers(0, 256, shape, dtype=np.uint8),
            rng.integers(0, 256, shape, dtype=np.uint8), "random")


def time_skimage(a, b, colour, reps):
    """(wall, cpu) milliseconds per call, one entry per repetition."""
    wall, cpu = [], []
    for _ in range(reps):
        t, c = time.perf_counter(), time.process_time()
        structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
                              use_sample_covariance=False, data_range=255,
                              channel_axis=-1 if colour else None)
        cpu.append((time.process_time() - c) * 1e3)
        wall.append((time.perf_counter() - t) * 1e3)
    return wall, cpu


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bench", required=True, help="the bench_ssim executable")
    ap.add_argument("--data", default=os.environ.get("MVTM_DATA", "../shared/data"))
    ap.add_argument("--repetitions", type=int, default=9)
    ap.add_argument("--min-time", default="0.2", help="--benchmark_min_time per repetition")
    args = ap.parse_args()

    env = dict(os.environ, MVTM_DATA=args.data)
    out = subprocess.run(
        [args.bench, "--benchmark_format=json", f"--benchmark_min_time={args.min_time}",
         f"--benchmark_repetitions={args.repetitions}",
         "--benchmark_filter=MvtmSsim/colour:./threads:./simd:0|OpenCvRecipe"],
        env=env, capture_output=True, text=True, check=True).stdout
    wall, cpu = {}, {}  # benchmark name -> milliseconds per iteration, one per repetition
    for b in json.loads(out)["benchmarks"]:
        if b.get("run_type") == "iteration":
            name = b["run_name"].replace("/real_time", "")
            scale = {"ms": 1.0, "us": 1e-3, "ns": 1e-6}[b["time_unit"]]
            wall.setdefault(name, []).append(b["real_time"] * scale)
            cpu.setdefault(name, []).append(b["cpu_time"] * scale)
    rows = []
    for colour in (0, 1):
        a, b, kind = load(args.data, colour)
        label = f"{a.shape[1]}x{a.shape[0]} {'colour' if colour else 'grey'} ({kind})"
        ours, ours1 = (f"BM_MvtmSsim/colour:{colour}/threads:{t}/simd:0" for t in (0, 1))
        cv, cv1 = (f"BM_OpenCvRecipe/colour:{colour}/threads:{t}" for t in (0, 1))
        sk_wall, sk_cpu = time_skimage(a, b, colour, args.repetitions)
        rows.append((label, wall[ours], wall[ours1], wall[cv], sk_wall,
                     cpu[ours1], cpu[cv1], sk_cpu))
    header = (f"  {'pair':<30} {'mvtm':>7} {'mvtm 1T':>8} {'OpenCV':>7} {'skimage':>8} "
              f"{'skimage/mvtm':>13} {'OpenCV/mvtm':>12}")
    for title, stat in (("best of", min), ("median of", statistics.median)):
        print(f"wall-clock, {title} {args.repetitions} repetitions, ms per image pair "
              f"({os.cpu_count()} cores; mvtm and OpenCV use all of them, 1T = one thread):")
        print(header)
        for label, o, o1, c, k, *_ in rows:
            o, o1, c, k = stat(o), stat(o1), stat(c), stat(k)
            print(f"  {label:<30} {o:7.2f} {o1:8.2f} {c:7.2f} {k:8.2f} {k / o:12.1f}x "
                  f"{c / o:11.1f}x")
    print(f"CPU time of one thread, best of {args.repetitions} (mvtm and OpenCV limited to one "
          f"thread; scikit-image is single-threaded):")
    print(f"  {'pair':<30} {'mvtm 1T':>8} {'OpenCV 1T':>10} {'skimage':>8} "
          f"{'skimage/mvtm':>13} {'OpenCV/mvtm':>12}")
    for label, *_, o1, c1, k in rows:
        o1, c1, k = min(o1), min(c1), min(k)
        print(f"  {label:<30} {o1:8.2f} {c1:10.2f} {k:8.2f} {k / o1:12.1f}x {c1 / o1:11.1f}x")
    report = os.environ.get("MVTM_BENCH_CSV")
    if report:  # rows of the benchmark report (examples/bench_report.py)
        with open(report, "a", newline="") as f:
            w = csv.writer(f)
            for label, o, _, c, k, *_ in rows:
                for stat, name in ((min, "best"), (statistics.median, "median")):
                    for anchor, t in (("scikit-image", k), ("OpenCV recipe", c)):
                        w.writerow(["ssim", f"mean SSIM {label}, in process ({name} wall)",
                                    f"{stat(o):.6g}", "ms", anchor, f"{stat(t):.6g}"])
    return 0


if __name__ == "__main__":
    sys.exit(main())

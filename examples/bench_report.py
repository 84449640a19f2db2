#!/usr/bin/python3
"""One benchmark report: every figure against its anchor measured in the same run.

  bench_report.py [--bin BUILD] [--out DIR] [--data DIR] [--short]

Runs every benchmark of mvtm (BUILD/bench/bench_*, tests/bench/ssim_vs_skimage.py) with
$MVTM_BENCH_CSV set, so each appends its rows (bench, figure, value, unit, anchor, anchor value),
and measures whole processes itself:
  * start-up: every program's --version against /bin/true (median of N runs);
  * ssim on one 1241x376 pair, whole process, against scikit-image in a fresh Python;
  * ssim on a folder of 20 pairs, whole process, against scikit-image over the same 20 pairs.
Writes DIR/bench.csv and DIR/bench.md (the README's performance table) and prints the table.
Ratios are anchor / mvtm for times (above 1: mvtm is faster) and mvtm / anchor for rates (fps).
The machine is shared and noisy: only ratios within one run mean anything.
"""
import argparse
import csv
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

TOOLS = ["orb2colmap", "segtrack", "pickview", "bakedepth", "inpaint3d", "ptmrender", "ssim",
         "roadmesh", "densify", "drive", "gazemap", "exposure", "mkroad"]
RATES = {"fps", "frames/s"}
KITTI = "kitti_odom01_f000-050/image_0"

SKIMAGE_PAIRS = r"""
import sys
from skimage import io
from skimage.metrics import structural_similarity
pairs = sys.argv[1:]
for a, b in zip(pairs[0::2], pairs[1::2]):
    x, y = io.imread(a), io.imread(b)
    s = structural_similarity(x, y, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                              data_range=255, channel_axis=-1 if x.ndim == 3 else None)
    print(a, s)
"""


def whole_process_ms(cmd, runs):
    """Median and best wall-clock milliseconds of `runs` runs of cmd (output discarded)."""
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append((time.perf_counter() - t) * 1e3)
    return statistics.median(times), min(times)


def add(rows, bench, figure, value, unit, anchor, anchor_value):
    rows.append([bench, figure, f"{value:.6g}", unit, anchor, f"{anchor_value:.6g}"])


def measure_processes(args, rows):
    runs = 5 if args.short else 30
    true_med, _ = whole_process_ms(["/bin/true"], runs)
    for tool in TOOLS:
        exe = os.path.join(args.bin, "bin", tool)
        if not os.path.exists(exe):
            continue
        med, _ = whole_process_ms([exe, "--version"], runs)
        add(rows, "start-up", f"{tool} --version (median of {runs})", med, "ms", "/bin/true",
            true_med)
    ssim = os.path.join(args.bin, "bin", "ssim")
    frames = os.path.join(args.data, KITTI)
    if not os.path.isdir(frames):
        print(f"bench_report: {frames} missing: whole-process ssim rows skipped", file=sys.stderr)
        return
    a, b = os.path.join(frames, "000000.png"), os.path.join(frames, "000001.png")
    sk = [sys.executable, "-c", SKIMAGE_PAIRS]
    pair_runs = 3 if args.short else 10
    med, _ = whole_process_ms([ssim, a, b], pair_runs)
    sk_med, _ = whole_process_ms(sk + [a, b], pair_runs)
    add(rows, "ssim", "one 1241x376 pair, whole process", med, "ms",
        "scikit-image, whole process", sk_med)
    # A folder of 20 pairs: frames 0..19 against 1..20 under the same names.
    tmp = tempfile.mkdtemp(prefix="mvtm_bench_")
    try:
        da, db = os.path.join(tmp, "a"), os.path.join(tmp, "b")
        os.makedirs(da)
        os.makedirs(db)
        pairs = []
        for i in range(20):
            name = f"{i:06d}.png"
            os.symlink(os.path.join(frames, name), os.path.join(da, name))
            os.symlink(os.path.join(frames, f"{i + 1:06d}.png"), os.path.join(db, name))
            pairs += [os.path.join(da, name), os.path.join(db, name)]
        folder_runs = 2 if args.short else 5
        med, _ = whole_process_ms([ssim, da, db], folder_runs)
        sk_med, _ = whole_process_ms(sk + pairs, folder_runs)
        add(rows, "ssim", "folder of 20 1241x376 pairs, whole process", med, "ms",
            "scikit-image, whole process", sk_med)
    finally:
        shutil.rmtree(tmp)


def run_benches(args, csv_path):
    bench = os.path.join(args.bin, "bench")
    env = dict(os.environ, MVTM_BENCH_CSV=csv_path, MVTM_DATA=args.data,
               MESA_SHADER_CACHE_DISABLE="true")
    here = os.path.dirname(os.path.abspath(__file__))
    short = ["--short"] if args.short else []
    commands = [
        [sys.executable, os.path.join(here, "..", "tests", "bench", "ssim_vs_skimage.py"),
         "--bench", os.path.join(bench, "bench_ssim"), "--data", args.data,
         "--repetitions", "3" if args.short else "9", "--min-time", "0.05" if args.short else "0.2"],
        [os.path.join(bench, "bench_orb2colmap")] + short,
        [os.path.join(bench, "bench_pickview")] + short,
        [os.path.join(bench, "bench_segtrack")] + short,
        [os.path.join(bench, "bench_render")] + (short if args.short else ["--frames", "10"]),
        [os.path.join(bench, "bench_planesweep")] + short,
        [os.path.join(bench, "bench_ledger")] + short,
    ]
    for cmd in commands:
        print("+", " ".join(cmd), flush=True)
        subprocess.run(cmd, env=env, check=True)


def ratio(row):
    value, unit, anchor, anchor_value = float(row[2]), row[3], row[4], float(row[5])
    if not anchor or value <= 0 or anchor_value <= 0:
        return ""
    return f"{(value / anchor_value if unit in RATES else anchor_value / value):.3g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default="build", help="the build folder (bin/ and bench/ in it)")
    ap.add_argument("--out", default="out/bench")
    ap.add_argument("--data", default=os.environ.get("MVTM_DATA", "../shared/data"))
    ap.add_argument("--short", action="store_true", help="few repetitions (CI)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    raw = os.path.join(args.out, "bench_rows.csv")
    open(raw, "w").close()
    rows = []
    measure_processes(args, rows)
    run_benches(args, raw)
    with open(raw) as f:
        rows += [r for r in csv.reader(f) if r]
    header = ["bench", "figure", "mvtm", "unit", "anchor", "anchor value", "ratio"]
    table = [r + [ratio(r)] for r in rows]
    with open(os.path.join(args.out, "bench.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(table)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in table:
        lines.append("| " + " | ".join(x if x else "–" for x in r) + " |")
    md = "\n".join(lines) + "\n"
    with open(os.path.join(args.out, "bench.md"), "w") as f:
        f.write(f"Benchmark report ({os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}); ratio: "
                "anchor ÷ mvtm for times, mvtm ÷ anchor for rates (above 1: mvtm is faster).\n\n")
        f.write(md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())

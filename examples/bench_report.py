#!/usr/bin/python3
"""One benchmark report: every figure against its anchor measured in the same run.

  bench_report.py [--bin BUILD] [--out DIR] [--data DIR] [--short]

Runs every benchmark of mvtm (BUILD/bench/bench_*, tests/bench/ssim_vs_skimage.py) with
$MVTM_BENCH_CSV set, so each appends its rows (bench, figure, value, unit, anchor, anchor value),
and measures whole processes itself:
  * start-up: every program's --version against /bin/true (median of N runs);
  * ssim on one 1241x376 pair, whole process, against scikit-image in a fresh Python;
  * ssim on a folder of 20 pairs, whole process, against scikit-image over the same 20 pairs;
  * simulate on mkroad --full (255k triangles, baked depth): frames per second unadapted at
    640x360 and 1241x376 and at the lowest quality level, against ptmrender rendering the same
    poses in the same run; adaptive quality in real time with a window (SDL's offscreen driver),
    sustained over the last 20 s of a 30 s drive, against the 30 fps target; and the latency
    from an input (a step of SDL's virtual wheel) to the first frame showing it, in frames.
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


def simulate_fps(cmd, env):
    """(fps over the whole run, sustained fps over its last 20 s) of a simulate run with
    --record sim (poses.tsv's display times)."""
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    rows = [l.split() for l in open(os.path.join(env["PWD"], "sim", "poses.tsv"))
            if not l.startswith("#")]
    shown = [float(r[8]) for r in rows]
    span = shown[-1] - shown[0]
    window = min(20.0, span)
    late = sum(1 for t in shown if t > shown[-1] - window)
    return (len(shown) - 1) / span if span > 0 else 0.0, late / window if window > 0 else 0.0


def measure_simulate(args, rows):
    """simulate's frame rates and latency on mkroad --full (--short: a 640x192 road)."""
    b = os.path.abspath(os.path.join(args.bin, "bin"))
    work = tempfile.mkdtemp(prefix="mvtm-bench-sim-")
    env = dict(os.environ, MESA_SHADER_CACHE_DISABLE="true", PWD=work, SDL_VIDEODRIVER="offscreen")
    env.pop("DISPLAY", None)
    # --short (CI: keeps the report working): a small road and seconds-long drives.
    road = ["--frames", "12", "--size", "320x96"] if args.short else ["--full"]
    run = lambda cmd: subprocess.run(cmd, cwd=work, env=env, check=True,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    run([os.path.join(b, "mkroad"), "-q", "--vehicles", "0", "--offpath-every", "0"] + road + ["ws"])
    run([os.path.join(b, "bakedepth"), "-q", "ws"])
    seconds = 2 if args.short else 11.5
    with open(os.path.join(work, "log.tsv"), "w") as f:
        f.write(f"time steer speed\n0 0 8\n{seconds} 0 8\n")
    sim = [os.path.join(b, "simulate"), "-q", "--metric", "--replay", "log.tsv", "--record", "sim"]
    sim_env = dict(env)
    for size, extra, figure in [("640x360", [], "640x360 unadapted (full quality)"),
                                ("1241x376", [], "1241x376 unadapted (full quality)"),
                                ("640x360", ["--quality", "7"], "640x360 lowest level (7)")]:
        cmd = sim + ["--as-fast", "--fps", "30", "--no-window", "--no-adapt", "--size", size] + \
            extra + ["ws"]
        t = time.perf_counter()
        run(cmd)
        sim_s = time.perf_counter() - t
        n = sum(1 for l in open(os.path.join(work, "sim", "poses.tsv")) if not l.startswith("#"))
        ptm = [os.path.join(b, "ptmrender"), "-q", "--force", "--poses", "sim/poses.tum",
               "--size", size, "ws", "ptm"]
        t = time.perf_counter()
        run(ptm)
        ptm_s = time.perf_counter() - t
        add(rows, "simulate", figure + ", whole process", n / sim_s, "fps",
            "ptmrender at the same poses, whole process", n / ptm_s)
    # Adaptive, real time, with a window: 30 s around the road (looping at its end).
    with open(os.path.join(work, "long.tsv"), "w") as f:
        f.write(f"time steer speed\n0 0 6\n{3 if args.short else 30} 0 6\n")
    _, sustained = simulate_fps([os.path.join(b, "simulate"), "-q", "--metric", "--replay",
                                 os.path.join(work, "long.tsv"), "--size", "640x360", "--at-end",
                                 "loop", "--record", os.path.join(work, "sim"),
                                 os.path.join(work, "ws")], sim_env)
    add(rows, "simulate", "640x360 adaptive, real time, window: sustained fps (last 20 s of 30)",
        sustained, "fps", "the target (--fps 30)", 30.0)
    # Latency: the wheel turned at t = turn s; frames from the first at or after it to the first
    # whose heading shows the turn.
    turn = 1 if args.short else 2
    with open(os.path.join(work, "wheel.tsv"), "w") as f:
        f.write(f"time a0 a1 a2\n0 0 16000 0\n{turn} -20000 16000 0\n")
    subprocess.run([os.path.join(b, "simulate"), "-q", "--metric", "--virtual-input",
                    os.path.join(work, "wheel.tsv"), "--duration", str(turn + 1), "--no-window",
                    "--size", "640x360", "--record", os.path.join(work, "lat"),
                    os.path.join(work, "ws")],
                   env=env, check=True)
    poses = [[float(x) for x in l.split()] for l in open(os.path.join(work, "lat", "poses.tsv"))
             if not l.startswith("#")]
    first_after = next(i for i, p in enumerate(poses) if p[0] >= turn)

    def axes(p):  # the camera's forward and up axes in the world, from its quaternion
        x, y, z, w = p[4:8]
        fwd = (2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y))
        down = (2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x))
        return fwd, tuple(-c for c in down)

    f0, up0 = axes(poses[first_after - 1])

    def yawed(p):  # turned about the up axis (pitch and roll over the ground do not count)
        f1, _ = axes(p)
        cross = (f0[1] * f1[2] - f0[2] * f1[1], f0[2] * f1[0] - f0[0] * f1[2],
                 f0[0] * f1[1] - f0[1] * f1[0])
        return abs(sum(a * b for a, b in zip(cross, up0))) > 1e-4

    turned = next(i for i in range(first_after, len(poses)) if yawed(poses[i]))
    add(rows, "simulate", "input to display (virtual wheel step), frames after the input's time",
        max(0, turned - first_after), "frames", "", 0)
    shutil.rmtree(work)


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
    ap.add_argument("--only", choices=["simulate"], help="only this part of the report")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    raw = os.path.join(args.out, "bench_rows.csv")
    open(raw, "w").close()
    rows = []
    if args.only != "simulate":
        measure_processes(args, rows)
        run_benches(args, raw)
    measure_simulate(args, rows)
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

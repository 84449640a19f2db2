#!/usr/bin/env bash
# The main job on the embedded synthetic road (what the README's first command runs).
#
#   examples/main-job.sh [OUTDIR]        (default: out/main-job; tools from build/bin)
#
# 1. mkroad writes a synthetic road workspace (two drives, vehicles in pass A) with ray-traced
#    ground truth, and noisy SLAM-like keyframes (every 5th pose) of both passes.
# 2. orb2colmap turns the keyframes of each pass into a COLMAP model of every frame.
# 3. ssim scores: the recorded frames of pass A (with vehicles) against the vehicle-free truth —
#    the photo-consistency table vehicle removal has to improve on.
# Every step skips outputs that are already up to date, so a re-run is quick.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
out=${1:-$top/out/main-job}
ws=$out/road
mkdir -p "$out"

echo "== 1. mkroad: synthetic road and ray-traced truth -> $ws" >&2
[ -f "$ws/truth/mkroad.txt" ] || "$bin/mkroad" --keyframe-noise 0.02 "$ws"

echo "== 2. orb2colmap: keyframes -> COLMAP model of every frame" >&2
cam=$(grep -v '^#' "$ws/sparse/cameras.txt" | head -1 | cut -d' ' -f2-)
for pass in A B; do
  kf=$ws/truth/keyframes.txt
  [ $pass = B ] && kf=$ws/truth/keyframes_B.txt
  "$bin/orb2colmap" --camera "$cam" --frames "$ws/truth/frames_$pass.txt" "$kf" "$out/slam_$pass"
done

echo "== 3. ssim: recorded frames of pass A vs the vehicle-free truth" >&2
mkdir -p "$out/pass_A" "$out/truth_A"
for f in "$ws"/images/A_*.png; do
  n=$(basename "$f")
  ln -sf "$f" "$out/pass_A/$n"
  ln -sf "$ws/truth/background/$n" "$out/truth_A/$n"
done
"$bin/ssim" "$out/pass_A" "$out/truth_A" | tee "$out/ssim_pass_A.tsv"

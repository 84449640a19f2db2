#!/usr/bin/env bash
# The main job on the embedded synthetic road (what the README's first command runs).
#
#   examples/main-job.sh [OUTDIR]        (default: out/main-job; tools from build/bin)
#
# 1. mkroad     a synthetic road workspace (two drives, vehicles in drive A) with ray-traced truth
#               and noisy SLAM-like keyframes (every 5th pose, 2 cm noise)
# 2. orb2colmap the keyframes of each drive → a COLMAP model of every frame
# 3. bakedepth  one depth map per image, for the occlusion test
# 4. masks      vehicle masks — the fixture's exact masks stand in for segtrack (not yet written)
# 5. ptmrender  every recorded pose rendered from the *other* images (held out), with vertex
#               colours and with projective texture mapping; and the drives 1.5 m to the left
# 6. ssim       the photo-consistency table of the held-out renders against the truth
# Every step skips outputs that are up to date, so a re-run is quick.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
out=${1:-$top/out/main-job}
ws=$out/road
mkdir -p "$out"
export MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-true}

echo "== 1. mkroad: synthetic road and ray-traced truth -> $ws" >&2
[ -f "$ws/truth/mkroad.txt" ] || "$bin/mkroad" --keyframe-noise 0.02 "$ws"

echo "== 2. orb2colmap: noisy keyframes -> COLMAP model of every frame" >&2
cam=$(grep -v '^#' "$ws/sparse/cameras.txt" | head -1 | cut -d' ' -f2-)
"$bin/orb2colmap" --camera "$cam" --frames "$ws/truth/frames_A.txt" "$ws/truth/keyframes.txt" "$out/slam_A"
"$bin/orb2colmap" --camera "$cam" --frames "$ws/truth/frames_B.txt" "$ws/truth/keyframes_B.txt" "$out/slam_B"

echo "== 3. bakedepth" >&2
"$bin/bakedepth" "$ws"

echo "== 4. vehicle masks (the fixture's truth, standing in for segtrack)" >&2
mkdir -p "$ws/masks"
for m in "$ws"/truth/masks/*.png; do [ -f "$ws/masks/$(basename "$m")" ] || cp "$m" "$ws/masks/"; done

echo "== 5. ptmrender: held-out poses (vertex colours, PTM) and a 1.5 m lane change" >&2
"$bin/ptmrender" --mode vertex "$ws" "$out/heldout_vertex"
"$bin/ptmrender" --explain --at-images --exclude-self "$ws" "$out/heldout_ptm" > "$out/plan.json"
"$bin/ptmrender" --at-images --exclude-self --provenance "$ws" "$out/heldout_ptm"
"$bin/ptmrender" --lateral 1.5 "$ws" "$out/lane_left"

echo "== 6. ssim: held-out renders against the ray-traced truth (no vehicles)" >&2
"$bin/ssim" "$out/heldout_vertex" "$ws/truth/background" > "$out/ssim_vertex.tsv"
"$bin/ssim" "$out/heldout_ptm" "$ws/truth/background" > "$out/ssim_ptm.tsv"
mean() { awk -F'\t' -v c="$2" '$1 == "mean" { print $c }' "$1"; }
minv() { awk -F'\t' -v c="$2" '$1 == "min" { print $c }' "$1"; }
printf '\nphoto-consistency of held-out poses (%s frames) against the ray-traced truth\n' \
  "$(grep -c '^[AB]_' "$out/ssim_ptm.tsv")"
printf '%-22s %10s %10s %10s\n' method "mean SSIM" "min SSIM" "mean PSNR"
printf '%-22s %10s %10s %10s\n' "vertex colours" "$(mean "$out/ssim_vertex.tsv" 2)" "$(minv "$out/ssim_vertex.tsv" 2)" "$(mean "$out/ssim_vertex.tsv" 4)"
printf '%-22s %10s %10s %10s\n' "PTM (mvtm)" "$(mean "$out/ssim_ptm.tsv" 2)" "$(minv "$out/ssim_ptm.tsv" 2)" "$(mean "$out/ssim_ptm.tsv" 4)"
printf '\nlane change: %s frames in %s; effects plan in %s\n' "$(ls "$out/lane_left" | grep -c png)" "$out/lane_left" "$out/plan.json"

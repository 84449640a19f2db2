#!/usr/bin/env bash
# The main job on the embedded synthetic road (what the README's first command runs).
#
#   examples/main-job.sh [OUTDIR]        (default: out/main-job; tools from build/bin)
#
# 1. mkroad     a synthetic road workspace (two drives, vehicles in drive A) with ray-traced truth
#               and noisy SLAM-like keyframes (every 5th pose, 2 cm noise)
# 2. orb2colmap the keyframes of each drive → a COLMAP model of every frame
# 3. segtrack   vehicle masks from the semantic labels (CamVid ids, 8 = car)
# 4. pickview   partner images of the other drive; bakedepth: depth maps
# 5. ptmrender  every recorded pose rendered from the *other* images (held out): vertex colours,
#               PTM with the vehicles projected, PTM with masks; then inpaint3d removes the
#               vehicles from the photographs and PTM renders again; and a 1.5 m lane change
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

echo "== 3. segtrack: vehicle masks from the labels" >&2
[ -f "$ws/tracks.tsv" ] || "$bin/segtrack" --classes 8 --dilate 1 "$ws/labels" "$ws"

echo "== 4. pickview partners, bakedepth" >&2
[ -f "$ws/partners.tsv" ] || "$bin/pickview" --partners "$ws" > /dev/null
"$bin/bakedepth" "$ws"

echo "== 5. ptmrender held-out poses; inpaint3d; ptmrender again; a 1.5 m lane change" >&2
"$bin/ptmrender" --mode vertex "$ws" "$out/heldout_vertex"
[ -d "$ws/textures" ] || "$bin/ptmrender" --at-images --exclude-self --no-masks "$ws" "$out/heldout_ptm_vehicles"
[ -d "$ws/textures" ] || "$bin/ptmrender" --at-images --exclude-self "$ws" "$out/heldout_ptm_masks"
"$bin/inpaint3d" "$ws"
"$bin/ptmrender" --explain --at-images --exclude-self "$ws" "$out/heldout_ptm" > "$out/plan.json"
"$bin/ptmrender" --at-images --exclude-self --provenance "$ws" "$out/heldout_ptm"
"$bin/ptmrender" --lateral 1.5 "$ws" "$out/lane_left"

echo "== 6. ssim: held-out renders against the ray-traced truth (no vehicles)" >&2
for r in vertex ptm_vehicles ptm_masks ptm; do
  "$bin/ssim" "$out/heldout_$r" "$ws/truth/background" > "$out/ssim_$r.tsv"
done
mean() { awk -F'\t' -v c="$2" '$1 == "mean" { print $c }' "$1"; }
minv() { awk -F'\t' -v c="$2" '$1 == "min" { print $c }' "$1"; }
printf '\nphoto-consistency of held-out poses (%s frames) against the ray-traced truth\n' \
  "$(grep -c '^[AB]_' "$out/ssim_ptm.tsv")"
printf '%-34s %10s %10s %10s\n' method "mean SSIM" "min SSIM" "mean PSNR"
row() { printf '%-34s %10s %10s %10s\n' "$1" "$(mean "$2" 2)" "$(minv "$2" 2)" "$(mean "$2" 4)"; }
row "vertex colours" "$out/ssim_vertex.tsv"
row "PTM, vehicles projected" "$out/ssim_ptm_vehicles.tsv"
row "PTM, segtrack masks" "$out/ssim_ptm_masks.tsv"
row "PTM, masks + inpaint3d textures" "$out/ssim_ptm.tsv"
printf '\nlane change: %s frames in %s; effects plan in %s\n' "$(ls "$out/lane_left" | grep -c png)" "$out/lane_left" "$out/plan.json"

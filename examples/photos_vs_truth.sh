#!/usr/bin/env bash
# One KITTI clip built twice by examples/road-build.sh, every 4th frame held out strictly: with
# its ground-truth poses, and from its photos alone (POSES -, calib given, CAMERA_HEIGHT=1.65);
# prints the photos-only trajectory's error against the truth (georef --compare) and both
# builds' held-out SSIM side by side, and the right camera's (image_1, 0.537 m right of each left
# pose) when the clip has one.
#
# usage: examples/photos_vs_truth.sh KITTI_CLIP OUT     (environment: MVTM_BIN as road-build.sh)
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
clip=$1; out=$2
mkdir -p "$out"
export HOLDOUT=4 HOLDOUT_STRICT=1
"$top/examples/road-build.sh" "$clip/image_0" "$clip/poses.txt" "$out/truth" -- --kitti-calib "$clip/calib.txt" > "$out/truth.log" 2>&1
CAMERA_HEIGHT=1.65 "$top/examples/road-build.sh" "$clip/image_0" - "$out/photos" -- --kitti-calib "$clip/calib.txt" > "$out/photos.log" 2>&1
"$bin/georef" -q --force --camera-height 1.65 --compare "$clip/poses.txt" "$out/photos/ws/sparse" "$out/photos/compare" > "$out/compare.txt"
mean() { awk -F'\t' '$1 == "mean" { print $2 }' "$1"; }
echo "$(basename "$clip"): photos-only trajectory: $(cut -f2- "$out/compare.txt")"
printf "%-22s %10s %10s\n" "held-out SSIM (every 4th)" "truth poses" "photos only"
for r in vertex ptm strict_vertex strict_ptm; do
  printf "%-22s %10.4f %10.4f\n" "$r" "$(mean "$out/truth/ssim_$r.tsv")" "$(mean "$out/photos/ssim_$r.tsv")"
done
if [ -d "$clip/image_1" ]; then
  for b in truth photos; do
    "$bin/ptmrender" -q --force --at-images --lateral -0.537 "$out/$b/ws" "$out/$b/right"
    "$bin/ssim" "$out/$b/right" "$clip/image_1" > "$out/$b/right.tsv"
  done
  printf "%-22s %10.4f %10.4f\n" "right camera" "$(mean "$out/truth/right.tsv")" "$(mean "$out/photos/right.tsv")"
fi

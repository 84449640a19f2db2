#!/usr/bin/env bash
# Issue 19's mkroad off-path table on the mesh the road build makes from the photos: mkroad's
# 640x192 road (12 frames a drive, no vehicles, off-path truth at every frame), its photos and
# truth poses through road-build.sh (METRIC=1), then ptmrender at the off-path truth poses (1.5 m
# lane changes, 15 degree turns) scored with ssim against the ray-traced truth; once with the sky
# at infinity (--sky-distance 0) and once at the scene's far end (the default).
#
# usage: examples/offpath_table.sh SEED OUT   (the build in OUT/dynamic1, or OUT/dynamic0)
# environment: MVTM_BIN (default build/bin), DYNAMIC (passed to road-build.sh; default 1)
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
[ $# -eq 2 ] || { echo "usage: $0 SEED OUT" >&2; exit 2; }
seed=$1; out=$2/dynamic${DYNAMIC:-1}
mkdir -p "$out"; out=$(cd "$out" && pwd)
[ -d "$out/M" ] || "$bin/mkroad" -q --seed "$seed" --frames 12 --size 640x192 --vehicles 0 --offpath-every 1 "$out/M"
[ -f "$out/rb/ws/mesh.ply" ] ||
  MVTM_BIN=$bin METRIC=1 DYNAMIC=${DYNAMIC:-1} "$top/examples/road-build.sh" "$out/M/images" "$out/M/sparse" "$out/rb" > "$out/rb.log" 2>&1
printf '%-22s %10s %10s %10s %10s\n' "seed $seed" lane_left lane_right yaw_left yaw_right
for sky in 0 -1; do
  row=()
  for v in lane_left lane_right yaw_left yaw_right; do
    "$bin/ptmrender" -q --force --sky-distance "$sky" --poses "$out/M/truth/offpath/$v/sparse/images.txt" "$out/rb/ws" "$out/sky$sky/$v"
    row+=("$("$bin/ssim" "$out/sky$sky/$v" "$out/M/truth/offpath/$v/images" | awk '$1 == "mean" { print $2 }')")
  done
  label=$([ "$sky" = 0 ] && echo "sky at infinity" || echo "sky at the far end")
  printf '%-22s %10.4f %10.4f %10.4f %10.4f\n' "$label" "${row[@]}"
done

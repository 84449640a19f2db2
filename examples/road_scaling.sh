#!/usr/bin/env bash
# Roads of 0.5..8 km (mkroad --length, the default density of frames and points, timed): roadsplit,
# then ptmrender streaming each road, bakedepth on each fragment in turn, densify on fragment
# A/001 (the same stretch of the same seeded layout on every road), and ptmrender on the whole
# workspace for contrast; whole processes timed by /usr/bin/time -v. Writes OUT/scaling.tsv (README, "Roads of
# kilometres"). About 45 minutes on 2 cores, most of it the fixtures and the 8 km one-workspace
# render. usage: road_scaling.sh OUT [LENGTHS...]   (MVTM_BIN: the tools, default build/bin)
set -euo pipefail
out=$1; shift
lengths=${*:-500 1000 2000 4000 8000}
B=${MVTM_BIN:-build/bin}
export MESA_SHADER_CACHE_DISABLE=true
mkdir -p "$out"
tsv=$out/scaling.tsv
printf 'length_m\tmkroad_s\tmkroad_peak_MB\tfragments\tframes\tptm_wall_s\tptm_ms_per_frame\tptm_peak_MB\tbake_wall_s\tbake_ms_per_image\tbake_peak_MB\tws_ptm_wall_s\tws_ptm_peak_MB\tdensify_s_per_image\tdensify_peak_MB\n' > "$tsv"
wall() { awk '/Elapsed \(wall/ {n = split($NF, t, ":"); print (n == 3 ? t[1] * 3600 + t[2] * 60 + t[3] : t[1] * 60 + t[2])}' "$1"; }
peak() { awk '/Maximum resident/ {print $NF / 1024}' "$1"; }
for L in $lengths; do
  d=$out/mk$L r=$out/road$L
  # The fixture (made in stretches: flat memory, time linear in length); '-' when reused.
  mk_s=- mk_mb=-
  if [ ! -f "$d/truth/mkroad.txt" ]; then
    /usr/bin/time -v "$B/mkroad" -q --force --length "$L" --supersample 1 --offpath-every 0 \
      --fullsize-frames 0 "$d" 2> "$out/t_mk.txt"
    mk_s=$(wall "$out/t_mk.txt") mk_mb=$(peak "$out/t_mk.txt")
  fi
  "$B/roadsplit" -q "$d" "$r"
  rm -rf "$out/out$L"
  /usr/bin/time -v "$B/ptmrender" -q "$r" "$out/out$L" 2> "$out/t_ptm.txt"
  frames=$(find "$out/out$L" -maxdepth 1 -name '*.png' | wc -l)
  rm -rf "$r"/Models/*/*/depth
  bw=0 bm=0
  for f in "$r"/Models/*/*/; do
    /usr/bin/time -v "$B/bakedepth" -q "$f" 2> "$out/t_bake.txt"
    bw=$(echo "$bw + $(wall "$out/t_bake.txt")" | bc -l)
    m=$(peak "$out/t_bake.txt"); bm=$(echo "if ($m > $bm) $m else $bm" | bc -l)
  done
  nimg=$(find "$r"/Models -name '*.exr' -path '*/depth/*' | wc -l)
  /usr/bin/time -v "$B/densify" -q --force "$r/Models/A/001" 2> "$out/t_dense.txt"
  dimg=$(find "$r/Models/A/001/images" -type f | wc -l)
  rm -rf "$out/ws$L"
  /usr/bin/time -v "$B/ptmrender" -q "$d" "$out/ws$L" 2> "$out/t_ws.txt"
  rm -rf "$out/ws$L"
  pw=$(wall "$out/t_ptm.txt")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%.3f\t%s\t%s\t%.3f\t%s\t%s\t%s\t%.3f\t%s\n' "$L" "$mk_s" "$mk_mb" \
    "$(grep -vc '^#' "$r/Graph.txt")" "$frames" "$pw" "$(echo "1000 * $pw / $frames" | bc -l)" \
    "$(peak "$out/t_ptm.txt")" "$bw" "$(echo "1000 * $bw / $nimg" | bc -l)" "$bm" \
    "$(wall "$out/t_ws.txt")" "$(peak "$out/t_ws.txt")" \
    "$(echo "$(wall "$out/t_dense.txt") / $dimg" | bc -l)" "$(peak "$out/t_dense.txt")" >> "$tsv"
  tail -1 "$tsv"
done

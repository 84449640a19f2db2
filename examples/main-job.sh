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
#               ... with label-free masks (dynmask: the photos checked against each other, no
#               labels) + inpaint3d, and once more on a mesh built from the photos (densify + roadmesh --dense,
#               as a user without the fixture's true mesh would: workspace OUTDIR/photo_mesh)
# 6. ssim       the photo-consistency table of the held-out renders against the truth
# 7. drive      a car steered from a steering log (examples/steer-controls.awk) through a lane
#               change into the curve, and a 3.5 m lane change along the recorded path of
#               drive A; ptmrender renders the steered drive; gazemap maps a synthetic gaze
#               trace (examples/gaze-trace.awk: fixations, saccades, a blink) through those
#               frames onto the road and back to the photographs; the table of dwell time per
#               area of interest is printed
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

echo "== 5b. the same held-out renders on a mesh built from the photos (densify, roadmesh --dense)" >&2
pm=$out/photo_mesh
mkdir -p "$pm"
for item in images sparse masks textures partners.tsv; do
  [ -e "$pm/$item" ] || ln -s "$ws/$item" "$pm/$item"
done
"$bin/densify" -q "$pm"
"$bin/roadmesh" -q --dense --metric "$pm"
"$bin/bakedepth" -q "$pm"
"$bin/ptmrender" -q --at-images --exclude-self "$pm" "$out/heldout_ptm_photo_mesh"

echo "== 5c. the same held-out renders with label-free masks (dynmask: no labels read)" >&2
lf=$out/label_free
mkdir -p "$lf"
for item in images sparse mesh.ply partners.tsv depth; do
  [ -e "$lf/$item" ] || ln -s "$ws/$item" "$lf/$item"
done
"$bin/dynmask" -q "$lf"
"$bin/inpaint3d" -q "$lf"
"$bin/ptmrender" -q --at-images --exclude-self "$lf" "$out/heldout_ptm_label_free"

echo "== 6. ssim: held-out renders against the ray-traced truth (no vehicles)" >&2
for r in vertex ptm_vehicles ptm_masks ptm ptm_label_free ptm_photo_mesh; do
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
row "PTM, label-free masks + inpaint3d" "$out/ssim_ptm_label_free.tsv"
row "PTM, the same on the photos' mesh" "$out/ssim_ptm_photo_mesh.tsv"
printf '\nlane change: %s frames in %s; effects plan in %s\n' "$(ls "$out/lane_left" | grep -c png)" "$out/lane_left" "$out/plan.json"

echo "== 7. drive a lane change and the curve; ptmrender it; gazemap a synthetic gaze trace" >&2
# The steering log and the gaze trace are generated (see the awk files for what they hold) and
# replace the old ones only when they differ, so drive and gazemap, which skip outputs newer than
# their inputs, skip on a re-run.
put() { awk -f "$top/examples/$1" > "$2.new"; if cmp -s "$2.new" "$2"; then rm "$2.new"; else mv "$2.new" "$2"; fi; }
mkdir -p "$out/drive"
put steer-controls.awk "$out/drive/controls.tsv"
"$bin/drive" --metric --pass A_ --start A_0000.png --rate 5 \
  "$ws" "$out/drive/controls.tsv" "$out/drive/steered.txt"
# drive A's 20 photographs (4.2 m apart) taken as 2 a second (8.4 m/s): 3.5 m right from 2 s in 4 s
"$bin/drive" --metric --pass A_ --frame-rate 2 --rate 5 --lane-change 2:4:-3.5 \
  "$ws" "$out/drive/lane_change.txt"
# frames are redone only when the poses file's content (or an option, or an input) changed
"$bin/ptmrender" --poses "$out/drive/steered.txt" "$ws" "$out/steered"
# the frames shown 6x (1920x576) on a 531 mm wide screen, the eye 65 cm in front of it
put gaze-trace.awk "$out/drive/gaze.tsv"
"$bin/gazemap" --screen 1920x576 --screen-mm 531x159 --distance 650 \
  "$ws" "$out/drive/steered.txt" "$out/drive/gaze.tsv" "$out/gaze" > /dev/null
printf '\nsteered drive: %s frames in %s; lane change along drive A: %s poses in %s\n' \
  "$(ls "$out/steered" | grep -c png)" "$out/steered" \
  "$(grep -vc '^#' "$out/drive/lane_change.txt")" "$out/drive/lane_change.txt"
printf 'gaze on the steered drive: %s fixations; dwell time (s) per area of interest (%s)\n' \
  "$(tail -n +2 "$out/gaze/fixations.tsv" | wc -l)" "$out/gaze/aoi.tsv"
awk -F'\t' '{ printf "%-34s %10s %10s %10s\n", $1, $2, $3, $4 }' "$out/gaze/aoi.tsv"

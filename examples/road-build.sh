#!/usr/bin/env bash
# The whole road build as one shell script: photos (or a video) + poses (or none) + intrinsics
# (or none) → a rendered, scored mvtm workspace. A rerun skips what is done: each step skips when
# its output exists and was made from the same inputs and settings (OUT/.keys: other photos,
# poses, intrinsics or SfM settings redo the build, other mesh settings the mesh, another HOLDOUT
# the held-out renders and the strict workspace; the mvtm programs keep their own records), and
# COLMAP's outputs are committed whole, so a killed run's rerun redoes the step it was in. New
# poses (BORESIGHT, HOLDOUT_STRICT) redo the mesh; a new first mesh also redoes dynmask's masks
# and the mesh it judges against (dynmask-mesh.ply).
#
# usage: examples/road-build.sh IMAGES|VIDEO POSES|- OUT [-- INTRINSICS...]
#   IMAGES      folder of the frames (sorted by name = frame order); every photo is kept
#   VIDEO       a video file instead: frames picks its frames (OUT/frames: travelled motion, no
#               blurred frame, burned-in overlays masked) and the build runs on those
#   POSES       ORB-SLAM2 KeyFrameTrajectory / TUM or KITTI poses (camera-to-world), a COLMAP
#               model (folder, or its images.txt) or a NeRF/nerfstudio transforms.json, taken as
#               the poses of record (the last two bring their camera: INTRINSICS optional); or
#               - for none: COLMAP's incremental SfM finds them from the
#               photos (sequential matching, one shared camera), georef turns the model upright
#               and, with CAMERA_HEIGHT, metric
#   OUT         working folder; the workspace is OUT/ws
#   INTRINSICS  orb2colmap's intrinsics options, e.g. --kitti-calib calib.txt (add
#               --kitti-cam 1 for KITTI's image_1: poses.txt is then moved to that camera), or
#               --camera "PINHOLE W H fx fy cx cy", or --orb-settings TUM1.yaml [--frames rgb.txt];
#               with POSES -, optional: without them COLMAP self-calibrates a SIMPLE_RADIAL
#               camera (CAMERA_MODEL to choose another, e.g. OPENCV), or CALIB gives them
# environment: MVTM_BIN (default build/bin), HOLDOUT (every Nth frame scored, default 5),
#              LATERAL (lane change for the final render in model units, default 1.5: metres
#              for a metric model; a non-metric one needs 1.5 x its units per metre),
#              MATCH_OVERLAP (COLMAP sequential matching overlap, default 5; 10 with POSES -),
#              SFM_MAX_REPROJ (POSES -: the mapper's outlier threshold in pixels, default 2),
#              SFM_CHUNK (POSES -: map stretches of this many images each, SFM_CHUNK_OVERLAP
#              shared between neighbours, default 8, and join them with sfmjoin: a long drive's
#              mapping then costs the same per image whatever its length; 0, the default: all
#              images at once),
#              SFM_ONLY (1: stop once the model of record, OUT/ba, is made: to check the poses
#              before the dense steps),
#              SFM_THREADS (POSES -: threads of COLMAP's extraction, matching and mapping; 1 makes
#              a run repeatable, as COLMAP's RANSAC draws from per-thread generators),
#              LOOP_DETECTION (1: with POSES -, also match each frame against the frames most
#              alike in a vocabulary tree built from the photos, for drives that revisit a place),
#              CAMERA_HEIGHT (with POSES -: the camera's height above the road in metres, e.g.
#              1.65 for KITTI; the model is then in metres, METRIC=1 follows),
#              GPS (with POSES -: a GPX or NMEA log of the drive; the model goes to UTM in metres,
#              the zone and origin in OUT/ws/georef.json; a VIDEO's frames are timed by frames,
#              a folder of photos needs GPS_TIMES: frames.tsv-like NAME TIME lines or KITTI
#              times.txt), GPS_OFFSET (seconds from the log's first fix to the video's start,
#              default 0), GPS_SEARCH (seconds either side of GPS_OFFSET to search, default 0),
#              FRAME_SPACING (VIDEO: frames' --spacing, default 0.01 of the image width),
#              CALIB (a folder of chessboard photos or a video of the board, taken with the same
#              camera at the same size: calibrate's camera becomes the INTRINSICS; CALIB_PATTERN
#              its inner corners, default 9x6; CALIB_MODEL PINHOLE, SIMPLE_RADIAL, RADIAL or
#              OPENCV, the default; a database OUT/db.db made before keeps its camera),
#              MESH (dense | corridor: the mesh where COLMAP has no CUDA, default dense),
#              ROADMESH_FLAGS (extra roadmesh options, e.g. "--max-depth 80": fuse depths up to
#              80 camera spacings instead of 40, for far roadside geometry on fast roads),
#              METRIC (1: the poses are in metres, e.g. ground truth or GPS-aligned: roadmesh
#              takes lengths as metres instead of deriving its unit from the scene's camera
#              height, which a road without sparse points on the asphalt cannot give),
#              DYNAMIC (0: no label-free masks when OUT/ws/labels is missing; default 1: dynmask),
#              DYNMASK_FLAGS (extra dynmask options, e.g. "--threshold 0.08"),
#              BORESIGHT (0: keep the poses' recorded attitude; default 1: boresight fits the
#              camera's mount rotation to the photos' tracks, poses of record only),
#              HOLDOUT_STRICT (1: also score a strict hold-out: a second workspace without the
#              held-out photos builds the mesh, its colours and the projectors; they take part in
#              nothing that is scored, as in novel-view benchmarks)
#
# Steps: [frames (VIDEO)] → orb2colmap (poses as priors, or the camera alone with POSES -) →
# COLMAP feature_extractor / sequential_matcher / point_triangulator / bundle_adjuster (poses of
# record; then boresight) or mapper + georef (POSES -) / image_undistorter (CPU) → [segtrack,
# when OUT/ws/labels exists] → mesh (COLMAP dense MVS + poisson_mesher when COLMAP has CUDA, else
# densify + roadmesh --dense, or roadmesh alone; without the masked pixels) → [without labels:
# dynmask, label-free, and the mesh again without the masked pixels] →
# pickview --partners (when the names carry several passes, A_0000.png …) → bakedepth →
# inpaint3d (when there are masks) → ptmrender (held-out poses and a lane change) → ssim.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
usage() { echo "usage: $0 IMAGES|VIDEO POSES|- OUT [-- INTRINSICS...]" >&2; exit 2; }
[ $# -ge 3 ] || usage
if [ $# -ge 4 ]; then [ "$4" = "--" ] || usage; fi
named_poses() { [ -d "$1" ] || [[ "$1" == *.json ]] || [[ "$(basename "$1")" == images.txt ]] || [[ "$(basename "$1")" == images.bin ]]; }
[ "$2" = - ] || [ $# -ge 5 ] || named_poses "$2" || [ -n "${CALIB:-}" ] || { echo "$0: error: these poses need INTRINSICS after --" >&2; usage; }
[ -e "$1" ] || { echo "$0: error: $1: no such file or folder" >&2; exit 2; }
input=$1; poses=$2; out=$3; shift 3; [ $# -ge 1 ] && shift
mkdir -p "$out"; out=$(cd "$out" && pwd); ws=$out/ws
holdout=${HOLDOUT:-5}; lateral=${LATERAL:-1.5}
log() { echo "== $*" >&2; }
# COLMAP's version and build (read whole: grep -q or head would end the pipe early, and with
# pipefail COLMAP's SIGPIPE would fail it).
colmap_help=$(colmap -h 2> /dev/null || true)
colmap_log() { "$@" > "$out/colmap.log" 2>&1 || { tail -20 "$out/colmap.log" >&2; exit 1; }; }
# Puts TMP (a file or a folder another program wrote whole) in DEST's place: synced (the file
# system's, sync -f: COLMAP syncs nothing), renamed into place over any old DEST, and the folder
# synced. Steps are skipped when their output exists, so each output of a program that writes in
# place (COLMAP) is made under a temporary name and committed only once it is complete: a kill or
# a power loss never leaves a partial DEST that a rerun would take for done.
commit_whole() {  # TMP DEST
  { sync -f "$1" && { [ ! -d "$2" ] || rm -rf "$2"; } &&
    mv -T -f "$1" "$2" && sync "$(dirname "$2")"; } ||
    { echo "$0: error: cannot write $2" >&2; exit 1; }
}
# A temporary's name beside DEST, as mvtm names its own (a killed run's is removed first).
temp_for() {  # DEST
  rm -rf "$(dirname "$1")/.$(basename "$1").tmp-"*
  echo "$(dirname "$1")/.$(basename "$1").tmp-$$"
}
# What a stage's outputs are made from, in OUT/.keys/NAME: a stage whose key changed (other
# photos, poses, intrinsics or settings) is done again from scratch, its outputs removed first
# and then the new key written. So a rerun never hands back outputs made with other inputs or
# settings; one with the same skips what is done (each output is committed whole, so a killed
# run's rerun goes on from the outputs it finished).
key_changed() {  # NAME TEXT; true when the key differs
  [ "$(cat "$out/.keys/$1" 2> /dev/null)" != "$2" ]
}
key_done() {  # NAME TEXT
  local tmp
  mkdir -p "$out/.keys"; tmp=$(temp_for "$out/.keys/$1")
  printf '%s\n' "$2" > "$tmp" || { echo "$0: error: cannot write $out/.keys/$1" >&2; exit 1; }
  commit_whole "$tmp" "$out/.keys/$1"
}
# The first mesh and what is made with it: dynmask's kept copy, COLMAP's fused points and mesh.
drop_meshes() { rm -f "$ws/mesh.ply" "$ws/dynmask-mesh.ply" "$ws/meshed-poisson.ply" "$ws/fused.ply"; }
# A file's or a folder's content as one line: its files' names and md5 sums (the argument as
# it is when it names neither).
content_of() {  # PATH
  if [ -d "$1" ]; then
    # (linked files followed; temporaries, named .NAME.tmp-*, left out)
    (cd "$1" && find -L . -type f ! -name '.*' -print0 | LC_ALL=C sort -z | xargs -0 -r md5sum) |
      md5sum | cut -c1-32
  elif [ -f "$1" ]; then
    md5sum < "$1" | cut -c1-32
  else
    printf '%s\n' "$1"
  fi
}
# Copies SRC (a file or a folder) to DEST whole (commit_whole).
copy_whole() {  # SRC DEST
  local tmp
  tmp=$(temp_for "$2")
  cp -r "$1" "$tmp" || { echo "$0: error: cannot copy $1 to $2" >&2; exit 1; }
  commit_whole "$tmp" "$2"
}
if [ -n "${CALIB:-}" ]; then
  log "0. calibrate: the camera from the chessboard views in $CALIB"
  spec=$("$bin/calibrate" --pattern "${CALIB_PATTERN:-9x6}" --model "${CALIB_MODEL:-OPENCV}" "$CALIB" "$out/calib")
  set -- --camera "$spec"
fi
overlay=
if [ -d "$input" ]; then
  images=$(cd "$input" && pwd)
else
  log "0. frames: the video's frames, chosen by travelled image motion, blurred ones dropped"
  "$bin/frames" ${FRAME_SPACING:+--spacing "$FRAME_SPACING"} "$input" "$out/frames"
  images=$out/frames/images
  [ -f "$out/frames/mask.png" ] && overlay=$out/frames
fi

# The model of record (steps 1-2) and all that follows is made from the photos, the poses, the
# intrinsics (the files they name too) and the structure-from-motion settings.
sfm_key="photos $(content_of "$images")
poses $(content_of "$poses") $(case $(basename "$poses") in images.txt | images.bin) content_of "$(dirname "$poses")" ;; esac)
intrinsics $(for a in "$@"; do printf '%s=%s ' "$a" "$(content_of "$a")"; done)
gps $(content_of "${GPS:-}") $(content_of "${GPS_TIMES:-}") ${GPS_OFFSET:-} ${GPS_SEARCH:-}
settings ${MATCH_OVERLAP:-}|${SFM_MAX_REPROJ:-}|${SFM_CHUNK:-}|${SFM_CHUNK_OVERLAP:-}|${SFM_THREADS:-}|${LOOP_DETECTION:-}|${CAMERA_HEIGHT:-}|${CAMERA_MODEL:-}
colmap $(sed -n 1,3p <<< "$colmap_help" | tr '\n' ' ')"
if key_changed sfm "$sfm_key"; then
  [ -d "$out/.keys" ] && log "the photos, poses, intrinsics or SfM settings changed: the build is done again"
  rm -rf "$out/.keys" "$out/db.db" "$out/db.db.tmp" "$out/prior" "$out/tri" "$out/ba" "$out/sfm" \
    "$out"/sfm_* "$out/vocab_tree.bin" "$out/overlay" "$out/overlay_masks" "$out/sparse_record" \
    "$out/train" "$ws/sparse" "$ws/partners.tsv" "$ws/tracks.tsv" "$ws/masks" "$ws/georef.json" \
    "$out/db.db-wal" "$out/db.db-shm"
  drop_meshes
  key_done sfm "$sfm_key"
fi
# COLMAP's database (SQLite, which COLMAP writes without syncing): one a power loss damaged is
# made again before the steps that read it (without the sqlite3 shell it is trusted).
if [ ! -f "$out/ba/images.bin" ] && [ -f "$out/db.db" ] && command -v sqlite3 > /dev/null &&
  [ "$(sqlite3 -init /dev/null -batch "$out/db.db" 'PRAGMA quick_check;' 2> /dev/null)" != ok ]; then
  log "COLMAP's database $out/db.db is damaged: it is made again"
  rm -rf "$out/db.db" "$out/db.db-wal" "$out/db.db-shm" "$out/prior"
fi

if [ "$poses" = - ]; then
  log "1. orb2colmap: the camera (when intrinsics are given) and the images into a COLMAP database, no poses"
  if [ $# -ge 1 ] && [ ! -f "$out/db.db" ]; then
    rm -f "$out/db.db.tmp"  # a killed run's
    "$bin/orb2colmap" --images "$images" --database "$out/db.db.tmp" "$@" - "$out/prior"
    commit_whole "$out/db.db.tmp" "$out/db.db"
  fi
  log "2. COLMAP (CPU): SIFT, sequential matching, incremental SfM; georef: up and scale"
  if [ ! -f "$out/ba/images.bin" ]; then
    mask_opt=(); [ -n "$overlay" ] && mask_opt=(--ImageReader.camera_mask_path "$overlay/colmap_mask.png")
    colmap_log colmap feature_extractor --database_path "$out/db.db" --image_path "$images" \
      --SiftExtraction.use_gpu 0 --ImageReader.single_camera 1 \
      --ImageReader.camera_model "${CAMERA_MODEL:-SIMPLE_RADIAL}" "${mask_opt[@]}" \
      ${SFM_THREADS:+--SiftExtraction.num_threads "$SFM_THREADS"}
    loop_opt=()
    if [ "${LOOP_DETECTION:-0}" = 1 ]; then
      if [ ! -f "$out/vocab_tree.bin" ]; then
        tmp=$(temp_for "$out/vocab_tree.bin")
        colmap_log colmap vocab_tree_builder --database_path "$out/db.db" --vocab_tree_path "$tmp"
        commit_whole "$tmp" "$out/vocab_tree.bin"
      fi
      loop_opt=(--SequentialMatching.loop_detection 1 --SequentialMatching.vocab_tree_path "$out/vocab_tree.bin")
    fi
    colmap_log colmap sequential_matcher --database_path "$out/db.db" --SiftMatching.use_gpu 0 \
      --SequentialMatching.overlap "${MATCH_OVERLAP:-10}" "${loop_opt[@]}" \
      ${SFM_THREADS:+--SiftMatching.num_threads "$SFM_THREADS"}
    # Given intrinsics stay as they are; without them the mapper refines focal length and
    # distortion of the one shared camera. Observations over SFM_MAX_REPROJ px (default 2) are
    # outliers: COLMAP's default 4 keeps wrong matches on repetitive facades and lane dashes (the
    # CI fixture's video drifts to 3 % of its path with 4, 0.05 % with 2; KITTI 01: 0.59 % and
    # 0.64 %).
    fixed=(--Mapper.filter_max_reproj_error "${SFM_MAX_REPROJ:-2}")
    [ -n "${SFM_THREADS:-}" ] && fixed+=(--Mapper.num_threads "$SFM_THREADS")
    self_calibrating=1
    if [ $# -ge 1 ]; then
      self_calibrating=0; fixed+=(--Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_extra_params 0)
    fi
    # Forward motion gives small triangulation angles: the mapper starts from a wide initial
    # pair (wide_pair, below) with the dashcam's initial-pair settings (from 1 degree and 50
    # inliers, forward-moving pairs allowed; KITTI 06 and CamVid need them), and while under half
    # the images register, runs again (map_best); the largest model is kept.
    map_run() {  # OUTDIR [mapper options...]; succeeds even when the mapper fails
      rm -rf "$1"; mkdir -p "$1"; local d=$1; shift
      colmap mapper --database_path "$out/db.db" --image_path "$images" --output_path "$d" \
        "${fixed[@]}" "$@" >> "$out/colmap.log" 2>&1 || true
    }
    largest() {  # SFM_DIR → "count path" of its largest model ("0 " when none)
      local b='' n=0 k m
      for m in "$1"/*/; do
        [ -d "$m" ] || continue
        k=$(colmap model_analyzer --path "$m" 2>&1 | sed -n 's/.*Registered images: *\([0-9]*\).*/\1/p')
        if [ "${k:-0}" -gt "$n" ]; then b=$m; n=$k; fi
      done
      echo "$n $b"
    }
    # Keeps NEW's models in place of DIR's when NEW's largest registered more images than best_n;
    # removes NEW; sets best_n and best to DIR's largest. Returns 1 when DIR's were kept.
    adopt_if_more() {  # DIR NEW
      local n m kept=1
      read -r n m <<< "$(largest "$2")"
      if [ "$n" -gt "$best_n" ]; then rm -rf "$1"; mv "$2" "$1"; kept=0; fi
      rm -rf "$2"
      read -r best_n best <<< "$(largest "$1")"
      return "$kept"
    }
    # The initial pair for a forward drive: the middle image of those mapped (name order: frame
    # order; all, or the --image_list_path given) and the image farthest from it in that order
    # that shares at least 100 verified matches with it (a wider baseline for the same view),
    # as "ID1 ID2" of the database; nothing when none does.
    wide_pair() {  # [mapper options...]
      local list=
      while [ $# -gt 0 ]; do
        [ "$1" = --image_list_path ] && list=${2-}
        shift
      done
      local values
      values=$(if [ -n "$list" ]; then cat "$list"; else LC_ALL=C ls "$images"; fi |
        awk 'NF { gsub(/\x27/, "\x27\x27"); printf "%s(\x27%s\x27, %d)", n ? ", " : "", $0, n; n++ }')
      [ -n "$values" ] || return 0
      # The SQL on standard input (a long drive's list exceeds one argument's limit); no user
      # settings (~/.sqliterc). The middle and the order are over the names the database holds.
      sqlite3 -init /dev/null -batch -noheader -list -separator ' ' "$out/db.db" <<SQL 2> /dev/null || true
WITH o(name, k) AS (VALUES $values),
     i AS (SELECT images.image_id AS id, ROW_NUMBER() OVER (ORDER BY o.k) - 1 AS k
           FROM images JOIN o USING (name)),
     m AS (SELECT id, k FROM i WHERE k = (SELECT COUNT(*) FROM i) / 2)
SELECT m.id, i.id FROM m, i, two_view_geometries g
WHERE g.pair_id = MIN(m.id, i.id) * 2147483647 + MAX(m.id, i.id)
  AND g.config >= 2 AND g.rows >= 100 AND i.k <> m.k
ORDER BY ABS(i.k - m.k) DESC, i.k > m.k DESC LIMIT 1;
SQL
    }
    # The mapper on one set of images (all, or one stretch's list): from wide_pair's initial
    # pair (COLMAP's own choice when there is none), and while under half the images register,
    # again from COLMAP's own, as forward motion, and self-calibrating with the camera held; the
    # largest model is kept.
    # Sets best_n and best (count, path); several models when the chain of matches breaks: each
    # is reported.
    map_best() {  # OUTDIR COUNT [mapper options...]
      local d=$1 want=$2 m k p1 p2 pair; shift 2
      local half=$(( (want + 1) / 2 )) start=() forward=(--Mapper.init_min_tri_angle 1
        --Mapper.init_min_num_inliers 50 --Mapper.init_max_forward_motion 1.0)
      local held=(--Mapper.ba_refine_focal_length 0 --Mapper.ba_refine_extra_params 0)
      # The first two images set the model's shape. The mapper's own choice, a pair a few frames
      # apart, bends a forward drive: the CI fixture's video with its camera given, two
      # databases: 9.0-9.9 % of the path off the truth at worst after a similarity fit, 0.48-
      # 0.54 px; from wide_pair's pair 0.23-0.25 %, 0.32 px. Self-calibrating (CamVid 0016E5,
      # the camera held at the guess 576 px) 42-47 degrees of false turn over its straight
      # street, 0.63-0.65 px, the ground 16 degrees off and a nonsense k1 of 0.5-0.8 refined
      # from it; from the wide pair 5 degrees, 0.37 px, then 561 px and k1 -0.07.
      command -v sqlite3 > /dev/null ||
        echo "warning: no sqlite3 shell: the mapper chooses its own initial pair" >&2
      # Every attempt maps into ${d}_NAME and is kept in $d when it registered more (adopt_if_more);
      # it runs under || or && (errexit off inside it): a step of it that fails leaves an attempt
      # that registered nothing, and the next one runs.
      local args=("$@")
      attempt() {  # NAME [mapper options...]; returns 0 when its model was kept
        local name=$1; shift
        map_run "${d}_$name" "${args[@]}" "$@"
        adopt_if_more "$d" "${d}_$name"
      }
      rm -rf "$d"; best_n=0; best=
      pair=$(wide_pair "$@")
      read -r p1 p2 <<< "$pair"
      if [[ "${p1:-}" =~ ^[0-9]+$ && "${p2:-}" =~ ^[0-9]+$ ]]; then
        # (COLMAP may start further models from the same pair for the images left over; the
        # largest is kept. With --Mapper.multiple_models 0 a self-calibrating CamVid run stopped
        # at 9 of 60 where one without registered 60.)
        start=(--Mapper.init_image_id1 "$p1" --Mapper.init_image_id2 "$p2" "${forward[@]}")
        attempt wide "${start[@]}" || true
        if [ "$best_n" -lt "$half" ]; then
          echo "SfM from the wide initial pair registered $best_n of $want images: again from COLMAP's own" >&2
          attempt own || true
        fi
      else
        attempt own || true
      fi
      if [ "$best_n" -lt "$half" ]; then
        echo "SfM registered $best_n of $want images: again as forward motion" >&2
        attempt forward "${forward[@]}" || true
      fi
      # Self-calibrating, a two-view start can refine the one camera into nonsense (focal length
      # and distortion from a pair with a small baseline), after which no further image registers
      # (CamVid 0016E5: 0 of 60 on some runs). Then the mapper runs with the camera held at its
      # starting guess (from the wide pair, then from its own choice while under half), and one
      # bundle adjustment of the whole model refines it when such a model was kept.
      if [ "$best_n" -lt "$half" ] && [ "$self_calibrating" = 1 ]; then
        echo "SfM registered $best_n of $want images: again with the camera held, refined afterwards" >&2
        local refine=0
        attempt held "${held[@]}" "${start[@]}" && refine=1
        if [ "$best_n" -lt "$half" ] && [ ${#start[@]} -gt 0 ]; then
          attempt held_own "${held[@]}" && refine=1
        fi
        if [ "$refine" = 1 ]; then
          colmap bundle_adjuster --input_path "$best" --output_path "$best" \
            --BundleAdjustment.refine_focal_length 1 --BundleAdjustment.refine_extra_params 1 \
            >> "$out/colmap.log" 2>&1 ||
            echo "warning: the camera held at its starting guess (its refinement failed: $out/colmap.log)" >&2
        fi
      fi
      for m in "$d"/*/; do
        [ -d "$m" ] || continue
        k=$(colmap model_analyzer --path "$m" 2>&1 | sed -n 's/.*Registered images: *\([0-9]*\).*/\1/p')
        echo "SfM model $m: ${k:-0} of $want images registered" >&2
      done
      [ -n "$best" ] || { echo "$0: error: COLMAP registered no image of $want (see $out/colmap.log)" >&2; exit 1; }
    }
    total=$(ls "$images" | wc -l)
    : > "$out/colmap.log"
    chunk=${SFM_CHUNK:-0}; chunk_overlap=${SFM_CHUNK_OVERLAP:-8}
    [[ "$chunk" =~ ^[0-9]+$ && "$chunk_overlap" =~ ^[0-9]+$ ]] ||
      { echo "$0: error: SFM_CHUNK and SFM_CHUNK_OVERLAP must be whole numbers" >&2; exit 2; }
    if [ "$chunk" -gt 0 ] && [ "$total" -gt "$chunk" ]; then
      # Long drives: the mapper per stretch of SFM_CHUNK images (name order), neighbours sharing
      # SFM_CHUNK_OVERLAP, so each costs the same whatever the road's length; sfmjoin places the
      # stretches in one frame by the images they share; georef below aligns the road once.
      [ "$chunk_overlap" -ge 3 ] && [ "$chunk_overlap" -lt "$chunk" ] ||
        { echo "$0: error: SFM_CHUNK_OVERLAP must be at least 3 and under SFM_CHUNK" >&2; exit 2; }
      rm -rf "$out/sfm_chunks"; mkdir -p "$out/sfm_chunks"
      [ $# -ge 1 ] || echo "warning: SFM_CHUNK without INTRINSICS: each stretch calibrates its own camera (renders use the first)" >&2
      LC_ALL=C ls "$images" > "$out/sfm_chunks/all.txt"  # byte order, as sfmjoin and COLMAP sort
      # The fewest stretches of at most SFM_CHUNK images, all of one length (to an image).
      parts=$(( (total - chunk_overlap + chunk - chunk_overlap - 1) / (chunk - chunk_overlap) ))
      [ "$parts" -ge 1 ] || parts=1
      models=()
      for ((k = 0; k < parts; k++)); do
        s=$(( k * (total - chunk_overlap) / parts )); e=$(( (k + 1) * (total - chunk_overlap) / parts + chunk_overlap ))
        list=$out/sfm_chunks/$k.txt
        sed -n "$((s + 1)),${e}p" "$out/sfm_chunks/all.txt" > "$list"
        map_best "$out/sfm_chunks/$k" $((e - s)) --image_list_path "$list"
        models+=("$best")
      done
      "$bin/sfmjoin" -q --binary "${models[@]}" "$out/sfm_chunks/joined"
      best=$out/sfm_chunks/joined
      best_n=$(colmap model_analyzer --path "$best" 2>&1 | sed -n 's/.*Registered images: *\([0-9]*\).*/\1/p')
      best_n=${best_n:-0}
    else
      map_best "$out/sfm" "$total"
    fi
    [ "$best_n" -lt "$total" ] && echo "warning: $((total - best_n)) of $total images not in the model built (the others above, or unregistered)" >&2
    gps_opt=()
    if [ -n "${GPS:-}" ]; then
      gps_times=${GPS_TIMES:-}
      [ -z "$gps_times" ] && [ -f "$out/frames/frames.tsv" ] && gps_times=$out/frames/frames.tsv
      [ -n "$gps_times" ] || { echo "$0: error: GPS with a folder of photos needs GPS_TIMES (each photo's time)" >&2; exit 2; }
      gps_opt=(--gps "$GPS" --times "$gps_times" --gps-offset "${GPS_OFFSET:-0}" --gps-search "${GPS_SEARCH:-0}")
    fi
    tmp=$(temp_for "$out/ba")
    "$bin/georef" --binary ${CAMERA_HEIGHT:+--camera-height "$CAMERA_HEIGHT"} "${gps_opt[@]}" "$best" "$tmp"
    commit_whole "$tmp" "$out/ba"
  fi
  if [ -n "${CAMERA_HEIGHT:-}" ] || [ -n "${GPS:-}" ]; then METRIC=1; fi
else
  log "1. orb2colmap: poses -> COLMAP model of every frame + database with pose priors"
  [ -f "$out/prior/images.txt" ] || "$bin/orb2colmap" --images "$images" --database "$out/db.db" "$@" "$poses" "$out/prior"

  log "2. COLMAP (CPU): SIFT, sequential matching, triangulation with the poses, bundle adjustment"
  if [ ! -f "$out/ba/images.bin" ]; then
    colmap_log colmap feature_extractor --database_path "$out/db.db" --image_path "$images" \
      --SiftExtraction.use_gpu 0 --ImageReader.single_camera 1
    colmap_log colmap sequential_matcher --database_path "$out/db.db" --SiftMatching.use_gpu 0 \
      --SequentialMatching.overlap "${MATCH_OVERLAP:-5}"
    rm -rf "$out/tri"; tmp=$(temp_for "$out/ba")
    mkdir -p "$out/tri" "$tmp"
    colmap_log colmap point_triangulator --database_path "$out/db.db" --image_path "$images" \
      --input_path "$out/prior" --output_path "$out/tri"
    # The poses are the poses of record (SLAM or ground truth, metric): bundle adjustment refines
    # the points only. Left free, COLMAP's gauge lets the whole trajectory drift and rescale.
    # (COLMAP writes its three files in place, one after the other: under a temporary name.)
    colmap_log colmap bundle_adjuster --input_path "$out/tri" --output_path "$tmp" \
      --BundleAdjustment.refine_extrinsics 0 --BundleAdjustment.refine_focal_length 0 \
      --BundleAdjustment.refine_principal_point 0 --BundleAdjustment.refine_extra_params 0
    commit_whole "$tmp" "$out/ba"
  fi
fi
if [ "${SFM_ONLY:-0}" = 1 ]; then
  log "SFM_ONLY=1: the model of record is $out/ba; stopping before the workspace and the mesh"
  exit 0
fi
if [ ! -d "$ws/sparse" ]; then
  # The undistorter makes sparse/ first and its model last: it writes into a temporary folder,
  # whose parts then go into the workspace (which may hold labels already), sparse/ the last.
  tmp=$(temp_for "$out/undistorted")
  colmap_log colmap image_undistorter --image_path "$images" --input_path "$out/ba" \
    --output_path "$tmp" --output_type COLMAP
  mkdir -p "$ws"
  for f in "$tmp"/*; do [ "$(basename "$f")" = sparse ] || commit_whole "$f" "$ws/$(basename "$f")"; done
  rm -rf "$out/sparse_record"
  commit_whole "$tmp/sparse" "$ws/sparse"
  rmdir "$tmp"
fi
# Poses of record carry the attitude of the vehicle's navigation, not of the camera: one mount
# rotation (boresight) fitted to the photos' tracks turns every camera about its recorded centre
# (SfM poses need none: they are the photos' own). The undistorted model as recorded is kept in
# OUT/sparse_record; boresight fits it on every run (its record makes a rerun with the same inputs
# and settings cheap) and the workspace gets its output, or the record again with BORESIGHT=0.
# With HOLDOUT_STRICT the held-out photos take no part in the fit.
if [ "$poses" != - ]; then
  [ -d "$out/sparse_record" ] || copy_whole "$ws/sparse" "$out/sparse_record"
  model=$out/sparse_record
  if [ "${BORESIGHT:-1}" = 1 ]; then
    log "2b. boresight: the camera's mount rotation against the poses of record"
    bs_opts=()
    if [ "${HOLDOUT_STRICT:-0}" = 1 ]; then
      ls "$ws/images" | awk -v h="$holdout" '(NR - 1) % h == 0' > "$out/boresight_excluded.tmp"
      cmp -s "$out/boresight_excluded.tmp" "$out/boresight_excluded.txt" ||
        mv "$out/boresight_excluded.tmp" "$out/boresight_excluded.txt"
      rm -f "$out/boresight_excluded.tmp"
      bs_opts=(--exclude "$out/boresight_excluded.txt")
    fi
    "$bin/boresight" --binary "${bs_opts[@]}" "$model" "$out/boresight"
    model=$out/boresight
  fi
  for f in cameras.bin images.bin points3D.bin; do
    # New poses: the first mesh (and the one dynmask kept of it) was built with the old ones.
    cmp -s "$model/$f" "$ws/sparse/$f" ||
      { drop_meshes; copy_whole "$model/$f" "$ws/sparse/$f"; }
  done
fi
if [ -f "$out/ba/georef.json" ]; then
  cmp -s "$out/ba/georef.json" "$ws/georef.json" || copy_whole "$out/ba/georef.json" "$ws/georef.json"
fi
# A video's burned-in overlay: undistorted like the photos, one mask per image, so that fusion,
# vertex colours and projection leave those pixels out (ptmrender fills them from other photos);
# dynmask ORs them into its masks.
overlay_masks=
if [ -n "$overlay" ]; then
  overlay_masks=$out/overlay_masks
  if [ ! -d "$overlay_masks" ]; then
    rm -rf "$out/overlay"; mkdir -p "$out/overlay/in"
    for f in "$images"/*; do ln -s "$overlay/mask.png" "$out/overlay/in/$(basename "$f")"; done
    colmap_log colmap image_undistorter --image_path "$out/overlay/in" --input_path "$out/ba" \
      --output_path "$out/overlay/out" --output_type COLMAP
    commit_whole "$out/overlay/out/images" "$overlay_masks"
  fi
  [ -d "$ws/masks" ] || copy_whole "$overlay_masks" "$ws/masks"
fi
colmap model_analyzer --path "$ws/sparse" 2>&1 | grep -E "Registered images|Points:|Mean reprojection" >&2 || true

# The mesh of a workspace where COLMAP has no CUDA: dense plane-sweep stereo fused on a sparse
# signed-distance volume, closed by the corridor's ground (MESH=dense), or the corridor alone.
read -r -a roadmesh_opts <<< "${ROADMESH_FLAGS:-}"
[ "${METRIC:-0}" = 1 ] && roadmesh_opts+=(--metric)
cpu_mesh() {
  if [ "${MESH:-dense}" = dense ]; then
    "$bin/densify" "$1" && "$bin/roadmesh" --dense "${roadmesh_opts[@]}" "$1"
  else
    "$bin/roadmesh" "${roadmesh_opts[@]}" "$1"
  fi
}

log "3. mesh"
# The first mesh (and the masks dynmask judged against it) is made with the mesh settings; with
# DYNAMIC=0 after 1, the label-free masks go with it (below) and the mesh is made without them.
mesh_key="MESH=${MESH:-dense} METRIC=${METRIC:-0} ROADMESH_FLAGS=${ROADMESH_FLAGS:-} DYNAMIC=${DYNAMIC:-1}"
if key_changed mesh "$mesh_key"; then
  drop_meshes; rm -f "$out/.keys/holdout"
  key_done mesh "$mesh_key"
fi
read -r -a dynmask_opts <<< "${DYNMASK_FLAGS:-}"
# dynmask keeps the mesh it judges against (dynmask-mesh.ply) unless it is told to judge against
# densify's maps (--depth stereo) or another mesh (--mesh FILE).
dynmask_keeps=1
for i in "${!dynmask_opts[@]}"; do
  case "${dynmask_opts[$i]}" in
    --mesh | --mesh=?* | --depth=stereo) dynmask_keeps=0 ;;
    --depth) [ "${dynmask_opts[$((i + 1))]:-}" != stereo ] || dynmask_keeps=0 ;;
  esac
done
# A workspace whose masks dynmask made without keeping its mesh (an earlier mvtm, or
# dynmask-mesh.ply deleted): mesh.ply was built without the masked pixels, so the first mesh is
# built again (below) for dynmask to judge against.
if [ ! -d "$ws/labels" ] && [ -f "$ws/tracks.tsv" ] && [ -f "$ws/mesh.ply" ] &&
  [ "$dynmask_keeps" = 1 ] && [ ! -f "$ws/dynmask-mesh.ply" ]; then
  rm -f "$ws/mesh.ply"
fi
# Labelled photos: their masks first (segtrack's record redoes them when a label changed), so
# that the mesh leaves the vehicles out of fusion and vertex colours. (Before 8 Dec 2026 the
# mesh was made before segtrack ran, with the vehicles, and never again.)
if [ -d "$ws/labels" ]; then
  log "3a. segtrack: the vehicle masks from the labels"
  "$bin/segtrack" "$ws/labels" "$ws"
fi
if [ ! -f "$ws/mesh.ply" ] && [ ! -f "$ws/meshed-poisson.ply" ]; then
  # dynmask judges against this new first mesh, the scene as recorded: the masks an earlier
  # dynmask run made (tracks.tsv says one did) are not left out of it, only a video's overlay.
  rm -f "$ws/dynmask-mesh.ply"
  if [ ! -d "$ws/labels" ] && [ -f "$ws/tracks.tsv" ]; then
    rm -rf "$ws/masks" "$ws/tracks.tsv"
    [ -z "$overlay_masks" ] || copy_whole "$overlay_masks" "$ws/masks"
  fi
  if [[ "$colmap_help" == *"with CUDA"* ]]; then
    # patch_match_stereo skips a view whose maps exist: none may be a killed run's or of other poses.
    rm -f "$ws"/stereo/depth_maps/* "$ws"/stereo/normal_maps/* "$ws"/stereo/consistency_graphs/*
    colmap_log colmap patch_match_stereo --workspace_path "$ws"
    colmap_log colmap stereo_fusion --workspace_path "$ws" --output_path "$ws/fused.ply"
    tmp=$(temp_for "$ws/meshed-poisson.ply")
    colmap_log colmap poisson_mesher --input_path "$ws/fused.ply" --output_path "$tmp"
    # poisson_mesher can write an empty mesh and still exit 0.
    if grep -aq "element face [1-9]" "$tmp"; then commit_whole "$tmp" "$ws/meshed-poisson.ply"; else
      rm -f "$tmp"; cpu_mesh "$ws"; fi
  else
    cpu_mesh "$ws"
  fi
fi


log "3b. exposure: a gain and an offset per photo, so that projectors blend at one exposure"
"$bin/exposure" -q "$ws"

log "4. vehicle masks and partners"
[ -n "$overlay_masks" ] && dynmask_opts+=(--also "$overlay_masks")
if [ -d "$ws/labels" ]; then
  # segtrack's masks (step 3a): roadmesh's inputs include them, so it redoes a mesh made
  # without the masks of now.
  [ -f "$ws/meshed-poisson.ply" ] || cpu_mesh "$ws"
elif [ "${DYNAMIC:-1}" = 1 ]; then
  # No labels: label-free masks from the photos checked against each other through the first
  # mesh (dynmask), then the mesh again without the masked pixels (roadmesh's inputs include the
  # masks, so it redoes the mesh when they changed; COLMAP's Poisson mesh is kept as it is).
  "$bin/dynmask" -q "${dynmask_opts[@]}" "$ws"
  [ -f "$ws/meshed-poisson.ply" ] || cpu_mesh "$ws"
fi
passes=$(ls "$ws/images" | sed -n 's/^\([^_]*\)_.*/\1/p' | sort -u | wc -l)
# (pickview's record redoes the partners when the poses changed)
if [ "$passes" -ge 2 ]; then "$bin/pickview" --partners "$ws" > /dev/null; fi

log "5. bakedepth, inpaint3d"
"$bin/bakedepth" "$ws"
if [ -d "$ws/masks" ] && [ -f "$ws/partners.tsv" ]; then "$bin/inpaint3d" "$ws"; fi

log "6. ptmrender: every ${holdout}th pose held out (vertex colours, PTM), and a lane change of ${lateral} (model units: metres when the model is metric)"
mapfile -t photos < <(ls "$ws/images")
sel=(); held=()  # the held-out photos' indices and names
for i in $(seq 0 "$holdout" $((${#photos[@]} - 1))); do sel+=("$i"); held+=("${photos[$i]}"); done
# The held-out renders and scores, and the strict hold-out's workspace, are made for one choice
# of held-out photos, from the workspace's model and with the mesh settings: another choice (a
# new HOLDOUT) or model starts them again, so that no frame of an earlier choice is scored and no
# held-out photo is in the strict workspace.
holdout_key="held out: $(printf '%s ' "${held[@]}")
model $(content_of "$ws/sparse")
$mesh_key"
if key_changed holdout "$holdout_key"; then
  rm -rf "$out/heldout_truth" "$out"/heldout_vertex "$out"/heldout_ptm1 "$out"/heldout_ptm "$out/train" \
    "$out"/strict_vertex "$out"/strict_ptm "$out"/ssim_*.tsv "$out/heldout_names.txt" "$out/heldout_poses.txt"
  key_done holdout "$holdout_key"
fi
mkdir -p "$out/heldout_truth"
for k in "${!sel[@]}"; do
  i=${sel[$k]} name=${held[$k]}
  ln -sf "$ws/images/$name" "$out/heldout_truth/${name%.*}.png"
  "$bin/ptmrender" -q --mode vertex --frames "$i" "$ws" "$out/heldout_vertex"
  "$bin/ptmrender" -q --at-images --exclude-self --projectors 1 --no-occlusion --frames "$i" "$ws" "$out/heldout_ptm1"
  "$bin/ptmrender" -q --at-images --exclude-self --frames "$i" "$ws" "$out/heldout_ptm"
done
"$bin/ptmrender" -q --lateral "$lateral" --provenance "$ws" "$out/lane"

log "7. ssim: held-out renders against the real photographs"
for r in vertex ptm1 ptm; do "$bin/ssim" "$out/heldout_$r" "$out/heldout_truth" > "$out/ssim_$r.tsv"; done
# The same renders with the held-out photo's own exposure fitted (ssim --fit-exposure): the photo
# was taken at an exposure no other photo knows; raw scores above, fitted ones here.
"$bin/ssim" --fit-exposure "$out/heldout_ptm" "$out/heldout_truth" > "$out/ssim_ptm_fitted.tsv"
paste "$out/ssim_vertex.tsv" "$out/ssim_ptm1.tsv" "$out/ssim_ptm.tsv" |
  awk -F'\t' 'NR == 1 { printf "%-12s %10s %10s %14s\n", "frame", "vertex", "PTM 1 proj", "PTM all effects"; next }
              { printf "%-12s %10s %10s %14s\n", $1, $2, $6, $10 }'
echo "PTM, all effects, held-out photo's exposure fitted (ssim --fit-exposure): mean SSIM $(awk -F'\t' '$1 == "mean" { print $2 }' "$out/ssim_ptm_fitted.tsv"), PSNR $(awk -F'\t' '$1 == "mean" { print $4 }' "$out/ssim_ptm_fitted.tsv") (raw PSNR $(awk -F'\t' '$1 == "mean" { print $4 }' "$out/ssim_ptm.tsv"))" >&2

if [ "${HOLDOUT_STRICT:-0}" = 1 ]; then
  log "8. strict hold-out: mesh, colours and projectors from a workspace without the held-out photos"
  train=$out/train
  printf '%s\n' "${held[@]}" > "$out/heldout_names.txt"
  if [ ! -d "$train/sparse" ]; then
    mkdir -p "$train"; tmp=$(temp_for "$train/sparse"); mkdir "$tmp"
    colmap_log colmap image_deleter --input_path "$ws/sparse" --output_path "$tmp" \
      --image_names_path "$out/heldout_names.txt"
    ln -sfn "$ws/images" "$train/images"
    commit_whole "$tmp" "$train/sparse"
  fi
  if [ -d "$ws/masks" ]; then ln -sfn "$ws/masks" "$train/masks"; else rm -f "$train/masks"; fi
  mkdir -p "$out/full_txt"
  # The held-out poses of record (images.txt lines of the full model) as ptmrender's trajectory.
  colmap_log colmap model_converter --input_path "$ws/sparse" --output_path "$out/full_txt" --output_type TXT
  awk 'NR == FNR { keep[$1] = 1; next } /^#/ { next }
       ++n % 2 == 1 { ok = ($10 in keep); if (ok) print; next } ok { print "" }' \
    "$out/heldout_names.txt" "$out/full_txt/images.txt" > "$out/heldout_poses.txt"
  cpu_mesh "$train"  # (the records of densify and roadmesh redo it when the masks changed)
  "$bin/exposure" -q "$train"
  "$bin/bakedepth" -q "$train"
  "$bin/ptmrender" -q --mode vertex --poses "$out/heldout_poses.txt" "$train" "$out/strict_vertex"
  "$bin/ptmrender" -q --poses "$out/heldout_poses.txt" "$train" "$out/strict_ptm"
  for r in vertex ptm; do "$bin/ssim" "$out/strict_$r" "$out/heldout_truth" > "$out/ssim_strict_$r.tsv"; done
  echo "strict hold-out (held-out photos in nothing scored) beside leave-one-out:" >&2
  paste "$out/ssim_vertex.tsv" "$out/ssim_strict_vertex.tsv" "$out/ssim_ptm.tsv" "$out/ssim_strict_ptm.tsv" |
    awk -F'\t' 'NR == 1 { printf "%-12s %10s %12s %10s %12s\n", "frame", "vertex", "vertex strict", "PTM", "PTM strict"; next }
                { printf "%-12s %10s %12s %10s %12s\n", $1, $2, $6, $10, $14 }'
fi

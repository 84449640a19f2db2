#!/usr/bin/env bash
# orb2colmap's text and binary output through `colmap model_converter` (the peer tool):
#  - COLMAP reads our text and our binary and writes text identical to ours, value for value at
#    full precision (COLMAP 3.8 writes records in hash-map order, so records are compared
#    sorted by id; headers and each record must match byte for byte);
#  (our binary reader reading COLMAP's binary is checked in io_test, ColmapPeer.*)
# usage: colmap_roundtrip.sh BIN_DIR DATA_DIR     (exit 77 when colmap is not installed)
set -eu
bin=$1 data=$2
command -v colmap >/dev/null || { echo "colmap not installed" >&2; exit 77; }
w=$(mktemp -d); trap 'rm -rf "$w"' EXIT
traj=$data/slam_trajectories/kitti00/KITTI_00_gt.txt
if [ ! -f "$traj" ]; then  # no real data: a synthetic helix with awkward rotations
  /usr/bin/python3 -c "
import numpy as np
from scipy.spatial.transform import Rotation as R
for i in range(500):
    r = R.from_euler('zyx', [0.37*i, 0.011*i, -0.05*i]).as_matrix()
    t = [100*np.cos(0.01*i), 100*np.sin(0.01*i), 0.3*i]
    print(' '.join('%.17g' % v for v in np.hstack([r, np.array(t)[:, None]]).ravel()))" > "$w/poses.txt"
  traj=$w/poses.txt
fi
cam="PINHOLE 1241 376 718.856 718.856 607.1928 185.2157"
"$bin/orb2colmap" -q --camera "$cam" "$traj" "$w/txt"
"$bin/orb2colmap" -q --binary --camera "$cam" "$traj" "$w/bin"
mkdir -p "$w/c_txt" "$w/c_bin"
colmap model_converter --input_path "$w/txt" --output_path "$w/c_txt" --output_type TXT >/dev/null
colmap model_converter --input_path "$w/bin" --output_path "$w/c_bin" --output_type TXT >/dev/null
records() { grep -v '^#' "$1" | paste -d'|' - - | sort -n; }
headers() { grep '^#' "$1"; }
fail=0
for c in c_txt c_bin; do
  for f in cameras points3D; do cmp "$w/txt/$f.txt" "$w/$c/$f.txt" || fail=1; done
  cmp <(headers "$w/txt/images.txt") <(headers "$w/$c/images.txt") || fail=1
  if ! cmp <(records "$w/txt/images.txt") <(records "$w/$c/images.txt"); then
    diff <(records "$w/txt/images.txt") <(records "$w/$c/images.txt") | head -4; fail=1
  fi
done
n=$(grep -vc '^#' "$w/txt/images.txt")
echo "colmap model_converter round trip: $((n / 2)) images, text and binary identical: $([ $fail = 0 ] && echo yes || echo NO)"
exit $fail

#!/usr/bin/env bash
# Label-free vehicle masks on real photos, scored against labels the method never reads.
#
#   examples/label_free.sh [OUT]      (MVTM_DATA: ../shared/data; tools from build/bin)
#
# 1. CamVid 0016E5 (60 photos, one drive) built from its photos alone: examples/road-build.sh
#    with POSES - (COLMAP SfM, self-calibrated camera), densify + roadmesh, then dynmask (the
#    workspace has no labels/) and the mesh again without the masked pixels.
# 2. The CamVid labels of cars, pedestrians and cyclists (classes 8, 9, 10) made into masks and
#    undistorted exactly as the photos were (COLMAP's image_undistorter with the same model), so
#    they line up with the workspace's images; then tests/dynamic/score_masks.py: mean IoU over
#    the frames where they cover at least 0.5 % of the image, pixel precision and recall.
# 3. KITTI 01 and 06 (51 photos each, one drive, no labels exist): built from their photos alone
#    (CAMERA_HEIGHT=1.65), dynmask's masks shown.
# 4. OUT/label_free.png: frames of each sequence with the masks in red (CamVid: the labels'
#    vehicles the masks miss in blue).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
bin=${MVTM_BIN:-$top/build/bin}
data=${MVTM_DATA:-$(cd "$top/.." && pwd)/shared/data}
out=${1:-$top/out/label_free}
py=${MVTM_PYTHON:-/usr/bin/python3}
mkdir -p "$out"
export MVTM_BIN=$bin MESA_SHADER_CACHE_DISABLE=${MESA_SHADER_CACHE_DISABLE:-true}

echo "== CamVid 0016E5 from its photos alone" >&2
bash "$top/examples/road-build.sh" "$data/camvid_0016E5_seg/images" - "$out/camvid" > "$out/camvid.out"
truth=$out/camvid/label_masks
if [ ! -d "$truth/images" ]; then
  rm -rf "$out/camvid/label_in"; mkdir -p "$out/camvid/label_in"
  "$py" - "$data/camvid_0016E5_seg/labels" "$out/camvid/label_in" <<'PY'
import os, sys
import imageio
import numpy as np
src, dst = sys.argv[1], sys.argv[2]
for n in sorted(os.listdir(src)):
    lab = np.asarray(imageio.imread(os.path.join(src, n)))
    imageio.imwrite(os.path.join(dst, n), (np.isin(lab, [8, 9, 10]) * 255).astype(np.uint8))
PY
  colmap image_undistorter --image_path "$out/camvid/label_in" --input_path "$out/camvid/ba" \
    --output_path "$truth" --output_type COLMAP > "$out/camvid/label_undistort.log" 2>&1
fi
echo "CamVid 0016E5, label-free masks against the labels' cars, pedestrians and cyclists:"
"$py" "$top/tests/dynamic/score_masks.py" --masks "$out/camvid/ws/masks" --truth "$truth/images" \
  --min-share 0.005 | tee "$out/camvid_score.tsv"

for s in 01 06; do
  echo "== KITTI $s from its photos alone" >&2
  CAMERA_HEIGHT=1.65 HOLDOUT=4 bash "$top/examples/road-build.sh" \
    "$data/kitti_odom${s}_f000-050/image_0" - "$out/kitti$s" -- \
    --kitti-calib "$data/kitti_odom${s}_f000-050/calib.txt" > "$out/kitti$s.out"
  "$py" - "$out/kitti$s/ws/masks" <<'PY'
import os, sys
import imageio
import numpy as np
d = sys.argv[1]
share = [(np.asarray(imageio.imread(os.path.join(d, n))) > 0).mean() for n in sorted(os.listdir(d))]
print(f"KITTI masks: {100 * np.mean(share):.2f} % of the image on average, "
      f"{100 * np.max(share):.2f} % at most, {sum(s > 0 for s in share)} of {len(share)} frames")
PY
done

"$py" - "$out" <<'PY'
import os, sys
import imageio
import numpy as np
out = sys.argv[1]

def tile(ws, name, truth=None, width=480):
    im = np.asarray(imageio.imread(os.path.join(ws, "images", name))).astype(float)
    if im.ndim == 2:
        im = np.stack([im] * 3, -1)
    im = im[..., :3] * (255.0 / (65535.0 if im.max() > 255 else 255.0))
    m = np.asarray(imageio.imread(os.path.join(ws, "masks", os.path.splitext(name)[0] + ".png"))) > 0
    im[m] = 0.5 * im[m] + 0.5 * np.array([255, 0, 0])
    if truth is not None:
        t = np.asarray(imageio.imread(os.path.join(truth, name)))
        t = t.reshape(t.shape[0], t.shape[1], -1)[..., 0] > 127
        miss = t & ~m
        im[miss] = 0.5 * im[miss] + 0.5 * np.array([0, 0, 255])
    step = max(1, im.shape[1] // width)
    return im[::step, ::step]

rows = []
for seq, truth in (("camvid", os.path.join(out, "camvid", "label_masks", "images")),
                   ("kitti01", None), ("kitti06", None)):
    ws = os.path.join(out, seq, "ws")
    names = sorted(os.listdir(os.path.join(ws, "images")))
    picks = [names[i] for i in np.linspace(0, len(names) - 1, 4).astype(int)]
    tiles = [tile(ws, n, truth) for n in picks]
    h = min(t.shape[0] for t in tiles)
    rows.append(np.concatenate([t[:h] for t in tiles], 1))
w = min(r.shape[1] for r in rows)
imageio.imwrite(os.path.join(out, "label_free.png"),
                np.concatenate([r[:, :w] for r in rows], 0).astype(np.uint8))
print(os.path.join(out, "label_free.png"))
PY

#!/usr/bin/env python3
"""What photos-only SfM accuracy costs: the knobs of examples/road-build.sh's POSES - path (COLMAP
CPU SfM + georef), scored against KITTI's ground-truth poses.

usage: /usr/bin/python3 examples/sweep_sfm.py [--bin build/bin] [--out out/sweep_sfm]
                                              [--data ../shared/data] [--seq kitti_odom01_f000-050]

For each setting, the sequence's left photos go through COLMAP feature_extractor (one shared
PINHOLE camera from calib.txt), sequential_matcher and mapper (intrinsics fixed, COLMAP's default
4 px outlier threshold where road-build.sh uses 2; as road-build.sh, from a wide initial pair, and
again from COLMAP's own and as forward motion while under half the images register), then georef
--camera-height 1.65 --compare poses.txt: registered images, the trajectory's RMS error after a
similarity fit as a share of the path length, and the scale error of the camera-height metric,
against the whole SfM's wall-clock seconds per frame (2 cores; run it on an idle machine).

Knobs: the initial pair (road-build.sh's wide pair, COLMAP's own choice), matching overlap (5,
20; 10, the default, is the initial-pair group's "wide pair" row), SIFT image size
(--SiftExtraction.max_image_size 1241 = full, 800, 500), frame spacing (every 1st, 2nd, 3rd
photo: what frames --spacing chooses on a faster drive), and mapping in stretches joined by
sfmjoin (road-build.sh's SFM_CHUNK: 21 images sharing 6, 30 sharing 8). Writes OUT/sfm.csv,
OUT/sfm.png and OUT/index.html.
"""
import argparse
import os
import re
import shutil
import sqlite3
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import sweeplib as sl  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("--bin", default=os.path.join(HERE, "..", "build", "bin"))
ap.add_argument("--out", default="out/sweep_sfm")
ap.add_argument("--data", default=os.environ.get("MVTM_DATA", os.path.join(HERE, "..", "..", "shared", "data")))
ap.add_argument("--seq", default="kitti_odom01_f000-050")
a = ap.parse_args()
seq = os.path.join(a.data, a.seq)
os.makedirs(a.out, exist_ok=True)
work = os.path.join(a.out, "work")


def camera():
    P0 = [l for l in open(os.path.join(seq, "calib.txt")) if l.startswith("P0:")][0].split()[1:]
    return float(P0[0]), float(P0[5]), float(P0[2]), float(P0[6])


def run(cmd, log):
    with open(log, "a") as f:
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT).returncode


def registered(model):
    r = subprocess.run(["colmap", "model_analyzer", "--path", model], capture_output=True, text=True)
    m = re.search(r"Registered images: *(\d+)", r.stdout + r.stderr)
    return int(m.group(1)) if m else 0


def wide_pair(db, names):
    """road-build.sh's wide_pair: the middle of `names` (name order) and the one farthest from it
    in that order sharing at least 100 verified matches with it, the one ahead on a tie; the
    database's image ids, or None."""
    con = sqlite3.connect(db)
    ids = dict(con.execute("SELECT name, image_id FROM images"))
    order = [ids[n] for n in sorted(names) if n in ids]
    con_rows = {}
    for pid, n, cfg in con.execute("SELECT pair_id, rows, config FROM two_view_geometries"):
        con_rows[pid] = n if cfg >= 2 else 0
    con.close()
    if not order:
        return None
    mk = len(order) // 2
    m = order[mk]
    best = None
    for k, i in enumerate(order):
        if k == mk or con_rows.get(min(m, i) * 2147483647 + max(m, i), 0) < 100:
            continue
        key = (abs(k - mk), k > mk)
        if best is None or key > best[0]:
            best = (key, i)
    return (m, best[1]) if best else None


FORWARD = ["--Mapper.init_min_tri_angle", "1", "--Mapper.init_min_num_inliers", "50",
           "--Mapper.init_max_forward_motion", "1.0"]


def map_best(d, name, db, imgs, log, want, opts, names, wide=True):
    """As road-build.sh: from wide_pair's initial pair (with `wide`), else or when under half of
    `want` images register, COLMAP's own choice, then as forward motion: (the largest model, its
    registered images)."""
    best, best_n = None, 0
    pair = wide_pair(db, names) if wide else None
    tries = []
    if pair:
        tries.append(("_wide", ["--Mapper.init_image_id1", str(pair[0]),
                                "--Mapper.init_image_id2", str(pair[1])] + FORWARD))
    tries += [("", []), ("_forward", FORWARD)]
    for suffix, extra in tries:
        sdir = os.path.join(d, name + suffix)
        os.makedirs(sdir)
        run(["colmap", "mapper", "--database_path", db, "--image_path", imgs, "--output_path", sdir,
             "--Mapper.ba_refine_focal_length", "0", "--Mapper.ba_refine_extra_params", "0",
             "--Mapper.ba_refine_principal_point", "0"] + opts + extra, log)
        for m in sorted(os.listdir(sdir)):
            k = registered(os.path.join(sdir, m))
            if k > best_n:
                best, best_n = os.path.join(sdir, m), k
        if best_n >= (want + 1) // 2:
            break
    return best, best_n


def sfm(name, every=1, overlap=10, max_size=1241, chunk=0, chunk_overlap=8, wide=True):
    d = os.path.join(work, name)
    shutil.rmtree(d, ignore_errors=True)
    imgs = os.path.join(d, "images")
    os.makedirs(imgs)
    names = sorted(os.listdir(os.path.join(seq, "image_0")))[::every]
    for n in names:
        os.symlink(os.path.join(seq, "image_0", n), os.path.join(imgs, n))
    fx, fy, cx, cy = camera()
    db, log = os.path.join(d, "db.db"), os.path.join(d, "colmap.log")
    t0 = time.time()
    run(["colmap", "feature_extractor", "--database_path", db, "--image_path", imgs,
         "--SiftExtraction.use_gpu", "0", "--SiftExtraction.max_image_size", str(max_size),
         "--ImageReader.single_camera", "1", "--ImageReader.camera_model", "PINHOLE",
         "--ImageReader.camera_params", f"{fx},{fy},{cx},{cy}"], log)
    run(["colmap", "sequential_matcher", "--database_path", db, "--SiftMatching.use_gpu", "0",
         "--SequentialMatching.overlap", str(overlap)], log)
    if chunk and chunk < len(names):
        # As road-build.sh's SFM_CHUNK: stretches of `chunk` images sharing `chunk_overlap`, each
        # mapped alone, joined by sfmjoin.
        parts = max(1, (len(names) - chunk_overlap + chunk - chunk_overlap - 1) // (chunk - chunk_overlap))
        models = []
        for k in range(parts):
            s0 = k * (len(names) - chunk_overlap) // parts
            e0 = (k + 1) * (len(names) - chunk_overlap) // parts + chunk_overlap
            lst = os.path.join(d, f"list{k}.txt")
            open(lst, "w").write("\n".join(names[s0:e0]) + "\n")
            m, _ = map_best(d, f"part{k}", db, imgs, log, e0 - s0, ["--image_list_path", lst],
                            names[s0:e0], wide)
            if m:
                models.append(m)
        best = os.path.join(d, "joined")
        if len(models) < parts or run([os.path.join(a.bin, "sfmjoin"), "-q"] + models + [best], log):
            best = None
        best_n = registered(best) if best else 0
    else:
        best, best_n = map_best(d, "sfm", db, imgs, log, len(names), [], names, wide)
    secs = time.time() - t0
    row = {"group": "", "setting": name, "registered": best_n, "frames": len(names),
           "s_per_frame": round(secs / len(names), 2)}
    if best:
        r = subprocess.run([os.path.join(a.bin, "georef"), "-q", "--force", "--camera-height",
                            "1.65", "--compare", os.path.join(seq, "poses.txt"), best,
                            os.path.join(d, "up")], capture_output=True, text=True)
        m = dict(kv.split(" ") for kv in r.stdout.strip().split("\t")[1:]) if r.returncode == 0 else {}
        row["ate_percent"] = float(m.get("ate_percent", "nan"))
        row["scale_error_percent"] = round(100 * abs(float(m.get("reference_scale", "nan")) - 1), 2)
    sl.log("sfm", name, f"{best_n}/{len(names)} registered  ATE {row.get('ate_percent')} %  "
           f"scale {row.get('scale_error_percent')} %  {row['s_per_frame']} s/frame")
    return row


rows = []
for wide in (True, False):
    r = sfm("wide pair" if wide else "COLMAP's own pair", wide=wide)
    r["group"], r["default"] = "initial pair", wide
    rows.append(r)
for ov in (5, 20):
    r = sfm(f"overlap {ov}", overlap=ov)
    r["group"] = "matching overlap"
    rows.append(r)
for size in (800, 500):
    r = sfm(f"SIFT size {size}", max_size=size)
    r["group"] = "image size"
    rows.append(r)
for every in (2, 3):
    r = sfm(f"every {every} frames", every=every)
    r["group"] = "frame spacing"
    rows.append(r)
for chunk, chunk_overlap in ((21, 6), (30, 8)):
    r = sfm(f"stretches of {chunk}, {chunk_overlap} shared", chunk=chunk, chunk_overlap=chunk_overlap)
    r["group"] = "mapped in stretches (SFM_CHUNK)"
    rows.append(r)
fields = ["group", "setting", "registered", "frames", "ate_percent", "scale_error_percent",
          "s_per_frame"]
sec = sl.Section("sfm", f"Photos-only SfM on {a.seq}: trajectory error against time", rows, fields,
                 "Trajectory RMS error after a similarity fit, % of the path length (KITTI's "
                 "poses), against COLMAP's wall-clock seconds per frame (feature extraction, "
                 "sequential matching, mapping; 2 cores).")
sl.emit(a.out, sec, "s_per_frame", "ate_percent", xlabel="seconds per frame",
        ylabel="ATE, % of path", lines=[(0.5, "issue target 0.5 %")])
print(sl.write_page(a.out, [sec], "Photos-only SfM: accuracy against time",
                    "examples/sweep_sfm.py"))

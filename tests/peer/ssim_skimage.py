#!/usr/bin/python3
"""Peer check: `ssim --json` against scikit-image (Debian python3-skimage) within 1e-6.

  ssim_skimage.py --ssim BUILD/bin/ssim --cases hard            # generated cases, no data needed
  ssim_skimage.py --ssim BUILD/bin/ssim --cases real --data DIR # real pairs from $MVTM_DATA

Reference values: SSIM from skimage.metrics.structural_similarity(gaussian_weights=True,
sigma=1.5, use_sample_covariance=False, data_range=R, full=True) (the map, averaged over the
cropped region ∩ mask when there is a mask); PSNR from skimage.metrics.peak_signal_noise_ratio
(numpy on the mask pixels with a mask); NCC from numpy (zero-mean NCC, per channel, averaged).
Exit status: 0 pass, 1 fail, 77 skipped (no scikit-image, or --cases real without the data).
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    from skimage import io
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity
except ImportError as e:  # pragma: no cover
    print(f"SKIP: {e}")
    sys.exit(77)

TOL = 1e-6
TRUNCATE = 3.5


def radius(sigma):
    return int(TRUNCATE * sigma + 0.5)


def reference(a, b, mask=None, sigma=1.5, k1=0.01, k2=0.03, data_range=None):
    """(ssim, ncc, psnr) as documented in man/ssim.1, from scikit-image and numpy."""
    if data_range is None:
        data_range = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}[a.dtype]
    if a.ndim == 3 and a.shape[2] in (2, 4):  # alpha is ignored
        a, b = a[..., :-1], b[..., :-1]
    if a.ndim == 3 and a.shape[2] == 1:
        a, b = a[..., 0], b[..., 0]
    colour = a.ndim == 3
    try:
        _, smap = structural_similarity(
            a, b, gaussian_weights=True, sigma=sigma, use_sample_covariance=False,
            data_range=data_range, K1=k1, K2=k2, full=True, channel_axis=-1 if colour else None)
    except ValueError as e:
        return ("error", str(e))
    mssim = structural_similarity(
        a, b, gaussian_weights=True, sigma=sigma, use_sample_covariance=False,
        data_range=data_range, K1=k1, K2=k2, channel_axis=-1 if colour else None)
    a3 = a.astype(np.float64).reshape(a.shape[0], a.shape[1], -1)
    b3 = b.astype(np.float64).reshape(b.shape[0], b.shape[1], -1)
    inside = np.ones(a.shape[:2], bool) if mask is None else mask
    if mask is None:
        ssim = mssim
        psnr = peak_signal_noise_ratio(a, b, data_range=data_range) if (a != b).any() else math.inf
    else:
        pad = radius(sigma)
        crop = np.zeros_like(inside)
        crop[pad:inside.shape[0] - pad, pad:inside.shape[1] - pad] = True
        sel = inside & crop
        s2 = smap.mean(axis=-1) if colour else smap
        ssim = s2[sel].mean() if sel.any() else math.nan
        mse = ((a3 - b3)[inside] ** 2).mean() if inside.any() else math.nan
        psnr = math.nan if math.isnan(mse) else (
            math.inf if mse == 0 else 10 * math.log10(data_range ** 2 / mse))
    nccs = []
    for c in range(a3.shape[2]):
        x = a3[..., c][inside]
        y = b3[..., c][inside]
        if x.size == 0:
            nccs.append(math.nan)
            continue
        x = x - x.mean()
        y = y - y.mean()
        den = math.sqrt((x * x).sum() * (y * y).sum())
        nccs.append((x * y).sum() / den if den > 0 else math.nan)
    ncc = float(np.mean(nccs))
    return (float(ssim), ncc, float(psnr))


def run_ssim(exe, args):
    p = subprocess.run([exe, "--json"] + args, capture_output=True, text=True)
    if p.returncode != 0:
        return p.returncode, p.stderr.strip()
    return 0, json.loads(p.stdout)


def same(ours, ref, kind):
    """ours: JSON value (None = not finite); ref: float (nan/inf allowed)."""
    if ours is None:
        if kind == "psnr":
            return math.isnan(ref) or math.isinf(ref), 0.0
        return math.isnan(ref), 0.0
    if math.isnan(ref) or math.isinf(ref):
        return False, math.inf
    d = abs(ours - ref)
    return d <= TOL, d


class Checker:
    def __init__(self, exe):
        self.exe = exe
        self.failures = 0
        self.count = 0
        self.maxdiff = {"ssim": 0.0, "ncc": 0.0, "psnr": 0.0}

    def fail(self, name, msg):
        self.failures += 1
        print(f"FAIL {name}: {msg}")

    def compare(self, name, pair, ref):
        self.count += 1
        ok_all = True
        for i, kind in enumerate(("ssim", "ncc", "psnr")):
            ok, d = same(pair[kind], ref[i], kind)
            if not ok:
                ok_all = False
                self.fail(name, f"{kind}: ours {pair[kind]!r} skimage/numpy {ref[i]!r}")
            elif d > self.maxdiff[kind]:
                self.maxdiff[kind] = d
        return ok_all

    def pair(self, name, fa, fb, mask=None, opts=(), **ref_kw):
        args = list(opts) + ([] if mask is None else ["--mask", mask]) + [fa, fb]
        a, b = io.imread(fa), io.imread(fb)
        m = None if mask is None else io.imread(mask) != 0
        if m is not None and m.ndim == 3:
            m = m.any(axis=2)
        ref = reference(a, b, m, **ref_kw)
        rc, out = run_ssim(self.exe, args)
        if ref[0] == "error":
            if rc != 1 or "smaller than the" not in out:
                self.fail(name, f"skimage: {ref[1]}; ours: status {rc}, {out!r}")
            else:
                print(f"ok   {name}: both refuse ({out})")
            return None
        if rc != 0:
            self.fail(name, f"status {rc}: {out}")
            return None
        p = out["pairs"][0]
        if self.compare(name, p, ref):
            print(f"ok   {name}: ssim {p['ssim']} ncc {p['ncc']} psnr {p['psnr']}")
        return p

    def folder(self, name, da, db, mask=None, ref_a=None, ref_b=None, **ref_kw):
        """Folder mode; ref_a/ref_b map a file name to the real file (symlink targets)."""
        args = [da, db] + ([] if mask is None else ["--mask", mask])
        rc, out = run_ssim(self.exe, args)
        if rc != 0:
            self.fail(name, f"status {rc}: {out}")
            return
        ok = 0
        for p in out["pairs"]:
            a = io.imread(os.path.join(da, p["name"]))
            b = io.imread(os.path.join(db, p["name"]))
            m = None
            if mask is not None:
                m = io.imread(os.path.join(mask, p["name"])) != 0
            ref = reference(a, b, m, **ref_kw)
            ok += self.compare(f"{name}/{p['name']}", p, ref)
        print(f"ok   {name}: {ok}/{len(out['pairs'])} pairs within {TOL}")


def hard_cases(c, tmp):
    rng = np.random.default_rng(7)

    def save(name, arr):
        path = os.path.join(tmp, name)
        io.imsave(path, arr, check_contrast=False)
        return path

    smooth = lambda h, w, hi: (  # noqa: E731 — a smooth random image with full-range values
        np.clip(np.cumsum(np.cumsum(rng.normal(size=(h, w)), 0), 1), -40, 40) + 40) / 80 * hi

    # Flat images (zero variance everywhere).
    f100 = save("flat100.png", np.full((48, 64), 100, np.uint8))
    f140 = save("flat140.png", np.full((48, 64), 140, np.uint8))
    c.pair("flat vs flat", f100, f140)
    p = c.pair("flat identical", f100, f100)
    if p and p["ssim"] != 1.0:
        c.fail("flat identical", f"ssim {p['ssim']!r} is not exactly 1")
    # Identical noise images: exactly 1, grey and colour.
    n1 = save("noise.png", rng.integers(0, 256, (57, 83), dtype=np.uint8))
    p = c.pair("identical grey", n1, n1)
    if p and p["ssim"] != 1.0:
        c.fail("identical grey", f"ssim {p['ssim']!r} is not exactly 1")
    rgb1 = save("rgb1.png", rng.integers(0, 256, (40, 50, 3), dtype=np.uint8))
    rgb2 = save("rgb2.png", np.clip(io.imread(rgb1).astype(int)
                                    + rng.integers(-30, 31, (40, 50, 3)), 0, 255).astype(np.uint8))
    p = c.pair("identical colour", rgb1, rgb1)
    if p and p["ssim"] != 1.0:
        c.fail("identical colour", f"ssim {p['ssim']!r} is not exactly 1")
    c.pair("colour noisy", rgb1, rgb2)
    # Random grey pair, odd size.
    n2 = save("noise2.png", rng.integers(0, 256, (57, 83), dtype=np.uint8))
    c.pair("noise vs noise", n1, n2)
    # 16-bit input (data range 65535).
    s1 = smooth(70, 90, 65535).astype(np.uint16)
    s2 = np.clip(s1 + rng.normal(0, 900, s1.shape), 0, 65535).astype(np.uint16)
    c.pair("16-bit", save("s16a.png", s1), save("s16b.png", s2))
    c.pair("16-bit data-range 4096", save("s16c.png", (s1 // 16).astype(np.uint16)),
           save("s16d.png", (s2 // 16).astype(np.uint16)), opts=["--data-range", "4096"],
           data_range=4096.0)
    # Options.
    g1 = save("g1.png", smooth(60, 70, 255).astype(np.uint8))
    g2 = save("g2.png", np.clip(io.imread(g1) + rng.normal(0, 12, (60, 70)), 0, 255).astype(np.uint8))
    c.pair("default options", g1, g2)
    c.pair("sigma 2.5 k1 0.02 k2 0.05", g1, g2,
           opts=["--sigma", "2.5", "--k1", "0.02", "--k2", "0.05"], sigma=2.5, k1=0.02, k2=0.05)
    c.pair("sigma 0.6", g1, g2, opts=["--sigma", "0.6"], sigma=0.6)
    # Window-sized and smaller-than-window images.
    w11a = save("w11a.png", rng.integers(0, 256, (11, 11), dtype=np.uint8))
    w11b = save("w11b.png", rng.integers(0, 256, (11, 11), dtype=np.uint8))
    c.pair("exactly 11x11", w11a, w11b)
    c.pair("10x12 (smaller than the window)", save("s10a.png", np.zeros((10, 12), np.uint8)),
           save("s10b.png", np.ones((10, 12), np.uint8)))
    # Masks: general, one pixel inside the cropped region, one pixel in the border strip, empty.
    m = rng.random((60, 70)) < 0.4
    c.pair("mask 40%", g1, g2, mask=save("m40.png", (m * 255).astype(np.uint8)))
    one = np.zeros((60, 70), np.uint8)
    one[30, 33] = 255
    c.pair("mask one pixel", g1, g2, mask=save("m1.png", one))
    edge = np.zeros((60, 70), np.uint8)
    edge[2, 40] = 255
    c.pair("mask one border pixel", g1, g2, mask=save("m1edge.png", edge))
    p = c.pair("mask empty", g1, g2, mask=save("m0.png", np.zeros((60, 70), np.uint8)))
    if p and (p["ssim"] is not None or p["pixels"] != 0):
        c.fail("mask empty", f"expected null ssim and 0 pixels, got {p}")
    mrgb = rng.random((40, 50)) < 0.5
    c.pair("colour mask", rgb1, rgb2, mask=save("mrgb.png", (mrgb * 255).astype(np.uint8)))


def real_cases(c, data, tmp):
    def linked_folders(name, files_a, files_b, ext):
        da, db = os.path.join(tmp, name, "A"), os.path.join(tmp, name, "B")
        os.makedirs(da)
        os.makedirs(db)
        for i, (fa, fb) in enumerate(zip(files_a, files_b)):
            os.symlink(fa, os.path.join(da, f"{i:04d}{ext}"))
            os.symlink(fb, os.path.join(db, f"{i:04d}{ext}"))
        return da, db

    kitti = sorted(glob.glob(os.path.join(data, "kitti_odom06_f000-050/image_0/*.png")))
    camvid = sorted(glob.glob(os.path.join(data, "camvid_0016E5_seg/images/*.png")))
    labels = sorted(glob.glob(os.path.join(data, "camvid_0016E5_seg/labels/*.png")))
    kitti01 = sorted(glob.glob(os.path.join(data, "kitti_odom01_f000-050/image_0/*.png")))
    depth = sorted(glob.glob(os.path.join(data, "tum_fr1_desk_9frames/depth/*.png")))
    if len(kitti) < 2 or len(camvid) < 2:
        print(f"SKIP: real data not found under {data}")
        sys.exit(77)
    # Every 5th consecutive pair across each sequence: the same variety of content at a fifth of
    # scikit-image's time (CI budget).
    da, db = linked_folders("kitti06", kitti[:-1:5], kitti[1::5], ".png")
    c.folder("kitti06 grey consecutive frames", da, db)
    da, db = linked_folders("camvid", camvid[:-1:5], camvid[1::5], ".png")
    c.folder("camvid colour consecutive frames", da, db)
    # Vehicle masks from the CamVid labels (class 8 = Car), on the pair (frame i, frame i+1).
    dm = os.path.join(tmp, "camvid_masks")
    os.makedirs(dm)
    for i, f in enumerate(labels[:-1:5]):
        io.imsave(os.path.join(dm, f"{i:04d}.png"),
                  ((io.imread(f) == 8) * 255).astype(np.uint8), check_contrast=False)
    c.folder("camvid colour, car masks", da, db, mask=dm)
    if len(kitti01) >= 2:
        c.pair("kitti01 1241x376", kitti01[0], kitti01[1])
        c.pair("kitti01 far frames", kitti01[0], kitti01[-1])
    if len(depth) >= 2:
        da, db = linked_folders("tum_depth16", depth[:-1], depth[1:], ".png")
        c.folder("TUM 16-bit depth consecutive frames", da, db)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ssim", required=True, help="the ssim executable")
    ap.add_argument("--cases", choices=["hard", "real"], required=True)
    ap.add_argument("--data", default=os.environ.get("MVTM_DATA", "../shared/data"))
    args = ap.parse_args()
    c = Checker(args.ssim)
    with tempfile.TemporaryDirectory() as tmp:
        if args.cases == "hard":
            hard_cases(c, tmp)
        else:
            if not os.path.isdir(args.data):
                print(f"SKIP: MVTM_DATA {args.data} is not a folder")
                return 77
            real_cases(c, args.data, tmp)
    d = c.maxdiff
    print(f"{args.cases}: {c.count} comparisons, max |ours - skimage/numpy|: "
          f"ssim {d['ssim']:.3g}, ncc {d['ncc']:.3g}, psnr {d['psnr']:.3g} dB; "
          f"{c.failures} failure(s)")
    return 1 if c.failures else 0


if __name__ == "__main__":
    sys.exit(main())

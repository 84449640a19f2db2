"""Shared helpers of the accuracy-against-time sweeps (examples/sweep.py, sweep_densify.py).

Running the tools and timing them, the mkroad fixture, reading float images, one CSV and one
matplotlib plot per tool, the HTML page that gathers the plots, and the checks that make the short
mode a test. Needs Debian's python3-matplotlib, python3-numpy and python3-openimageio: run it
with /usr/bin/python3.
"""
import csv
import html
import os
import shutil
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker as ticker  # noqa: E402
import numpy as np  # noqa: E402
import OpenImageIO as oiio  # noqa: E402


class Tools:
    """The mvtm programs of one build folder, run with their output captured."""

    def __init__(self, bin_dir):
        self.bin = os.path.abspath(bin_dir)

    def run(self, tool, *args, stdin=None):
        """(stdout, stderr, whole-process wall seconds); a failing tool ends the sweep."""
        cmd = [os.path.join(self.bin, tool), *map(str, args)]
        t0 = time.perf_counter()
        r = subprocess.run(cmd, text=True, input=stdin, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE)
        wall = time.perf_counter() - t0
        if r.returncode != 0:
            raise SystemExit(f"sweep: error: {' '.join(cmd)} exited {r.returncode}: "
                             f"{r.stderr.strip()}")
        return r.stdout, r.stderr, wall

    def best_wall(self, repeat, tool, *args):
        """(stdout, stderr, wall seconds) of the fastest of `repeat` runs (less noise from other
        load), and the slowest run's wall seconds: the spread shows what is noise."""
        runs = [self.run(tool, *args) for _ in range(repeat)]
        return min(runs, key=lambda r: r[2]), max(r[2] for r in runs)

    def mkroad(self, ws, *options):
        """An mkroad workspace at ws (kept when it exists: mkroad is a pure function of options)."""
        stamp = os.path.join(ws, "truth", "mkroad.txt")
        want = " ".join(map(str, options))
        mark = os.path.join(ws, "sweep-options.txt")
        if os.path.exists(stamp) and os.path.exists(mark) and open(mark).read() == want:
            return ws
        shutil.rmtree(ws, ignore_errors=True)
        self.run("mkroad", "--quiet", *options, ws)
        with open(mark, "w") as f:
            f.write(want)
        return ws

    def ssim_mean(self, a, b, *options):
        """The mean SSIM over the pairs of two folders (ssim's "mean" row)."""
        out, _, _ = self.run("ssim", *options, a, b)
        for line in out.splitlines():
            cols = line.split("\t")
            if cols[0] == "mean":
                return float(cols[1])
        raise SystemExit(f"sweep: error: no mean in ssim's table for {a}")


def copy_workspace(src, dst, skip=("truth",), leave_out=()):
    """A private copy of a workspace (truth/ is linked, not copied: the sweeps only read it;
    the names in leave_out are not copied at all)."""
    shutil.rmtree(dst, ignore_errors=True)
    os.makedirs(dst)
    for name in os.listdir(src):
        s, d = os.path.join(src, name), os.path.join(dst, name)
        if name in leave_out:
            continue
        if name in skip:
            os.symlink(os.path.abspath(s), d)
        elif os.path.isdir(s):
            shutil.copytree(s, d)
        else:
            shutil.copy2(s, d)
    return dst


def link_subset(src_dir, names, dst_dir):
    """A folder of symbolic links to src_dir/NAME for each name (ssim pairs folders by name)."""
    shutil.rmtree(dst_dir, ignore_errors=True)
    os.makedirs(dst_dir)
    for n in names:
        os.symlink(os.path.abspath(os.path.join(src_dir, n)), os.path.join(dst_dir, n))
    return dst_dir


def read_float(path):
    """The first channel of an image as float32 (EXR depth maps). Read with ImageInput, not
    ImageBuf: ImageBuf goes through OpenImageIO's image cache, which can hand back the old
    pixels of a file that a tool has since rewritten under the same name."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SystemExit(f"sweep: error: {path}: {oiio.geterror()}")
    spec = inp.spec()
    pixels = inp.read_image(0, 1, oiio.FLOAT)
    inp.close()
    if pixels is None:
        raise SystemExit(f"sweep: error: {path}: cannot read its pixels")
    return pixels.reshape(spec.height, spec.width)


def resample_nearest(img, shape):
    """img looked up at the pixel centres of an image of `shape` (same field of view)."""
    ys = np.minimum(((np.arange(shape[0]) + 0.5) * img.shape[0] / shape[0]).astype(int),
                    img.shape[0] - 1)
    xs = np.minimum(((np.arange(shape[1]) + 0.5) * img.shape[1] / shape[1]).astype(int),
                    img.shape[1] - 1)
    return img[np.ix_(ys, xs)]


def log(section, setting, text):
    print(f"{section:10s} {setting:30s} {text}", file=sys.stderr, flush=True)


def write_csv(path, rows, fields):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def plot(path, rows, x, y, *, xlabel, ylabel, title, logx=False, yscale=None, ylim=None,
         lines=(), xmax=None, label="setting", group="group"):
    """One scatter plot: accuracy (y) against time (x), a colour per group (a line through each
    group's points in order), every point labelled with its setting, the rows whose "default"
    is true ringed (and labelled once: they are one setting, run again in each group).
    lines: (y, text) horizontal references; yscale: a name or (name, keyword arguments);
    xmax: a column with the slowest of the runs, drawn as a bar from the point (the fastest)."""
    fig, ax = plt.subplots(figsize=(8.5, 5.2), dpi=100)
    groups = list(dict.fromkeys(r[group] for r in rows))
    colours = plt.get_cmap("tab10")
    for i, g in enumerate(groups):
        pts = [r for r in rows if r[group] == g]
        ax.plot([r[x] for r in pts], [r[y] for r in pts], "o", color=colours(i % 10), label=g,
                markersize=6, linestyle="-" if len(pts) > 1 else "none", linewidth=0.8,
                alpha=0.9)
        if xmax:
            ax.errorbar([r[x] for r in pts], [r[y] for r in pts], fmt="none",
                        xerr=[[0] * len(pts), [r[xmax] - r[x] for r in pts]],
                        ecolor=colours(i % 10), elinewidth=0.8, alpha=0.5)
        for r in pts:
            if not r.get("default"):
                ax.annotate(r[label], (r[x], r[y]), textcoords="offset points", xytext=(5, 4),
                            fontsize=7.5, color=colours(i % 10))
    d = [r for r in rows if r.get("default")]
    if d:
        ax.plot([r[x] for r in d], [r[y] for r in d], "o", markersize=15,
                markerfacecolor="none", markeredgecolor="black", markeredgewidth=1.5,
                linestyle="none", label="default setting")
        ax.annotate(f"default: {d[0][label]}" if len(d) == 1 else "default", (d[0][x], d[0][y]),
                    textcoords="offset points", xytext=(9, 6), fontsize=7.5)
    for value, text in lines:
        ax.axhline(value, color="grey", linestyle="--", linewidth=1)
        ax.annotate(text, (0.01, value), xycoords=("axes fraction", "data"),
                    textcoords="offset points", xytext=(0, 3), fontsize=7.5, color="grey")
    if logx:
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1, 2, 5)))
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(ticker.NullFormatter())
    if yscale:
        name, kw = yscale if isinstance(yscale, tuple) else (yscale, {})
        ax.set_yscale(name, **kw)
    if ylim:
        ax.set_ylim(*ylim)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


class Section:
    """One tool's part of the page: its CSV, its plot and a caption."""

    def __init__(self, tool, title, rows, fields, caption, note=""):
        self.tool, self.title, self.rows, self.fields = tool, title, rows, fields
        self.caption, self.note = caption, note
        self.csv, self.png = f"{tool}.csv", f"{tool}.png"


def write_page(out, sections, heading, intro):
    """OUT/index.html: every section's plot, caption and table, in order."""
    h = html.escape
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{h(heading)}</title>",
        "<style>body{font-family:sans-serif;max-width:60em;margin:2em auto;line-height:1.4}"
        "table{border-collapse:collapse;font-size:85%}td,th{border:1px solid #ccc;"
        "padding:2px 6px;text-align:right}td:first-child,td:nth-child(2){text-align:left}"
        "img{max-width:100%}section{margin-bottom:3em}</style></head><body>",
        f"<h1>{h(heading)}</h1>", f"<p>{intro}</p>", "<ul>"]
    parts += [f'<li><a href="#{s.tool}">{h(s.title)}</a></li>' for s in sections]
    parts.append("</ul>")
    for s in sections:
        parts += [f'<section id="{s.tool}"><h2>{h(s.title)}</h2>',
                  f'<img src="{s.png}" alt="{h(s.title)}: accuracy against time">',
                  f"<p>{s.caption}</p>"]
        if s.note:
            parts.append(f"<p><em>{s.note}</em></p>")
        parts.append(f'<details><summary>The numbers (<a href="{s.csv}">{s.csv}</a>)'
                     "</summary><table><tr>")
        parts += [f"<th>{h(f)}</th>" for f in s.fields]
        parts.append("</tr>")
        for r in s.rows:
            parts.append("<tr>" + "".join(f"<td>{h(str(r.get(f, '')))}</td>" for f in s.fields)
                         + "</tr>")
        parts.append("</table></details></section>")
    parts.append("</body></html>")
    path = os.path.join(out, "index.html")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(parts) + "\n")
    os.replace(path + ".tmp", path)
    return path


def emit(out, section, x, y, plot_rows=None, **plot_args):
    """Write a section's CSV (every row) and plot (plot_rows, default every row) into out."""
    write_csv(os.path.join(out, section.csv), section.rows, section.fields)
    plot(os.path.join(out, section.png), section.rows if plot_rows is None else plot_rows, x, y,
         title=section.title, **plot_args)
    return section


class Checks:
    """Named pass/fail checks; the sweep exits 1 when one failed."""

    def __init__(self):
        self.failed = []

    def __call__(self, ok, what):
        print(f"check {'ok  ' if ok else 'FAIL'} {what}", file=sys.stderr, flush=True)
        if not ok:
            self.failed.append(what)
        return ok

    def page(self, out, sections):
        """The page references every plot and CSV written, and each one exists."""
        text = open(os.path.join(out, "index.html")).read()
        for s in sections:
            for f in (s.png, s.csv):
                self(os.path.exists(os.path.join(out, f)) and f'"{f}"' in text,
                     f"index.html references {f} and it exists")
        pngs = sorted(f for f in os.listdir(out) if f.endswith(".png"))
        self(all(f'src="{p}"' in text for p in pngs), f"index.html shows every plot ({pngs})")

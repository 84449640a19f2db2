"""Helpers of the rerun_new_inputs case: COLMAP text models and a PLY's vertices."""
import sys

import numpy as np


def rotation(qw, qx, qy, qz):
    """The world-to-camera rotation of a COLMAP quaternion."""
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])


def pose_lines(path):
    """(index, fields) of each image line of an images.txt (every other non-comment line)."""
    lines = open(path).read().split("\n")
    body = [i for i, l in enumerate(lines) if l and not l.startswith("#")]
    return lines, body[0::2]


def centres(path):
    """Camera centre of each image of an images.txt, by name."""
    lines, heads = pose_lines(path)
    out = {}
    for i in heads:
        f = lines[i].split()
        q = [float(v) for v in f[1:5]]
        t = np.array([float(v) for v in f[5:8]])
        out[f[9]] = -rotation(*q).T @ t
    return out


def shift(src, dst, d):
    """images.txt with the world moved by d: each centre C becomes C + d (t' = t - R d)."""
    lines, heads = pose_lines(src)
    for i in heads:
        f = lines[i].split()
        r = rotation(*[float(v) for v in f[1:5]])
        t = np.array([float(v) for v in f[5:8]]) - r @ d
        f[5:8] = ["%.17g" % v for v in t]
        lines[i] = " ".join(f)
    open(dst, "w").write("\n".join(lines))


def vertex_median(path):
    """Median (per coordinate) of a binary little-endian PLY's vertex positions."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    types = {"float": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1", "int": "<i4",
             "uint": "<u4", "short": "<i2", "ushort": "<u2", "char": "i1"}
    fields, count, in_vertex = [], 0, False
    for line in data[:end].decode().split("\n"):
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count, in_vertex = int(w[2]), True
        elif w[:1] == ["element"]:
            in_vertex = False
        elif w[:1] == ["property"] and in_vertex:
            fields.append((w[2], types[w[1]]))
    v = np.frombuffer(data, dtype=np.dtype(fields), count=count, offset=end)
    return np.array([np.median(v[c].astype(float)) for c in "xyz"])


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "shift":
        shift(sys.argv[2], sys.argv[3], np.array([float(v) for v in sys.argv[4].split(",")]))
    elif cmd == "centres_off":  # largest distance between the centres of two images.txt
        a, b = centres(sys.argv[2]), centres(sys.argv[3])
        print("%.6f" % max(np.linalg.norm(a[n] - b[n]) for n in a))
    elif cmd == "median":
        print(" ".join("%.6f" % v for v in vertex_median(sys.argv[2])))

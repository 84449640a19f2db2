#!/usr/bin/python3
"""Scores a georeferenced model (georef --gps) against true UTM positions.

usage: score_utm.py MODEL_TXT_DIR GEOREF_JSON TRUTH_UTM [--match number|order]
TRUTH_UTM  lines "t easting northing altitude" (make_gps.py --truth-utm), row k = the image
           whose name's number is k (--match number) or the k-th image by name (order).
Prints: horizontal RMS (m), 3-D RMS (m), and the model's metres per true metre (the scale of the
similarity from the model's centres to the truth; 1 = metric).
"""
import json
import os
import sys

import numpy as np

model, gj, truth = sys.argv[1:4]
match = sys.argv[5] if len(sys.argv) > 5 and sys.argv[4] == "--match" else "number"
g = json.load(open(gj))
origin = np.array(g["crs"]["origin"])
T = np.array([list(map(float, l.split()[1:4])) for l in open(truth) if l.strip()])
lines = [l for l in open(os.path.join(model, "images.txt")) if not l.startswith("#")]
cams = []
for l in lines[0::2]:
    f = l.split()
    w, x, y, z = map(float, f[1:5])
    t = np.array(list(map(float, f[5:8])))
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-w*z), 2*(x*z+w*y)], [2*(x*y+w*z), 1-2*(x*x+z*z), 2*(y*z-w*x)],
                  [2*(x*z-w*y), 2*(y*z+w*x), 1-2*(x*x+y*y)]])
    cams.append((f[9], -R.T @ t + origin))
cams.sort()
A, B = [], []
for k, (name, c) in enumerate(cams):
    idx = int(os.path.splitext(name)[0]) if match == "number" else k
    if idx < len(T):
        A.append(c)
        B.append(T[idx])
A, B = np.array(A), np.array(B)
d = A - B
a, b = A - A.mean(0), B - B.mean(0)
U, S, Vt = np.linalg.svd(b.T @ a)
D = np.eye(3)
D[2, 2] = np.sign(np.linalg.det(U @ Vt))
s = (S * np.diag(D)).sum() / (a ** 2).sum()
print("horizontal_rms\t%.3f\trms_3d\t%.3f\tmodel_metres_per_metre\t%.4f\tn\t%d" %
      (np.sqrt((d[:, :2] ** 2).sum(1).mean()), np.sqrt((d ** 2).sum(1).mean()), 1 / s, len(A)))

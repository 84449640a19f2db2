#!/usr/bin/python3
"""A GPS log of a known trajectory, for tests: positions sampled at RATE Hz, placed at a UTM
origin, turned by HEADING, with Gaussian noise, written as GPX or NMEA (RMC + GGA). Coordinates
go through PROJ (pyproj), a library mvtm does not use, so the test's truth is independent of
mvtm's GeographicLib path.

usage: make_gps.py TRAJ OUT [--format gpx|nmea] [--axes kitti|enu] [--times TIMES]
         [--zone 32] [--south] [--origin E,N,ALT] [--heading DEG] [--rate HZ] [--noise M]
         [--alt-noise M] [--seed N] [--start ISO] [--no-time] [--bad-checksum-every K]
         [--truth-utm OUT.tsv]
TRAJ   TUM (t x y z qx qy qz qw) or KITTI (12 numbers a line; times from --times, else 0.1 s apart)
--axes kitti: world x right, y down, z forward (KITTI's first camera): east = x, north = z,
       up = -y; enu: x east, y north, z up (mkroad).
--truth-utm writes each trajectory row's exact UTM position: t easting northing altitude.
"""
import argparse
import datetime
import math

import numpy as np
from pyproj import Transformer

ap = argparse.ArgumentParser()
ap.add_argument("traj")
ap.add_argument("out")
ap.add_argument("--format", default="gpx", choices=["gpx", "nmea"])
ap.add_argument("--axes", default="kitti", choices=["kitti", "enu"])
ap.add_argument("--times")
ap.add_argument("--zone", type=int, default=32)
ap.add_argument("--south", action="store_true")
ap.add_argument("--origin", default="455000,5429000,115")
ap.add_argument("--heading", type=float, default=30.0)
ap.add_argument("--rate", type=float, default=1.0)
ap.add_argument("--noise", type=float, default=3.0)
ap.add_argument("--alt-noise", type=float, default=5.0)
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--start", default="2011-09-26T13:02:25Z")
ap.add_argument("--no-time", action="store_true")
ap.add_argument("--bad-checksum-every", type=int, default=0)
ap.add_argument("--truth-utm")
a = ap.parse_args()

rows = [list(map(float, l.split())) for l in open(a.traj) if l.strip() and not l.startswith("#")]
if len(rows[0]) == 12:
    pos = np.array([[r[3], r[7], r[11]] for r in rows])
    t = np.loadtxt(a.times) if a.times else 0.1 * np.arange(len(rows))
else:
    pos = np.array([r[1:4] for r in rows])
    t = np.array([r[0] for r in rows])
if a.axes == "kitti":
    enu = np.stack([pos[:, 0], pos[:, 2], -pos[:, 1]], axis=1)
else:
    enu = pos.copy()
h = math.radians(a.heading)
R = np.array([[math.cos(h), -math.sin(h), 0], [math.sin(h), math.cos(h), 0], [0, 0, 1]])
E0, N0, A0 = map(float, a.origin.split(","))
utm = (R @ enu.T).T + np.array([E0, N0, A0])
epsg = (32700 if a.south else 32600) + a.zone
to_geo = Transformer.from_crs(f"EPSG:{epsg}", "EPSG:4326", always_xy=True)
if a.truth_utm:
    with open(a.truth_utm, "w") as f:
        for ti, u in zip(t, utm):
            f.write("%.6f %.4f %.4f %.4f\n" % (ti, *u))
start = datetime.datetime.fromisoformat(a.start.replace("Z", "+00:00"))
rng = np.random.default_rng(a.seed)
samples = np.arange(t[0], t[-1] + 1e-9, 1.0 / a.rate)
pts = []
for s in samples:
    u = np.array([np.interp(s, t, utm[:, k]) for k in range(3)])
    u[:2] += rng.normal(0, a.noise, 2)
    u[2] += rng.normal(0, a.alt_noise)
    lon, lat = to_geo.transform(u[0], u[1])
    pts.append((start + datetime.timedelta(seconds=float(s - t[0])), lat, lon, u[2]))


def nmea(body):
    c = 0
    for ch in body:
        c ^= ord(ch)
    return "$%s*%02X" % (body, c)


def dm(v, deg_digits, pos, neg):
    hemi = pos if v >= 0 else neg
    v = abs(v)
    d = int(v)
    m = (v - d) * 60
    return ("%0*d%07.4f" % (deg_digits, d, m)), hemi


with open(a.out, "w") as f:
    if a.format == "gpx":
        f.write('<?xml version="1.0" encoding="UTF-8"?>\n'
                '<gpx version="1.1" creator="mvtm tests/gps/make_gps.py" '
                'xmlns="http://www.topografix.com/GPX/1/1">\n<trk><name>drive</name><trkseg>\n')
        for when, lat, lon, alt in pts:
            f.write('<trkpt lat="%.9f" lon="%.9f"><ele>%.3f</ele>' % (lat, lon, alt))
            if not a.no_time:
                f.write("<time>%sZ</time>" % when.strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3])
            f.write("</trkpt>\n")
        f.write("</trkseg></trk>\n</gpx>\n")
    else:
        for k, (when, lat, lon, alt) in enumerate(pts):
            hms = when.strftime("%H%M%S.") + "%02d" % (when.microsecond // 10000)
            la, lh = dm(lat, 2, "N", "S")
            lo, oh = dm(lon, 3, "E", "W")
            gga = nmea("GPGGA,%s,%s,%s,%s,%s,1,08,0.9,%.2f,M,47.0,M,," % (hms, la, lh, lo, oh, alt))
            rmc = nmea("GPRMC,%s,A,%s,%s,%s,%s,10.0,30.0,%s,,,A" % (hms, la, lh, lo, oh,
                                                                  when.strftime("%d%m%y")))
            if a.bad_checksum_every and k % a.bad_checksum_every == 0:
                rmc = rmc[:-2] + ("00" if rmc[-2:] != "00" else "01")
            f.write(gga + "\r\n" + rmc + "\r\n")

# A synthetic eye-tracker trace for gazemap (GAZE: time, x, y, valid) on the steered drive of
# examples/steer-controls.awk (frames at 0 .. 7.8 s), used by main-job.sh and Makefile.examples.
#
# 120 Hz, screen pixels of the frames shown full screen at 1920x576: fixations (start end x y:
# the road ahead, the sky, a tree on the left, the road ahead again (a building: the car heads
# right in its lane change) with a 120 ms blink inside, the outer lane, the inside of the curve,
# a facade, the road ahead), 40 ms saccades between them, +-1.5 px of deterministic tracker noise.
BEGIN {
  n = split("0 0.80 990 372 | 0.84 1.50 960 15 | 1.54 2.30 120 180 | 2.34 3.30 960 340 | " \
            "3.34 4.20 1300 470 | 4.24 5.50 660 348 | 5.54 6.40 1680 210 | 6.44 7.85 960 360",
            f, / \| /)
  for (k = 1; k <= n; k++) {
    split(f[k], a, " ")
    t0[k] = a[1]; t1[k] = a[2]; fx[k] = a[3]; fy[k] = a[4]
  }
  print "time\tx\ty\tvalid"
  for (i = 0; i / 120 <= t1[n]; i++) {
    t = i / 120
    for (k = 1; k < n && t > t1[k]; k++) ;
    if (t >= t0[k]) {            # fixation k
      x = fx[k]; y = fy[k]
    } else {                     # saccade from fixation k-1 to k
      u = (t - t1[k-1]) / (t0[k] - t1[k-1])
      x = fx[k-1] + u * (fx[k] - fx[k-1]); y = fy[k-1] + u * (fy[k] - fy[k-1])
    }
    x += 1.5 * sin(1.7 * i); y += 1.5 * cos(2.3 * i)
    if (t >= 2.70 && t < 2.82) printf "%.6f\tnan\tnan\t0\n", t    # the blink
    else printf "%.6f\t%.2f\t%.2f\t1\n", t, x, y
  }
}

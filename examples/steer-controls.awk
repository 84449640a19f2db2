# A steering log for drive (CONTROLS: time, steering-wheel degrees, m/s) on mkroad's synthetic
# road, used by main-job.sh and Makefile.examples
# (awk -f examples/steer-controls.awk > controls.tsv).
#
# The road (tests/fixtures/mkroad): straight along x to x = 40 m, then a left curve of 60 m radius
# (1 rad); lanes 3.5 m wide, drive A in the lane at -1.75 m (right of the centre line). At 10 m/s
# from A_0000.png: a sine of steering (peak 53.6 deg over 3 s) moves the car 3.5 m right into the
# outer lane, which it follows into the curve at a constant steer, 15 * atan(2.7 m / 65.25 m) =
# 35.54 deg (drive's default steering ratio 15 and wheelbase 2.7 m). A sample holds until the
# next one, so it takes the profile's mid-interval value. 7.8 s, 78 m: the curve is 0.6 rad in,
# the car still among the photographs (0 to 80 m).
BEGIN {
  pi = atan2(0, -1)
  print "time\tsteer\tspeed"
  for (i = 0; i <= 78; i++) {
    t = i / 10
    s = 0
    if (t >= 0.5 && t < 3.5) s = -53.6 * sin(2 * pi * (t + 0.05 - 0.5) / 3)
    else if (t >= 4.0) s = 35.54
    printf "%.1f\t%.2f\t10\n", t, s
  }
}

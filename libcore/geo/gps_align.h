// mvtm — a model's camera centres aligned to a GPS log: UTM, time synchronisation, a robust
// similarity in the horizontal plane, and the scale from GPS fused with the camera height's.
//
// A consumer GPS fix is good to a few metres horizontally and worse vertically, while the road
// under the cameras gives up (gravity) far better (scene/upright.h). So the model is first made
// upright (z up), then only what GPS knows well is taken from it:
//  * UTM: every fix is projected (GeographicLib, WGS84) into the UTM zone of the first fix
//    (forced, so a track across a zone border stays in one grid; the southern hemisphere's
//    northings are carried on across the equator).
//  * Time: the frame at time t (seconds) is at GPS time t0 + offset + t, t0 the log's first fix
//    (so by default the log and the video start together); frames whose times are already
//    absolute (> 1e8 s: seconds since 1970) are at t + offset. Each fix within the frames' span
//    is paired with the camera centre interpolated linearly between the two frames around its
//    time (not the other way round: the fixes are the independent measurements, and a 10 Hz
//    video between 1 Hz fixes would count each fix's error ten times); fixes between frames
//    more than `max_gap` seconds apart are left out. With `search` > 0, the offset is searched
//    in [offset − search, offset + search] (0.1 s steps, then 0.01 s around the best) for the
//    least median of squared residuals of the fit below: a wrong offset moves every camera
//    along the drive and the residuals grow, but only where speed or curvature changes: at a
//    constant speed on a straight or an arc a time shift is a translation or rotation the
//    similarity absorbs, and there the offset cannot be told (nor does it matter much).
//  * Horizontal similarity (scale, rotation about z, translation) from the cameras' (x, y) to the
//    fixes' (easting, northing): least median of squares over two pairs (every pair up to
//    2000, else a seeded sample), the inliers within 2.5 robust sigmas, then least squares on
//    them (closed form, complex numbers). Its scale's standard error is σ/√Σ|p−p̄|² with σ the
//    residual RMS.
//  * Scale: with a camera-height scale given (relative standard error `height_sigma`, 2 % by
//    default: KITTI 01 measured 1.7 %), the two are fused by inverse variance, and rotation and
//    translation are solved again at the fused scale; else GPS alone.
//  * Height: z is offset so that the cameras sit at the fixes' altitudes (the median offset over
//    the inliers: the antenna is taken to be at the camera); without altitudes in the log, the
//    origin's altitude is 0 and z = 0 stays the road under the first camera.
// The result maps upright model coordinates to a local frame in metres: x east, y north, z up,
// about an origin (easting, northing, altitude rounded to whole metres) recorded with the zone, so
// UTM = origin + local; local coordinates stay small, for float renderers.
// Thread safety: pure functions.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geo/gps_log.h"
#include "geometry/align.h"

namespace mvtm {

struct UtmZone {
  int zone = 0;  // 1..60 (0: UPS, polar)
  bool north = true;
  int Epsg() const;          // WGS 84 / UTM zone, or UPS North (32661) / South (32761)
  std::string Name() const;  // "32N"
};

// Easting and northing of (lat, lon) in `zone` (forced), metres.
Eigen::Vector2d ToUtm(const UtmZone& zone, double lat, double lon);
// The standard zone of (lat, lon).
UtmZone ZoneOf(double lat, double lon);

struct GpsAlignOptions {
  double offset = 0;           // seconds, see above
  double search = 0;           // seconds either side of `offset` searched for the best (0: none)
  double max_gap = 10;         // seconds between fixes to interpolate across
  double height_scale = 0;     // metres per model unit from the camera height (0: none)
  double height_sigma = 0.02;  // its relative standard error
};

struct GpsAlignment {
  Sim3 T;  // upright model → local metres (x east, y north, z up about `origin`)
  UtmZone zone;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // easting, northing, altitude (m)
  bool has_altitude = false;
  size_t frames = 0, matched = 0;  // frames, and those within the log's span
  size_t pairs = 0, inliers = 0;   // fixes paired with an interpolated camera, inliers of those
  double rms = 0;                  // horizontal residual RMS of the inliers, metres
  double scale_gps = 0, scale_gps_sigma = 0;  // metres per model unit from GPS alone
  std::string scale_source;                   // "gps" or "gps+camera-height"
  double log_start = 0, log_end = 0;          // the log's times (s since 1970)
  double offset = 0;                          // the offset used (searched, or as given)
};

// Aligns cameras at `centres` (upright model coordinates, z up) taken at `times` (seconds) to
// `log`. Throws Error (naming `log_name`) when fewer than 3 frames fall within the log, with the
// two time spans in the message, or when those frames do not move (no horizontal extent).
GpsAlignment AlignToGps(const std::vector<Eigen::Vector3d>& centres,
                        const std::vector<double>& times, const GpsLog& log,
                        const std::string& log_name, const GpsAlignOptions& options);

}  // namespace mvtm

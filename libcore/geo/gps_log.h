// mvtm — GPS logs: a GPX track or an NMEA 0183 log → timed WGS84 fixes.
//
// GPX (1.0/1.1, parsed with pugixml): every <trkpt lat lon> of every track segment (and <rtept>,
// <wpt> when the file has no track points), its <ele> (metres) and <time> (ISO 8601 / RFC 3339:
// 2011-09-26T13:02:25Z, fractional seconds and ±hh:mm offsets allowed). A point without a time
// cannot be synchronised to the frames: a GPX whose points have no <time> is an Error.
// NMEA: $xxRMC (time, status A = valid, latitude, longitude, date) and $xxGGA (time, latitude,
// longitude, fix quality > 0, altitude above mean sea level), any talker (GP, GN, GL, GA, BD);
// each sentence's checksum (*hh, XOR of the characters between $ and *) is checked, and a
// sentence with a wrong or missing checksum is skipped and counted. A fix is an RMC sentence
// (it carries the date), with the altitude of the GGA sentence of the same time when there is
// one; times of day before the previous fix's wrap to the next day. A log without a valid RMC
// sentence has no date: an Error.
// Fixes come out sorted by time (seconds since 1970-01-01 UTC), duplicates of one time merged.
// Bad data (no fix at all, unreadable numbers in a valid sentence, latitudes beyond ±90) is an
// Error naming FILE:LINE.
// Thread safety: pure functions.
#pragma once

#include <cstddef>
#include <istream>
#include <string>
#include <vector>

namespace mvtm {

struct GpsFix {
  double time = 0;          // seconds since 1970-01-01 00:00:00 UTC
  double lat = 0, lon = 0;  // degrees, WGS84
  double alt = 0;           // metres (GPX <ele>, NMEA GGA altitude)
  bool has_alt = false;
};

struct GpsLog {
  std::string format;  // "gpx" or "nmea"
  std::vector<GpsFix> fixes;
  size_t bad_checksums = 0;  // NMEA sentences skipped for their checksum
  size_t invalid = 0;        // NMEA sentences without a valid fix (RMC status V, GGA quality 0)
};

// Reads a GPX or NMEA file (told apart by content: '<' first → GPX, '$' lines → NMEA).
GpsLog ReadGpsLog(const std::string& path);
GpsLog ReadGpsLog(std::istream& in, const std::string& name);

// Seconds since 1970-01-01 UTC of an ISO 8601 date-time (YYYY-MM-DDThh:mm:ss[.fff](Z|±hh:mm));
// false when `text` is not one.
bool ParseIsoTime(const std::string& text, double& seconds);
// The other way: "YYYY-MM-DDThh:mm:ss.sssZ" (UTC, milliseconds).
std::string FormatIsoTime(double seconds);

}  // namespace mvtm

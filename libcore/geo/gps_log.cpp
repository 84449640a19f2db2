#include "geo/gps_log.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <pugixml.hpp>
#include <sstream>

#include "base/error.h"

namespace mvtm {

namespace {

// Days from 1970-01-01 to y-m-d in the proleptic Gregorian calendar (Howard Hinnant's
// days_from_civil), so no time zone or locale of the machine enters.
long DaysFromCivil(long y, long m, long d) {
  y -= m <= 2;
  const long era = (y >= 0 ? y : y - 399) / 400;
  const long yoe = y - era * 400;
  const long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

// The inverse (Hinnant's civil_from_days).
void CivilFromDays(long z, long& y, long& m, long& d) {
  z += 719468;
  const long era = (z >= 0 ? z : z - 146096) / 146097;
  const long doe = z - era * 146097;
  const long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const long doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const long mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = yoe + era * 400 + (m <= 2);
}

bool Digits(const std::string& s, size_t pos, size_t n, long& out) {
  if (pos + n > s.size()) return false;
  out = 0;
  for (size_t i = pos; i < pos + n; ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
    out = out * 10 + (s[i] - '0');
  }
  return true;
}

bool ParseDouble(const std::string& s, double& out) {
  if (s.empty()) return false;
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return end && *end == '\0' && std::isfinite(out);
}

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// NMEA ddmm.mmmm / dddmm.mmmm with its hemisphere letter → signed degrees.
bool ParseNmeaAngle(const std::string& v, const std::string& hemi, int deg_digits, double& out) {
  if (v.size() < static_cast<size_t>(deg_digits) + 2) return false;
  long deg;
  double min;
  if (!Digits(v, 0, static_cast<size_t>(deg_digits), deg) ||
      !ParseDouble(v.substr(static_cast<size_t>(deg_digits)), min) || min < 0 || min >= 60)
    return false;
  out = static_cast<double>(deg) + min / 60;
  if (hemi == "S" || hemi == "W")
    out = -out;
  else if (hemi != "N" && hemi != "E")
    return false;
  return true;
}

// hhmmss[.sss] → seconds of the day.
bool ParseNmeaTime(const std::string& v, double& out) {
  long h, m;
  double s;
  if (v.size() < 6 || !Digits(v, 0, 2, h) || !Digits(v, 2, 2, m) || !ParseDouble(v.substr(4), s) ||
      h > 23 || m > 59 || s < 0 || s >= 61)
    return false;
  out = static_cast<double>(h * 3600 + m * 60) + s;
  return true;
}

void CheckLatLon(const std::string& name, long line, double lat, double lon) {
  if (!(std::abs(lat) <= 90) || !(std::abs(lon) <= 180))
    throw Error(name, line,
                "latitude/longitude out of range (" + std::to_string(lat) + ", " +
                    std::to_string(lon) + ")");
}

void SortAndMerge(std::vector<GpsFix>& fixes) {
  std::stable_sort(fixes.begin(), fixes.end(),
                   [](const GpsFix& a, const GpsFix& b) { return a.time < b.time; });
  std::vector<GpsFix> out;
  for (const GpsFix& f : fixes)
    if (out.empty() || f.time > out.back().time) out.push_back(f);
  fixes.swap(out);
}

GpsLog ReadGpx(const std::string& text, const std::string& name) {
  pugi::xml_document doc;
  const pugi::xml_parse_result r = doc.load_buffer(text.data(), text.size());
  if (!r) {
    const long line =
        1 + static_cast<long>(std::count(
                text.begin(),
                text.begin() + std::min<ptrdiff_t>(r.offset, static_cast<ptrdiff_t>(text.size())),
                '\n'));
    throw Error(name, line, std::string("not a well-formed GPX file: ") + r.description());
  }
  const pugi::xml_node gpx = doc.child("gpx");
  if (!gpx) throw Error(name, 0, "not a GPX file (no <gpx> element)");
  GpsLog log;
  log.format = "gpx";
  size_t points = 0;
  auto take = [&](const pugi::xml_node& pt) {
    ++points;
    const pugi::xml_node time = pt.child("time");
    double t;
    if (!time || !ParseIsoTime(time.text().as_string(), t)) return;
    GpsFix f;
    f.time = t;
    if (!ParseDouble(pt.attribute("lat").as_string(), f.lat) ||
        !ParseDouble(pt.attribute("lon").as_string(), f.lon))
      throw Error(
          name, 0,
          "a point without a readable lat/lon (time " + std::string(time.text().as_string()) + ")");
    CheckLatLon(name, 0, f.lat, f.lon);
    if (pt.child("ele")) f.has_alt = ParseDouble(pt.child("ele").text().as_string(), f.alt);
    log.fixes.push_back(f);
  };
  for (const pugi::xml_node& trk : gpx.children("trk"))
    for (const pugi::xml_node& seg : trk.children("trkseg"))
      for (const pugi::xml_node& pt : seg.children("trkpt")) take(pt);
  if (points == 0) {
    for (const pugi::xml_node& rte : gpx.children("rte"))
      for (const pugi::xml_node& pt : rte.children("rtept")) take(pt);
    for (const pugi::xml_node& pt : gpx.children("wpt")) take(pt);
  }
  if (points == 0) throw Error(name, 0, "the GPX file has no track, route or way points");
  if (log.fixes.empty())
    throw Error(name, 0,
                "none of the GPX file's " + std::to_string(points) +
                    " points has a <time>: it cannot be synchronised to the frames");
  SortAndMerge(log.fixes);
  return log;
}

struct NmeaSentence {
  std::vector<std::string> f;  // fields, f[0] = "GPRMC" etc.
  long line = 0;
};

// The sentence on `raw` when its checksum is right; false (and `bad` set) when it is wrong.
bool ParseSentence(std::string raw, NmeaSentence& s, bool& bad) {
  bad = false;
  while (!raw.empty() && (raw.back() == '\r' || raw.back() == '\n' || raw.back() == ' '))
    raw.pop_back();
  const size_t dollar = raw.find('$');
  if (dollar == std::string::npos) return false;
  raw = raw.substr(dollar + 1);
  const size_t star = raw.rfind('*');
  if (star == std::string::npos || star + 3 != raw.size()) {
    bad = true;
    return false;
  }
  unsigned sum = 0;
  for (size_t i = 0; i < star; ++i) sum ^= static_cast<unsigned char>(raw[i]);
  char* end = nullptr;
  const std::string hex = raw.substr(star + 1);
  const unsigned long want = std::strtoul(hex.c_str(), &end, 16);
  if (!end || *end != '\0' || want != sum) {
    bad = true;
    return false;
  }
  s.f = Split(raw.substr(0, star), ',');
  return s.f.size() >= 1 && s.f[0].size() == 5;
}

struct Rmc {
  double tod;  // seconds of the day
  long days;   // since 1970-01-01
  double lat, lon;
};

// The fixes of the RMC sentences in order, each with the altitude of the GGA sentence of its
// time of day; a date that stays behind after midnight is carried on.
std::vector<GpsFix> NmeaFixes(const std::vector<Rmc>& rmc, const std::map<long, double>& gga_alt) {
  std::vector<GpsFix> fixes;
  double prev = -1;
  long day_carry = 0;
  for (const Rmc& r : rmc) {
    GpsFix fx;
    fx.lat = r.lat;
    fx.lon = r.lon;
    fx.time = static_cast<double>(r.days + day_carry) * 86400 + r.tod;
    // A receiver that reports the old date for a moment after midnight.
    if (prev >= 0 && fx.time < prev - 43200) {
      ++day_carry;
      fx.time += 86400;
    }
    prev = fx.time;
    auto it = gga_alt.find(std::lround(r.tod * 1000));
    if (it != gga_alt.end()) {
      fx.alt = it->second;
      fx.has_alt = true;
    }
    fixes.push_back(fx);
  }
  return fixes;
}

GpsLog ReadNmea(const std::string& text, const std::string& name) {
  GpsLog log;
  log.format = "nmea";
  std::istringstream in(text);
  std::string raw;
  long line = 0;
  std::map<long, double> gga_alt;  // milliseconds of the day → altitude
  std::vector<Rmc> rmc;
  while (std::getline(in, raw)) {
    ++line;
    NmeaSentence s;
    s.line = line;
    bool bad = false;
    if (!ParseSentence(raw, s, bad)) {
      log.bad_checksums += bad;
      continue;
    }
    const std::string type = s.f[0].substr(2);
    const auto& f = s.f;
    if (type == "RMC") {
      if (f.size() < 10)
        throw Error(name, line, "RMC sentence with " + std::to_string(f.size()) + " fields");
      if (f[2] != "A") {
        ++log.invalid;
        continue;
      }
      Rmc r;
      long dd, mm, yy;
      if (!ParseNmeaTime(f[1], r.tod) || !ParseNmeaAngle(f[3], f[4], 2, r.lat) ||
          !ParseNmeaAngle(f[5], f[6], 3, r.lon) || f[9].size() != 6 || !Digits(f[9], 0, 2, dd) ||
          !Digits(f[9], 2, 2, mm) || !Digits(f[9], 4, 2, yy) || dd < 1 || dd > 31 || mm < 1 ||
          mm > 12)
        throw Error(name, line, "RMC sentence with an unreadable time, date or position");
      CheckLatLon(name, line, r.lat, r.lon);
      // Two-digit years: 1980–2079 (GPS began in 1980).
      r.days = DaysFromCivil(yy < 80 ? 2000 + yy : 1900 + yy, mm, dd);
      rmc.push_back(r);
    } else if (type == "GGA") {
      if (f.size() < 10)
        throw Error(name, line, "GGA sentence with " + std::to_string(f.size()) + " fields");
      if (f[6].empty() || f[6] == "0") {
        ++log.invalid;
        continue;
      }
      double tod, alt;
      if (!ParseNmeaTime(f[1], tod))
        throw Error(name, line, "GGA sentence with an unreadable time");
      if (ParseDouble(f[9], alt)) gga_alt[std::lround(tod * 1000)] = alt;
    }
  }
  if (rmc.empty()) {
    if (log.bad_checksums > 0)
      throw Error(name, 0,
                  "no NMEA sentence with a valid fix and a right checksum (" +
                      std::to_string(log.bad_checksums) + " with a wrong checksum)");
    throw Error(name, 0,
                "no valid RMC sentence: the log has no date (GGA alone gives only the time of "
                "day)");
  }
  log.fixes = NmeaFixes(rmc, gga_alt);
  SortAndMerge(log.fixes);
  return log;
}

}  // namespace

bool ParseIsoTime(const std::string& text, double& seconds) {
  std::string s = text;
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t b = 0;
  while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  s = s.substr(b);
  long y, mo, d, h, mi, sec;
  if (s.size() < 19 || !Digits(s, 0, 4, y) || s[4] != '-' || !Digits(s, 5, 2, mo) || s[7] != '-' ||
      !Digits(s, 8, 2, d) || (s[10] != 'T' && s[10] != ' ') || !Digits(s, 11, 2, h) ||
      s[13] != ':' || !Digits(s, 14, 2, mi) || s[16] != ':' || !Digits(s, 17, 2, sec))
    return false;
  if (mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 || sec > 60) return false;
  size_t p = 19;
  double frac = 0;
  if (p < s.size() && (s[p] == '.' || s[p] == ',')) {
    size_t q = p + 1;
    double scale = 0.1;
    while (q < s.size() && s[q] >= '0' && s[q] <= '9') {
      frac += scale * (s[q] - '0');
      scale /= 10;
      ++q;
    }
    if (q == p + 1) return false;
    p = q;
  }
  long offset = 0;  // seconds east of UTC
  if (p < s.size()) {
    if (s[p] == 'Z' || s[p] == 'z') {
      ++p;
    } else if (s[p] == '+' || s[p] == '-') {
      long oh, om;
      const bool colon = p + 3 < s.size() && s[p + 3] == ':';
      if (!Digits(s, p + 1, 2, oh) || !Digits(s, p + (colon ? 4 : 3), 2, om) || oh > 23 || om > 59)
        return false;
      offset = (s[p] == '-' ? -1 : 1) * (oh * 3600 + om * 60);
      p += colon ? 6 : 5;
    } else {
      return false;
    }
  }
  if (p != s.size()) return false;
  seconds =
      static_cast<double>(DaysFromCivil(y, mo, d) * 86400 + h * 3600 + mi * 60 + sec - offset) +
      frac;
  return true;
}

std::string FormatIsoTime(double seconds) {
  const double ms_total = std::round(seconds * 1000);
  if (!std::isfinite(ms_total) || std::abs(ms_total) > 1e17) return "(no time)";
  long long ms = static_cast<long long>(ms_total);
  long long days = ms / 86400000;
  long long rest = ms % 86400000;
  if (rest < 0) {
    rest += 86400000;
    --days;
  }
  long y, m, d;
  CivilFromDays(static_cast<long>(days), y, m, d);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04ld-%02ld-%02ldT%02lld:%02lld:%02lld.%03lldZ", y, m, d,
                rest / 3600000, rest / 60000 % 60, rest / 1000 % 60, rest % 1000);
  return buf;
}

GpsLog ReadGpsLog(std::istream& in, const std::string& name) {
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  size_t i = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;  // UTF-8 byte order mark
  while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
  if (i == text.size()) throw Error(name, 0, "empty GPS log");
  if (text[i] == '<') return ReadGpx(text, name);
  if (text.find('$') != std::string::npos) return ReadNmea(text, name);
  throw Error(name, 1, "not a GPS log: neither GPX (XML) nor NMEA ($ sentences)");
}

GpsLog ReadGpsLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, 0, "cannot open");
  return ReadGpsLog(in, path);
}

}  // namespace mvtm

#include "io/partners.h"

#include <algorithm>
#include <cstdio>
#include <ostream>

#include "base/atomic_file.h"
#include "base/text.h"

namespace mvtm {

namespace {

constexpr const char* kHeader = "query\trank\timage\tdistance\theading_deg\n";

std::vector<PartnerRow> ReadRows(LineReader& r) {
  std::string line;
  if (!r.Next(line))
    r.Fail("empty file: expected the header 'query rank image distance heading_deg'");
  auto head = SplitBlank(line);
  if (head.size() != 5 || head[0] != "query" || head[1] != "rank" || head[2] != "image")
    r.Fail("expected the header 'query rank image distance heading_deg' (pickview --partners)");
  std::vector<PartnerRow> rows;
  while (r.Next(line)) {
    auto f = SplitChar(line, '\t');
    if (f.size() != 5) r.Fail("expected 5 tab-separated fields, found " + std::to_string(f.size()));
    PartnerRow row;
    row.query = std::string(f[0]);
    row.rank = ParseInt(f[1], r, "rank");
    if (row.rank < 1) r.Fail("rank must be >= 1");
    row.image = std::string(f[2]);
    row.distance = ParseDouble(f[3], r, "distance");
    row.heading_deg = ParseDouble(f[4], r, "heading_deg");
    rows.push_back(std::move(row));
  }
  return rows;
}

// "%.6f": snprintf follows the C locale, which mvtm never changes from "C" (only the C++ global
// locale may be a comma-decimal one, and it does not reach snprintf).
std::string Fixed6(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

}  // namespace

std::vector<PartnerRow> ReadPartners(std::istream& in, const std::string& name) {
  LineReader r(in, name);
  return ReadRows(r);
}

std::vector<PartnerRow> ReadPartners(const std::string& path) {
  LineReader r(path);
  return ReadRows(r);
}

void WritePartners(std::ostream& out, const std::vector<PartnerRow>& rows) {
  std::string text = kHeader;
  for (const PartnerRow& row : rows)
    text += row.query + '\t' + std::to_string(row.rank) + '\t' + row.image + '\t' +
            Fixed6(row.distance) + '\t' + Fixed6(row.heading_deg) + '\n';
  out << text;
}

void WritePartners(const std::string& path, const std::vector<PartnerRow>& rows) {
  WriteTextAtomic(path, [&](std::ostream& f) { WritePartners(f, rows); });
}

std::map<std::string, std::vector<std::string>> PartnersByQuery(
    const std::vector<PartnerRow>& rows) {
  std::map<std::string, std::vector<const PartnerRow*>> by_query;
  for (const PartnerRow& row : rows) by_query[row.query].push_back(&row);
  std::map<std::string, std::vector<std::string>> out;
  for (auto& [query, v] : by_query) {
    std::stable_sort(v.begin(), v.end(),
                     [](const PartnerRow* a, const PartnerRow* b) { return a->rank < b->rank; });
    for (const PartnerRow* row : v) out[query].push_back(row->image);
  }
  return out;
}

}  // namespace mvtm

// mvtm — partners.tsv: view selection, written by pickview, read by inpaint3d.
//
// Format (man/pickview.1, OUTPUT; man/mvtm-workspace.5): tab-separated text, the header line
//   query<TAB>rank<TAB>image<TAB>distance<TAB>heading_deg
// then one row per selected image, best first: query and image are image names (as in
// images.txt; a query of a trajectory file without names is its pose index, 000000, ...), rank
// counts from 1, distance is the camera-centre distance in the model's unit and heading_deg the
// angle between the viewing directions in degrees, both written with 6 decimals ("%.6f").
// pickview prints the same table on standard output in every mode.
// Conventions:
//  * Numbers are written and read in the classic "C" form whatever the global locale.
//  * Readers skip blank lines and '#' comments, and report malformed input as "FILE:LINE: what"
//    (base/text.h). The header is recognised by its first three names and five fields.
//  * Writers write rows in the order given; the path version is atomic (base/atomic_file.h).
// Thread safety: functions are reentrant.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace mvtm {

struct PartnerRow {
  std::string query;       // the image (or pose) the row selects for
  int64_t rank = 1;        // 1 = best
  std::string image;       // the selected image
  double distance = 0;     // camera-centre distance, model units
  double heading_deg = 0;  // angle between the viewing directions, degrees
};

// Reads a table; `name` is used in messages. Throws Error("NAME:LINE: what").
std::vector<PartnerRow> ReadPartners(std::istream& in, const std::string& name);
std::vector<PartnerRow> ReadPartners(const std::string& path);
// Writes the header and the rows. The stream version leaves checking the stream to the caller;
// the path version throws Error when the file cannot be written.
void WritePartners(std::ostream& out, const std::vector<PartnerRow>& rows);
void WritePartners(const std::string& path, const std::vector<PartnerRow>& rows);

// Each query's selected images in rank order (rows of equal rank keep their file order).
std::map<std::string, std::vector<std::string>> PartnersByQuery(
    const std::vector<PartnerRow>& rows);

}  // namespace mvtm

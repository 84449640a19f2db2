// pickview — view selection: the best projector images for each query pose, and partner images
// between passes of the same road (thesis §D.2, §5.3.3). The metric is SelectViews'
// (index/view_selection.h); the search is index/pose_index.h's, exact or approximate.
//
// Output (stdout, and WS/partners.tsv in partners mode): a TSV with the header
//   query  rank  image  distance  heading_deg
// one row per selected image, best first (rank 1..K), ties broken by image name; distance is the
// camera-centre distance in the model's unit and heading_deg the angle between the viewing
// directions, both printed with 6 decimals. A query with no admissible image has no rows.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include "index/pose_index.h"
#include "run/option_table.h"

namespace mvtm {

// --method: the search methods (index/pose_index.h) by name, in the order --help lists them.
inline const std::vector<std::pair<SearchMethod, std::string>> kSearchMethods = {
    {SearchMethod::kKdTree, "kdtree"},
    {SearchMethod::kBrute, "brute"},
    {SearchMethod::kFlann, "flann"},
    {SearchMethod::kGrid9, "grid9"}};

struct PickViewOptions {
  std::string workspace;  // WS: the projectors are its images (sparse/)
  std::string
      queries;  // trajectory file (TUM, KITTI, COLMAP images.txt), "-" = stdin; empty = WS's images
  int64_t k = 4;                // images per query, 1 or more
  double max_heading_deg = 45;  // heading gate, degrees, (0, 180]
  double heading_weight = 0;    // metres per radian of heading difference, >= 0
  double ahead_weight =
      0;  // metres per metre a projector is ahead of the query, >= 0 (0: thesis nearest pose)
  SearchMethod method = SearchMethod::kKdTree;
  int checks = 32;            // flann: leaves visited per query, 1 or more
  bool exclude_self = false;  // with WS's own images as queries: never select the image itself
  bool partners = false;      // partners mode: images of the other passes (prefix before '_')
  std::string other;          // partners: the other pass is this second workspace
  bool prefer_unmasked =
      false;  // partners: near-ties go to partners masked less where the image is masked
  double tie_margin =
      1.0;             // partners: a near-tie is within this many metres of the best remaining cost
  bool force = false;  // partners: rewrite WS/partners.tsv even when it is up to date
  bool quiet = false;  // no summary on stderr

  void Check() const;  // throws UsageError naming the bad value
};

// The option table (run/option_table.h) bound to `o`: --help, the range checks, the provenance
// and the staleness key of WS/partners.tsv.
OptionTable DeclareOptions(PickViewOptions& o);

struct PickViewReport {
  size_t queries = 0, rows = 0, unmatched = 0;  // unmatched: queries with no admissible image
  size_t candidates = 0;
  double us_per_query = 0;  // search time only
  std::string method;
  bool compared = false;          // approximate method: compared with the exact search
  size_t slots = 0, misses = 0;   // exact results, and those the approximate search missed
  double mean_extra = 0;          // mean extra cost per rank slot against exact (metres)
  double grid_cell = 0;           // grid9's cell side
  std::string partners_path;      // partners mode: WS/partners.tsv
  bool partners_written = false;  // partners mode: it was (re)written (else it was up to date)
  std::string why;                // why an existing partners.tsv was rewritten, or ""
};

// Writes the TSV to `out`; reads queries from `in` when options.queries is "-". Partners mode
// also writes WS/partners.tsv unless it is up to date (its record: WS/provenance/pickview.json,
// run/ledger.h); the table on `out` is computed either way.
PickViewReport RunPickView(const PickViewOptions& options, std::ostream& out, std::istream& in);

}  // namespace mvtm

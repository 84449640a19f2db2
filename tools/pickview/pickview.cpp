#include "pickview.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>

#include "base/error.h"
#include "base/text.h"
#include "cli/work.h"
#include "image/mask.h"
#include "index/pose_index.h"
#include "io/colmap_model.h"
#include "io/partners.h"
#include "io/trajectory.h"
#include "queries.h"
#include "run/ledger.h"
#include "workspace/workspace.h"

namespace mvtm {

OptionTable DeclareOptions(PickViewOptions& o) {
  OptionTable t("pickview");
  t.Positional("WS", &o.workspace, "Workspace folder (sparse/; masks/ with --prefer-unmasked)")
      .Dir();
  t.OptionalPositional("QUERIES", &o.queries,
                       "Query poses: COLMAP images.txt, TUM or KITTI trajectory; - for stdin "
                       "(default: the workspace's own images)")
      .File();
  t.Integer("--k", &o.k, "Images per query").AtLeast(1);
  t.Real("--max-heading", &o.max_heading_deg,
         "Heading gate, degrees: images looking further away are never picked")
      .Range(0, 180, true);
  t.Real("--heading-weight", &o.heading_weight, "Metres of cost per radian of heading difference")
      .AtLeast(0);
  t.Real("--ahead-weight", &o.ahead_weight,
         "Metres of cost per metre an image is ahead of the query (ptmrender uses 1; 0 = "
         "nearest pose)")
      .AtLeast(0);
  t.Choice("--method", &o.method, kSearchMethods,
           "Search: kdtree and brute are exact; flann (randomised trees) and grid9 (the thesis's "
           "grid) approximate");
  t.Integer("--checks", &o.checks, "flann: leaves visited per query (more: slower, fewer misses)")
      .AtLeast(1);
  t.Flag("--exclude-self", &o.exclude_self,
         "With the workspace's own images as queries: never pick the image itself");
  t.Flag("--partners", &o.partners,
         "Partners mode: for every image, the nearest images of the other passes (name prefix "
         "before '_'); also writes WS/partners.tsv");
  t.Text("--other", &o.other, "Partners: the other pass is this workspace").Dir();
  t.Flag("--prefer-unmasked", &o.prefer_unmasked,
         "Partners: near-ties go to images with fewer mask pixels where the image's own mask is "
         "set");
  t.Real("--tie-margin", &o.tie_margin,
         "Partners with --prefer-unmasked: metres of cost within which candidates are near-ties")
      .AtLeast(0);
  t.Flag("--force", &o.force, "Partners: rewrite WS/partners.tsv even when it is up to date")
      .Cosmetic();
  t.Flag("-q,--quiet", &o.quiet, "No summary on stderr (and no comparison with the exact search)")
      .Cosmetic();
  return t;
}

void PickViewOptions::Check() const {
  CheckDeclared(*this);
  if (!partners && !other.empty()) throw UsageError("--other needs --partners");
  if (!partners && prefer_unmasked) throw UsageError("--prefer-unmasked needs --partners");
  if (partners && !queries.empty())
    throw UsageError("--partners takes no QUERIES: the queries are the images of WS");
  if (partners && exclude_self)
    throw UsageError(
        "--exclude-self does not apply to --partners: partners are always other passes");
  if (exclude_self && !queries.empty())
    throw UsageError("--exclude-self needs the workspace's own images as queries (no QUERIES)");
}

std::vector<PickViewQuery> ReadPickViewQueries(const std::string& path, std::istream& in) {
  // Standard input is read as a stream (no temporary copy): the reader detects the format from
  // the lines it has buffered.
  const Trajectory tr = path == "-" ? ReadTrajectory(in, "-") : ReadTrajectory(path);
  std::vector<PickViewQuery> q;
  for (size_t i = 0; i < tr.poses.size(); ++i) {
    Rigid3d w2c = tr.poses[i].pose.Inverse();
    if (!w2c.t.allFinite() || !w2c.q.coeffs().allFinite())
      throw Error(path, tr.poses[i].line, "pose is not finite");
    q.push_back({PoseName(tr, i), w2c});
  }
  return q;
}

namespace {

constexpr size_t kNone = static_cast<size_t>(-1);

using Query = PickViewQuery;

struct Model {
  std::vector<std::string> names;  // sorted by name
  std::vector<Rigid3d> w2c;
};

Model LoadModel(const Workspace& ws) {
  ws.Require("pickview", {WsItem::kSparse});
  Reconstruction rec = ReadColmapModel(ws.SparseDir().string());
  if (rec.images.empty()) throw Error(ws.SparseDir().string(), 0, "the model has no images");
  Model m;
  for (const auto* im : rec.ImagesByName()) {
    m.names.push_back(im->name);
    m.w2c.push_back(im->world_to_camera);
  }
  return m;
}

// Masks as bit sets, loaded once each.
class Masks {
 public:
  struct Bits {
    int width = 0, height = 0;
    std::vector<uint64_t> words;
    size_t set = 0;
  };
  // nullptr when the image has no mask file.
  const Bits* Get(const fs::path& path) {
    auto it = cache_.find(path.string());
    if (it != cache_.end()) return it->second ? &*it->second : nullptr;
    std::optional<Bits> b;
    if (fs::exists(path)) {
      Image im = ReadMask(path.string());
      b.emplace();
      b->width = im.width;
      b->height = im.height;
      b->words.assign((im.pixels() + 63) / 64, 0);
      for (size_t p = 0; p < im.pixels(); ++p)
        if (im.data[p] != 0) {
          b->words[p / 64] |= uint64_t{1} << (p % 64);
          ++b->set;
        }
    }
    auto& slot = cache_[path.string()] = std::move(b);
    return slot ? &*slot : nullptr;
  }
  // Pixels set in both; throws Error when the sizes differ.
  static size_t Overlap(const Bits& a, const fs::path& a_path, const Bits& b,
                        const fs::path& b_path) {
    if (a.width != b.width || a.height != b.height)
      throw Error(b_path.string(), 0,
                  "mask is " + std::to_string(b.width) + "x" + std::to_string(b.height) + " but " +
                      a_path.string() + " is " + std::to_string(a.width) + "x" +
                      std::to_string(a.height));
    size_t n = 0;
    for (size_t i = 0; i < a.words.size(); ++i)
      n += static_cast<size_t>(__builtin_popcountll(a.words[i] & b.words[i]));
    return n;
  }

 private:
  std::map<std::string, std::optional<Bits>> cache_;
};

// The selection as partners.tsv rows (io/partners.h), the table printed in every mode.
std::vector<PartnerRow> Rows(const std::vector<Query>& queries,
                             const std::vector<std::vector<Candidate>>& picks,
                             const std::vector<std::string>& names) {
  std::vector<PartnerRow> rows;
  for (size_t i = 0; i < queries.size(); ++i)
    for (size_t r = 0; r < picks[i].size(); ++r)
      rows.push_back({queries[i].name, static_cast<int64_t>(r + 1), names[picks[i][r].index],
                      picks[i][r].distance, picks[i][r].heading_deg});
  return rows;
}

// One group of candidates with its own index (a pass of the road, or all of --other).
struct Group {
  std::string pass;
  std::vector<size_t> members;  // global candidate indices, ascending (name order)
  std::unique_ptr<PoseIndex> index, all;
};

class Selector {
 public:
  Selector(const PickViewOptions& o, const Model& cands, SearchMethod method)
      : o_(o), cands_(cands), method_(method) {}

  // Query mode: one index over all candidates.
  std::vector<std::vector<Candidate>> Queries(const std::vector<Query>& qs, double& grid_cell) {
    ViewSelectionOptions sel = Selection(static_cast<size_t>(o_.k));
    PoseIndexOptions po;
    po.method = method_;
    po.checks = o_.checks;
    PoseIndex idx(cands_.w2c, sel, po);
    grid_cell = idx.grid_cell();
    std::vector<std::vector<Candidate>> out(qs.size());
    for (size_t i = 0; i < qs.size(); ++i)
      out[i] = idx.Select(qs[i].w2c, o_.exclude_self ? qs[i].self : kNone);
    return out;
  }

  // Partners mode. `query_pass` is each query's pass ("" with --other: every group is eligible).
  std::vector<std::vector<Candidate>> Partners(const std::vector<Query>& qs,
                                               const std::vector<std::string>& query_pass,
                                               bool by_pass, const Workspace& query_ws,
                                               const Workspace& cand_ws, double& grid_cell) {
    const size_t k = static_cast<size_t>(o_.k);
    const size_t pool = o_.prefer_unmasked ? 4 * k : k;
    std::map<std::string, Group> groups;
    for (size_t i = 0; i < cands_.names.size(); ++i)
      groups[by_pass ? PassOf(cands_.names[i]) : std::string()].members.push_back(i);
    PoseIndexOptions po;
    po.method = method_;
    po.checks = o_.checks;
    for (auto& [pass, g] : groups) {
      g.pass = pass;
      std::vector<Rigid3d> w2c;
      for (size_t i : g.members) w2c.push_back(cands_.w2c[i]);
      g.index = std::make_unique<PoseIndex>(w2c, Selection(pool), po);
      grid_cell = std::max(grid_cell, g.index->grid_cell());
    }
    Masks masks;
    std::vector<std::vector<Candidate>> out(qs.size());
    for (size_t i = 0; i < qs.size(); ++i) {
      std::vector<Group*> eligible;
      for (auto& [pass, g] : groups)
        if (!by_pass || pass != query_pass[i]) eligible.push_back(&g);
      bool exhaustive = true;
      std::vector<Candidate> merged = Merge(eligible, qs[i].w2c, false, pool, exhaustive);
      if (!o_.prefer_unmasked) {
        out[i] = std::move(merged);
        continue;
      }
      fs::path own_path = query_ws.MaskPath(qs[i].name);
      const Masks::Bits* own = masks.Get(own_path);
      if (!own || own->set == 0) {  // nothing masked: plain cost order
        merged.resize(std::min(merged.size(), k));
        out[i] = std::move(merged);
        continue;
      }
      auto overlap = [&](const Candidate& c) -> size_t {
        fs::path p = cand_ws.MaskPath(cands_.names[c.index]);
        const Masks::Bits* b = masks.Get(p);
        return b ? Masks::Overlap(*own, own_path, *b, p) : 0;
      };
      std::optional<std::vector<Candidate>> picked = Greedy(merged, exhaustive, overlap);
      if (!picked) {  // the near-tie window ran past the pool: use every admissible candidate
        std::vector<Candidate> all = Merge(eligible, qs[i].w2c, true, kNone, exhaustive);
        picked = Greedy(all, true, overlap);
      }
      out[i] = std::move(*picked);
    }
    return out;
  }

 private:
  ViewSelectionOptions Selection(size_t k) const {
    ViewSelectionOptions s;
    s.k = k;
    s.max_heading_deg = o_.max_heading_deg;
    s.heading_weight = o_.heading_weight;
    s.ahead_weight = o_.ahead_weight;
    return s;
  }

  // The best `limit` candidates of the eligible groups, by (cost, global index). `exhaustive`
  // is cleared when a group may hold more admissible candidates than it returned.
  std::vector<Candidate> Merge(const std::vector<Group*>& groups, const Rigid3d& q, bool every,
                               size_t limit, bool& exhaustive) {
    std::vector<Candidate> merged;
    exhaustive = true;
    for (Group* g : groups) {
      PoseIndex* idx = g->index.get();
      if (every) {
        if (!g->all) {
          std::vector<Rigid3d> w2c;
          for (size_t i : g->members) w2c.push_back(cands_.w2c[i]);
          g->all = std::make_unique<PoseIndex>(w2c, Selection(std::max<size_t>(1, w2c.size())),
                                               PoseIndexOptions{SearchMethod::kBrute});
        }
        idx = g->all.get();
      }
      auto got = idx->Select(q);
      if (!every && got.size() >= limit) exhaustive = false;
      for (auto c : got) {
        c.index = g->members[c.index];
        merged.push_back(c);
      }
    }
    std::sort(merged.begin(), merged.end(), CandidateBefore);
    if (merged.size() > limit) merged.resize(limit);
    return merged;
  }

  // --prefer-unmasked: rank by rank, among the remaining candidates within tie_margin of the
  // best remaining cost, take the one with the fewest mask pixels where the query's mask is set
  // (then cost, then name). nullopt when a window reaches the end of a non-exhaustive pool.
  template <class Overlap>
  std::optional<std::vector<Candidate>> Greedy(std::vector<Candidate> pool, bool exhaustive,
                                               Overlap&& overlap) {
    const size_t k = static_cast<size_t>(o_.k);
    std::vector<Candidate> picked;
    std::map<size_t, size_t> ov;
    while (picked.size() < k && !pool.empty()) {
      double limit = pool.front().cost + o_.tie_margin;
      if (!exhaustive && pool.back().cost <= limit) return std::nullopt;
      size_t best = 0;
      for (size_t j = 0; j < pool.size() && pool[j].cost <= limit; ++j) {
        for (size_t t : {j, best})
          if (!ov.count(pool[t].index)) ov[pool[t].index] = overlap(pool[t]);
        if (ov[pool[j].index] < ov[pool[best].index]) best = j;  // pool is in (cost, name) order
      }
      picked.push_back(pool[best]);
      pool.erase(pool.begin() + static_cast<long>(best));
    }
    return picked;
  }

  const PickViewOptions& o_;
  const Model& cands_;
  SearchMethod method_;
};

// Partners mode: WS/partners.tsv unless it is up to date, and its record. Its inputs: the
// models of WS (and of --other), and with --prefer-unmasked the masks of both (an absent mask
// that appears makes it stale).
void WritePartnersIfStale(const PickViewOptions& o, const Workspace& ws, const Workspace* other_ws,
                          const Model& model, const Model& cands,
                          const std::vector<PartnerRow>& rows, PickViewReport& rep) {
  std::vector<fs::path> inputs = ws.SparseModelFiles();
  if (other_ws)
    for (const auto& f : other_ws->SparseModelFiles()) inputs.push_back(f);
  if (o.prefer_unmasked) {
    for (const std::string& n : model.names) inputs.push_back(ws.MaskPath(n));
    for (const std::string& n : cands.names)
      inputs.push_back((other_ws ? *other_ws : ws).MaskPath(n));
  }
  PickViewOptions resolved = o;
  const OptionTable table = DeclareOptions(resolved);
  Ledger ledger(ws.root(), "pickview", table, inputs, ws.root());
  rep.partners_path = ws.PartnersPath().string();
  rep.partners_written = !ledger.Stale(ws.PartnersPath(), {}, o.force).empty();
  rep.why = ledger.Summary();
  if (!rep.partners_written) return;
  WritePartners(rep.partners_path, rows);
  ledger.Done(ws.PartnersPath());
  ledger.Write();
}

}  // namespace

PickViewReport RunPickView(const PickViewOptions& o, std::ostream& out, std::istream& in) {
  o.Check();
  const SearchMethod method = o.method;
  Workspace ws(o.workspace);
  Model model = LoadModel(ws);
  PickViewReport rep;
  rep.method = SearchMethodName(method);

  std::vector<Query> queries;
  std::vector<std::string> query_pass;
  std::optional<Workspace> other_ws;
  Model cands;
  if (o.partners) {
    for (size_t i = 0; i < model.names.size(); ++i) {
      queries.push_back({model.names[i], model.w2c[i], kNone});
      query_pass.push_back(PassOf(model.names[i]));
    }
    if (!o.other.empty()) {
      other_ws.emplace(o.other);
      cands = LoadModel(*other_ws);
    } else {
      cands = model;
      std::vector<std::string> passes = query_pass;
      std::sort(passes.begin(), passes.end());
      if (std::unique(passes.begin(), passes.end()) - passes.begin() < 2)
        throw Error(o.workspace, 0,
                    "all " + std::to_string(model.names.size()) +
                        " images belong to one pass (passes are told apart by the name's prefix "
                        "before '_', "
                        "as in A_0000.png, B_0000.png); give the other pass with --other WS2");
    }
  } else {
    cands = model;
    if (o.queries.empty()) {
      for (size_t i = 0; i < model.names.size(); ++i)
        queries.push_back({model.names[i], model.w2c[i], i});
    } else {
      queries = ReadPickViewQueries(o.queries, in);
    }
  }
  rep.queries = queries.size();
  rep.candidates = cands.names.size();

  auto compute = [&](SearchMethod m, double& grid_cell) {
    Selector s(o, cands, m);
    if (o.partners)
      return s.Partners(queries, query_pass, o.other.empty(), ws, other_ws ? *other_ws : ws,
                        grid_cell);
    return s.Queries(queries, grid_cell);
  };
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::vector<Candidate>> picks = compute(method, rep.grid_cell);
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rep.us_per_query = queries.empty() ? 0 : s / static_cast<double>(queries.size()) * 1e6;
  if (!IsExact(method) && !o.quiet) {
    double unused = 0;
    auto exact = compute(SearchMethod::kKdTree, unused);
    SelectionDiff d;
    for (size_t i = 0; i < queries.size(); ++i) d.Add(exact[i], picks[i]);
    rep.compared = true;
    rep.slots = d.slots;
    rep.misses = d.misses;
    rep.mean_extra = d.MeanExtraCost();
  }
  for (const auto& p : picks) {
    rep.rows += p.size();
    rep.unmatched += p.empty();
  }

  std::vector<PartnerRow> rows = Rows(queries, picks, cands.names);
  if (o.partners)
    WritePartnersIfStale(o, ws, other_ws ? &*other_ws : nullptr, model, cands, rows, rep);
  WritePartners(out, rows);
  out.flush();
  if (!out) throw Error("-", 0, "cannot write the output");
  return rep;
}

}  // namespace mvtm

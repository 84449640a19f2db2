// mvtm — a road of several fragments on disk (man mvtm-workspace(5), thesis Appendix D.3).
//
// Layout:
//   ROAD/Graph.txt                     the graph of the fragments (thesis Table D.2)
//   ROAD/Models/SEQ/FRAGMENT/          one workspace per fragment (workspace/workspace.h)
//   ROAD/Models/SEQ/FRAGMENT/fragment.json   what the fragment owns (below)
//
// Graph.txt: text, '#' starts a comment, blank lines skipped; one line per fragment, in the
// road's order (the order of its recorded frames):
//   NODE [NEIGHBOUR POSE]...
// NODE and NEIGHBOUR are fragment ids "SEQ/FRAGMENT" (folders under ROAD/Models); POSE is the
// name of an image that both fragments hold, where a drive passes from NODE to NEIGHBOUR.
// Neighbours are symmetric (each link is listed on both nodes' lines); a junction is a node
// with more than two neighbours.
//
// path.txt: the path of record roadsplit measured the arc lengths along ("s" below): '#'
// comments, then "step STEP" (its PathIndex's sampling step), then "NAME X Y Z" per image in
// path order (camera centres, %.17g).
//
// fragment.json: {"images": [NAME, ...], "owned_faces": N, "s": [BEGIN, END], "overlap": M,
//                 "mesh_faces": T, "mesh_vertices": V,
//                 "bounds": [[XMIN, YMIN, ZMIN], [XMAX, YMAX, ZMAX]]}
//   images       the images the fragment owns (each image of the road is owned by exactly one
//                fragment; the fragment also holds its neighbours' images within the overlap)
//   owned_faces  its mesh's first N triangles are its own; the others are copies of its
//                neighbours' triangles within the overlap (so the fragment renders alone), and
//                the union of every fragment's own triangles is the road's mesh, each once
//   s, overlap   arc length (metres) of its own stretch of the path of record, and the overlap
//   mesh_faces, mesh_vertices
//                the triangles and vertices of the mesh.ply roadsplit wrote, own and copies
//                (optional): a mesh whose PLY header says other counts was made anew since
//                (roadmesh run on the fragment) owns the triangles over its stretch of path.txt
//                instead (workspace/road_meshes.h)
//   bounds       the axis-aligned box of its own triangles (optional: absent when it owns none)
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mvtm {

namespace fs = std::filesystem;

struct RoadPath {
  double step = 0;  // PathIndex sampling step
  std::vector<std::string> names;
  std::vector<Eigen::Vector3d> centres;
};

struct RoadLink {
  size_t to = 0;     // fragment index
  std::string pose;  // image name held by both fragments
};

struct RoadFragment {
  std::string id;  // SEQ/FRAGMENT
  fs::path dir;    // ROAD/Models/SEQ/FRAGMENT
  std::vector<RoadLink> links;
  std::vector<std::string> owned_images;
  size_t owned_faces = 0;
  double s_begin = 0, s_end = 0, overlap = 0;
  std::optional<size_t> mesh_faces, mesh_vertices;       // of its mesh.ply as roadsplit wrote it
  std::optional<std::array<Eigen::Vector3d, 2>> bounds;  // of the own triangles: lo, hi
};

class Road {
 public:
  // True when DIR/Graph.txt exists (a road, not a workspace).
  static bool IsRoad(const fs::path& dir);
  static fs::path GraphPathOf(const fs::path& root) { return root / "Graph.txt"; }
  static fs::path FragmentDir(const fs::path& root, const std::string& id) {
    return root / "Models" / id;
  }
  static fs::path RecordPath(const fs::path& fragment_dir) {
    return fragment_dir / "fragment.json";
  }
  static fs::path PathFileOf(const fs::path& root) { return root / "path.txt"; }

  // Reads and checks ROAD/Graph.txt and every fragment.json. Throws Error("FILE:LINE: what")
  // for a malformed line, a fragment named twice, a neighbour that is not a node of the graph,
  // a fragment folder without a workspace model or fragment.json, a link that is not mutual,
  // and a POSE that is not an image of both fragments.
  explicit Road(fs::path root);

  const fs::path& root() const { return root_; }
  fs::path GraphPath() const { return GraphPathOf(root_); }
  const std::vector<RoadFragment>& fragments() const { return fragments_; }
  // The fragments resident while the camera is in `home`: home first, then its neighbours in
  // the order of its links.
  std::vector<size_t> Resident(size_t home) const;
  bool Adjacent(size_t a, size_t b) const;
  // The fragment whose own stretch [s_begin, s_end) holds arc length s (the first and the last
  // fragment in Graph.txt's order reach on without end), as roadsplit assigns triangles.
  size_t FragmentAt(double s) const;
  // The files the road around `home` is made of: path.txt, each resident fragment's mesh and
  // fragment.json (what a render or a depth map made there depends on).
  std::vector<fs::path> ResidentFiles(size_t home) const;
  // The road's recorded frames in order (what --frames counts on a road): each fragment's own
  // images, fragments in Graph.txt's order, as (fragment index, image name).
  std::vector<std::pair<size_t, std::string>> RecordedFrames() const;

 private:
  fs::path root_;
  std::vector<RoadFragment> fragments_;
};

// Writes ROAD/Graph.txt atomically from the fragments' ids and links.
void WriteRoadGraph(const fs::path& root, const std::vector<RoadFragment>& fragments);
// Writes ROAD/path.txt atomically; reads it (Error "FILE:LINE: what"; a road made before
// path.txt existed: Error naming the missing file).
void WriteRoadPath(const fs::path& root, const RoadPath& path);
RoadPath ReadRoadPath(const fs::path& root);
// Writes FRAGMENT/fragment.json atomically.
void WriteFragmentRecord(const RoadFragment& fragment);

}  // namespace mvtm

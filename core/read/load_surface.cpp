// load_surface.cpp — closed 2-manifold checks on a polygon soup; see load_surface.h.
#include "core/read/load_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <tuple>
#include <utility>

#include "core/base/disjoint_sets.h"
#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/read/format_reader.h"
#include "core/validity/inside_test.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {
namespace {

std::string fmt_point(const Vec3d& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p.x, p.y, p.z);
  return buf;
}

/// Collects up to `max` examples of one rule and counts all of them.
struct ProblemCollector {
  SurfaceProblem problem;
  std::size_t max;
  std::vector<std::string> examples;
  ProblemCollector(std::string rule, std::string remedy, std::size_t max_listed) : max(max_listed) {
    problem.rule = std::move(rule);
    problem.remedy = std::move(remedy);
  }
  void add(const std::string& example) {
    if (examples.size() < max) examples.push_back(example);
    ++problem.count;
  }
  void flush_into(std::vector<SurfaceProblem>& out) {
    if (problem.count == 0) return;
    for (std::size_t i = 0; i < examples.size(); ++i)
      problem.first += (i ? "; " : "") + examples[i];
    out.push_back(std::move(problem));
  }
};

/// A triangle of the fan triangulation, with the polygon it came from.
struct SoupTriangle {
  Triangle v;
  std::size_t polygon;
};

/// One side of an edge: the triangle and whether it runs lo -> hi.
struct EdgeUse {
  std::uint32_t lo, hi;
  std::uint32_t tri;
  bool forward;
  bool operator<(const EdgeUse& o) const {
    return std::tie(lo, hi, tri) < std::tie(o.lo, o.hi, o.tri);
  }
};

std::vector<EdgeUse> edge_uses(const std::vector<SoupTriangle>& tris) {
  std::vector<EdgeUse> uses;
  uses.reserve(tris.size() * 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tris[t].v[k], b = tris[t].v[(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(t), a < b});
    }
  std::sort(uses.begin(), uses.end());
  return uses;
}

std::vector<SoupTriangle> fan_triangulate(const PolygonSoup& soup) {
  std::vector<SoupTriangle> tris;
  tris.reserve(soup.polygons.size());
  for (std::size_t p = 0; p < soup.polygons.size(); ++p) {
    const auto& poly = soup.polygons[p];
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      tris.push_back({{static_cast<std::uint32_t>(poly[0]), static_cast<std::uint32_t>(poly[k]),
                       static_cast<std::uint32_t>(poly[k + 1])},
                      p});
  }
  return tris;
}

/// The triangles of a soup whose indices and coordinates are valid, with names for messages.
/// The geometric checks read points(): the soup's points times 2^scale (unit_scale_exponent()),
/// so that they hold for any unit; messages name the soup's own points.
struct SoupFaces {
  SoupFaces(const PolygonSoup& s, std::vector<SoupTriangle> t)
      : soup(s), tris(std::move(t)), scale(unit_scale_exponent(s.points)) {
    if (scale == 0) return;
    scaled = s.points;
    scale_by_power_of_two(scaled, scale);
  }

  const PolygonSoup& soup;
  std::vector<SoupTriangle> tris;
  int scale;                  // points() = soup.points times 2^scale
  std::vector<Vec3d> scaled;  // empty when scale is 0

  const std::vector<Vec3d>& points() const { return scale == 0 ? soup.points : scaled; }
  /// A point of points()' frame, named in the soup's.
  std::string point_name(const Vec3d& p) const {
    return fmt_point({std::ldexp(p.x, -scale), std::ldexp(p.y, -scale), std::ldexp(p.z, -scale)});
  }

  std::string face_name(const SoupTriangle& t) const {
    const bool tri_only = soup.polygons[t.polygon].size() == 3;
    return (tri_only ? "face " : "polygon ") + std::to_string(t.polygon);
  }
  std::string edge_name(std::uint32_t a, std::uint32_t b) const {
    return "edge (" + std::to_string(a) + ", " + std::to_string(b) + ") at " +
           fmt_point(soup.points[a]) + "-" + fmt_point(soup.points[b]);
  }
};

/// `mesh` with its points times 2^k, k = unit_scale_exponent() of them (also returned in `k`).
SurfaceMesh at_unit_scale(const SurfaceMesh& mesh, int& k) {
  k = unit_scale_exponent(mesh.points);
  SurfaceMesh unit = mesh;
  scale_by_power_of_two(unit.points, k);
  return unit;
}

/// Element-wise rules: finite coordinates, indices in range, at least three corners. Returns
/// false when indices or coordinates are bad (nothing else is meaningful then).
bool check_elements(const PolygonSoup& soup, std::size_t max,
                    std::vector<SurfaceProblem>& problems) {
  const auto& pts = soup.points;
  const std::size_t nv = pts.size();
  ProblemCollector bad_coords("NaN/Inf coordinates",
                              "the file holds invalid numbers; re-export the mesh", max);
  for (std::size_t i = 0; i < nv; ++i)
    if (!is_finite(pts[i])) bad_coords.add("vertex " + std::to_string(i) + " " + fmt_point(pts[i]));
  ProblemCollector bad_index("out-of-range vertex indices",
                             "the file is corrupt or truncated; re-export the mesh", max);
  ProblemCollector short_poly("faces with fewer than 3 corners",
                              "remove the points/lines from the file", max);
  for (std::size_t p = 0; p < soup.polygons.size(); ++p) {
    const auto& poly = soup.polygons[p];
    if (poly.size() < 3)
      short_poly.add("face " + std::to_string(p) + " has " + std::to_string(poly.size()));
    for (std::int64_t idx : poly)
      if (idx < 0 || static_cast<std::size_t>(idx) >= nv) {
        bad_index.add("face " + std::to_string(p) + " uses vertex " + std::to_string(idx) + " of " +
                      std::to_string(nv));
        break;
      }
  }
  const bool elements_ok = bad_coords.problem.count == 0 && bad_index.problem.count == 0;
  bad_coords.flush_into(problems);
  bad_index.flush_into(problems);
  short_poly.flush_into(problems);
  return elements_ok;
}

/// Per point, the index in `positions` (filled here, in order of first appearance) of its
/// position: points at exactly one position share one index.
std::vector<std::int64_t> position_indices(const std::vector<Vec3d>& points,
                                           std::vector<Vec3d>& positions) {
  std::vector<std::int64_t> index(points.size());
  read_detail::PositionWelder weld(positions);
  for (std::size_t i = 0; i < points.size(); ++i) index[i] = weld.index(points[i]);
  return index;
}

double points_diagonal(const std::vector<Vec3d>& points) {
  BBox box;
  for (const Vec3d& p : points) box.expand(p);
  return box.diagonal();
}

/// Twice the area at or below which a face of a surface of bounding-box diagonal `diag` has zero
/// area.
double zero_twice_area(double diag, const ValidationOptions& options) {
  return 2.0 * options.degenerate_area_fraction * diag * diag;
}

/// Faces of zero area (a repeated corner, or below the area threshold), and faces with an edge
/// below the short-edge threshold; marks the faces with a repeated corner.
void check_degenerate(const SoupFaces& f, const ValidationOptions& options,
                      ProblemCollector& degenerate, ProblemCollector& short_edge,
                      std::vector<char>& repeated_corner) {
  const auto& pts = f.points();
  const double diag = points_diagonal(pts);
  const double min_twice_area = zero_twice_area(diag, options);
  const double min_edge = options.short_edge_fraction * diag;
  repeated_corner.assign(f.tris.size(), 0);
  for (std::size_t t = 0; t < f.tris.size(); ++t) {
    const Triangle& v = f.tris[t].v;
    const bool repeated = v[0] == v[1] || v[1] == v[2] || v[0] == v[2];
    const double twice_area =
        repeated ? 0.0 : norm(cross(pts[v[1]] - pts[v[0]], pts[v[2]] - pts[v[0]]));
    if (repeated || twice_area <= min_twice_area) {
      repeated_corner[t] = repeated;
      degenerate.add(f.face_name(f.tris[t]) + " (" + std::to_string(v[0]) + ", " +
                     std::to_string(v[1]) + ", " + std::to_string(v[2]) + ") at " +
                     fmt_point(f.soup.points[v[0]]));
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = v[k], b = v[(k + 1) % 3];
      const double length = distance(pts[a], pts[b]);
      if (!(length <= min_edge)) continue;
      char apart[32];
      std::snprintf(apart, sizeof apart, "%.3g", length);
      short_edge.add(f.face_name(f.tris[t]) + ": vertices " + std::to_string(a) + " and " +
                     std::to_string(b) + ", " + apart + " apart at " + fmt_point(f.soup.points[a]));
      break;
    }
  }
}

/// Faces with the corners of an earlier one: the same three vertices, or vertices at the same
/// three positions (two parts touching face to face: between them the solid has no thickness,
/// and a shell's tets on both sides would meet at faces that should bound it).
void check_duplicates(const SoupFaces& f, ProblemCollector& duplicate) {
  // Corners by position: the first vertex at each position stands for all.
  std::vector<Vec3d> positions;
  const std::vector<std::int64_t> at = position_indices(f.soup.points, positions);
  std::vector<std::pair<Triangle, std::uint32_t>> sorted;
  sorted.reserve(f.tris.size());
  for (std::size_t t = 0; t < f.tris.size(); ++t) {
    Triangle k = f.tris[t].v;
    for (std::uint32_t& v : k) v = static_cast<std::uint32_t>(at[v]);
    std::sort(k.begin(), k.end());
    sorted.push_back({k, static_cast<std::uint32_t>(t)});
  }
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i].first != sorted[i - 1].first) continue;
    Triangle a = f.tris[sorted[i].second].v, b = f.tris[sorted[i - 1].second].v;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    duplicate.add(f.face_name(f.tris[sorted[i].second]) + (a == b ? " repeats " : " lies on ") +
                  f.face_name(f.tris[sorted[i - 1].second]));
  }
}

/// Edge rules: every edge shared by exactly two faces that traverse it in opposite directions.
/// Joins, in `corners` (three per triangle), the corners of the two faces of every manifold edge.
void check_edges(const SoupFaces& f, ProblemCollector& boundary, ProblemCollector& nonmanifold_edge,
                 ProblemCollector& orientation, DisjointSets& corners) {
  const std::vector<EdgeUse> uses = edge_uses(f.tris);
  auto corner_of = [&](std::uint32_t tri, std::uint32_t vertex) {
    const Triangle& v = f.tris[tri].v;
    const int k = v[0] == vertex ? 0 : (v[1] == vertex ? 1 : 2);
    return static_cast<std::size_t>(tri) * 3 + static_cast<std::size_t>(k);
  };
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].lo == uses[i].lo && uses[j].hi == uses[i].hi) ++j;
    const std::size_t count = j - i;
    const std::uint32_t a = uses[i].lo, b = uses[i].hi;
    if (a != b) {
      if (count == 1) {
        boundary.add(f.edge_name(a, b));
      } else if (count > 2) {
        nonmanifold_edge.add(f.edge_name(a, b) + " in " + std::to_string(count) + " faces");
      } else {
        if (uses[i].forward == uses[i + 1].forward)
          orientation.add(f.face_name(f.tris[uses[i].tri]) + " and " +
                          f.face_name(f.tris[uses[i + 1].tri]) + " along " + f.edge_name(a, b));
        corners.unite(corner_of(uses[i].tri, a), corner_of(uses[i + 1].tri, a));
        corners.unite(corner_of(uses[i].tri, b), corner_of(uses[i + 1].tri, b));
      }
    }
    i = j;
  }
}

/// A vertex is manifold when its corners (of faces with three distinct corners: zero-area ones
/// too, which the flips of make_surface() keep) form one fan: one connected set through shared
/// edges.
void check_vertices(const SoupFaces& f, const std::vector<char>& repeated_corner,
                    DisjointSets& corners, ProblemCollector& nonmanifold_vertex) {
  const std::size_t nv = f.soup.points.size();
  std::vector<std::size_t> first_root(nv, SIZE_MAX);
  std::vector<char> reported(nv, 0);
  for (std::size_t t = 0; t < f.tris.size(); ++t) {
    if (repeated_corner[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = f.tris[t].v[k];
      const std::size_t root = corners.find(t * 3 + static_cast<std::size_t>(k));
      if (first_root[v] == SIZE_MAX) {
        first_root[v] = root;
      } else if (first_root[v] != root && !reported[v]) {
        reported[v] = 1;
        nonmanifold_vertex.add("vertex " + std::to_string(v) + " at " +
                               fmt_point(f.soup.points[v]));
      }
    }
  }
}

/// Crossing pairs counted at most: a crumpled surface has billions of them, and listing them all
/// took longer and more memory than anything else (a 94k-face one: 24 GB after 7 minutes).
constexpr std::size_t kCrossingsCounted = 10000;

/// Pairs of faces whose interiors cross (surface_self_intersections()), each named with a point
/// of the crossing; counted up to kCrossingsCounted.
void check_crossings(const SoupFaces& faces, ProblemCollector& crossing) {
  SurfaceMesh mesh;
  mesh.points = faces.points();
  mesh.triangles.reserve(faces.tris.size());
  for (const SoupTriangle& t : faces.tris) mesh.triangles.push_back(t.v);
  const std::vector<std::array<std::uint32_t, 2>> pairs =
      surface_self_intersections(mesh, kCrossingsCounted);
  crossing.problem.at_least = pairs.size() == kCrossingsCounted;
  for (const auto& [f, g] : pairs)
    crossing.add(crossing.examples.size() >= crossing.max
                     ? std::string()
                     : faces.face_name(faces.tris[f]) + " and " + faces.face_name(faces.tris[g]) +
                           " cross at " + faces.point_name(triangles_crossing_point(mesh, f, g)));
}

/// `soup` with the points at exactly one position made one (the first), and how many vertices
/// its polygons use that are gone in it (0, with an empty soup, when it has no such points or an
/// index out of range).
PolygonSoup weld_positions(const PolygonSoup& soup, std::size_t& welded) {
  welded = 0;
  PolygonSoup out;
  const std::vector<std::int64_t> index = position_indices(soup.points, out.points);
  if (out.points.size() == soup.points.size()) return {};
  const std::int64_t n = static_cast<std::int64_t>(soup.points.size());
  std::vector<char> used(soup.points.size()), used_after(out.points.size());
  out.polygons = soup.polygons;
  for (auto& poly : out.polygons)
    for (std::int64_t& v : poly) {
      if (v < 0 || v >= n) return {};
      used[static_cast<std::size_t>(v)] = 1;
      v = index[static_cast<std::size_t>(v)];
      used_after[static_cast<std::size_t>(v)] = 1;
    }
  welded = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1) -
                                    std::count(used_after.begin(), used_after.end(), 1));
  return out;
}

/// One side of a polygon: its ends (lo < hi), the polygon's corners there (indices into all
/// corners, polygon by polygon), the polygon, and whether it runs from lo to hi.
struct Side {
  std::int64_t lo, hi;
  std::size_t corner_lo, corner_hi;
  std::uint32_t polygon;
  bool forward;
  bool operator<(const Side& o) const {
    return std::tie(lo, hi, corner_lo) < std::tie(o.lo, o.hi, o.corner_lo);
  }
};

/// Every side of every polygon of `soup`, sorted by its ends; `start` gets each polygon's first
/// corner (and, last, the number of corners).
std::vector<Side> polygon_sides(const PolygonSoup& soup, std::vector<std::size_t>& start) {
  start.assign(soup.polygons.size() + 1, 0);
  for (std::size_t p = 0; p < soup.polygons.size(); ++p)
    start[p + 1] = start[p] + soup.polygons[p].size();
  std::vector<Side> sides;
  sides.reserve(start.back());
  for (std::size_t p = 0; p < soup.polygons.size(); ++p) {
    const auto& poly = soup.polygons[p];
    const auto polygon = static_cast<std::uint32_t>(p);
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const std::size_t l = (k + 1) % poly.size();
      const std::size_t ck = start[p] + k, cl = start[p] + l;
      sides.push_back(poly[k] < poly[l] ? Side{poly[k], poly[l], ck, cl, polygon, true}
                                        : Side{poly[l], poly[k], cl, ck, polygon, false});
    }
  }
  std::sort(sides.begin(), sides.end());
  return sides;
}

/// Calls visit(a, b) for every run of sides [a, b) with the same ends, in order.
template <class Visit>
void for_each_edge(const std::vector<Side>& sides, const Visit& visit) {
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i;
    while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
    visit(i, j);
    i = j;
  }
}

/// The open edges of a soup (sides of one polygon) among its `sides`, each from and to as its
/// polygon runs it, sorted.
std::vector<std::pair<std::int64_t, std::int64_t>> open_edges(const std::vector<Side>& sides) {
  std::vector<std::pair<std::int64_t, std::int64_t>> open;
  for_each_edge(sides, [&](std::size_t i, std::size_t j) {
    if (j - i != 1) return;
    const Side& side = sides[i];
    open.push_back(side.forward ? std::make_pair(side.lo, side.hi)
                                : std::make_pair(side.hi, side.lo));
  });
  std::sort(open.begin(), open.end());
  return open;
}

/// `soup` with each vertex of its open edges (edges of one polygon) within `tolerance` of another
/// such vertex made one with it (a group of them with the first, at its position), and how many
/// vertices are gone in it (0, with an empty soup, when none is): a crack where two patches were
/// written with their shared vertices a rounding apart. A group holding both ends of an edge is
/// left as it is (welding would collapse the edge). Its indices must be valid (make_surface()
/// calls it and close_thin_cracks() only when find_surface_problems() names open edges, which
/// it does only then).
PolygonSoup weld_open_seams(const PolygonSoup& soup, double tolerance, std::size_t& welded) {
  welded = 0;
  std::vector<std::size_t> start;
  const std::vector<Side> sides = polygon_sides(soup, start);
  std::vector<char> open(soup.points.size(), 0);
  for (const auto& [a, b] : open_edges(sides))
    open[static_cast<std::size_t>(a)] = open[static_cast<std::size_t>(b)] = 1;
  // The open edges' vertices by the cell of side `tolerance` they lie in; each one against those
  // in its own and the 26 cells around.
  BBox box;
  for (const Vec3d& p : soup.points) box.expand(p);
  if (!(tolerance > 0) || !(box.diagonal() / tolerance < 1e15)) return {};  // (NaN too)
  using Cell = std::array<std::int64_t, 3>;
  const auto cell_of = [&](const Vec3d& p) {
    const Vec3d c = (p - box.lo) / tolerance;
    return Cell{static_cast<std::int64_t>(std::floor(c.x)),
                static_cast<std::int64_t>(std::floor(c.y)),
                static_cast<std::int64_t>(std::floor(c.z))};
  };
  std::vector<std::pair<Cell, std::size_t>> cells;
  for (std::size_t v = 0; v < soup.points.size(); ++v)
    if (open[v] && is_finite(soup.points[v])) cells.push_back({cell_of(soup.points[v]), v});
  if (cells.empty()) return {};
  std::sort(cells.begin(), cells.end());
  DisjointSets groups(soup.points.size());
  for (const auto& [cell, v] : cells)
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const Cell near{cell[0] + dx, cell[1] + dy, cell[2] + dz};
          for (auto it = std::lower_bound(cells.begin(), cells.end(),
                                          std::make_pair(near, std::size_t{0}));
               it != cells.end() && it->first == near; ++it)
            if (it->second > v && distance(soup.points[v], soup.points[it->second]) <= tolerance)
              groups.unite(v, it->second);
        }
  std::vector<char> collapses(soup.points.size(), 0);
  for (const Side& side : sides)
    if (groups.find(static_cast<std::size_t>(side.lo)) ==
        groups.find(static_cast<std::size_t>(side.hi)))
      collapses[groups.find(static_cast<std::size_t>(side.lo))] = 1;
  // Every vertex to its group's first (or itself), then the points left renumbered in order.
  std::vector<std::int64_t> index(soup.points.size());
  PolygonSoup out;
  for (std::size_t v = 0; v < soup.points.size(); ++v) {
    const std::size_t root = groups.find(v);
    if (root != v && !collapses[root]) {
      index[v] = index[root];
      ++welded;
    } else {
      index[v] = static_cast<std::int64_t>(out.points.size());
      out.points.push_back(soup.points[v]);
    }
  }
  if (welded == 0) return {};
  out.polygons = soup.polygons;
  for (auto& poly : out.polygons)
    for (std::int64_t& v : poly) v = index[static_cast<std::size_t>(v)];
  return out;
}

/// `soup` with every loop of its open edges that runs along one line — its vertices within
/// `max_width` of the line through its two farthest — closed by slivers (`added` of them, after
/// the soup's polygons; 0, with an empty soup, when no loop is closed): a crack where one side has
/// vertices on an edge of the other (T-junctions). Each sliver cuts off a vertex lying between its
/// two neighbours along the line, so each is of zero area where the vertices are on the line.
PolygonSoup close_thin_cracks(const PolygonSoup& soup, double max_width, std::size_t& added) {
  added = 0;
  std::vector<std::size_t> start;
  const std::vector<Side> sides = polygon_sides(soup, start);
  if (std::any_of(sides.begin(), sides.end(), [](const Side& e) { return e.lo == e.hi; }))
    return {};
  const std::vector<std::pair<std::int64_t, std::int64_t>> open = open_edges(sides);
  std::vector<char> used(open.size(), 0);
  PolygonSoup out = soup;
  for (std::size_t first = 0; first < open.size(); ++first) {
    if (used[first]) continue;
    // A loop from this edge on; where two open edges leave a vertex (two cracks meet there), the
    // one turning back the most (a crack's loop turns back at both its ends, runs straight on
    // between them).
    used[first] = 1;
    std::vector<std::int64_t> loop{open[first].first};
    std::int64_t from = open[first].first, at = open[first].second;
    while (at != loop[0]) {
      loop.push_back(at);
      auto it = std::lower_bound(open.begin(), open.end(), std::make_pair(at, std::int64_t{-1}));
      std::size_t best = open.size();
      double best_turn = INFINITY;
      for (; it != open.end() && it->first == at; ++it) {
        const std::size_t e = static_cast<std::size_t>(it - open.begin());
        if (used[e]) continue;
        const double turn = dot(normalized(soup.points[at] - soup.points[from]),
                                normalized(soup.points[it->second] - soup.points[at]));
        if (turn < best_turn) best = e, best_turn = turn;
      }
      if (best == open.size()) break;
      used[best] = 1;
      from = at;
      at = open[best].second;
    }
    if (at != loop[0] || loop.size() < 3) continue;
    // The line: through the loop's vertex farthest from its first and the one farthest from that.
    const auto farthest = [&](const Vec3d& from) {
      return *std::max_element(loop.begin(), loop.end(), [&](std::int64_t a, std::int64_t b) {
        return distance(soup.points[a], from) < distance(soup.points[b], from);
      });
    };
    const Vec3d p = soup.points[farthest(soup.points[loop[0]])];
    const Vec3d q = soup.points[farthest(p)];
    if (!(distance(p, q) > 0)) continue;
    const Vec3d axis = normalized(q - p);
    std::vector<double> along(loop.size());
    bool thin = true;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Vec3d d = soup.points[loop[i]] - p;
      along[i] = dot(d, axis);
      thin = thin && norm(d - axis * along[i]) <= max_width;
    }
    if (!thin) continue;
    // Slivers cut off the loop run the other way round (the open edges' other sides), each at the
    // first vertex lying strictly between its neighbours along the line.
    std::vector<std::size_t> left(loop.size());
    std::iota(left.begin(), left.end(), std::size_t{0});
    std::reverse(left.begin(), left.end());
    // (A cut changes only its neighbours: the next search starts at the one before it.)
    std::vector<std::vector<std::int64_t>> slivers;
    for (std::size_t from_i = 0; left.size() >= 3;) {
      const std::size_t m = left.size();
      std::size_t cut = m;
      for (std::size_t j = 0; j < m && cut == m; ++j) {
        const std::size_t i = (from_i + j) % m;
        const double a = along[left[(i + m - 1) % m]], b = along[left[i]],
                     c = along[left[(i + 1) % m]];
        if ((a < b && b < c) || (a > b && b > c)) cut = i;
      }
      if (cut == m) break;
      slivers.push_back(
          {loop[left[(cut + m - 1) % m]], loop[left[cut]], loop[left[(cut + 1) % m]]});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(cut));
      from_i = cut > 0 ? cut - 1 : 0;
    }
    if (left.size() > 2) continue;  // zig-zags back and forth: left open
    added += slivers.size();
    for (auto& sliver : slivers) out.polygons.push_back(std::move(sliver));
  }
  if (added == 0) return {};
  return out;
}

/// `soup` without the polygons that repeat an earlier one corner for corner, in the same
/// direction (a face written twice), and how many are gone (0, with an empty soup, when none).
/// The first polygon dropped is `first`.
PolygonSoup drop_repeated_polygons(const PolygonSoup& soup, std::size_t& dropped,
                                   std::size_t& first) {
  dropped = 0;
  // Each polygon's corners from its smallest index on: equal for the same cycle in one direction.
  std::vector<std::pair<std::vector<std::int64_t>, std::size_t>> cycles(soup.polygons.size());
  for (std::size_t p = 0; p < soup.polygons.size(); ++p) {
    std::vector<std::int64_t> c = soup.polygons[p];
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    cycles[p] = {std::move(c), p};
  }
  std::sort(cycles.begin(), cycles.end());
  std::vector<char> repeat(soup.polygons.size(), 0);
  for (std::size_t i = 1; i < cycles.size(); ++i)
    if (cycles[i].first == cycles[i - 1].first) repeat[cycles[i].second] = 1;
  PolygonSoup out;
  for (std::size_t p = 0; p < soup.polygons.size(); ++p)
    if (!repeat[p])
      out.polygons.push_back(soup.polygons[p]);
    else if (dropped++ == 0)
      first = p;
  if (dropped == 0) return {};
  out.points = soup.points;
  return out;
}

/// The rules that make_surface() mends (after welding) when they are all that is left:
/// inconsistent orientation (orient_faces_alike()), zero-area faces (flip_zero_area_faces(),
/// last), pinched vertices and edges where parts touch (split_pinched_vertices()); and those it
/// tries to mend whenever they are broken: open edges (weld_open_seams(), close_thin_cracks()) and
/// duplicate faces (drop_repeated_polygons()).
constexpr const char* kOrientationRule = "inconsistently oriented faces";
constexpr const char* kBoundaryRule = "boundary edges (the surface is not closed)";
constexpr const char* kDuplicateRule = "duplicate faces (the corners of another face)";
constexpr const char* kZeroAreaRule = "degenerate (zero-area) faces";
constexpr const char* kPinchedVertexRule = "non-manifold vertices (faces meeting only at a vertex)";
constexpr const char* kTouchingEdgeRule = "non-manifold edges (more than two faces on an edge)";
constexpr const char* kCrossingRule = "self-intersections (pairs of faces that cross)";
/// Checked last, on the surface to be shelled (oriented, zero-area faces flipped away).
constexpr const char* kInsideContactRule =
    "places where the surface touches itself from inside (a corner or an edge of one face on "
    "another face, inside its edges, the solid on both sides of that face: a wall of no "
    "thickness, which no prism under the face can keep out of)";

/// `soup` with polygons turned so that the two polygons on every side shared by exactly two run
/// along it in opposite directions, the fewer of each group of polygons joined by such sides
/// turning (ties: those that disagree with the group's first), and how many were turned (0, with
/// an empty soup, when none, or when a group cannot agree: a one-sided surface).
PolygonSoup orient_faces_alike(const PolygonSoup& soup, std::size_t& turned) {
  turned = 0;
  std::vector<std::size_t> start;
  const std::vector<Side> sides = polygon_sides(soup, start);
  // Across each manifold side: the neighbour, and whether the two run the same way.
  std::vector<std::vector<std::pair<std::uint32_t, bool>>> across(soup.polygons.size());
  for_each_edge(sides, [&](std::size_t i, std::size_t j) {
    if (j - i != 2 || sides[i].lo == sides[i].hi) return;
    const bool same = sides[i].forward == sides[i + 1].forward;
    across[sides[i].polygon].emplace_back(sides[i + 1].polygon, same);
    across[sides[i + 1].polygon].emplace_back(sides[i].polygon, same);
  });
  std::vector<signed char> flip(soup.polygons.size(), -1);  // -1 not reached yet
  std::vector<std::uint32_t> stack, group;
  for (std::uint32_t root = 0; root < soup.polygons.size(); ++root) {
    if (flip[root] >= 0) continue;
    flip[root] = 0;
    stack.push_back(root);
    group.clear();
    std::size_t flips = 0;
    while (!stack.empty()) {
      const std::uint32_t p = stack.back();
      stack.pop_back();
      group.push_back(p);
      flips += static_cast<std::size_t>(flip[p]);
      for (const auto& [q, same] : across[p]) {
        const signed char want = static_cast<signed char>(flip[p] ^ (same ? 1 : 0));
        if (flip[q] < 0) {
          flip[q] = want;
          stack.push_back(q);
        } else if (flip[q] != want) {
          return {};  // one-sided: no orientation agrees everywhere
        }
      }
    }
    // The fewer turn (which way the whole group faces is decided after).
    if (2 * flips > group.size())
      for (const std::uint32_t p : group) flip[p] ^= 1;
  }
  PolygonSoup out = soup;
  for (std::size_t p = 0; p < out.polygons.size(); ++p)
    if (flip[p] == 1) {
      std::reverse(out.polygons[p].begin(), out.polygons[p].end());
      ++turned;
    }
  if (turned == 0) return {};
  return out;
}

/// The sides [i, j) of one edge (more than two), paired up where parts of a surface touch along
/// it (a union of solids meeting only along the edge, a solid touching itself): around the edge,
/// polygons must alternate in direction, and each is paired with its neighbour on the side where
/// it faces into the solid (`across_solid`) or out of it. Returns the pairs as offsets from i
/// (empty when the polygons do not alternate or two lie in one half-plane, e.g. parts touching
/// face to face).
std::vector<std::pair<std::size_t, std::size_t>> touching_pairs(
    const PolygonSoup& soup, const std::vector<Side>& sides, const std::vector<std::size_t>& start,
    std::size_t i, std::size_t j, bool across_solid) {
  const std::size_t n = j - i;
  if (n % 2) return {};
  // Directions only, each scaled by its largest component first: any unit works (products of
  // coordinates far from 1 would overflow or vanish).
  const auto direction = [](const Vec3d& d) {
    const double largest = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    return largest > 0 && std::isfinite(largest) ? normalized(d / largest) : Vec3d{};
  };
  const Vec3d lo = soup.points[static_cast<std::size_t>(sides[i].lo)];
  const Vec3d axis = direction(soup.points[static_cast<std::size_t>(sides[i].hi)] - lo);
  // Each polygon's half-plane: the direction from the edge to the corner after the side.
  std::vector<std::pair<double, std::size_t>> around;
  Vec3d u, v;
  for (std::size_t s = i; s < j; ++s) {
    const Side& side = sides[s];
    const std::size_t p = side.polygon, size = soup.polygons[p].size();
    const std::size_t second = side.forward ? side.corner_hi : side.corner_lo;
    const std::int64_t next = soup.polygons[p][(second - start[p] + 1) % size];
    const Vec3d w = direction(soup.points[static_cast<std::size_t>(next)] - lo);
    const Vec3d across = w - axis * dot(w, axis);  // w less its part along the axis
    if (!(norm(across) > 0)) return {};
    if (s == i) {
      u = normalized(across);
      v = cross(axis, u);
    }
    around.emplace_back(std::atan2(dot(across, v), dot(across, u)), s - i);
  }
  std::sort(around.begin(), around.end());
  for (std::size_t k = 0; k + 1 < n; ++k)
    if (!(around[k].first < around[k + 1].first)) return {};
  // A polygon running lo to hi faces towards larger angles (its normal is the axis times its
  // direction), so the solid lies between one running hi to lo and the next running lo to hi
  // (pairs starting lo to hi enclose the space outside).
  const bool pair_start = !across_solid;  // the direction of each pair's first polygon
  const std::size_t first = sides[i + around[0].second].forward == pair_start ? 0 : 1;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t k = first; k < n + first; k += 2) {
    const std::size_t a = around[k].second, b = around[(k + 1) % n].second;
    if (sides[i + a].forward != pair_start || sides[i + b].forward == pair_start) return {};
    pairs.emplace_back(a, b);
  }
  return pairs;
}

/// Passes over the edges where parts touch, each pairing across the space outside those whose
/// ends no pairing across the solid split, before the fans are left as they are.
constexpr int kTouchingPasses = 8;

/// `soup` with every vertex whose faces form several fans (parts of the surface meeting only at
/// that point) given a copy of its own for each fan after the first (an empty soup when none).
/// Fans are joined across the polygons' sides shared by exactly two polygons, and across those
/// of edges where parts touch by the pairs touching_pairs() makes: the vertices along such an
/// edge are then split, one copy per pair. Such an edge is paired across the solid (each part
/// keeps its own edge), unless that splits neither of its ends (its part joins up again at both,
/// as where two cavities meet along an edge): then across the space outside. Copies follow the
/// soup's points, in the order their fans are met. `pinched` counts the vertices split that are
/// on no such edge, `touching` the edges.
PolygonSoup split_pinched_vertices(const PolygonSoup& soup, std::size_t& pinched,
                                   std::size_t& touching) {
  pinched = 0;
  touching = 0;
  std::vector<std::size_t> start;
  const std::vector<Side> sides = polygon_sides(soup, start);
  std::vector<std::pair<std::size_t, std::size_t>> edges;  // [i, j) of each touching edge
  for_each_edge(sides, [&](std::size_t i, std::size_t j) {
    if (j - i > 2 && sides[i].lo != sides[i].hi) edges.emplace_back(i, j);
  });
  std::vector<char> on_edge(soup.points.size(), 0), outside(edges.size(), 0);
  for (const auto& [i, j] : edges) {
    on_edge[static_cast<std::size_t>(sides[i].lo)] = 1;
    on_edge[static_cast<std::size_t>(sides[i].hi)] = 1;
  }
  // Each touching edge paired both ways once: [e][0] across the solid, [e][1] outside.
  std::vector<std::array<std::vector<std::pair<std::size_t, std::size_t>>, 2>> pairs(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    for (const bool across_solid : {true, false})
      pairs[e][across_solid ? 0 : 1] =
          touching_pairs(soup, sides, start, edges[e].first, edges[e].second, across_solid);
    // Left to be refused, not split by whatever its ends' fans make of it.
    if (pairs[e][0].empty() || pairs[e][1].empty()) return {};
  }
  const auto join = [&](DisjointSets& sets, const Side& a, const Side& b) {
    sets.unite(a.corner_lo, b.corner_lo);
    sets.unite(a.corner_hi, b.corner_hi);
  };
  DisjointSets manifold(start.back());  // across the sides of exactly two polygons
  for_each_edge(sides, [&](std::size_t i, std::size_t j) {
    if (j - i == 2) join(manifold, sides[i], sides[i + 1]);
  });
  DisjointSets fans = manifold;
  for (int pass = 0;; ++pass) {
    for (std::size_t e = 0; e < edges.size(); ++e)
      for (const auto& [a, b] : pairs[e][outside[e]])
        join(fans, sides[edges[e].first + a], sides[edges[e].first + b]);
    if (edges.empty() || pass + 1 == kTouchingPasses) break;
    // The vertices of touching edges with more than one fan.
    std::vector<std::size_t> first_fan(soup.points.size(), SIZE_MAX);
    std::vector<char> splits(soup.points.size(), 0);
    for (std::size_t p = 0; p < soup.polygons.size(); ++p)
      for (std::size_t k = 0; k < soup.polygons[p].size(); ++k) {
        const auto v = static_cast<std::size_t>(soup.polygons[p][k]);
        if (!on_edge[v]) continue;
        const std::size_t fan = fans.find(start[p] + k);
        if (first_fan[v] == SIZE_MAX) first_fan[v] = fan;
        if (fan != first_fan[v]) splits[v] = 1;
      }
    bool changed = false;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const Side& side = sides[edges[e].first];
      if (outside[e] || splits[static_cast<std::size_t>(side.lo)] ||
          splits[static_cast<std::size_t>(side.hi)])
        continue;
      outside[e] = 1;
      changed = true;
    }
    if (!changed) break;
    fans = manifold;
  }
  touching = edges.size();
  std::size_t split = 0;
  // Per vertex, the fan met first keeps it; per other fan (by its root corner), a copy.
  PolygonSoup out = soup;
  std::vector<std::size_t> first_fan(soup.points.size(), SIZE_MAX);
  std::vector<std::int64_t> copy_of(start.back(), -1);
  std::vector<char> was_split(soup.points.size(), 0);
  for (std::size_t p = 0; p < out.polygons.size(); ++p)
    for (std::size_t k = 0; k < out.polygons[p].size(); ++k) {
      std::int64_t& v = out.polygons[p][k];
      const std::size_t fan = fans.find(start[p] + k);
      std::size_t& first = first_fan[static_cast<std::size_t>(v)];
      if (first == SIZE_MAX) first = fan;
      if (fan == first) continue;
      if (copy_of[fan] < 0) {
        copy_of[fan] = static_cast<std::int64_t>(out.points.size());
        out.points.push_back(soup.points[static_cast<std::size_t>(v)]);
        if (!was_split[static_cast<std::size_t>(v)]) {
          ++split;
          pinched += on_edge[static_cast<std::size_t>(v)] ? 0 : 1;
        }
        was_split[static_cast<std::size_t>(v)] = 1;
      }
      v = copy_of[fan];
    }
  if (split == 0) {
    pinched = touching = 0;
    return {};
  }
  return out;
}

/// Faces of each component tried, largest first, before its orientation is left undecided.
constexpr std::size_t kOrientationProbes = 8;

/// Turns every component of `tris` (a valid surface: closed, consistently oriented, components
/// apart) whose faces point into the solid, the solid being where a ray crosses the surface an
/// odd number of times (the even-odd rule of OpenVDB's sign fill and of independent checkers):
/// a component inside an odd number of others bounds a cavity and faces into it. One component
/// is judged by the sign of its enclosed volume; each of several by two points just in front of
/// and just behind one of its largest faces, of which exactly the one behind must be inside
/// (when a nearby part leaves both on one side, the next face decides). Returns the first
/// triangle of each component turned, ascending, and sets `components`.
std::vector<std::uint32_t> orient_components(const std::vector<Vec3d>& points,
                                             std::vector<SoupTriangle>& tris,
                                             std::size_t& components) {
  DisjointSets sets(points.size());
  for (const SoupTriangle& t : tris) {
    sets.unite(t.v[0], t.v[1]);
    sets.unite(t.v[1], t.v[2]);
  }
  // Components numbered in the order of their first triangle.
  std::vector<std::uint32_t> number(points.size(), UINT32_MAX), comp(tris.size()), first;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    std::uint32_t& n = number[sets.find(tris[t].v[0])];
    if (n == UINT32_MAX) {
      n = static_cast<std::uint32_t>(first.size());
      first.push_back(static_cast<std::uint32_t>(t));
    }
    comp[t] = n;
  }
  components = first.size();
  SurfaceMesh unit;
  unit.points = points;
  scale_by_power_of_two(unit.points, unit_scale_exponent(points));
  unit.triangles.reserve(tris.size());
  for (const SoupTriangle& t : tris) unit.triangles.push_back(t.v);

  std::vector<char> turn(components, 0);
  if (components == 1) {
    turn[0] = signed_volume(unit) < 0.0;
  } else if (components > 1) {
    // Each component's largest faces, by twice their area.
    std::vector<std::vector<std::pair<double, std::uint32_t>>> probes(components);
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const Triangle& v = unit.triangles[t];
      const Vec3d& a = unit.points[v[0]];
      auto& best = probes[comp[t]];
      best.emplace_back(-norm(cross(unit.points[v[1]] - a, unit.points[v[2]] - a)),
                        static_cast<std::uint32_t>(t));
      if (best.size() > 2 * kOrientationProbes) {
        std::nth_element(best.begin(), best.begin() + kOrientationProbes, best.end());
        best.resize(kOrientationProbes);
      }
    }
    const double tolerance = 1e-12 * bounding_box(unit).diagonal();
    const InsideTester inside(unit, tolerance);
    for_each_index(components, [&](std::size_t c) {
      auto& best = probes[c];
      std::sort(best.begin(), best.end());
      for (std::size_t i = 0; i < std::min(best.size(), kOrientationProbes); ++i) {
        const Triangle& v = unit.triangles[best[i].second];
        const Vec3d &a = unit.points[v[0]], &b = unit.points[v[1]], &d = unit.points[v[2]];
        const Vec3d n = cross(b - a, d - a);
        const double twice_area = norm(n);
        // A thousandth of the inscribed circle's radius off the face.
        const double offset =
            1e-3 * twice_area / (distance(a, b) + distance(b, d) + distance(d, a));
        if (!(offset > 4.0 * tolerance)) continue;
        const Vec3d centre = (a + b + d) / 3.0, step = n * (offset / twice_area);
        const bool front_outside = inside.outside(centre + step);
        const bool back_outside = inside.outside(centre - step);
        if (front_outside == back_outside) continue;
        turn[c] = back_outside;
        return;
      }
    });
  }
  std::vector<std::uint32_t> turned;
  for (std::size_t c = 0; c < components; ++c)
    if (turn[c]) turned.push_back(first[c]);
  if (turned.empty()) return turned;
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (turn[comp[t]]) std::swap(tris[t].v[1], tris[t].v[2]);
  return turned;
}

}  // namespace

std::vector<SurfaceProblem> find_surface_problems(const PolygonSoup& soup,
                                                  const ValidationOptions& options) {
  std::vector<SurfaceProblem> problems;
  const std::size_t max = options.max_listed;
  if (!check_elements(soup, max, problems)) return problems;

  const SoupFaces faces{soup, fan_triangulate(soup)};
  ProblemCollector degenerate(kZeroAreaRule, "remove or collapse the zero-area faces", max);
  char fraction[32];  // 1e-9, not printf's 1e-09
  std::snprintf(fraction, sizeof fraction, "%g", options.short_edge_fraction);
  std::string under = fraction;
  for (const char* zero : {"e-0", "e+0"})
    if (const auto at = under.find(zero); at != std::string::npos) under.erase(at + 2, 1);
  ProblemCollector short_edge("faces with an edge under " + under +
                                  " of the bounding box diagonal (readers that weld positions "
                                  "join its ends)",
                              "collapse the short edges (merge each pair of vertices)", max);
  std::vector<char> repeated_corner;
  check_degenerate(faces, options, degenerate, short_edge, repeated_corner);
  ProblemCollector duplicate(kDuplicateRule,
                             "remove the repeated faces, or join the parts that touch face to "
                             "face",
                             max);
  check_duplicates(faces, duplicate);
  ProblemCollector boundary(kBoundaryRule, "close the holes or rebuild a watertight surface", max);
  ProblemCollector nonmanifold_edge(kTouchingEdgeRule, "remove or separate the extra faces", max);
  ProblemCollector orientation(kOrientationRule,
                               "orient all faces coherently (e.g. MeshLab's Re-Orient)", max);
  DisjointSets corners(faces.tris.size() * 3);  // fans around each vertex, for the vertex rule
  check_edges(faces, boundary, nonmanifold_edge, orientation, corners);
  ProblemCollector nonmanifold_vertex(kPinchedVertexRule,
                                      "split the vertex or join the parts along an edge", max);
  if (nonmanifold_edge.problem.count == 0)
    check_vertices(faces, repeated_corner, corners, nonmanifold_vertex);

  // Crossings only mean something on an otherwise valid surface (neighbours across an edge are
  // told apart by the edge), and cost as much as the rest together: last.
  ProblemCollector crossing(kCrossingRule,
                            "separate or re-mesh the crossing parts (for a .vdb input, a lower "
                            "--adaptivity)",
                            max);
  if (boundary.problem.count + nonmanifold_edge.problem.count + orientation.problem.count +
          nonmanifold_vertex.problem.count + degenerate.problem.count + duplicate.problem.count +
          short_edge.problem.count ==
      0)
    check_crossings(faces, crossing);

  boundary.flush_into(problems);
  nonmanifold_edge.flush_into(problems);
  nonmanifold_vertex.flush_into(problems);
  degenerate.flush_into(problems);
  short_edge.flush_into(problems);
  duplicate.flush_into(problems);
  orientation.flush_into(problems);
  crossing.flush_into(problems);
  return problems;
}

PolygonSoup polygon_soup_of(const SurfaceMesh& mesh) {
  PolygonSoup soup;
  soup.points = mesh.points;
  soup.polygons.reserve(mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) soup.polygons.push_back({t[0], t[1], t[2]});
  return soup;
}

SurfaceStats surface_stats(const SurfaceMesh& mesh) {
  SurfaceStats s;
  s.vertices = mesh.points.size();
  s.faces = mesh.triangles.size();
  s.bbox = bounding_box(mesh);
  // Measured at unit scale: only a volume beyond the doubles' range is Inf (or 0).
  int k = 0;
  const SurfaceMesh unit = at_unit_scale(mesh, k);
  s.mean_edge_length = std::ldexp(mean_edge_length(unit), -k);
  s.enclosed_volume = std::ldexp(signed_volume(unit), -3 * k);

  DisjointSets sets(mesh.points.size());
  for (const Triangle& t : mesh.triangles) {
    sets.unite(t[0], t[1]);
    sets.unite(t[1], t[2]);
  }
  // Per component: V, E, F for the Euler characteristic.
  std::vector<long long> comp_v(mesh.points.size(), 0), comp_e(mesh.points.size(), 0),
      comp_f(mesh.points.size(), 0);
  std::vector<char> used(mesh.points.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    ++comp_f[sets.find(t[0])];
    for (std::uint32_t v : t) used[v] = 1;
  }
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    if (used[v]) ++comp_v[sets.find(v)];
  const auto edges = unique_edges(mesh);
  s.edges = edges.size();
  for (const auto& e : edges) ++comp_e[sets.find(e.first)];
  long long genus2 = 0;
  for (std::size_t c = 0; c < mesh.points.size(); ++c) {
    if (comp_f[c] == 0) continue;
    ++s.components;
    genus2 += 2 - (comp_v[c] - comp_e[c] + comp_f[c]);
  }
  s.genus = static_cast<int>(genus2 / 2);
  return s;
}

LoadedSurface make_surface(const PolygonSoup& input, const std::string& source,
                           const ValidationOptions& options) {
  std::vector<SurfaceProblem> problems = find_surface_problems(input, options);
  // Faults mended keeping every polygon as written (but for its direction), tried only on a
  // surface that fails as it is (the parts of a valid surface that touch keep their own
  // vertices) and kept only if the result passes every rule. Seams: vertices repeated at exactly
  // one position along UV or normal seams, made one. If open edges are left, cracks: their
  // vertices a rounding apart made one, then loops of them along a line (T-junctions) closed by
  // slivers. Faces written twice: the repeats dropped. Then, if nothing else is left, faces
  // running against their neighbours, turned to agree with them; and pinches: parts of the
  // surface meeting only at a vertex, that vertex split, one per fan (and parts touching along
  // an edge, split along it).
  // Zero-area faces, when nothing else is left, are flipped away (zero_area.h) once the surface
  // is oriented, kept only if that makes a valid surface; if they do not, or if crossings are
  // all that is left, slivers are flipped with them (rounding folds them over their neighbours).
  std::size_t seam_vertices = 0, crack_vertices = 0, crack_faces = 0, repeated_faces = 0,
              first_repeated = 0, reoriented_faces = 0, pinched_vertices = 0, touching_edges = 0;
  PolygonSoup welded, near_welded, slivered, once, oriented, split;
  const PolygonSoup* mended = &input;
  bool flip = false;
  if (!problems.empty()) {
    std::vector<SurfaceProblem> left = problems;
    const auto take = [&](PolygonSoup& soup, std::size_t count) {
      if (count == 0) return;
      mended = &soup;
      left = find_surface_problems(soup, options);
    };
    const auto left_has = [&](const char* rule) {
      return std::any_of(left.begin(), left.end(),
                         [&](const SurfaceProblem& p) { return p.rule == rule; });
    };
    const auto left_only = [&](const char* rule) {
      return left_has(rule) && std::all_of(left.begin(), left.end(), [](const SurfaceProblem& p) {
               return p.rule == kOrientationRule || p.rule == kPinchedVertexRule ||
                      p.rule == kTouchingEdgeRule || p.rule == kZeroAreaRule;
             });
    };
    welded = weld_positions(input, seam_vertices);
    take(welded, seam_vertices);
    if (left_has(kBoundaryRule)) {
      near_welded = weld_open_seams(
          *mended, options.open_seam_fraction * points_diagonal(mended->points), crack_vertices);
      take(near_welded, crack_vertices);
    }
    if (left_has(kBoundaryRule)) {
      slivered = close_thin_cracks(
          *mended, options.t_junction_fraction * points_diagonal(mended->points), crack_faces);
      take(slivered, crack_faces);
    }
    if (left_has(kDuplicateRule)) {
      once = drop_repeated_polygons(*mended, repeated_faces, first_repeated);
      take(once, repeated_faces);
    }
    if (left_only(kOrientationRule)) {
      oriented = orient_faces_alike(*mended, reoriented_faces);
      take(oriented, reoriented_faces);
    }
    if (left_only(kPinchedVertexRule) || left_only(kTouchingEdgeRule)) {
      split = split_pinched_vertices(*mended, pinched_vertices, touching_edges);
      take(split, pinched_vertices + touching_edges);
    }
    flip = !left.empty() && std::all_of(left.begin(), left.end(), [](const SurfaceProblem& p) {
      return p.rule == kZeroAreaRule || p.rule == kCrossingRule;
    });
    if (left.empty()) problems.clear();
    if (flip) problems = std::move(left);  // what to say if the flips do not make it valid
  }
  const auto refuse = [&] {
    std::string msg = source + ": not a closed 2-manifold triangle surface: ";
    for (std::size_t i = 0; i < problems.size(); ++i) {
      const SurfaceProblem& p = problems[i];
      msg += std::string(i ? " | " : "") + (p.at_least ? "at least " : "") +
             std::to_string(p.count) + " " + p.rule + ", first: " + p.first + " — fix: " + p.remedy;
    }
    throw InputError(msg);
  };
  if (!problems.empty() && !flip) refuse();

  const PolygonSoup& soup = *mended;
  LoadedSurface out;
  out.source = source;
  out.seam_vertices = seam_vertices;
  out.crack_vertices = crack_vertices;
  out.crack_faces = crack_faces;
  out.repeated_faces = repeated_faces;
  out.reoriented_faces = reoriented_faces;
  out.pinched_vertices = pinched_vertices;
  out.touching_edges = touching_edges;
  out.polygons_read = soup.polygons.size();
  for (const auto& poly : soup.polygons)
    if (poly.size() > 3) ++out.triangulated_polygons;

  // Keep only the vertices some face uses, in their original order.
  std::vector<std::uint32_t> remap(soup.points.size(), UINT32_MAX);
  for (const auto& poly : soup.polygons)
    for (std::int64_t idx : poly) remap[static_cast<std::size_t>(idx)] = 0;
  for (std::size_t i = 0; i < soup.points.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = static_cast<std::uint32_t>(out.mesh.points.size());
      out.mesh.points.push_back(soup.points[i]);
    }
  out.dropped_unused_vertices = soup.points.size() - out.mesh.points.size();
  std::vector<SoupTriangle> tris = fan_triangulate(soup);
  for (SoupTriangle& t : tris)
    for (std::uint32_t& v : t.v) v = remap[v];

  std::size_t components = 0;
  const std::vector<std::uint32_t> turned = orient_components(out.mesh.points, tris, components);
  out.mesh.triangles.reserve(tris.size());
  for (const SoupTriangle& t : tris) out.mesh.triangles.push_back(t.v);
  if (!turned.empty() && turned.size() == components) {
    out.flipped = true;
    out.notices.push_back(
        "the surface was oriented inward (its faces point into the solid it bounds); all faces "
        "were flipped to point outward");
  } else if (!turned.empty()) {
    out.flipped_components = turned.size();
    const bool tri_only = soup.polygons[tris[turned[0]].polygon].size() == 3;
    out.notices.push_back(
        std::to_string(turned.size()) + " of " + std::to_string(components) +
        " components faced into the solid (a body's faces must point out of it, a cavity's into "
        "it) and were flipped, the first being the component of " +
        (tri_only ? "face " : "polygon ") + std::to_string(tris[turned[0]].polygon));
  }
  if (flip) {
    // At unit scale (the flat tets' volumes are cubes of lengths): the same faces, flipped alike.
    int k = 0;
    const SurfaceMesh unit = at_unit_scale(out.mesh, k);
    const double diag = points_diagonal(unit.points),
                 min_twice_area = zero_twice_area(diag, options);
    std::vector<SurfaceProblem> after_flips;  // what the flips valid() tried last leave wrong
    const auto valid = [&](const std::optional<ZeroAreaFlips>& flips) {
      if (!flips || flips->empty()) return false;
      after_flips =
          find_surface_problems(polygon_soup_of(flipped_surface(out.mesh, *flips)), options);
      return after_flips.empty();
    };
    std::optional<ZeroAreaFlips> flips = flip_zero_area_faces(unit, min_twice_area);
    if (!valid(flips)) {
      // What the zero-area flips alone leave (crossings are not looked for while such faces
      // are there) is said too, should the surface be refused.
      for (SurfaceProblem& p : after_flips)
        if (std::none_of(problems.begin(), problems.end(),
                         [&](const SurfaceProblem& q) { return q.rule == p.rule; })) {
          p.rule += " once the zero-area faces are flipped away";
          problems.push_back(std::move(p));
        }
      // Slivers with a corner where the surface crosses itself, before or after those flips.
      SliverFlips slivers{options.sliver_fraction * diag, std::vector<char>(unit.points.size()),
                          1e-12 * diag};
      const auto mark = [&](const SurfaceMesh& mesh) {
        for (const auto& pair : surface_self_intersections(mesh, kCrossingsCounted))
          for (const std::uint32_t f : pair)
            for (const std::uint32_t v : mesh.triangles[f]) slivers.near[v] = 1;
      };
      mark(unit);
      if (flips && !flips->empty()) mark(flipped_surface(unit, *flips));
      flips = flip_zero_area_faces(unit, min_twice_area, slivers);
      if (!valid(flips)) refuse();
    }
    out.zero_area = std::move(*flips);
    const auto zero = std::find_if(problems.begin(), problems.end(),
                                   [](const SurfaceProblem& p) { return p.rule == kZeroAreaRule; });
    if (zero != problems.end())
      out.notices.push_back(
          std::to_string(zero->count) +
          " faces have zero area (three corners on one line): the shell is built with the edge "
          "facing each one's widest angle flipped, and each is kept on its outer boundary by a "
          "flat tet (zero volume) glued on there");
    if (out.zero_area.slivers) {
      std::ostringstream within;
      within << options.sliver_fraction;
      out.notices.push_back(
          std::to_string(out.zero_area.slivers) +
          " slivers (faces with the corner facing their longest edge within " + within.str() +
          " of the bounding box diagonal of it, as rounding leaves where a vertex sits on or "
          "next to another face's edge) were flipped the same way" +
          (zero != problems.end() ? "" : ", the surface crossing itself at them") +
          ": each is kept on the outer boundary by a flat tet glued on there (the sliver, the "
          "face across its longest edge and the two faces the flip made)");
    }
  }
  {
    // Only now is "inside" known: the surface oriented outward, and with the flips made.
    int k = 0;
    SurfaceMesh unit = at_unit_scale(out.mesh, k);
    if (!out.zero_area.empty()) unit = flipped_surface(unit, out.zero_area);
    // Inside a face by more than a sliver's height: a corner nearer its edge is a T-junction.
    const double margin = options.sliver_fraction * points_diagonal(unit.points);
    const std::vector<std::array<std::uint32_t, 2>> contacts =
        surface_inside_contacts(unit, margin, kCrossingsCounted);
    if (!contacts.empty()) {
      ProblemCollector contact(kInsideContactRule,
                               "move the parts apart, or into each other, so that the wall has a "
                               "thickness (a cut ending exactly on a face: let it stop short of "
                               "the face or go through it)",
                               options.max_listed);
      contact.problem.at_least = contacts.size() == kCrossingsCounted;
      const SoupFaces faces{soup, {}};
      for (const auto& [f, g] : contacts) {
        if (contact.examples.size() >= contact.max) {
          contact.add({});
          continue;
        }
        const Vec3d x = *surface_triangles_touch_inside(unit, f, g, margin);
        contact.add(faces.face_name(tris[f]) + " and " + faces.face_name(tris[g]) + " touch at " +
                    fmt_point({std::ldexp(x.x, -k), std::ldexp(x.y, -k), std::ldexp(x.z, -k)}));
      }
      problems.clear();
      contact.flush_into(problems);
      refuse();
    }
  }
  const auto note = [&](std::size_t count, const char* what) {
    if (count) out.notices.push_back(std::to_string(count) + what);
  };
  note(out.seam_vertices,
       " vertices at the position of an earlier vertex (seams written twice) were welded to it: "
       "welded, the surface is closed");
  if (out.crack_vertices) {
    std::ostringstream at;
    at << options.open_seam_fraction;
    out.notices.push_back(std::to_string(out.crack_vertices) + " vertices of open edges within " +
                          at.str() +
                          " of the bounding box diagonal of another were welded to it (a crack "
                          "where two patches' shared vertices were written a rounding apart): "
                          "welded, the surface is closed");
  }
  if (out.crack_faces)
    out.notices.push_back(
        std::to_string(out.crack_faces) +
        " slivers were added to close cracks along a line where one side has vertices on an "
        "edge of the other (T-junctions): closed, the surface is valid; they come after the "
        "input's faces (source_triangle " +
        std::to_string(out.mesh.triangles.size() - out.crack_faces) + " on)");
  if (out.repeated_faces)
    out.notices.push_back(std::to_string(out.repeated_faces) +
                          " faces repeated an earlier face corner for corner (written twice) and "
                          "were dropped, the first being polygon " +
                          std::to_string(first_repeated) +
                          " (the shell's source_triangle counts the faces without them)");
  note(out.reoriented_faces,
       " faces ran against their neighbours (inconsistent orientation) and were turned to agree "
       "with them");
  note(out.pinched_vertices,
       " vertices where parts of the surface meet only at that point were split, one vertex per "
       "fan of faces: split, the surface is 2-manifold");
  note(out.touching_edges,
       " edges where parts of the surface touch (more than two faces on the edge, faces of the "
       "parts alternating around it) were split, one edge per part: split, the surface is "
       "2-manifold");
  note(out.triangulated_polygons,
       " polygons with more than three corners were split into triangles");
  note(out.dropped_unused_vertices, " vertices used by no face were dropped");
  out.stats = surface_stats(out.mesh);
  return out;
}

LoadedSurface load_surface(const std::string& path, const ValidationOptions& options) {
  return make_surface(read_polygon_soup(path), path, options);
}

}  // namespace vdb_shell

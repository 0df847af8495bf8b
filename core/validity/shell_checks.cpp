// shell_checks.cpp — see shell_checks.h: check_shell(), check_added_tets(), check_volumes(),
// surface_self_intersections() and describe_problems(). The parts live in their own files:
//   * check_steps.h: the checks of single elements (volumes, surface points, boundary faces,
//     inner points) and the recording of the intersections, shared with ShellChecker
//     (shell_checker.cpp);
//   * inside_test.h: point inside the surface (ray parity; when ambiguous, rays from points
//     near it, then the winding number);
//   * tet_grid.h, tet_intersections.h: the broad and the narrow phase of the overlap and leak
//     tests, shared with ShellChecker; tet_predicates.h: the separating-axis tests.
#include "core/validity/shell_checks.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>

#include "core/base/errors.h"
#include "core/base/index_lists.h"
#include "core/base/parallel.h"
#include "core/base/timer.h"
#include "core/validity/check_steps.h"
#include "core/validity/inside_test.h"
#include "core/validity/tet_grid.h"
#include "core/validity/tet_intersections.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// Inner points inside the surface.
void check_inner_points(const TetMesh& mesh, const std::vector<std::uint32_t>& inner_points,
                        const InsideTester& inside, const ShellCheckOptions& options,
                        ShellCheckResult& result) {
  std::vector<std::uint8_t> outside(inner_points.size(), 0);
  for_each_index(inner_points.size(), [&](std::size_t i) {
    outside[i] = inside.outside(mesh.points[inner_points[i]]) ? 1 : 0;
  });
  record_outside_points(inner_points, outside, options, result);
}

// Tet-tet overlaps and leaks of the tets `queries` (mesh indices): the tets `tets` (mesh
// indices, ascending, the queries among them) in one BroadPhase over their bounding box; the
// queries go to the narrow phase, against each other and the rest. Consecutive tets of `tets` with
// one source triangle (the tets of a prism) share a group of the phase, up to 3 * options.layers
// of them; without source triangles, or when most groups would be partial, each tet is a group.
void check_intersections(const SurfaceMesh& surface, const TetMesh& mesh,
                         const std::vector<std::uint32_t>& tets,
                         const std::vector<std::uint32_t>& queries, const InsideTester& inside,
                         const ShellCheckOptions& options, ShellCheckResult& result) {
  const std::size_t n = tets.size();
  if (n == 0) return;
  // Per position in `tets`: its key, in groups of `size` keys; the keys a group leaves unused
  // are absent. Returns how many keys that takes.
  std::vector<std::uint32_t> key_of(n);
  const auto assign_keys = [&](std::uint64_t size) {
    std::uint64_t next = 0;  // the next free key
    for (std::size_t k = 0; k < n; ++k) {
      const bool same_group = size > 1 && k > 0 && next % size != 0 &&
                              mesh.source_triangle[tets[k]] == mesh.source_triangle[tets[k - 1]];
      if (!same_group) next = (next + size - 1) / size * size;  // a fresh group's first key
      key_of[k] = static_cast<std::uint32_t>(next++);
    }
    return (next + size - 1) / size * size;
  };
  std::uint32_t G = mesh.source_triangle.size() == mesh.tets.size()
                        ? 3 * static_cast<std::uint32_t>(std::max(1, options.layers))
                        : 1;
  std::uint64_t key_count = assign_keys(G);
  // Mostly partial groups (a subset of each prism's tets) would cost more absent keys than the
  // grouping saves: each tet is a group then.
  if (G > 1 && (key_count > 2 * std::uint64_t{n} || key_count > UINT32_MAX)) {
    G = 1;
    key_count = assign_keys(G);
  }
  // Every key set once: each tet's, then the absent keys up to the next tet's (key_of ascends
  // from 0) as empty boxes.
  TetGeometries geo(key_count);
  std::vector<std::uint32_t> tet_of_key(key_count, 0);
  for_each_chunk(
      n,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k != end; ++k) {
          geo[key_of[k]] = tet_geometry(tet_corners(mesh, tets[k]));
          tet_of_key[key_of[k]] = tets[k];
          const std::uint64_t next = k + 1 < n ? key_of[k + 1] : key_count;
          for (std::uint64_t j = key_of[k] + 1; j < next; ++j) geo[j] = TetGeometry{};
        }
      },
      1024);
  const BBox box = bounding_box_of(geo);
  const double cell_size = grid_cell_size(geo, box);
  BroadPhase phase(surface, box, cell_size, std::move(geo), options.check_leaks, G);
  std::vector<std::uint32_t> query_keys(queries.size());
  phase.insert(key_of);
  for (std::size_t i = 0; i < queries.size(); ++i)
    query_keys[i] = key_of[static_cast<std::size_t>(
        std::lower_bound(tets.begin(), tets.end(), queries[i]) - tets.begin())];
  const std::vector<TetFindings> found = find_intersections(phase, query_keys, inside, options);
  record_intersections(
      found, query_keys, [&](std::uint32_t key) { return tet_of_key[key]; }, options, result);
}

// The tets flagged in `added` and every tet whose box meets one of theirs, ascending.
std::vector<std::uint32_t> tets_near_added(const TetMesh& mesh, const std::vector<char>& added) {
  std::vector<BBox> boxes;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    if (added[t]) boxes.push_back(tet_geometry(tet_corners(mesh, t)).box);
  std::vector<std::uint8_t> near(mesh.tets.size(), 0);
  for_each_chunk(
      mesh.tets.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t != end; ++t) {
          if (added[t]) {
            near[t] = 1;
            continue;
          }
          BBox box;
          for (const std::uint32_t v : mesh.tets[t]) box.expand(mesh.points[v]);
          near[t] = std::any_of(boxes.begin(), boxes.end(),
                                [&](const BBox& b) { return boxes_overlap(box, b); });
        }
      },
      4096);
  std::vector<std::uint32_t> out;
  for (std::size_t t = 0; t < near.size(); ++t)
    if (near[t]) out.push_back(static_cast<std::uint32_t>(t));
  return out;
}

// check_shell() with the overlap and leak tests for every tet (`added` null) or only for the
// tets flagged in `added`, against the tets whose boxes meet theirs (check_added_tets()).
ShellCheckResult check_tets(const SurfaceMesh& surface, const TetMesh& mesh,
                            const ShellCheckOptions& options, const std::vector<char>* added) {
  const auto start = Clock::now();
  ShellCheckResult result;
  const std::vector<std::uint32_t> inner_points = check_elements(surface, mesh, options, result);
  check_boundary_faces(surface, mesh, options, result);
  const InsideTester inside(surface, on_surface_distance(surface, options));
  check_inner_points(mesh, inner_points, inside, options, result);
  if (options.check_overlaps || options.check_leaks) {
    const std::size_t shell_tets = mesh.tets.size() - std::min(options.flat_tets, mesh.tets.size());
    std::vector<std::uint32_t> queries;
    for (std::size_t t = 0; t < shell_tets; ++t)
      if (!added || (*added)[t]) queries.push_back(static_cast<std::uint32_t>(t));
    if (!added) {
      check_intersections(surface, mesh, queries, queries, inside, options, result);
    } else {
      std::vector<std::uint32_t> near = tets_near_added(mesh, *added);
      near.erase(std::lower_bound(near.begin(), near.end(), shell_tets), near.end());
      check_intersections(surface, mesh, near, queries, inside, options, result);
    }
  }
  result.seconds = seconds_since(start);
  return result;
}

// The cell size of surface_self_intersections()'s grid over `box`: the triangles' mean edge
// length, grown until the grid has at most 8 cells per triangle (plus 64).
double triangle_cell_size(const SurfaceMesh& surface, const BBox& box) {
  const std::size_t n = surface.triangles.size();
  double mean_edge = 0;
  for (std::size_t f = 0; f < n; ++f) {
    const std::array<Vec3d, 3> t = triangle_corners(surface, f);
    mean_edge += (distance(t[0], t[1]) + distance(t[1], t[2]) + distance(t[2], t[0])) / (3.0 * n);
  }
  double h = std::max(mean_edge, 1e-12 * box.diagonal());
  while (std::ceil(box.extent().x / h + 1) * std::ceil(box.extent().y / h + 1) *
             std::ceil(box.extent().z / h + 1) >
         8.0 * static_cast<double>(n) + 64.0)
    h *= 1.25;
  return h;
}

// Whether surface triangles f and g cross, neighbours across an edge excepted (they only touch
// on a 2-manifold); the tolerance is relative to the longest edge of the two, as for tets.
bool surface_triangles_cross(const SurfaceMesh& surface, std::uint32_t f, std::uint32_t g) {
  const Triangle& ta = surface.triangles[f];
  const Triangle& tb = surface.triangles[g];
  int shared = 0;
  for (const std::uint32_t u : ta) shared += (u == tb[0]) + (u == tb[1]) + (u == tb[2]);
  if (shared > 2) return false;
  const std::array<Vec3d, 3> a = triangle_corners(surface, f);
  const std::array<Vec3d, 3> b = triangle_corners(surface, g);
  const double tol = ShellCheckOptions{}.overlap_tolerance *
                     std::max({distance(a[0], a[1]), distance(a[1], a[2]), distance(a[2], a[0]),
                               distance(b[0], b[1]), distance(b[1], b[2]), distance(b[2], b[0])});
  if (shared < 2) return triangles_cross(a, b, tol);
  // Two faces of an edge cross where one folds back onto the other: their third corners on one
  // side of the edge, the nearer one to the edge within tol of the other's plane (a sliver that
  // rounding turned over, as CAD exports leave).
  int k = 0, j = 0;
  while (std::find(tb.begin(), tb.end(), ta[k]) != tb.end()) ++k;
  while (std::find(ta.begin(), ta.end(), tb[j]) != ta.end()) ++j;
  const Vec3d &u = a[(k + 1) % 3], along = normalized(a[(k + 2) % 3] - u);
  const auto off_edge = [&](const Vec3d& x) { return (x - u) - along * dot(x - u, along); };
  const Vec3d p = off_edge(a[k]), q = off_edge(b[j]);
  return dot(p, q) > 0 && norm(cross(p, q)) <= tol * std::max(norm(p), norm(q));
}

std::string format_list(const std::vector<std::uint32_t>& list) {
  std::ostringstream s;
  for (std::size_t i = 0; i < list.size(); ++i) s << (i ? ", " : "") << list[i];
  return s.str();
}

}  // namespace

bool ShellCheckResult::valid() const {
  return inverted_tets == 0 && zero_volume_tets == 0 && outside_inner_vertices == 0 &&
         moved_surface_points == 0 && missing_triangles == 0 && shared_triangles == 0 &&
         misoriented_triangles == 0 && nonmanifold_faces == 0 && overlapping_pairs == 0 &&
         leaking_tets == 0 && !too_many_tets;
}

ShellCheckResult check_volumes(const TetMesh& mesh, const ShellCheckOptions& options) {
  const auto start = Clock::now();
  ShellCheckResult result;
  result.tets = mesh.tets.size();
  count_volumes(mesh, options, result);
  result.seconds = seconds_since(start);
  return result;
}

ShellCheckResult check_shell(const SurfaceMesh& surface, const TetMesh& mesh,
                             const ShellCheckOptions& options) {
  return check_tets(surface, mesh, options, nullptr);
}

ShellCheckResult check_added_tets(const SurfaceMesh& surface, const TetMesh& mesh,
                                  const std::vector<char>& added,
                                  const ShellCheckOptions& options) {
  if (added.size() != mesh.tets.size())
    throw InputError("check_added_tets: " + std::to_string(added.size()) + " flags for " +
                     std::to_string(mesh.tets.size()) + " tets; give one per tet");
  return check_tets(surface, mesh, options, &added);
}

namespace {

// The pairs of surface triangles (f, g), f < g, that `pair_found(f, g)` accepts among those
// sharing a cell of a grid one cell larger than the surface's box on every side: at most
// `max_listed`, by ascending f, then g. Parallel over blocks of triangles, each keeping at most
// max_listed pairs, joined in triangle order: the same pairs for any thread count.
template <class PairFound>
std::vector<std::array<std::uint32_t, 2>> surface_pairs(const SurfaceMesh& surface,
                                                        std::size_t max_listed,
                                                        const PairFound& pair_found) {
  std::vector<std::array<std::uint32_t, 2>> out;
  const std::size_t n = surface.triangles.size();
  if (n == 0) return out;
  const BBox box = bounding_box(surface);
  const double h = triangle_cell_size(surface, box);
  BBox grid_box = box;
  grid_box.expand(box.lo - Vec3d{h, h, h});
  grid_box.expand(box.hi + Vec3d{h, h, h});
  const TetGrid grid(grid_box, h);
  // The cells of each face, and the faces of each cell (ascending).
  IndexLists face_cells, cell_faces;
  lists_in_blocks(
      n, 4096,
      [&](std::size_t f, std::vector<std::uint32_t>& cells) {
        const std::array<Vec3d, 3> t = triangle_corners(surface, f);
        const std::size_t at = cells.size();
        cells.resize(at + grid.cells_of_triangle(t, nullptr));
        grid.cells_of_triangle(t, cells.data() + at);
      },
      face_cells.start, face_cells.items);
  invert_lists(
      n,
      [&](std::size_t f) {
        const IndexLists::Range cells = face_cells[f];
        return std::make_pair(cells.begin(), cells.end());
      },
      grid.num_cells(), cell_faces.start, cell_faces.items);
  // Each face against the later ones sharing one of its cells, each pair once (a face met
  // again in another cell is marked with the face it was met for); chunks of blocks in
  // parallel, each block keeping at most max_listed pairs.
  const std::size_t blocks = std::min<std::size_t>(n, 256);
  std::vector<std::vector<std::array<std::uint32_t, 2>>> found(blocks);
  for_each_chunk(
      blocks,
      [&](std::size_t first, std::size_t last) {
        std::vector<std::uint32_t> met(n, UINT32_MAX), pairs;
        for (std::size_t b = first; b != last; ++b)
          for (auto f = static_cast<std::uint32_t>(b * n / blocks);
               f < (b + 1) * n / blocks && found[b].size() < max_listed; ++f) {
            pairs.clear();
            for (const std::uint32_t c : face_cells[f]) {
              const IndexLists::Range faces = cell_faces[c];
              for (const std::uint32_t* g = std::upper_bound(faces.begin(), faces.end(), f);
                   g != faces.end(); ++g)
                if (std::exchange(met[*g], f) != f && pair_found(f, *g)) pairs.push_back(*g);
            }
            std::sort(pairs.begin(), pairs.end());
            for (const std::uint32_t g : pairs)
              if (found[b].size() < max_listed) found[b].push_back({f, g});
          }
      },
      16);
  for (const auto& pairs : found)
    for (const auto& pair : pairs)
      if (out.size() < max_listed) out.push_back(pair);
  return out;
}

bool share_a_corner(const Triangle& a, const Triangle& b) {
  for (const std::uint32_t u : a)
    if (u == b[0] || u == b[1] || u == b[2]) return true;
  return false;
}

// Where a corner or an edge of triangle `b` lies on triangle `a` at least `margin` inside its
// edges, `b` reaching below `a`'s plane: within `tol` of the plane is on it, more is below.
std::optional<Vec3d> touches_from_below(const std::array<Vec3d, 3>& a,
                                        const std::array<Vec3d, 3>& b, double tol, double margin) {
  const Vec3d n = cross(a[1] - a[0], a[2] - a[0]);
  if (!(norm(n) > 0.0)) return std::nullopt;
  const Vec3d unit = n / norm(n);
  std::array<double, 3> height{};
  bool below = false;
  for (int k = 0; k < 3; ++k) {
    height[k] = dot(unit, b[k] - a[0]);
    below = below || height[k] < -tol;
  }
  if (!below) return std::nullopt;
  // Inside a's edges by at least `margin`: x + t d for t in [lo, hi] (a point: d = 0).
  const auto inside_part = [&](const Vec3d& x, const Vec3d& d) -> std::optional<Vec3d> {
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 3; ++k) {
      const Vec3d in = normalized(cross(unit, a[(k + 1) % 3] - a[k]));  // into a, in its plane
      const double s0 = dot(in, x - a[k]) - margin, ds = dot(in, d);
      if (ds == 0.0) {
        if (s0 < 0.0) return std::nullopt;
      } else if (ds > 0.0) {
        lo = std::max(lo, -s0 / ds);
      } else {
        hi = std::min(hi, -s0 / ds);
      }
    }
    if (lo > hi) return std::nullopt;
    return x + d * (0.5 * (lo + hi));
  };
  for (int k = 0; k < 3; ++k) {
    if (std::abs(height[k]) > tol) continue;
    const int j = (k + 1) % 3;
    const bool edge_on = std::abs(height[j]) <= tol;
    if (const auto x = inside_part(b[k], edge_on ? b[j] - b[k] : Vec3d{0, 0, 0})) return x;
  }
  return std::nullopt;
}

}  // namespace

std::vector<std::array<std::uint32_t, 2>> surface_self_intersections(const SurfaceMesh& surface,
                                                                     std::size_t max_listed) {
  return surface_pairs(surface, max_listed, [&](std::uint32_t f, std::uint32_t g) {
    return surface_triangles_cross(surface, f, g);
  });
}

std::optional<Vec3d> surface_triangles_touch_inside(const SurfaceMesh& surface, std::uint32_t f,
                                                    std::uint32_t g, double margin) {
  if (share_a_corner(surface.triangles[f], surface.triangles[g])) return std::nullopt;
  const std::array<Vec3d, 3> a = triangle_corners(surface, f);
  const std::array<Vec3d, 3> b = triangle_corners(surface, g);
  const double tol = ShellCheckOptions{}.overlap_tolerance *
                     std::max({distance(a[0], a[1]), distance(a[1], a[2]), distance(a[2], a[0]),
                               distance(b[0], b[1]), distance(b[1], b[2]), distance(b[2], b[0])});
  if (const auto x = touches_from_below(a, b, tol, margin)) return x;
  return touches_from_below(b, a, tol, margin);
}

std::vector<std::array<std::uint32_t, 2>> surface_inside_contacts(const SurfaceMesh& surface,
                                                                  double margin,
                                                                  std::size_t max_listed) {
  // Faces whose boxes, grown by the tolerance (at most that of the box's diagonal), do not
  // meet do not touch: most pairs of a grid cell.
  std::vector<BBox> boxes(surface.triangles.size());
  for_each_index(boxes.size(), [&](std::size_t f) {
    for (const Vec3d& p : triangle_corners(surface, f)) boxes[f].expand(p);
    const double slack = ShellCheckOptions{}.overlap_tolerance * boxes[f].diagonal();
    boxes[f] = {boxes[f].lo - Vec3d{slack, slack, slack}, boxes[f].hi + Vec3d{slack, slack, slack}};
  });
  return surface_pairs(surface, max_listed, [&](std::uint32_t f, std::uint32_t g) {
    return !share_a_corner(surface.triangles[f], surface.triangles[g]) &&
           boxes_overlap(boxes[f], boxes[g]) &&
           surface_triangles_touch_inside(surface, f, g, margin).has_value();
  });
}

Vec3d triangles_crossing_point(const SurfaceMesh& surface, std::uint32_t f, std::uint32_t g) {
  const std::array<Vec3d, 3> a = triangle_corners(surface, f);
  const std::array<Vec3d, 3> b = triangle_corners(surface, g);
  // Barycentric coordinates of x in the plane of t, all >= -eps: x lies in t.
  const auto inside = [](const std::array<Vec3d, 3>& t, const Vec3d& x) {
    const Vec3d n = cross(t[1] - t[0], t[2] - t[0]);
    const double n2 = norm2(n);
    if (!(n2 > 0.0)) return false;
    for (int k = 0; k < 3; ++k)
      if (dot(cross(t[(k + 1) % 3] - t[k], x - t[k]), n) < -1e-9 * n2) return false;
    return true;
  };
  const auto edge_through = [&](const std::array<Vec3d, 3>& e, const std::array<Vec3d, 3>& t,
                                Vec3d& x) {
    const Vec3d n = normalized(cross(t[1] - t[0], t[2] - t[0]));
    for (int k = 0; k < 3; ++k) {
      const Vec3d &p = e[k], &q = e[(k + 1) % 3];
      const double dp = dot(n, p - t[0]), dq = dot(n, q - t[0]);
      if ((dp > 0) == (dq > 0) || dp == dq) continue;
      x = p + (q - p) * (dp / (dp - dq));
      if (inside(t, x)) return true;
    }
    return false;
  };
  Vec3d x;
  if (edge_through(a, b, x) || edge_through(b, a, x)) return x;
  // (Not a corner they share: a face folded back onto its neighbour has its third one there.)
  const auto corner_of = [](const std::array<Vec3d, 3>& t, const Vec3d& x) {
    return std::find(t.begin(), t.end(), x) != t.end();
  };
  for (const Vec3d& p : a)
    if (!corner_of(b, p) && inside(b, p)) return p;
  for (const Vec3d& p : b)
    if (!corner_of(a, p) && inside(a, p)) return p;
  return ((a[0] + a[1] + a[2]) + (b[0] + b[1] + b[2])) / 6.0;
}

std::string describe_problems(const ShellCheckResult& r) {
  std::ostringstream s;
  const auto line = [&](std::size_t count, const char* what,
                        const std::vector<std::uint32_t>& first) {
    if (count == 0) return;
    s << count << ' ' << what;
    if (!first.empty()) s << " (first: " << format_list(first) << ')';
    s << '\n';
  };
  line(r.inverted_tets, "inverted tets", r.first_inverted_tets);
  line(r.zero_volume_tets, "zero-volume tets", r.first_zero_volume_tets);
  line(r.outside_inner_vertices, "inner vertices outside the surface", r.first_outside_vertices);
  line(r.moved_surface_points, "surface points moved", r.first_moved_surface_points);
  line(r.missing_triangles, "input triangles not a face of any tet", r.first_missing_triangles);
  line(r.shared_triangles, "input triangles shared by several tets", r.first_shared_triangles);
  line(r.misoriented_triangles, "input triangles on a tet turned the wrong way",
       r.first_misoriented_triangles);
  line(r.nonmanifold_faces, "faces shared by three or more tets", {});
  if (r.overlapping_pairs > 0) {
    s << r.overlapping_pairs << " overlapping tet pairs (first:";
    for (std::size_t i = 0; i < r.first_overlapping_pairs.size(); ++i)
      s << (i ? ", " : " ") << '(' << r.first_overlapping_pairs[i][0] << ", "
        << r.first_overlapping_pairs[i][1] << ')';
    s << ")\n";
  }
  line(r.leaking_tets, "tets reaching outside the surface", r.first_leaking_tets);
  if (r.too_many_tets) s << r.tets << " tets for " << r.faces << " triangles: more than 3 per\n";
  return s.str();
}

}  // namespace vdb_shell

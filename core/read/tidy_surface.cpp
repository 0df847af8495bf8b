// tidy_surface.cpp — see tidy_surface.h.
#include "core/read/tidy_surface.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <tuple>
#include <utility>
#include <vector>

#include "core/base/disjoint_sets.h"
#include "core/base/surface_mesh.h"

namespace vdb_shell {
namespace {

// A collapse may turn a face by at most this much (cos 30 degrees), and may not leave a face
// below kFairQuality and below half its quality before.
constexpr double kMaxTurnCos = 0.8660254037844386;
constexpr double kFairQuality = 0.1;

// The surface being edited: triangles (dead ones marked), and per vertex the triangles that may
// hold it (dead faces and stale entries are pruned where read).
class Editor {
 public:
  Editor(std::vector<Vec3d> points, std::vector<Triangle> triangles, double min_edge)
      : points_(std::move(points)),
        tris_(std::move(triangles)),
        alive_(tris_.size(), 1),
        faces_of_(points_.size()),
        min_edge2_(min_edge * min_edge) {
    for (std::uint32_t f = 0; f < tris_.size(); ++f)
      for (const std::uint32_t v : tris_[f]) faces_of_[v].push_back(f);
  }

  bool collapse(std::uint32_t a, std::uint32_t b);

  const std::vector<Vec3d>& points() const { return points_; }
  const std::vector<Triangle>& triangles() const { return tris_; }
  bool alive(std::uint32_t f) const { return alive_[f] != 0; }

 private:
  // The live faces holding vertex v.
  const std::vector<std::uint32_t>& faces_of(std::uint32_t v) {
    std::vector<std::uint32_t>& list = faces_of_[v];
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](std::uint32_t f) {
                                const Triangle& t = tris_[f];
                                return !alive_[f] || (t[0] != v && t[1] != v && t[2] != v);
                              }),
               list.end());
    return list;
  }
  Vec3d normal(const Triangle& t) const {
    return cross(points_[t[1]] - points_[t[0]], points_[t[2]] - points_[t[0]]);
  }
  double quality(const Triangle& t) const {
    return triangle_quality(points_[t[0]], points_[t[1]], points_[t[2]]);
  }
  double longest_edge2(const Triangle& t) const {
    return std::max({norm2(points_[t[1]] - points_[t[0]]), norm2(points_[t[2]] - points_[t[1]]),
                     norm2(points_[t[0]] - points_[t[2]])});
  }
  // The live face holding the directed edge u -> v, or -1.
  std::int64_t face_with_edge(std::uint32_t u, std::uint32_t v) {
    for (const std::uint32_t f : faces_of(u))
      for (int k = 0; k < 3; ++k)
        if (tris_[f][k] == u && tris_[f][(k + 1) % 3] == v) return f;
    return -1;
  }
  // The vertices joined to v by an edge, ascending.
  std::vector<std::uint32_t> ring(std::uint32_t v) {
    std::vector<std::uint32_t> out;
    for (const std::uint32_t f : faces_of(v))
      for (const std::uint32_t w : tris_[f])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // Whether a face of normal n0 and quality q0 may become `now` (at the current points): it keeps
  // an area, turns by less than 30 degrees and stays fair or within half its quality — unless all
  // its edges are short, when it is collapsed in turn.
  bool acceptable(const Vec3d& n0, double q0, const Triangle& now) const {
    const Vec3d n1 = normal(now);
    const double l0 = norm(n0), l1 = norm(n1);
    if (!(l1 > 0.0)) return false;
    if (longest_edge2(now) < min_edge2_) return true;
    if (!(l0 > 0.0) || dot(n0, n1) < kMaxTurnCos * l0 * l1) return false;
    const double q = quality(now);
    return q >= kFairQuality || q >= 0.5 * q0;
  }

  std::vector<Vec3d> points_;
  std::vector<Triangle> tris_;
  std::vector<char> alive_;
  std::vector<std::vector<std::uint32_t>> faces_of_;
  double min_edge2_;
};

// Collapses edge ab into its midpoint (vertex a stays, b goes) when the link condition holds (a
// and b share exactly the two neighbours across the edge, and are not two corners of a
// tetrahedron: the surface stays a 2-manifold) and every face that stays is acceptable().
bool Editor::collapse(std::uint32_t a, std::uint32_t b) {
  const std::int64_t f = face_with_edge(a, b), g = face_with_edge(b, a);
  if (f < 0 || g < 0) return false;
  if (faces_of(a).size() + faces_of(b).size() < 7) return false;
  const std::vector<std::uint32_t> ra = ring(a), rb = ring(b);
  std::vector<std::uint32_t> common;
  std::set_intersection(ra.begin(), ra.end(), rb.begin(), rb.end(), std::back_inserter(common));
  if (common.size() != 2) return false;
  // Every other face of a or b: its normal and quality now, then with both at the middle.
  std::vector<std::uint32_t> moved;
  std::vector<std::pair<Vec3d, double>> was;
  for (const std::uint32_t v : {a, b})
    for (const std::uint32_t h : faces_of(v))
      if (h != f && h != g) {
        moved.push_back(h);
        was.emplace_back(normal(tris_[h]), quality(tris_[h]));
      }
  const Vec3d pa = points_[a], pb = points_[b];
  points_[a] = points_[b] = (pa + pb) * 0.5;
  for (std::size_t i = 0; i < moved.size(); ++i)
    if (!acceptable(was[i].first, was[i].second, tris_[moved[i]])) {
      points_[a] = pa, points_[b] = pb;
      return false;
    }
  alive_[f] = alive_[g] = 0;
  for (const std::uint32_t h : faces_of(b)) {
    for (std::uint32_t& v : tris_[h])
      if (v == b) v = a;
    faces_of_[a].push_back(h);
  }
  faces_of_[b].clear();
  return true;
}

}  // namespace

double triangle_quality(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const double sum = norm2(b - a) + norm2(c - b) + norm2(a - c);
  if (!(sum > 0.0)) return 0.0;
  return 2.0 * std::sqrt(3.0) * norm(cross(b - a, c - a)) / sum;
}

PolygonSoup tidy_contoured_surface(const PolygonSoup& soup, const TidyOptions& options,
                                   TidyCounts* counts) {
  TidyCounts done;
  const std::vector<Vec3d>& p = soup.points;
  const auto is_frozen = [&](std::uint32_t v) {
    return v < options.frozen.size() && options.frozen[v] != 0;
  };
  // The parts (points joined by polygons) and six times the volume each encloses.
  DisjointSets parts(p.size());
  for (const std::vector<std::int64_t>& poly : soup.polygons)
    for (std::size_t k = 1; k < poly.size(); ++k)
      parts.unite(static_cast<std::size_t>(poly[0]), static_cast<std::size_t>(poly[k]));
  std::vector<double> volume6(p.size(), 0.0);  // per root
  std::vector<char> used(p.size(), 0);         // per root
  for (const std::vector<std::int64_t>& poly : soup.polygons) {
    const std::size_t r = parts.find(static_cast<std::size_t>(poly[0]));
    used[r] = 1;
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      volume6[r] += dot(p[poly[0]], cross(p[poly[k]], p[poly[k + 1]]));
  }
  std::vector<char> dropped(p.size(), 0);  // per root
  for (std::uint32_t v = 0; v < p.size(); ++v)
    if (used[v] && std::abs(volume6[v]) < 6.0 * options.min_part_volume) {
      dropped[v] = 1;
      ++done.dropped_parts;
    }

  std::vector<Triangle> tris;
  tris.reserve(2 * soup.polygons.size());
  for (const std::vector<std::int64_t>& poly : soup.polygons) {
    std::vector<std::uint32_t> v(poly.begin(), poly.end());
    if (dropped[parts.find(v[0])]) continue;
    if (v.size() == 4) {
      // Along the diagonal whose pair of triangles has the better worst one.
      const double q02 = std::min(triangle_quality(p[v[0]], p[v[1]], p[v[2]]),
                                  triangle_quality(p[v[0]], p[v[2]], p[v[3]]));
      const double q13 = std::min(triangle_quality(p[v[0]], p[v[1]], p[v[3]]),
                                  triangle_quality(p[v[1]], p[v[2]], p[v[3]]));
      if (q13 > q02) std::rotate(v.begin(), v.begin() + 1, v.end());
    }
    for (std::size_t k = 1; k + 1 < v.size(); ++k) tris.push_back({v[0], v[k], v[k + 1]});
  }
  Editor editor(p, std::move(tris), options.min_edge);

  // Rounds of collapses, shortest edge first; an edge with a corner moved this round waits for
  // the next one, at its new length.
  const double min2 = options.min_edge * options.min_edge;
  for (int round = 0; round < 64; ++round) {
    std::vector<std::tuple<double, std::uint32_t, std::uint32_t>> short_edges;
    const std::vector<Triangle>& t = editor.triangles();
    for (std::uint32_t f = 0; f < t.size(); ++f) {
      if (!editor.alive(f)) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t u = t[f][k], v = t[f][(k + 1) % 3];
        if (u > v || is_frozen(u) || is_frozen(v)) continue;  // each edge once: u -> v, u < v
        const double l2 = norm2(editor.points()[u] - editor.points()[v]);
        if (l2 < min2) short_edges.emplace_back(l2, u, v);
      }
    }
    std::sort(short_edges.begin(), short_edges.end());
    std::vector<char> moved(editor.points().size(), 0);
    std::size_t made = 0;
    for (const auto& [l2, u, v] : short_edges) {
      if (moved[u] || moved[v] || !editor.collapse(u, v)) continue;
      moved[u] = moved[v] = 1;
      ++made;
    }
    done.collapsed += made;
    if (made == 0) break;
  }

  // The live triangles on the points they use, in their order.
  PolygonSoup out;
  std::vector<std::int64_t> index(editor.points().size(), -1);
  const std::vector<Triangle>& t = editor.triangles();
  for (std::uint32_t f = 0; f < t.size(); ++f) {
    if (!editor.alive(f)) continue;
    std::vector<std::int64_t> poly;
    for (const std::uint32_t v : t[f]) {
      if (index[v] < 0) {
        index[v] = static_cast<std::int64_t>(out.points.size());
        out.points.push_back(editor.points()[v]);
      }
      poly.push_back(index[v]);
    }
    out.polygons.push_back(std::move(poly));
  }
  if (counts) *counts = done;
  return out;
}

}  // namespace vdb_shell

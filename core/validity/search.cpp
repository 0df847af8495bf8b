// search.cpp — moving inner vertices back along their traces until the shell is valid; see
// search.h for the method and why it terminates.
#include "core/validity/search.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <queue>

#include "core/assemble/quality.h"
#include "core/base/errors.h"
#include "core/base/index_lists.h"
#include "core/base/parallel.h"
#include "core/base/timer.h"
#include "core/inner/sectors.h"

namespace vdb_shell {
namespace {

/// First directions with a smaller inward margin (sine of the angle to the nearest incident
/// face plane) are bent towards the most inward direction.
constexpr double kMinMargin = 0.1;

/// Vertices joined by edges no longer than this fraction of the longest edge at each end form
/// a cluster (a vertex inserted on an edge next to its end, as T-junction repairs and CAD exports
/// leave, or several). Every other member m of a cluster follows its root a (its smallest
/// vertex) and a vertex b next to the cluster when m lies on the segment ab, and a's and b's
/// first directions go in at m's faces (else m's inner vertex could go out): its inner vertex is
/// a' + lambda (b' - a'), never a trace of its own. The sliver faces (a, m, c) then have the
/// inner faces (a', m', c'), lambda times the inner face (a', b', c') of the face the cluster
/// stands in for, never flipped when that one is not. An own trace would cross a's over such a
/// short edge, and the edge's floors would fall below the zero-volume tolerance.
constexpr double kClusterEdge = 1e-2;
/// m follows a and b when lambda <= this and m lies within kFollowOffLine * lambda |ab| of the
/// line through a and b.
constexpr double kFollowEnd = 1e-2;
constexpr double kFollowOffLine = 1e-2;
/// A member m on no such line follows its cluster's root a alone, at its offset from a, when
/// |am| <= this times the longest edge at a and at m: the two are nearly one.
constexpr double kNearlyOne = 1e-3;

/// A face (a, b, m) whose corner m lies within this fraction of |ab| of the segment ab, between
/// its ends (lambda in [kFollowEnd, 1 - kFollowEnd]), is a cap: m follows a and b
/// (find_followers()) at its own offset from the segment.
constexpr double kCapHeight = 1e-2;

/// Faces of a lower shape quality are slivers (ShellSearch::quality_demand()).
constexpr double kSliverShape = 0.1;

/// A tet below --min-quality whose longest edge is this many times its deepest inner corner's
/// depth is flat: it steps back only where that can bring it to the demand, or where every inner
/// corner is within kFlatFloors floors of the surface (ShellSearch::below_curable_quality()).
constexpr double kFlatEdges = 8;
constexpr double kFlatFloors = 4;
/// Steps back a needle below --min-quality must reach it within, to be stepped back (a vertex
/// keeps 0.85^8 = 27% of its depth after 8 steps; ShellSearch::reaches_by_steps()).
constexpr int kCurableSteps = 8;

/// The vertices of a follower's inner vertex: lambda along a' -> b' (a.k.a. m' above), moved
/// by `offset`, its own offset from the segment ab.
struct Leaders {
  std::uint32_t a = UINT32_MAX, b = UINT32_MAX;
  double lambda = 0;
  Vec3d offset;
  /// +1 or -1 when the follower is on a cap, as its base (x, y) runs in the cap's corner order
  /// (x, y, apex): from a to b or back; 0 on no cap (ShellSearch::demand()).
  int turn = 0;
  bool end = true;  ///< next to an edge's end (a cluster's member), or in a strip
};

/// m on the line through a and b: lambda along a -> b and its offset from the line.
Leaders along(const SurfaceMesh& surface, std::uint32_t m, std::uint32_t a, std::uint32_t b) {
  const Vec3d &pa = surface.points[a], &pb = surface.points[b];
  const double lambda = dot(surface.points[m] - pa, pb - pa) / norm2(pb - pa);
  return {a, b, lambda, surface.points[m] - (pa + (pb - pa) * lambda)};
}

/// Corner k of `tri` against the opposite side (along()) in `l`: whether the side has a length
/// and the corner lies within kCapHeight of it from the side's line.
bool near_side(const SurfaceMesh& surface, const Triangle& tri, int k, Leaders& l) {
  const std::uint32_t x = tri[(k + 1) % 3], y = tri[(k + 2) % 3];
  const double l2 = norm2(surface.points[y] - surface.points[x]);
  if (!(l2 > 0)) return false;
  l = along(surface, tri[k], x, y);
  return norm(l.offset) <= kCapHeight * std::sqrt(l2);
}

/// Whether every corner of face f lies within kCapHeight of the line through a and b, as a
/// fraction of |ab| and of f's longest edge: one of the caps (or needles) along ab, whose normal
/// its apexes' hair-thin offsets decide (a small face near the line has a normal of its own).
bool along_base(const SurfaceMesh& surface, std::uint32_t f, std::uint32_t a, std::uint32_t b) {
  if (a == b) return false;
  const Triangle& t = surface.triangles[f];
  double longest = 0;
  for (int k = 0; k < 3; ++k)
    longest = std::max(longest, distance(surface.points[t[k]], surface.points[t[(k + 1) % 3]]));
  const double height =
      kCapHeight * std::min(distance(surface.points[a], surface.points[b]), longest);
  for (const std::uint32_t u : surface.triangles[f])
    if (u != a && u != b && !(norm(along(surface, u, a, b).offset) <= height)) return false;
  return true;
}

/// Per vertex of `surface`: its leaders, or none (a = UINT32_MAX); empty when no vertex follows.
/// Two kinds, strips first: the vertices of strips of caps (kCapHeight) but their ends, then a
/// cluster's members next to an edge's end (kClusterEdge). Leaders are vertices that follow
/// none, and none of them is in a cluster but as its root. Sectors (`start.constraints`)
/// follow nothing and join no cluster. A cap's apex m follows its base (a, b), and a strip's
/// vertex m its ends a and b, only where `inward(m, a, b)`: the ways a and b go in each go in
/// at m too.
template <class Inward>
std::vector<Leaders> find_followers(const SurfaceMesh& surface, const IndexLists& faces,
                                    const InnerVertices& start, const Inward& inward) {
  const auto n = static_cast<std::uint32_t>(surface.points.size());
  const auto sector = [&](std::uint32_t v) {
    return v < start.constraints.size() && !start.constraints[v].empty();
  };
  std::vector<Leaders> out;
  std::vector<char> leads;
  const auto follows = [&](std::uint32_t v) { return !out.empty() && out[v].a != UINT32_MAX; };
  const auto leader = [&](std::uint32_t v) { return !out.empty() && leads[v]; };
  const auto follow = [&](std::uint32_t m, const Leaders& l) {
    if (out.empty()) {
      out.resize(n);
      leads.assign(n, 0);
    }
    out[m] = l;
    leads[l.a] = leads[l.b] = 1;
  };
  // Union-find, each set rooted at its smallest member.
  const auto find = [](std::vector<std::uint32_t>& root, std::uint32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  const auto join = [&](std::vector<std::uint32_t>& root, std::uint32_t u, std::uint32_t w) {
    const std::uint32_t ru = find(root, u), rw = find(root, w);
    root[std::max(ru, rw)] = std::min(ru, rw);
  };

  // Caps: faces (a, b, m) with m within kCapHeight |ab| of the segment ab, lambda in
  // [kFollowEnd, 1 - kFollowEnd]. Caps sharing an edge form a strip (a fan of slivers along
  // one edge, as T-junctions zipped shut leave): every vertex of it but its two ends p and q,
  // the farthest apart along it, follows them at its own offset from pq, when all lie that
  // close to the segment pq.
  const auto n_faces = static_cast<std::uint32_t>(surface.triangles.size());
  std::vector<std::uint32_t> strip;  // per face: a cap's set, UINT32_MAX for other faces
  std::vector<double> base;          // per face: a cap's base length
  std::vector<int> apex;             // per face: a cap's apex corner
  struct CapEdge {
    std::uint64_t key;  ///< the edge's ends, smaller first
    std::uint32_t face;
    bool base;
    bool operator<(const CapEdge& o) const { return key != o.key ? key < o.key : face < o.face; }
  };
  std::vector<CapEdge> cap_edges;
  for (std::uint32_t f = 0; f < n_faces; ++f)
    for (int k = 0; k < 3; ++k) {
      const Triangle& tri = surface.triangles[f];
      Leaders l;
      if (!near_side(surface, tri, k, l) ||
          !(l.lambda >= kFollowEnd && l.lambda <= 1 - kFollowEnd) || !inward(tri[k], l.a, l.b))
        continue;
      if (strip.empty()) {
        strip.assign(n_faces, UINT32_MAX);
        base.assign(n_faces, 0.0);
        apex.assign(n_faces, 0);
      }
      strip[f] = f;
      base[f] = distance(surface.points[l.a], surface.points[l.b]);
      apex[f] = k;
      for (int e = 0; e < 3; ++e) {  // the base, (k + 1, k + 2), marked
        const std::uint32_t u = tri[e], w = tri[(e + 1) % 3];
        cap_edges.push_back(
            {std::uint64_t(std::min(u, w)) << 32 | std::max(u, w), f, e == (k + 1) % 3});
      }
      break;
    }
  if (!strip.empty()) {
    // Caps on the two sides of their common base are two strips: the base's side quad can be
    // cut to suit only one of them (ShellSearch::demand()); the other's prisms are
    // valid only where the search's depths leave the quad less twisted than the caps are high.
    std::sort(cap_edges.begin(), cap_edges.end());
    for (std::size_t i = 1; i < cap_edges.size(); ++i) {
      const CapEdge &x = cap_edges[i - 1], &y = cap_edges[i];
      if (x.key == y.key && !(x.base && y.base)) join(strip, x.face, y.face);
    }
    // A needle between two caps of a strip (two of its vertices nearly one) joins it when its
    // third vertex lies as close to the line of a cap it shares a side (not the base) with.
    for (std::uint32_t g = 0; g < n_faces; ++g) {
      if (strip[g] != UINT32_MAX) continue;
      const Triangle& tri = surface.triangles[g];
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t u = tri[e], w = tri[(e + 1) % 3];
        const std::uint64_t key = std::uint64_t(std::min(u, w)) << 32 | std::max(u, w);
        const auto at =
            std::lower_bound(cap_edges.begin(), cap_edges.end(), CapEdge{key, 0, false});
        if (at == cap_edges.end() || at->key != key || at->base) continue;
        const Triangle& cap = surface.triangles[at->face];
        const Leaders l = along(surface, tri[(e + 2) % 3], cap[(apex[at->face] + 1) % 3],
                                cap[(apex[at->face] + 2) % 3]);
        if (l.lambda > 0 && l.lambda < 1 && norm(l.offset) <= kCapHeight * base[at->face]) {
          if (strip[g] == UINT32_MAX) strip[g] = g;
          join(strip, g, at->face);
        }
      }
    }
    IndexLists strips;
    strips.build(n_faces, [&](const auto& emit) {
      for (std::uint32_t f = 0; f < n_faces; ++f)
        if (strip[f] != UINT32_MAX) emit(find(strip, f), f);
    });
    std::vector<std::uint32_t> members;
    for (std::uint32_t s = 0; s < n_faces; ++s) {
      const auto caps = strips[s];
      if (caps.size() == 0) continue;
      members.clear();
      std::uint32_t widest = *caps.begin();  // the cap with the longest base: the strip's line
      for (const std::uint32_t f : caps) {
        members.insert(members.end(), surface.triangles[f].begin(), surface.triangles[f].end());
        if (base[f] > base[widest]) widest = f;
      }
      const Triangle& w = surface.triangles[widest];
      const Vec3d line =
          surface.points[w[(apex[widest] + 2) % 3]] - surface.points[w[(apex[widest] + 1) % 3]];
      std::sort(members.begin(), members.end());
      members.erase(std::unique(members.begin(), members.end()), members.end());
      const auto at = [&](std::uint32_t v) { return dot(surface.points[v], line); };
      std::uint32_t a = members.front(), b = members.front();
      for (const std::uint32_t v : members) {
        if (at(v) < at(a)) a = v;
        if (at(v) > at(b)) b = v;
      }
      if (a > b) std::swap(a, b);
      const Vec3d ab = surface.points[b] - surface.points[a];
      bool fits = norm2(ab) > 0 && !follows(a) && !follows(b);
      std::vector<Leaders> strip_leaders;
      for (const std::uint32_t v : members) {
        if (!fits) break;
        if (v == a || v == b) continue;
        Leaders l = along(surface, v, a, b);
        fits = l.lambda > 0 && l.lambda < 1 && norm(l.offset) <= kCapHeight * norm(ab) &&
               !sector(v) && !follows(v) && !leader(v) && inward(v, a, b);
        l.turn = dot(ab, line) > 0 ? 1 : -1;
        l.end = false;
        strip_leaders.push_back(l);
      }
      if (fits) {
        std::size_t i = 0;
        for (const std::uint32_t v : members)
          if (v != a && v != b) follow(v, strip_leaders[i++]);
        continue;
      }
      for (const std::uint32_t f : caps) {  // a strip that does not fit: cap by cap
        if (!(base[f] > 0)) continue;       // a needle
        const Triangle& tri = surface.triangles[f];
        const std::uint32_t m = tri[apex[f]], x = tri[(apex[f] + 1) % 3],
                            y = tri[(apex[f] + 2) % 3];
        if (sector(m) || follows(m) || leader(m) || follows(x) || follows(y)) continue;
        Leaders l = along(surface, m, std::min(x, y), std::max(x, y));
        l.turn = l.a == x ? 1 : -1;
        l.end = false;
        follow(m, l);
      }
    }
  }

  // Clusters: union-find over the short edges between vertices of no strip.
  std::vector<double> longest(n, 0.0);  // squared
  for (const Triangle& tri : surface.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], w = tri[(k + 1) % 3];
      const double l2 = norm2(surface.points[w] - surface.points[u]);
      longest[u] = std::max(longest[u], l2);
      longest[w] = std::max(longest[w], l2);
    }
  std::vector<char> in_strip(n, 0);  // strips' followers, apart from every cluster
  for (std::uint32_t v = 0; v < n; ++v) in_strip[v] = follows(v);
  const auto apart = [&](std::uint32_t v) { return sector(v) || in_strip[v]; };
  std::vector<std::uint32_t> root;
  for (const Triangle& tri : surface.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = tri[k], w = tri[(k + 1) % 3];
      const double l2 = norm2(surface.points[w] - surface.points[u]);
      if (!(l2 <= kClusterEdge * kClusterEdge * std::min(longest[u], longest[w])) || apart(u) ||
          apart(w))
        continue;
      if (root.empty()) {
        root.resize(n);
        std::iota(root.begin(), root.end(), 0u);
      }
      join(root, u, w);
    }
  if (root.empty()) return out;
  for (std::uint32_t v = 0; v < n; ++v) root[v] = find(root, v);
  IndexLists members;
  members.build(n, [&](const auto& emit) {
    for (std::uint32_t v = 0; v < n; ++v) emit(root[v], v);
  });
  // Each headed by its smallest vertex, or by the one leading a strip (two: none follows).
  std::vector<std::uint32_t> head(n);
  std::vector<char> led_twice(n, 0);
  for (std::uint32_t r = 0; r < n; ++r) {
    if (root[r] != r) continue;
    const auto cluster = members[r];
    const auto strip_leaders = std::count_if(cluster.begin(), cluster.end(), leader);
    head[r] = strip_leaders == 1 ? *std::find_if(cluster.begin(), cluster.end(), leader) : r;
    led_twice[r] = strip_leaders > 1;
  }
  std::vector<std::uint32_t> around;
  for (std::uint32_t r = 0; r < n; ++r) {
    const auto cluster = members[r];
    if (root[r] != r || cluster.size() < 2 || led_twice[r]) continue;
    const std::uint32_t a = head[r];
    around.clear();  // the roots of the vertices next to the cluster
    for (const std::uint32_t m : cluster)
      for (const std::uint32_t f : faces[m])
        for (const std::uint32_t u : surface.triangles[f])
          if (root[u] != r && !in_strip[u]) around.push_back(head[root[u]]);
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    const Vec3d& pa = surface.points[a];
    for (const std::uint32_t m : cluster) {
      if (m == a) continue;
      double best_off = std::numeric_limits<double>::infinity();
      Leaders best;
      for (const std::uint32_t b : around) {
        const double l2 = norm2(surface.points[b] - pa);
        if (!(l2 > 0)) continue;
        const Leaders l = along(surface, m, a, b);
        if (!(l.lambda > 0 && l.lambda <= kFollowEnd)) continue;
        const double off = norm(l.offset) / (l.lambda * std::sqrt(l2));
        if (off <= kFollowOffLine && off < best_off && inward(m, a, b)) {
          best_off = off;
          best = l;
        }
      }
      if (best.a == UINT32_MAX) {
        // On no such segment (vertices nearly one, in general position): m's inner point is
        // a's moved by m - a, where a's way in goes in at m. Traces of their own would cross
        // over so short an edge, and their floors put the tets there below the zero-volume
        // tolerance.
        const double l2 = norm2(surface.points[m] - pa);
        if (!(l2 <= kNearlyOne * kNearlyOne * std::min(longest[a], longest[m])) || !inward(m, a, a))
          continue;
        best = Leaders{a, a, 0.0, surface.points[m] - pa};
      }
      for (const std::uint32_t f : faces[m]) {  // m is the apex of a cap on ab too
        const Triangle& tri = surface.triangles[f];
        const int k = static_cast<int>(std::find(tri.begin(), tri.end(), m) - tri.begin());
        if (tri[(k + 1) % 3] == best.a && tri[(k + 2) % 3] == best.b) best.turn = 1;
        if (tri[(k + 1) % 3] == best.b && tri[(k + 2) % 3] == best.a) best.turn = -1;
      }
      follow(m, best);
    }
  }
  return out;
}

/// Per-vertex state of the search.
struct State {
  std::vector<double> t;     ///< current arc length; 0: on the surface (folded vertices)
  std::vector<char> welded;  ///< still sharing its start weld group's point
};

class ShellSearch {
 public:
  ShellSearch(const SurfaceMesh& surface, const TraceResult& traces, const InnerVertices& start,
              const ValidityOptions& options, const StageMonitor& monitor)
      : surface_(surface), traces_(traces), start_(start), monitor_(monitor) {
    const std::size_t n = surface.points.size();
    full_.resize(n);
    floor_.assign(n, std::numeric_limits<double>::infinity());
    fallback_.resize(n);
    cached_t_.assign(n, -1.0);
    drops_.assign(n, 0);
    cached_position_.resize(n);
    faces_.build(n, [&](const auto& emit) {
      for (std::uint32_t f = 0; f < surface.triangles.size(); ++f)
        for (std::uint32_t v : surface.triangles[f]) emit(v, f);
    });
    std::vector<Vec3d> normal(n);
    std::vector<std::vector<Vec3d>> face_normals(n);
    for (std::uint32_t f = 0; f < surface.triangles.size(); ++f) {
      const Vec3d nf = face_normal_area(surface, f);
      for (const std::uint32_t v : surface.triangles[f]) {
        normal[v] += nf;
        face_normals[v].push_back(normalized(nf));
      }
    }
    for (std::size_t v = 0; v < start.constraints.size(); ++v)
      face_normals[v].insert(face_normals[v].end(), start.constraints[v].begin(),
                             start.constraints[v].end());
    correction_.assign(n, Vec3d{});
    std::vector<char> folds(n, 0);
    for (std::size_t v = 0; v < n; ++v) {
      // Beyond the trace's end (only for traces shorter than the floor): continue straight
      // along its first step, or inward along the vertex normal for a trace that never moved.
      fallback_[v] = traces.end[v] > 0 ? normalized(traces.sample(v, 1) - traces.sample(v, 0))
                                       : -normalized(normal[v]);
      // The first direction must point inward for every incident face, with a margin, or the
      // thinnest shell already folds: bend the start of such a trace (within the floor depth)
      // into the most inward direction.
      const Vec3d first = fallback_[v];
      const double margin = inward_margin(face_normals[v], first);
      if (margin >= kMinMargin) continue;
      const Vec3d safe = most_inward_direction(face_normals[v]);
      const double safe_margin = norm2(safe) > 0 ? inward_margin(face_normals[v], safe) : 0.0;
      if (safe_margin > margin) correction_[v] = safe - first;
      // A sector (start.constraints) needs less than a vertex (sectors.h).
      const bool sector = v < start.constraints.size() && !start.constraints[v].empty();
      folds[v] = std::max(margin, safe_margin) < (sector ? kSectorMargin : kFoldMargin);
    }
    // A cap's apex m follows its base (a, b) only where a's first direction and b's each go
    // inward at m, for m's faces but those along the base (whose normals m's hair-thin offset
    // decides): m's inner point lies off m by a positive mix of the two, weighted by a's and b's
    // depths, which the search sets apart (a slot's floor corner, apex of a sliver 250 times
    // longer than high along a part's far bottom edge, followed that edge's ends up out of the
    // 0.2 floor; the lowest points of channels over a 0.2 floor, apexes of a fan of such slivers
    // from the part's corner, followed the corner up where its floor was the deeper).
    const auto inward = [&](std::uint32_t m, std::uint32_t a, std::uint32_t b) {
      const auto goes_in = [&](std::uint32_t e) {
        const Vec3d d = fallback_[e] + correction_[e];
        for (const std::uint32_t f : faces_[m])
          if (!along_base(surface, f, a, b) && !(dot(face_normal_area(surface, f), d) < 0))
            return false;
        return true;
      };
      return goes_in(a) && (b == a || goes_in(b));  // a cluster's lone leader: once
    };
    leaders_ = find_followers(surface, faces_, start, inward);
    for (std::uint32_t v = 0; v < n; ++v)  // followers are placed by their leaders
      if (folds[v] && !follows(v)) folded_.push_back(v);
    // A leader's floor ignores its edges to followers (they are the short ones); every move of
    // a leader settles its followers' prisms too.
    for (const Triangle& tri : surface.triangles)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t u = tri[k], w = tri[(k + 1) % 3];
        const double l = distance(surface.points[u], surface.points[w]);
        if (follows(u) || !follows(w)) floor_[u] = std::min(floor_[u], l);
        if (follows(w) || !follows(u)) floor_[w] = std::min(floor_[w], l);
      }
    for (std::uint32_t v = 0; v < n; ++v) {  // only followers around: their edges after all
      if (!std::isinf(floor_[v])) continue;
      for (const std::uint32_t f : faces_[v])
        for (const std::uint32_t u : surface.triangles[f])
          if (u != v)
            floor_[v] = std::min(floor_[v], distance(surface.points[u], surface.points[v]));
    }
    if (!leaders_.empty())
      faces_.build(n, [&](const auto& emit) {
        for (std::uint32_t f = 0; f < surface.triangles.size(); ++f)
          for (std::uint32_t v : surface.triangles[f]) {
            emit(v, f);
            if (follows(v))
              for_each_mover(v, [&](std::uint32_t u) {
                if (std::find(surface.triangles[f].begin(), surface.triangles[f].end(), u) ==
                    surface.triangles[f].end())
                  emit(u, f);
              });
          }
      });
    groups_.build(start.input.inner_points.size(), [&](const auto& emit) {
      for (std::uint32_t v = 0; v < n; ++v) emit(start.input.inner_id[v], v);
    });
    limit_ = start.limit;
    limit_.resize(n, std::numeric_limits<double>::infinity());
    for (std::size_t v = 0; v < n; ++v) {
      floor_[v] = std::min(floor_[v] * options.floor_fraction, 0.5 * limit_[v]);
      full_[v] = std::max(start.arc[v], floor_[v]);
    }
    if (!leaders_.empty()) make_split_order();
    floor_fraction_ = options.floor_fraction;
    floor_drop_ = options.floor_drop;
    layers_ = options.layers;
    shrink_ = options.shrink;
    layer_at_ = layer_fractions(options.layers, options.layer_ratio);
    update_caps();
  }

  /// What a follower on a cap asks of the split order (UINT32_MAX, UINT32_MAX: nothing): its
  /// leaders a, b ordered by the twist of their side quad, dot(b - a, d_b x d_a) with d the
  /// first directions, seen along the cap's base (Leaders::turn): the quad is cut from the
  /// first. The cap's prism, as thin as the cap, lies on the cut quad's two triangles, which
  /// bend towards it only when cut that way; cut the other way its tets invert wherever the
  /// twist outweighs the cap's height.
  std::array<std::uint32_t, 2> demand(std::uint32_t v) const {
    const Leaders& l = leaders_[v];
    if (!follows(v) || l.turn == 0) return {UINT32_MAX, UINT32_MAX};
    const Vec3d &pa = surface_.points[l.a], &pb = surface_.points[l.b];
    const Vec3d da = fallback_[l.a] + correction_[l.a], db = fallback_[l.b] + correction_[l.b];
    const double twist = dot(pb - pa, cross(db, da)) * l.turn;
    return twist >= 0 ? std::array<std::uint32_t, 2>{l.a, l.b}
                      : std::array<std::uint32_t, 2>{l.b, l.a};
  }

  /// The vertices that follow none in the vertex order, but for the followers' demands (a
  /// cycle of them broken at its smallest vertex); `rank` gets each one's place.
  std::vector<std::uint32_t> leader_order(std::vector<std::uint32_t>& rank) const {
    const auto n = static_cast<std::uint32_t>(full_.size());
    IndexLists later;  // leader -> the leaders that must come after it
    later.build(n, [&](const auto& emit) {
      for (std::uint32_t v = 0; v < n; ++v) {
        const auto [first, second] = demand(v);
        if (first != UINT32_MAX) emit(first, second);
      }
    });
    std::vector<std::uint32_t> pending(n, 0);
    for (const std::uint32_t second : later.items) ++pending[second];
    std::vector<char> placed(n, 0);
    std::priority_queue<std::uint32_t, std::vector<std::uint32_t>, std::greater<>> ready;
    for (std::uint32_t v = 0; v < n; ++v)
      if (!follows(v) && pending[v] == 0) ready.push(v);
    std::vector<std::uint32_t> leaders;
    leaders.reserve(n);
    std::uint32_t next = 0;  // the smallest vertex perhaps not placed: breaks cycles
    for (;;) {
      if (ready.empty()) {
        while (next < n && (placed[next] || follows(next))) ++next;
        if (next == n) break;
        ready.push(next);
      }
      const std::uint32_t v = ready.top();
      ready.pop();
      if (placed[v]) continue;
      placed[v] = 1;
      leaders.push_back(v);
      for (const std::uint32_t w : later[v])
        if (--pending[w] == 0 && !placed[w]) ready.push(w);
    }
    rank.assign(n, 0);
    for (std::uint32_t k = 0; k < leaders.size(); ++k) rank[leaders[k]] = k;
    return leaders;
  }

  /// The split order (ShellInput::split_order): leader_order(), each follower right after its
  /// first leader (a cluster's member after its root), nearest first.
  void make_split_order() {
    const auto n = static_cast<std::uint32_t>(full_.size());
    std::vector<std::uint32_t> anchor(n, UINT32_MAX);  // per follower: its first leader
    for (std::uint32_t v = 0; v < n; ++v)
      if (follows(v)) anchor[v] = leaders_[v].a;
    std::vector<std::uint32_t> rank;
    const std::vector<std::uint32_t> leaders = leader_order(rank);
    for (std::uint32_t v = 0; v < n; ++v)
      if (follows(v) && !leaders_[v].end && rank[leaders_[v].b] < rank[leaders_[v].a])
        anchor[v] = leaders_[v].b;
    IndexLists followers;  // each anchor's, nearest first: a strip's quads are cut alike
    followers.build(n, [&](const auto& emit) {
      for (std::uint32_t v = 0; v < n; ++v)
        if (follows(v)) emit(anchor[v], v);
    });
    for (std::uint32_t a = 0; a < n; ++a) {
      const auto from_a = [&](std::uint32_t v) {
        return distance(surface_.points[v], surface_.points[a]);
      };
      std::stable_sort(followers.items.begin() + followers.start[a],
                       followers.items.begin() + followers.start[a + 1],
                       [&](std::uint32_t u, std::uint32_t w) { return from_a(u) < from_a(w); });
    }
    sequence_.clear();
    sequence_.reserve(n);
    for (const std::uint32_t v : leaders) {
      sequence_.push_back(v);
      sequence_.insert(sequence_.end(), followers[v].begin(), followers[v].end());
    }
    order_.resize(n);
    for (std::uint32_t k = 0; k < n; ++k) order_[sequence_[k]] = k;
  }

  /// Keeps v on the surface from now on (t_v = 0, as a folded vertex) and returns true, unless
  /// it already is. The last resort for a sector of a folded vertex, or a vertex sharing its
  /// position with another, whose thinnest prisms still offend: two sectors whose directions
  /// cross overlap at any depth.
  /// A follower goes on the surface with its leaders (its inner vertex is then its own point).
  bool keep_on_surface(State& s, std::uint32_t v) {
    if (follows(v)) {
      bool kept = false;
      for_each_mover(v, [&](std::uint32_t u) { kept = keep_on_surface(s, u) || kept; });
      return kept;
    }
    const auto at = std::lower_bound(folded_.begin(), folded_.end(), v);
    if (at != folded_.end() && *at == v) return false;
    folded_.insert(at, v);
    s.t[v] = 0;
    s.welded[v] = 0;
    update_caps();
    return true;
  }

  /// Folded vertices stay on the surface (and followers of two folded leaders with them). A face
  /// with three corners there keeps a prism as one tet to a cap point of its own, at the floor
  /// depth below its centroid.
  void update_caps() {
    std::vector<char> folded(full_.size(), 0);  // on the surface
    for (std::uint32_t v : folded_) folded[v] = 1;
    for (std::uint32_t v = 0; v < folded.size(); ++v)
      if (follows(v) && folded[leaders_[v].a] && folded[leaders_[v].b]) folded[v] = 1;
    caps_ = ShellInput{};
    for (std::uint32_t f = 0; f < surface_.triangles.size(); ++f) {
      const Triangle& tri = surface_.triangles[f];
      if (!folded[tri[0]] || !folded[tri[1]] || !folded[tri[2]]) continue;
      const std::array<Vec3d, 3> p = {surface_.points[tri[0]], surface_.points[tri[1]],
                                      surface_.points[tri[2]]};
      const std::array<double, 3> edges{distance(p[0], p[1]), distance(p[1], p[2]),
                                        distance(p[2], p[0])};
      const double shortest = std::min({edges[0], edges[1], edges[2]}),
                   longest = std::max({edges[0], edges[1], edges[2]});
      const auto drops = cap_drops_.find(f);
      double depth = floor_fraction_ * shortest *
                     std::pow(floor_drop_, drops == cap_drops_.end() ? 0 : drops->second);
      const Vec3d centroid = (p[0] + p[1] + p[2]) / 3.0, normal = face_normal_area(surface_, f),
                  down = normalized(normal);
      // A sliver's cap (its area small for its longest edge) has no volume the checks see at
      // that depth: twice as deep until its volume exceeds 4 times their zero-volume tolerance,
      // at most as deep as the face is long.
      const auto thick_enough = [&](double d) {
        double l = longest;
        for (const Vec3d& corner : p) l = std::max(l, distance(corner, centroid - down * d));
        return norm(normal) * d / 6.0 > 4.0 * ShellCheckOptions{}.zero_volume_tolerance * l * l * l;
      };
      while (depth > 0 && depth < longest && !thick_enough(depth))
        depth = std::min(2.0 * depth, longest);
      caps_.cap_faces.push_back(f);
      caps_.cap_points.push_back(centroid - down * depth);
    }
  }

  /// The cap face of cap point `k` (ShellInput::cap_points), or UINT32_MAX.
  std::uint32_t cap_face(std::size_t k) const {
    return k < caps_.cap_faces.size() ? caps_.cap_faces[k] : UINT32_MAX;
  }
  bool is_cap(std::uint32_t f) const {
    return std::binary_search(caps_.cap_faces.begin(), caps_.cap_faces.end(), f);
  }
  /// Moves cap face f's cap point floor_drop times closer to the face, unless it was moved
  /// max_floor_drops times already (a cap is a floor element that never moves otherwise).
  bool drop_cap(std::uint32_t f, int max_drops) {
    int& drops = cap_drops_[f];
    if (drops >= max_drops) return false;
    ++drops;
    update_caps();
    return true;
  }

  /// Whether v is a sector of a folded vertex (InnerVertices::constraints, sectors.h).
  bool is_sector(std::uint32_t v) const {
    return v < start_.constraints.size() && !start_.constraints[v].empty();
  }

  /// How many vertices follow leaders.
  std::size_t followers() const {
    return static_cast<std::size_t>(std::count_if(
        leaders_.begin(), leaders_.end(), [](const Leaders& l) { return l.a != UINT32_MAX; }));
  }
  /// Whether v follows leaders (find_followers()): its inner vertex is theirs, interpolated.
  bool follows(std::uint32_t v) const { return !leaders_.empty() && leaders_[v].a != UINT32_MAX; }
  /// Calls f(u) for each vertex whose depth places v's inner vertex: v, or its two leaders.
  template <class F>
  void for_each_mover(std::uint32_t v, const F& f) const {
    if (!follows(v)) return f(v);
    f(leaders_[v].a);
    if (leaders_[v].b != leaders_[v].a) f(leaders_[v].b);
  }
  /// How deep v's inner vertex can still move back: a welded group's depth, t_v above the
  /// floor, 0 at the floor or on the surface; a follower's, its deeper leader's.
  double depth(const State& s, std::uint32_t v) const {
    double d = 0;
    for_each_mover(v, [&](std::uint32_t u) { d = std::max(d, own_depth(u, s.t[u], s.welded[u])); });
    return d;
  }
  /// depth() of a vertex that moves itself, at t, welded or not.
  double own_depth(std::uint32_t v, double t, bool welded) const {
    return welded ? group_depth_[start_.input.inner_id[v]] : (t > floor_[v] ? t : 0.0);
  }
  /// The point at `level` of v's column (layers_: the inner vertex) with v's inner vertex at
  /// `inner`.
  Vec3d column_point(std::uint32_t v, const Vec3d& inner, int level) const {
    const Vec3d& sv = surface_.points[v];
    return level == layers_ ? inner : sv + (inner - sv) * layer_at_[level];
  }

  /// Vertices kept on the surface (t_v = 0): those whose incident faces admit no common inward
  /// direction, and sectors given up by keep_on_surface(); ascending.
  const std::vector<std::uint32_t>& folded() const { return folded_; }
  /// Faces with three folded corners and their cap points (ShellInput::cap_faces).
  std::size_t caps() const { return caps_.cap_faces.size(); }

  const std::vector<double>& full() const { return full_; }
  const std::vector<double>& floor() const { return floor_; }

  State initial() {
    State s;
    s.t = full_;
    s.welded.resize(full_.size());
    for (std::uint32_t v = 0; v < full_.size(); ++v) {
      const auto group = groups_[start_.input.inner_id[v]];
      s.welded[v] = group.end() - group.begin() > 1 && start_.arc[v] >= floor_[v];
    }
    for (std::uint32_t v : folded_) {
      s.t[v] = 0;
      s.welded[v] = 0;
    }
    for (std::uint32_t v = 0; v < leaders_.size(); ++v)
      if (follows(v)) s.welded[v] = 0;  // t_v stays its full depth: never read, never moved
    // A weld group is one slot, ordered by its smallest welded member, until it unwelds whole.
    // Its depth, the deepest welded member's, holds as long: welded members do not move.
    group_key_.assign(groups_.start.size() - 1, UINT32_MAX);
    group_depth_.assign(groups_.start.size() - 1, 0.0);
    for (std::uint32_t v = static_cast<std::uint32_t>(full_.size()); v-- > 0;)
      if (s.welded[v]) {
        const std::uint32_t g = start_.input.inner_id[v];
        group_key_[g] = v;
        group_depth_[g] = std::max(group_depth_[g], s.t[v]);
      }
    return s;
  }

  /// Prism f as assemble_shell() would build it from build(s): ids in the same order as the
  /// assembled mesh's split keys (all the splits depend on; ShellInput::split_order) —
  /// ids[3 k + c] is corner c at layer boundary k (surface vertex v: o(v), layer point
  /// n + (layers - 1) o(v) + k - 1, inner vertex layers n + o(its group's key) or
  /// layers n + o(v), with o(v) = order(v): deeper boundaries have larger ids) — their
  /// positions, and its tets.
  struct LocalPrism {
    std::uint32_t face = 0;
    std::vector<std::uint32_t> ids;
    std::vector<Vec3d> at;
    std::vector<Tet> tets;
    bool cap = false;  ///< one tet to a cap point (ids[3])
    std::array<Vec3d, 4> corners(const Tet& t) const {
      std::array<Vec3d, 4> p;
      for (int c = 0; c < 4; ++c) p[c] = at[std::find(ids.begin(), ids.end(), t[c]) - ids.begin()];
      return p;
    }
    std::array<Vec3d, 4> corners(std::size_t i) const { return corners(tets[i]); }
  };
  /// v's place in the order the prism splits follow (ShellInput::split_order).
  std::uint32_t order(std::uint32_t v) const { return order_.empty() ? v : order_[v]; }
  /// LocalPrism's id of the inner vertex whose key vertex has order o.
  std::uint32_t inner_key(std::uint32_t o) const {
    return inner_point_key(static_cast<std::uint32_t>(full_.size()), layers_, o);
  }

  /// v's inner vertex in `s`: its id in LocalPrism's numbering (below n: on the surface) and its
  /// position. A follower's is on its leaders' (on the surface when both of theirs are, theirs
  /// when two share one: then returns the leader a, else UINT32_MAX), or its one leader's moved
  /// by its offset.
  std::uint32_t inner_vertex(const State& s, std::uint32_t v, std::uint32_t& id, Vec3d& at) const {
    const auto n = static_cast<std::uint32_t>(full_.size());
    if (follows(v)) {
      const Leaders& l = leaders_[v];
      std::uint32_t ia = 0, ib = 0;
      Vec3d pa, pb;
      inner_vertex(s, l.a, ia, pa);
      inner_vertex(s, l.b, ib, pb);
      if (ia < n && ib < n) {
        id = order(v);
        at = surface_.points[v];
      } else if (ia == ib && l.a != l.b) {  // one weld group: a separate point would coincide
        id = ia;
        at = pa;
        return l.a;
      } else {
        id = inner_key(order(v));
        at = pa + (pb - pa) * l.lambda + l.offset;
      }
    } else if (s.t[v] == 0) {
      id = order(v);
      at = surface_.points[v];
    } else if (s.welded[v]) {
      const std::uint32_t g = start_.input.inner_id[v];
      id = inner_key(order(group_key_[g]));
      at = start_.input.inner_points[g];
    } else {
      id = inner_key(order(v));
      at = cached_position(v, s.t[v]);
    }
    return UINT32_MAX;
  }

  /// Fills `p` with prism f of state `s` (its buffers are reused).
  void prism(const State& s, std::uint32_t f, LocalPrism& p) const {
    const auto n = static_cast<std::uint32_t>(full_.size());
    const Triangle& tri = surface_.triangles[f];
    const int K = layers_;
    p.face = f;
    p.ids.resize(3 * static_cast<std::size_t>(K + 1));
    p.at.resize(p.ids.size());
    p.tets.clear();
    p.cap = false;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = tri[c];
      const Vec3d& sv = surface_.points[v];
      p.ids[c] = order(v);
      p.at[c] = sv;
      std::uint32_t& inner = p.ids[3 * K + c];
      Vec3d& inner_at = p.at[3 * K + c];
      inner_vertex(s, v, inner, inner_at);
      for (int k = 1; k < K; ++k) {
        const std::size_t at = 3 * static_cast<std::size_t>(k) + c;
        p.ids[at] = inner < n ? inner : layer_point_key(n, K, order(v), k);
        p.at[at] = sv + (inner_at - sv) * layer_at_[k];
      }
    }
    const auto cap = std::lower_bound(caps_.cap_faces.begin(), caps_.cap_faces.end(), f);
    if (cap != caps_.cap_faces.end() && *cap == f) {  // as assemble_shell(): one tet, no mover
      p.ids[3] = UINT32_MAX;
      p.at[3] = caps_.cap_points[static_cast<std::size_t>(cap - caps_.cap_faces.begin())];
      p.tets.push_back({p.ids[0], p.ids[1], p.ids[3], p.ids[2]});
      p.cap = true;
      return;
    }
    split_layered_prism(p.ids.data(), K, [&](const Tet& t, int) { p.tets.push_back(t); });
  }

  /// The surface vertex owning the deepest movable inner corner of `tet`, a tet of `p` (as the
  /// rounds choose it), or UINT32_MAX when every inner corner is at its floor.
  std::uint32_t deepest_corner(const State& s, const LocalPrism& p, const Tet& tet) const {
    const auto n = static_cast<std::uint32_t>(full_.size());
    const Triangle& tri = surface_.triangles[p.face];
    std::uint32_t best = UINT32_MAX;
    double best_depth = 0;
    for (const std::uint32_t id : tet) {  // inner and layer points move with their vertex
      if (id < n) continue;
      const auto corner = (std::find(p.ids.begin() + 3, p.ids.end(), id) - p.ids.begin()) % 3;
      for_each_mover(tri[corner], [&](std::uint32_t v) {
        const double d = depth(s, v);
        if (d > best_depth) {
          best_depth = d;
          best = v;
        }
      });
    }
    return best;
  }

  /// Moves v's inner vertex back one step, as a round does: a welded group leaves its weld
  /// whole, anything else goes to max(floor, shrink * t). Calls moved(u) for every vertex moved;
  /// returns how many left their weld.
  template <class Moved>
  std::size_t step_back(State& s, std::uint32_t v, double shrink, const Moved& moved) const {
    if (follows(v)) {  // the vertices that move it and can
      std::size_t unwelded = 0;
      for_each_mover(v, [&](std::uint32_t u) {
        if (depth(s, u) > 0) unwelded += step_back(s, u, shrink, moved);
      });
      return unwelded;
    }
    if (!s.welded[v]) {
      s.t[v] = std::max(floor_[v], s.t[v] * shrink);
      moved(v);
      return 0;
    }
    std::size_t unwelded = 0;
    for (const std::uint32_t u : groups_[start_.input.inner_id[v]]) {
      if (!s.welded[u]) continue;
      s.welded[u] = 0;
      ++unwelded;
      moved(u);
    }
    return unwelded;
  }

  /// Works through the prisms in `queue` and those queued on the way: settle(p, again) for each,
  /// `p` the prism in `s` as it is then, again(v) queuing the prisms around vertex v that are not
  /// queued already (settle() must call it for every vertex it changes, and do nothing to a
  /// prism none of whose tets for_each_unsettled_tet() visits).
  ///
  /// A long queue is judged first in parallel; a prism found settled there is passed over unless
  /// a vertex of it changed since (a prism depends on its three vertices only), so the serial
  /// walk, and its outcome, are those of settling every prism in turn.
  template <class Settle>
  void for_each_queued_prism(const State& s, std::vector<std::uint32_t> queue,
                             double zero_volume_tolerance, double min_quality,
                             const Settle& settle) const {
    enum : char { kQueued = 1, kSettled = 2 };  // per prism, either or both
    std::vector<char> mark(surface_.triangles.size(), 0);
    for (std::uint32_t f : queue) mark[f] = kQueued;
    if (queue.size() >= 1024) {
      // The positions first, each vertex its own cache entry: the prisms then only read them.
      for_each_index(full_.size(), [&](std::size_t v) {
        if (s.t[v] != 0 && !s.welded[v]) cached_position(static_cast<std::uint32_t>(v), s.t[v]);
      });
      std::vector<char> settled(queue.size(), 1);
      for_each_chunk(
          queue.size(),
          [&](std::size_t begin, std::size_t end) {
            LocalPrism p;
            for (std::size_t i = begin; i != end; ++i) {
              prism(s, queue[i], p);
              settled[i] = !has_unsettled_tet(s, p, zero_volume_tolerance, min_quality);
            }
          },
          256);
      for (std::size_t i = 0; i < queue.size(); ++i)
        if (settled[i]) mark[queue[i]] |= kSettled;
    }
    const auto again = [&](std::uint32_t v) {
      for (const std::uint32_t f : faces_[v]) {
        if (!(mark[f] & kQueued)) queue.push_back(f);
        mark[f] = kQueued;
      }
    };
    LocalPrism p;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      if ((head & 1023) == 1023) monitor_.alive();
      const std::uint32_t f = queue[head];
      const bool settled = mark[f] & kSettled;
      mark[f] = 0;
      if (settled) continue;
      prism(s, f, p);
      settle(p, again);
    }
  }

  /// Calls visit(tet) for the tets of prism `p` that settle_volumes() does not accept, in its
  /// order, until visit returns true: with one layer (or a cap), those not positive or below
  /// `min_quality`; with K layers, those not positive or below min_quality / K, then, the prism's
  /// own 3 tets (split_prism() of its outer and inner triangles) below `min_quality`.
  template <class Visit>
  void for_each_unsettled_tet(const State& s, const LocalPrism& p, double zero_volume_tolerance,
                              double min_quality, const Visit& visit) const {
    const bool whole = layers_ == 1 || p.cap;  // p.tets are the prism's own 3 tets
    if (min_quality > 0) min_quality *= quality_demand(p.face);
    const double quality = whole ? min_quality : min_quality / layers_;
    for (const Tet& t : p.tets) {
      const std::array<Vec3d, 4> c = p.corners(t);
      if ((tet_volume_class(c, zero_volume_tolerance) != TetVolume::kPositive ||
           below_curable_quality(s, p, t, c, quality)) &&
          visit(t))
        return;
    }
    if (whole || !(min_quality > 0)) return;
    const std::uint32_t* inner = p.ids.data() + 3 * layers_;
    const PrismTets own = split_prism({p.ids[0], p.ids[1], p.ids[2], inner[0], inner[1], inner[2]});
    for (int i = 0; i < own.count; ++i) {
      if (below_curable_quality(s, p, own.tets[i], p.corners(own.tets[i]), min_quality) &&
          visit(own.tets[i]))
        return;
    }
  }

  /// Whether tet `t` of `p`, prism of `s` (corners `c`), is below `quality` and stepping back may
  /// bring it there. A needle (traces converging, or deep for their triangle) mostly gains quality
  /// fast as its inner corners step back, but not always: where its quality levels off below
  /// `quality` (a cone's side faces over its axis, a spike's tip), stepping it back to its floor
  /// thinned the shell for nothing. So a needle steps back only where kCurableSteps steps, taken
  /// as settle_volumes() takes them, bring it to `quality` (reaches_by_steps()). A flat tet, whose
  /// longest edge is kFlatEdges times its deepest inner corner's depth or more (a coarse CAD face
  /// over a thin part), can stay far below `quality` however far its corners step back: stepped
  /// back all the same, it thinned the shell around it down to the floors for a quality it could
  /// not reach. So a flat tet steps back only where the gain of one step of every inner corner
  /// along its trace, kept up, reaches `quality` before the deepest corner's floor. Either steps
  /// back where every inner corner is within kFlatFloors floors of the surface (a step costs
  /// little depth there, and the quality of so flat a tet hangs on its corners' small offsets),
  /// or where a corner follows (its leaders' steps are not modelled here). Otherwise it is left as
  /// it is: its volume is positive.
  bool below_curable_quality(const State& s, const LocalPrism& p, const Tet& t,
                             const std::array<Vec3d, 4>& c, double quality) const {
    const double q = tet_quality(c[0], c[1], c[2], c[3]);
    if (!(q < quality)) return false;
    if (p.cap || !(q > 0)) return true;
    const auto n = static_cast<std::uint32_t>(full_.size());
    const Triangle& tri = surface_.triangles[p.face];
    if (on_welded_side_quad(s, p, t)) return true;
    double longest = 0, deepest = 0, steps = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) longest = std::max(longest, distance(c[i], c[j]));
    bool near_floor = true;
    for (int i = 0; i < 4; ++i) {
      if (t[i] < n) continue;
      const auto at = std::find(p.ids.begin(), p.ids.end(), t[i]) - p.ids.begin();
      const auto column = at % 3;
      const std::uint32_t v = tri[column];
      const Vec3d& sv = surface_.points[v];
      const double depth = distance(c[i], sv);
      deepest = std::max(deepest, depth);
      near_floor = near_floor && depth < kFlatFloors * floor_[v];
      if (follows(v)) return true;
      const double arc = s.t[v];
      if (arc > floor_[v]) steps = std::max(steps, std::log(floor_[v] / arc) / std::log(shrink_));
    }
    if (near_floor) return true;
    if (longest < kFlatEdges * deepest) return reaches_by_steps(s, p, t, c, quality);
    // One step back: a welded vertex leaves its weld for its own trace, any other goes to
    // max(floor, shrink * t), as step_back() moves it; a layer point moves with it.
    std::array<Vec3d, 4> next = c;
    for (int i = 0; i < 4; ++i) {
      if (t[i] < n) continue;
      const auto at = std::find(p.ids.begin(), p.ids.end(), t[i]) - p.ids.begin();
      const std::uint32_t v = tri[at % 3];
      const double arc = s.t[v];
      const Vec3d inner =
          s.welded[v] ? position(v, arc) : position(v, std::max(floor_[v], arc * shrink_));
      next[i] = column_point(v, inner, static_cast<int>(at / 3));
    }
    const double stepped = tet_quality(next[0], next[1], next[2], next[3]);
    return stepped > q && std::log(quality / q) <= (steps + 1) * std::log(stepped / q);
  }

  /// Whether tet `t` of `p`, prism of `s`, is the four corners of a side quad of the innermost
  /// layer of a prism whose weld makes the quad's inner corner one point with the third column's.
  /// Where the quad is flat (its traces in one plane, as on a mirror plane) no step along the
  /// traces gives that tet a volume, but the welded group's step back, leaving its weld, splits
  /// the layer into three tets again.
  bool on_welded_side_quad(const State& s, const LocalPrism& p, const Tet& t) const {
    const Triangle& tri = surface_.triangles[p.face];
    const std::uint32_t* outside = p.ids.data() + 3 * (layers_ - 1);  // the layer outside inner
    const std::uint32_t* inner = p.ids.data() + 3 * layers_;
    for (int c = 0; c < 3; ++c) {  // c: the column the quad leaves out
      const int a = (c + 1) % 3, b = (c + 2) % 3;
      if (inner[a] == inner[b]) continue;
      const bool weld_a = inner[a] == inner[c] && s.welded[tri[a]] && s.welded[tri[c]];
      const bool weld_b = inner[b] == inner[c] && s.welded[tri[b]] && s.welded[tri[c]];
      if (!weld_a && !weld_b) continue;
      const std::array<std::uint32_t, 4> quad{outside[a], outside[b], inner[a], inner[b]};
      if (std::all_of(t.begin(), t.end(), [&](std::uint32_t id) {
            return std::find(quad.begin(), quad.end(), id) != quad.end();
          }))
        return true;
    }
    return false;
  }

  /// Whether tet `t` of `p`, prism of `s` (corners `c`, no corner following), reaches `quality`
  /// within kCurableSteps steps back of its inner corners' vertices taken as settle_volumes()
  /// takes them: the deepest movable one each time (deepest_corner()), a welded group leaving
  /// its weld whole first (step_back()). Only this tet is modelled: the other prisms' steps are
  /// not.
  bool reaches_by_steps(const State& s, const LocalPrism& p, const Tet& t, std::array<Vec3d, 4> c,
                        double quality) const {
    const auto n = static_cast<std::uint32_t>(full_.size());
    const Triangle& tri = surface_.triangles[p.face];
    struct Corner {
      std::uint32_t v;
      double t;
      bool welded, moved;
    };
    std::array<Corner, 4> vertices{};
    std::array<int, 4> vertex_of{-1, -1, -1, -1};
    std::array<std::ptrdiff_t, 4> slot{};
    int count = 0;
    for (int i = 0; i < 4; ++i) {
      if (t[i] < n) continue;
      slot[i] = std::find(p.ids.begin(), p.ids.end(), t[i]) - p.ids.begin();
      const std::uint32_t v = tri[slot[i] % 3];
      int j = 0;
      while (j < count && vertices[j].v != v) ++j;
      if (j == count) vertices[count++] = {v, s.t[v], s.welded[v] != 0, false};
      vertex_of[i] = j;
    }
    for (int step = 0; step < kCurableSteps; ++step) {
      int deepest = -1;
      double deepest_depth = 0;
      for (int j = 0; j < count; ++j) {
        const Corner& x = vertices[j];
        const double d = own_depth(x.v, x.t, x.welded);
        if (d > deepest_depth) deepest_depth = d, deepest = j;
      }
      if (deepest < 0) return false;  // every corner at its floor
      Corner& x = vertices[deepest];
      if (x.welded) {
        const std::uint32_t group = start_.input.inner_id[x.v];
        for (int j = 0; j < count; ++j)
          if (vertices[j].welded && start_.input.inner_id[vertices[j].v] == group)
            vertices[j].welded = false, vertices[j].moved = true;
      } else {
        x.t = std::max(floor_[x.v], x.t * shrink_);
        x.moved = true;
      }
      for (int i = 0; i < 4; ++i) {
        if (vertex_of[i] < 0 || !vertices[vertex_of[i]].moved) continue;
        const Corner& y = vertices[vertex_of[i]];
        c[i] = column_point(y.v, position(y.v, y.t), static_cast<int>(slot[i] / 3));
      }
      if (tet_quality(c[0], c[1], c[2], c[3]) >= quality) return true;
    }
    return false;
  }

  /// The share of --min-quality a prism on face f is settled to: 1, or on a sliver face its shape
  /// quality q (4 sqrt(3) area / sum of its squared edges, 1 for an equilateral triangle) over
  /// kSliverShape. No tet on a sliver is much better than the face, whatever the depth: stepping
  /// back to reach a quality it cannot have would only thin the shell around it.
  double quality_demand(std::uint32_t f) const {
    const Triangle& tri = surface_.triangles[f];
    const Vec3d &a = surface_.points[tri[0]], &b = surface_.points[tri[1]],
                &c = surface_.points[tri[2]];
    const double edges = norm2(b - a) + norm2(c - b) + norm2(a - c);
    const double shape = edges > 0 ? 2 * std::sqrt(3.0) * norm(cross(b - a, c - a)) / edges : 0;
    return std::min(1.0, shape / kSliverShape);
  }

  /// Whether for_each_unsettled_tet() visits a tet of `p`.
  bool has_unsettled_tet(const State& s, const LocalPrism& p, double zero_volume_tolerance,
                         double min_quality) const {
    bool found = false;
    for_each_unsettled_tet(s, p, zero_volume_tolerance, min_quality,
                           [&](const Tet&) { return found = true; });
    return found;
  }

  /// Sends the raised vertices of the prisms in `queue`, and of those around every vertex sent
  /// back on the way, back to `before` (their depth before the raise) while a tet of the prism
  /// is one settle_volumes() does not accept. A vertex is raised while s.t[v] != before[v].
  /// Ends with every prism either accepted or as it was before the raise. Local; serial but for
  /// for_each_queued_prism()'s first judgement.
  void lower_raised(State& s, const std::vector<double>& before, std::vector<std::uint32_t> queue,
                    double zero_volume_tolerance, double min_quality) const {
    const auto send_back = [&](const LocalPrism& p, const auto& again) {
      if (!has_unsettled_tet(s, p, zero_volume_tolerance, min_quality)) return;
      for (const std::uint32_t corner : surface_.triangles[p.face])
        for_each_mover(corner, [&](std::uint32_t v) {
          if (s.t[v] == before[v]) return;
          s.t[v] = before[v];
          again(v);
        });
    };
    for_each_queued_prism(s, std::move(queue), zero_volume_tolerance, min_quality, send_back);
  }

  /// Steps back, as a round does for an inverted or flat tet (its deepest movable inner corner),
  /// until every tet of the prisms in `queue`, and of the prisms around every vertex moved on
  /// the way, is positive with a quality of at least `min_quality`, or has all its inner
  /// corners at their floor (left to the checks; a sliver there is no violation). With K
  /// layers, the whole prism's 3 tets (split_prism() of its outer and inner triangles) must
  /// reach `min_quality` and each layer's tets min_quality / K: a layer is 1 / K as thick, so
  /// its tets are about K times flatter than the prism's, which stepping back does not cure.
  /// Local; serial but for for_each_queued_prism()'s first judgement. Marks the moved vertices
  /// in `lowered`; returns how many left their weld.
  std::size_t settle_volumes(State& s, std::vector<std::uint32_t> queue, double shrink,
                             double zero_volume_tolerance, double min_quality,
                             std::vector<char>& lowered) const {
    std::size_t unwelded = 0;
    // The first offending tet with a movable corner steps back; the prism is queued again.
    const auto step_first = [&](const LocalPrism& p, const auto& again) {
      for_each_unsettled_tet(s, p, zero_volume_tolerance, min_quality, [&](const Tet& t) {
        const std::uint32_t v = deepest_corner(s, p, t);
        if (v == UINT32_MAX) return false;  // at the floor: left to the checks
        unwelded += step_back(s, v, shrink, [&](std::uint32_t u) {
          lowered[u] = 1;
          again(u);
        });
        return true;
      });
    };
    for_each_queued_prism(s, std::move(queue), zero_volume_tolerance, min_quality, step_first);
    return unwelded;
  }

  /// Steps back, for every pair of overlapping prisms (f, g) in `pairs`, the deepest movable
  /// inner corner of each of their overlapping tets until the two no longer overlap or only
  /// corners at the floor remain, settling the volumes around every move. Marks the moved
  /// vertices in `lowered`; returns how many left their weld.
  std::size_t settle_overlaps(State& s, const std::vector<std::array<std::uint32_t, 2>>& pairs,
                              double shrink, const ShellCheckOptions& options, double min_quality,
                              std::vector<char>& lowered) const {
    std::size_t unwelded = 0;
    std::vector<std::uint32_t> step, around, moved;
    LocalPrism a, b;
    for (const auto& [f, g] : pairs) {
      monitor_.alive();
      for (;;) {
        prism(s, f, a);
        prism(s, g, b);
        step.clear();
        for (std::size_t i = 0; i < a.tets.size(); ++i)
          for (std::size_t j = f == g ? i + 1 : 0; j < b.tets.size(); ++j) {
            if (!tets_overlap(a.corners(i), b.corners(j), options)) continue;
            step.push_back(deepest_corner(s, a, a.tets[i]));
            step.push_back(deepest_corner(s, b, b.tets[j]));
          }
        std::sort(step.begin(), step.end());
        step.erase(std::unique(step.begin(), step.end()), step.end());
        if (!step.empty() && step.back() == UINT32_MAX) step.pop_back();
        if (step.empty()) break;  // apart, or only floor corners left: to the checks
        around.clear();
        moved.clear();
        for (const std::uint32_t v : step) {
          if (std::find(moved.begin(), moved.end(), v) != moved.end()) continue;  // its group
          unwelded += step_back(s, v, shrink, [&](std::uint32_t u) {
            lowered[u] = 1;
            moved.push_back(u);
            around.insert(around.end(), faces_[u].begin(), faces_[u].end());
          });
        }
        std::sort(around.begin(), around.end());
        around.erase(std::unique(around.begin(), around.end()), around.end());
        unwelded +=
            settle_volumes(s, around, shrink, options.zero_volume_tolerance, min_quality, lowered);
      }
    }
    return unwelded;
  }

  /// Multiplies v's floor by `factor` unless it was lowered `max_drops` times already.
  bool lower_floor(std::uint32_t v, double factor, int max_drops) {
    if (drops_[v] >= max_drops) return false;
    ++drops_[v];
    floor_[v] *= factor;
    return true;
  }

  State floor_state() const {
    State s{floor_, std::vector<char>(floor_.size(), 0)};
    for (std::uint32_t v : folded_) s.t[v] = 0;
    return s;
  }

  /// The faces around the vertices flagged in `flags`, in increasing order, into `out`.
  void faces_around(const std::vector<char>& flags, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t v = 0; v < flags.size(); ++v)
      if (flags[v]) out.insert(out.end(), faces_[v].begin(), faces_[v].end());
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  /// position(v, t), remembered per vertex (most keep their depth from round to round).
  Vec3d cached_position(std::uint32_t v, double t) const {
    if (cached_t_[v] != t) {
      cached_t_[v] = t;
      cached_position_[v] = position(v, t);
    }
    return cached_position_[v];
  }

  /// The point at arc length t along v's trace (bent at its start, continued straight past its
  /// end), pulled towards v where the bend would carry it past v's thickness limit.
  Vec3d position(std::size_t v, double t) const {
    const double end = traces_.end_arc(v);
    const Vec3d bend = correction_[v] * std::min(t, floor_[v]);
    const Vec3d p = t <= end ? point_at_arc(traces_, v, t) + bend
                             : traces_.end_point(v) + fallback_[v] * (t - end) + bend;
    const Vec3d& s = surface_.points[v];
    const double d = distance(p, s);
    return d > limit_[v] ? s + (p - s) * (limit_[v] / d) : p;
  }

  /// Inner vertices of `s` (slots in order of their smallest member) and each slot's members.
  ShellInput build(const State& s, IndexLists& members) const {
    const std::size_t n = full_.size();
    ShellInput in;
    in.inner_id.resize(n);
    in.inner_points.reserve(n);
    std::vector<std::uint32_t> group_slot(start_.input.inner_points.size(), UINT32_MAX);
    // Slots in the split order: the inner points' indices then order them as the search's ids.
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t v = sequence_.empty() ? k : sequence_[k];
      if (follows(v)) {
        std::uint32_t id = 0;
        Vec3d at;
        const std::uint32_t shared = inner_vertex(s, v, id, at);
        if (id < n) {
          in.inner_id[v] = kOnSurface;
        } else if (shared != UINT32_MAX) {  // placed before v: it follows its leader a
          in.inner_id[v] = in.inner_id[shared];
        } else {
          in.inner_id[v] = static_cast<std::uint32_t>(in.inner_points.size());
          in.inner_points.push_back(at);
        }
      } else if (s.t[v] == 0) {
        in.inner_id[v] = kOnSurface;
      } else if (s.welded[v]) {
        const std::uint32_t g = start_.input.inner_id[v];
        if (group_slot[g] == UINT32_MAX) {
          group_slot[g] = static_cast<std::uint32_t>(in.inner_points.size());
          in.inner_points.push_back(start_.input.inner_points[g]);
        }
        in.inner_id[v] = group_slot[g];
      } else {
        in.inner_id[v] = static_cast<std::uint32_t>(in.inner_points.size());
        in.inner_points.push_back(cached_position(v, s.t[v]));
      }
    }
    in.cap_faces = caps_.cap_faces;
    in.cap_points = caps_.cap_points;
    in.split_order = order_;
    members.build(in.inner_points.size(), [&](const auto& emit) {
      for (std::uint32_t v = 0; v < n; ++v)
        if (in.inner_id[v] != kOnSurface) emit(in.inner_id[v], v);
    });
    return in;
  }

 private:
  const SurfaceMesh& surface_;
  const TraceResult& traces_;
  const InnerVertices& start_;
  const StageMonitor& monitor_;  ///< checked every 1024 prisms of the serial loops
  std::vector<double> full_, floor_;
  std::vector<double> limit_;  ///< per vertex: InnerVertices::limit (infinity: none)
  std::vector<Vec3d> fallback_, correction_;
  IndexLists groups_;                     ///< start weld group -> its vertices
  std::vector<std::uint32_t> group_key_;  ///< per group: its smallest welded vertex (initial)
  std::vector<double> group_depth_;       ///< per group: its welded members' largest depth
  IndexLists faces_;                      ///< vertex -> its faces (a leader's: its followers' too)
  std::vector<Leaders> leaders_;          ///< find_followers()
  std::vector<std::uint32_t> order_;      ///< ShellInput::split_order (empty: no followers)
  std::vector<std::uint32_t> sequence_;   ///< the vertices in the split order
  std::vector<std::uint32_t> folded_;     ///< on the surface (t_v = 0), ascending
  double floor_fraction_ = 0;             ///< ValidityOptions::floor_fraction
  double floor_drop_ = 1;                 ///< ValidityOptions::floor_drop
  int layers_ = 1;                        ///< ValidityOptions::layers
  double shrink_ = 1;                     ///< ValidityOptions::shrink
  std::vector<double> layer_at_;          ///< layer_fractions() of the layers
  std::map<std::uint32_t, int> cap_drops_;  ///< per cap face: how often its depth was dropped
  std::vector<int> drops_;                  ///< per vertex: how often its floor was lowered
  ShellInput caps_;                         ///< cap_faces and cap_points only
  // position(v, t) of the last build, by vertex (t = -1: none yet).
  mutable std::vector<double> cached_t_;
  mutable std::vector<Vec3d> cached_position_;
};

/// The inner slot each point of an assembled shell moves with: an inner point's own, a layer
/// point's surface vertex's; UINT32_MAX for surface and cap points (they never move).
class PointSlots {
 public:
  PointSlots(const SurfaceMesh& surface, const ShellInput& in, const TetMesh& mesh)
      : in_(in),
        mesh_(mesh),
        n_(static_cast<std::uint32_t>(surface.points.size())),
        n_slots_(static_cast<std::uint32_t>(in.inner_points.size())),
        first_layer_point_(static_cast<std::uint32_t>(first_layer_point(surface, in))) {}
  std::uint32_t operator()(std::uint32_t p) const {
    if (p < n_) return UINT32_MAX;
    if (p < n_ + n_slots_) return p - n_;
    if (p < first_layer_point_) return UINT32_MAX;
    return in_.inner_id[mesh_.surface_vertex[p]];
  }

 private:
  const ShellInput& in_;
  const TetMesh& mesh_;
  std::uint32_t n_, n_slots_, first_layer_point_;
};

/// Offending tets (overlapping pairs aside) and inner slots of a check.
void collect_offenders(const SurfaceMesh& surface, const ShellInput& in, const PointSlots& slot_of,
                       const ShellCheckResult& c, std::vector<std::uint32_t>& tets,
                       std::vector<std::uint32_t>& slots) {
  tets.clear();
  slots.clear();
  tets.insert(tets.end(), c.first_inverted_tets.begin(), c.first_inverted_tets.end());
  tets.insert(tets.end(), c.first_zero_volume_tets.begin(), c.first_zero_volume_tets.end());
  tets.insert(tets.end(), c.first_leaking_tets.begin(), c.first_leaking_tets.end());
  for (std::uint32_t p : c.first_outside_vertices)
    if (slot_of(p) != UINT32_MAX) slots.push_back(slot_of(p));
  for (const auto* list :
       {&c.first_missing_triangles, &c.first_shared_triangles, &c.first_misoriented_triangles})
    for (std::uint32_t f : *list)
      for (std::uint32_t v : surface.triangles[f])
        if (in.inner_id[v] != kOnSurface) slots.push_back(in.inner_id[v]);
  std::sort(tets.begin(), tets.end());
  tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
}

/// The indices of the points lying within `tolerance` of another of `points`, ascending: inner
/// vertices at one place that are not one vertex (the ends of traces that met at a critical
/// point, back from their weld). A reader that welds duplicate positions (the independent
/// checker welds within 1e-9 of the diagonal) would join them and see non-manifold faces.
std::vector<std::uint32_t> coincident_points(const std::vector<Vec3d>& points, double tolerance) {
  std::vector<std::uint32_t> out;
  if (points.size() < 2 || !(tolerance > 0)) return out;
  BBox box;
  for (const Vec3d& p : points) box.expand(p);
  using Key = std::array<std::int64_t, 3>;
  std::vector<Key> key(points.size());  // per point: its cube of side `tolerance`
  std::vector<std::pair<Key, std::uint32_t>> cells(points.size());
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a)
      key[i][a] = static_cast<std::int64_t>((points[i][a] - box.lo[a]) / tolerance);
    cells[i] = {key[i], i};
  }
  std::sort(cells.begin(), cells.end());
  for (std::uint32_t i = 0; i < points.size(); ++i) {
    const Key& k = key[i];
    bool near = false;
    for (int dx = -1; dx <= 1 && !near; ++dx)
      for (int dy = -1; dy <= 1 && !near; ++dy)
        for (int dz = -1; dz <= 1 && !near; ++dz) {
          const std::pair<Key, std::uint32_t> lo{{k[0] + dx, k[1] + dy, k[2] + dz}, 0};
          for (auto it = std::lower_bound(cells.begin(), cells.end(), lo);
               it != cells.end() && it->first == lo.first && !near; ++it)
            near = it->second != i && distance(points[it->second], points[i]) <= tolerance;
        }
    if (near) out.push_back(i);
  }
  return out;
}

/// The prism pairs (f < g, ascending, each once) of the overlapping tet pairs of a check.
std::vector<std::array<std::uint32_t, 2>> overlapping_prisms(const ShellCheckResult& checks,
                                                             const TetMesh& mesh) {
  std::vector<std::array<std::uint32_t, 2>> pairs;
  for (const auto& pair : checks.first_overlapping_pairs) {
    const std::uint32_t f = mesh.source_triangle[pair[0]];
    const std::uint32_t g = mesh.source_triangle[pair[1]];
    pairs.push_back({std::min(f, g), std::max(f, g)});
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

/// Moved-back statistics of the final state: vertices below their traced depth (not welded),
/// and their mean relative step back.
void count_moved_back(const ShellSearch& search, const State& s, ValidShell& out) {
  double sum = 0;
  for (std::uint32_t v = 0; v < s.t.size(); ++v)
    if (!s.welded[v] && s.t[v] < search.full()[v] * (1.0 - 1e-12)) {
      ++out.moved_back;
      sum += (search.full()[v] - s.t[v]) / search.full()[v];
    }
  out.moved_back_mean = out.moved_back ? sum / static_cast<double>(out.moved_back) : 0.0;
}

/// Only elements at the floor offend. Next to a fold of the surface that is sharper than the
/// floor (a razor-thin fin, typically next to a folded vertex) the floor itself is too thick:
/// lowers the floors of the offenders' vertices (the overlapping prisms', the offending tets'
/// and slots' members), a bounded number of times each. Returns whether any floor was lowered.
bool drop_floors(ShellSearch& search, State& s, const SurfaceMesh& surface, const TetMesh& mesh,
                 const PointSlots& slot_of,
                 const std::vector<std::array<std::uint32_t, 2>>& prism_pairs,
                 const std::vector<std::uint32_t>& bad_tets,
                 const std::vector<std::uint32_t>& bad_slots, const IndexLists& members,
                 std::uint32_t n_slots, const ValidityOptions& options, std::vector<char>& lowered,
                 std::size_t& floor_drops) {
  bool dropped = false;
  auto drop = [&](std::uint32_t corner) {
    search.for_each_mover(corner, [&](std::uint32_t v) {
      if (lowered[v] || s.t[v] == 0 ||
          !search.lower_floor(v, options.floor_drop, options.max_floor_drops))
        return;
      lowered[v] = 1;
      s.t[v] = search.floor()[v];
      ++floor_drops;
      dropped = true;
    });
  };
  for (const auto& [f, g] : prism_pairs)
    for (const std::uint32_t face : {f, g})
      for (const std::uint32_t v : surface.triangles[face]) drop(v);
  for (std::uint32_t t : bad_tets)
    for (std::uint32_t p : mesh.tets[t])
      if (slot_of(p) != UINT32_MAX)
        for (std::uint32_t v : members[slot_of(p)]) drop(v);
  for (std::uint32_t slot : bad_slots)
    if (slot < n_slots)
      for (std::uint32_t v : members[slot]) drop(v);
  return dropped;
}

/// Once the shell is valid, ValidityOptions::give_back passes give depth back: pass k takes every
/// vertex below its traced depth (welded ones aside) to t / shrink^(1 / 2^(k + 1)), at most its
/// traced depth — half a step, then a quarter, ... Where that leaves a prism unsettled
/// (ShellSearch::lower_raised()) or an element offending, the raised vertices of the prisms
/// involved go back to their depth before the pass, never lower, and the check repeats until the
/// shell is valid: at worst every raise is undone and the shell is the valid one the pass began
/// with. `check` checks a mesh (the search's ShellChecker); `build` assembles `out` from `s`.
template <class Build, class Check>
void give_back(const ShellSearch& search, const SurfaceMesh& surface, State& s,
               const ValidityOptions& options, double zero_volume_tolerance,
               const IndexLists& members, ValidShell& out, std::vector<std::uint32_t>& seeds,
               const Build& build, const Check& check) {
  const auto n = static_cast<std::uint32_t>(s.t.size());
  std::vector<std::uint32_t> bad_tets, bad_slots;
  for (int pass = 0; pass < options.give_back && out.checks.valid(); ++pass) {
    const double step = std::pow(options.shrink, 1.0 / double(2 << pass));  // 1/2, 1/4, ...
    const std::vector<double> before = s.t;
    std::vector<char> raised(n, 0);
    bool any = false;
    for (std::uint32_t v = 0; v < n; ++v) {
      const double full = search.full()[v];
      if (s.welded[v] || s.t[v] == 0 || !(s.t[v] < full * (1 - 1e-12))) continue;
      s.t[v] = std::min(full, s.t[v] / step);
      raised[v] = 1;
      any = true;
    }
    if (!any) break;
    search.faces_around(raised, seeds);
    search.lower_raised(s, before, seeds, zero_volume_tolerance, options.min_quality);
    for (bool undone = false;;) {
      build();
      out.checks = check(out.shell.mesh);
      if (out.checks.valid() || undone) break;
      // The raised vertices of every prism with an offending tet, face or inner point go back.
      const TetMesh& mesh = out.shell.mesh;
      const PointSlots slot_of(surface, out.input, mesh);
      std::vector<char> sent(n, 0);
      bool moved = false;
      const auto send_back = [&](std::uint32_t corner) {
        search.for_each_mover(corner, [&](std::uint32_t v) {
          if (s.t[v] == before[v]) return;
          s.t[v] = before[v];
          sent[v] = 1;
          moved = true;
        });
      };
      const auto send_face = [&](std::uint32_t f) {
        for (const std::uint32_t v : surface.triangles[f]) send_back(v);
      };
      collect_offenders(surface, out.input, slot_of, out.checks, bad_tets, bad_slots);
      for (const auto& pair : out.checks.first_overlapping_pairs)
        for (const std::uint32_t t : pair) send_face(mesh.source_triangle[t]);
      for (const std::uint32_t t : bad_tets) send_face(mesh.source_triangle[t]);
      for (const std::uint32_t slot : bad_slots)
        for (const std::uint32_t v : members[slot]) send_back(v);
      if (!moved) {  // nothing raised offends (not expected): undo the pass whole
        s.t = before;
        undone = true;
        continue;
      }
      search.faces_around(sent, seeds);
      search.lower_raised(s, before, seeds, zero_volume_tolerance, options.min_quality);
    }
  }
}

/// assemble_shell() of the search's own input: should it refuse that input, the search broke an
/// invariant of its own (a bug, exit 3), not the user's file.
AssembleResult assemble_own(const SurfaceMesh& surface, const ShellInput& input,
                            const AssembleOptions& options) {
  try {
    return assemble_shell(surface, input, options);
  } catch (const InputError& e) {
    throw InternalError(std::string("the validity search built a shell it cannot assemble "
                                    "(please report this input): ") +
                        e.what());
  }
}

}  // namespace

ValidShell make_valid_shell(const SurfaceMesh& surface, const TraceResult& traces,
                            const InnerVertices& start, const ValidityOptions& options,
                            const StageMonitor& monitor,
                            const BeforeFinalCheck& before_final_check) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint32_t n = static_cast<std::uint32_t>(surface.points.size());
  if (std::uint64_t(options.layers + 1) * n > UINT32_MAX)  // LocalPrism's layer point ids
    throw InputError("make_valid_shell: " + std::to_string(n) + " surface vertices with " +
                     std::to_string(options.layers) +
                     " layers do not fit 32-bit point indices; use fewer layers");
  ShellSearch search(surface, traces, start, options, monitor);
  ValidShell out;
  IndexLists members;  ///< slot -> its surface vertices
  out.assemble.layers = options.layers;
  out.assemble.layer_ratio = options.layer_ratio;
  AssembleOptions no_quality = out.assemble;
  no_quality.compute_quality = false;

  ShellCheckOptions check_options;
  check_options.max_listed = std::numeric_limits<std::size_t>::max();
  check_options.layers = options.layers;
  // Released before the final check, which builds a grid of its own (after serving
  // before_final_check).
  auto checker = std::make_unique<ShellChecker>(surface, check_options);
  ShellCheckOptions first_few;  // the final check's: the first few offenders of each kind
  first_few.layers = options.layers;
  // Inverted tets first: they are found in O(T) and a shell with any is not worth the rest.
  auto check = [&](const TetMesh& mesh) {
    ShellCheckResult volumes = check_volumes(mesh, check_options);
    if (!volumes.valid()) return volumes;
    ++out.checks_run;
    return checker->check(mesh);
  };

  State s = search.initial();
  std::vector<std::uint32_t> bad_tets, bad_slots;
  std::vector<std::array<std::uint32_t, 2>> prism_pairs;
  std::vector<char> lowered(n);
  std::vector<std::uint32_t> seeds(surface.triangles.size());  // prisms to settle
  std::iota(seeds.begin(), seeds.end(), 0u);
  double first_offenders = 1;
  // Rounds until no element offends or the search stalls (the first search reports progress).
  // Which vertices share their position with another: found once, the first time the floor
  // configuration fails.
  std::vector<char> shared;
  const auto search_rounds = [&](bool report) {
    for (;; ++out.rounds) {
      // Inverted and flat tets are local: settle them prism by prism before a round.
      out.unwelded +=
          search.settle_volumes(s, seeds, options.shrink, check_options.zero_volume_tolerance,
                                options.min_quality, lowered);
      out.input = search.build(s, members);
      out.shell = assemble_own(surface, out.input, no_quality);
      out.checks = check(out.shell.mesh);
      if (out.checks.valid() || out.rounds >= options.max_rounds) break;
      const PointSlots slot_of(surface, out.input, out.shell.mesh);
      collect_offenders(surface, out.input, slot_of, out.checks, bad_tets, bad_slots);
      // Progress: the share of the first round's offenders gone (the final check is the last 10%).
      const double offenders =
          double(bad_tets.size() + bad_slots.size() + out.checks.first_overlapping_pairs.size());
      if (out.rounds == 0) first_offenders = std::max(offenders, 1.0);
      if (report) monitor.report(0.9 * (1.0 - offenders / first_offenders));
      std::fill(lowered.begin(), lowered.end(), 0);
      // Overlapping prisms, pair by pair: each is stepped back until it is apart.
      prism_pairs = overlapping_prisms(out.checks, out.shell.mesh);
      out.unwelded += search.settle_overlaps(s, prism_pairs, options.shrink, check_options,
                                             options.min_quality, lowered);
      bool progress = std::find(lowered.begin(), lowered.end(), 1) != lowered.end();
      const auto n_slots = static_cast<std::uint32_t>(out.input.inner_points.size());
      auto slot_depth = [&](std::uint32_t slot) {
        double d = 0;
        if (slot >= n_slots) return d;  // not an inner slot: nothing to move
        for (std::uint32_t v : members[slot]) d = std::max(d, search.depth(s, v));
        return d;  // 0: every member at its floor, nothing to move
      };
      auto lower = [&](std::uint32_t slot) {  // a welded slot leaves its weld whole
        for (std::uint32_t member : members[slot])
          search.for_each_mover(member, [&](std::uint32_t v) {
            if (!lowered[v])
              out.unwelded += search.step_back(s, v, options.shrink, [&](std::uint32_t u) {
                lowered[u] = 1;
                progress = true;
              });
          });
      };
      for (std::uint32_t t : bad_tets) {
        std::uint32_t best = UINT32_MAX;
        double best_depth = 0;
        for (std::uint32_t p : out.shell.mesh.tets[t]) {
          const std::uint32_t slot = slot_of(p);
          if (slot == UINT32_MAX) continue;
          const double d = slot_depth(slot);
          if (d > best_depth) {
            best_depth = d;
            best = slot;
          }
        }
        if (best != UINT32_MAX) lower(best);
      }
      for (std::uint32_t slot : bad_slots)
        if (slot_depth(slot) > 0) lower(slot);
      if (!progress) {
        progress = drop_floors(search, s, surface, out.shell.mesh, slot_of, prism_pairs, bad_tets,
                               bad_slots, members, n_slots, options, lowered, out.floor_drops);
      }
      if (!progress) {
        // The floors are as low as they go: the floor configuration itself must be invalid.
        const ShellInput in = search.build(search.floor_state(), members);
        const AssembleResult floor = assemble_own(surface, in, no_quality);
        const ShellCheckResult c = check_shell(surface, floor.mesh, check_options);
        // Sectors of a folded vertex among its offenders go on the surface (each once), and so
        // do vertices sharing their position with another (a pinch's or a touching edge's
        // copies: a copy whose faces all point into a notch of the solid can only go inward
        // into the notch across from it), their cap points move closer to their faces (as
        // floors drop), and the search goes on; with none of those left, any vertex of an
        // offending element goes on the surface; what offends with all its vertices there is a
        // failure.
        if (!c.valid()) {
          if (shared.empty()) {
            shared.assign(n, 0);
            std::vector<std::uint32_t> by_point(n);
            std::iota(by_point.begin(), by_point.end(), 0u);
            const auto less = [&](std::uint32_t a, std::uint32_t b) {
              const Vec3d &p = surface.points[a], &q = surface.points[b];
              return std::array<double, 3>{p[0], p[1], p[2]} <
                     std::array<double, 3>{q[0], q[1], q[2]};
            };
            std::sort(by_point.begin(), by_point.end(), less);
            for (std::size_t k = 1; k < n; ++k)
              if (surface.points[by_point[k]] == surface.points[by_point[k - 1]])
                shared[by_point[k]] = shared[by_point[k - 1]] = 1;
          }
          std::vector<std::uint32_t> offending;
          for (const auto& pair : c.first_overlapping_pairs)
            for (const std::uint32_t t : pair) offending.push_back(t);
          for (const auto* list :
               {&c.first_inverted_tets, &c.first_zero_volume_tets, &c.first_leaking_tets})
            offending.insert(offending.end(), list->begin(), list->end());
          std::vector<std::uint32_t> caps;
          const std::size_t first_cap = n + in.inner_points.size();
          const auto keep = [&](std::uint32_t v, bool any) {
            if ((any || search.is_sector(v) || shared[v]) && search.keep_on_surface(s, v)) {
              lowered[v] = 1;
              search.for_each_mover(v, [&](std::uint32_t u) { lowered[u] = 1; });
              progress = true;
            }
          };
          for (const std::uint32_t p : c.first_outside_vertices) {
            const std::uint32_t f = p >= first_cap ? search.cap_face(p - first_cap) : UINT32_MAX;
            if (f != UINT32_MAX) caps.push_back(f);
          }
          for (const std::uint32_t t : offending) {
            const std::uint32_t f = floor.mesh.source_triangle[t];
            if (search.is_cap(f)) caps.push_back(f);
            for (const std::uint32_t v : surface.triangles[f]) keep(v, false);
          }
          std::sort(caps.begin(), caps.end());
          caps.erase(std::unique(caps.begin(), caps.end()), caps.end());
          for (const std::uint32_t f : caps)
            if (search.drop_cap(f, options.max_floor_drops))
              for (const std::uint32_t v : surface.triangles[f]) {
                lowered[v] = 1;
                progress = true;
              }
          // With no sector, shared position or cap left to settle it, any vertex of an offending
          // element goes on the surface (where the surface nearly touches itself, or slivers
          // at their floors stay too thin, no depth serves it).
          if (!progress) {
            for (const std::uint32_t p : c.first_outside_vertices)
              if (p >= n && p < first_cap)  // an inner slot's point: its surface vertices
                for (const std::uint32_t v : members[p - n]) keep(v, true);
            for (const std::uint32_t t : offending)
              for (const std::uint32_t v : surface.triangles[floor.mesh.source_triangle[t]])
                keep(v, true);
          }
        }
        if (progress) {
          search.faces_around(lowered, seeds);
          continue;
        }
        out.floor_valid = c.valid();
        if (!out.floor_valid)  // the first few of each kind
          out.floor_problems = describe_problems(check_shell(surface, floor.mesh, first_few));
        out.stalled = true;
        break;
      }
      search.faces_around(lowered, seeds);
    }
  };
  search_rounds(true);
  give_back(
      search, surface, s, options, check_options.zero_volume_tolerance, members, out, seeds,
      [&] {
        out.input = search.build(s, members);
        out.shell = assemble_own(surface, out.input, no_quality);
      },
      check);
  // Inner vertices at one place but not one vertex step back (each along its own trace, apart;
  // below its floor when at it) and the rounds settle what that changed; a few passes at most,
  // each only lowering.
  const double coincident = 1e-8 * bounding_box(surface).diagonal();
  for (int pass = 0; pass < 8 && out.checks.valid(); ++pass) {
    const std::vector<std::uint32_t> slots = coincident_points(out.input.inner_points, coincident);
    if (slots.empty()) break;
    std::fill(lowered.begin(), lowered.end(), 0);
    bool moved = false;
    for (const std::uint32_t slot : slots)
      for (const std::uint32_t member : members[slot])
        search.for_each_mover(member, [&](std::uint32_t v) {
          if (!lowered[v] && search.depth(s, v) > 0)
            out.unwelded += search.step_back(s, v, options.shrink, [&](std::uint32_t u) {
              lowered[u] = 1;
              moved = true;
            });
        });
    if (!moved)  // every one at its floor (traces meeting within it): lower the floors
      moved = drop_floors(search, s, surface, out.shell.mesh,
                          PointSlots(surface, out.input, out.shell.mesh), {}, {}, slots, members,
                          static_cast<std::uint32_t>(out.input.inner_points.size()), options,
                          lowered, out.floor_drops);
    if (!moved) break;
    search.faces_around(lowered, seeds);
    search_rounds(false);
  }

  out.seconds = seconds_since(t0);
  monitor.milestone(0.9);  // the search is done; the final full check is the rest
  out.shell = assemble_own(surface, out.input, out.assemble);  // with quality, for the report
  if (before_final_check && out.checks.valid()) before_final_check(out, *checker);
  checker.reset();

  // The incremental checks trusted unchanged tets; the result carries one full check (the
  // confirmation every run gets, valid search or not: out.checks.seconds, not out.seconds).
  out.checks = check_shell(surface, out.shell.mesh, first_few);
  out.on_surface = search.folded();
  out.cap_faces = search.caps();
  out.followers = search.followers();
  count_moved_back(search, s, out);
  ++out.checks_run;  // the final full check
  return out;
}

}  // namespace vdb_shell

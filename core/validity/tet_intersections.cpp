// tet_intersections.cpp — see tet_intersections.h.
#include "core/validity/tet_intersections.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "core/base/parallel.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// The hull of a group, seen along the face normals of its first query tets: `axes`, and the
// extents [lo, hi] of the group's corners along them relative to `origin`. When the corners of
// another group (or a triangle) project on one of these axes overlapping the hull by nothing, the
// two are disjoint, and so is every pair of their tets, which the pair's separating-axis test
// would also find (its candidate axes include the direction of least penetration). Tested first,
// it spares the tests of the 3 x 3 pairs of tets of two prisms that are apart, most of them. Any
// axes would do: the normals of the first kHullTets query tets (a whole prism of one layer) keep
// the test short for prisms of many layers.
constexpr std::uint32_t kHullTets = 3;

struct GroupHull {
  Vec3d origin;
  std::vector<Vec3d> axes;
  std::vector<double> lo, hi;
  std::size_t last = 0;  // the axis that separated last

  void build(const BroadPhase& phase, std::uint32_t slot, const std::uint32_t* index,
             std::uint32_t count) {
    const Vec3d* corners = phase.slot_corners(slot);
    const std::uint32_t n_corners = phase.slot_corner_count(slot);
    origin = corners[0];
    axes.clear();
    last = 0;
    for (std::uint32_t q = 0; q < std::min(count, kHullTets); ++q)
      for (const Vec3d& n : phase.geometry_at(index[q]).n)
        if (norm2(n) > 0.0) axes.push_back(n);
    lo.assign(axes.size(), std::numeric_limits<double>::infinity());
    hi.assign(axes.size(), -std::numeric_limits<double>::infinity());
    for (std::uint32_t c = 0; c < n_corners; ++c) {
      const Vec3d d = corners[c] - origin;
      for (std::size_t k = 0; k < axes.size(); ++k) {
        const double x = dot(axes[k], d);
        lo[k] = std::min(lo[k], x);
        hi[k] = std::max(hi[k], x);
      }
    }
  }

  // Whether one of the axes separates the hull from the `count` points `p` (world units). The
  // axis that separated last is tried first: neighbouring candidates tend to be apart along the
  // same one.
  bool separates(const Vec3d* p, std::size_t count) {
    const std::size_t n_axes = axes.size();
    for (std::size_t i = 0; i < n_axes; ++i) {
      const std::size_t k = last + i < n_axes ? last + i : last + i - n_axes;
      const Vec3d& n = axes[k];
      double p_lo = dot(n, p[0] - origin), p_hi = p_lo;
      for (std::size_t c = 1; c < count; ++c) {
        const double x = dot(n, p[c] - origin);
        p_lo = std::min(p_lo, x);
        p_hi = std::max(p_hi, x);
      }
      if (p_lo >= hi[k] || p_hi <= lo[k]) {
        last = k;
        return true;
      }
    }
    return false;
  }
};

// Per chunk of queries: marks of the groups (by slot) and triangles met by the current group
// (entries equal to its slot + 1), so that one met in several cells is tested once, and the
// current group's hull (groups of more than one tet).
struct Scratch {
  std::vector<std::uint32_t> groups, triangles;
  std::vector<std::size_t> candidates;  // per query of the current group
  GroupHull hull;
};

// The queries of one group, in the phase's index order: query k of the group is at index
// index[first + k] of the phase and is queries[query[first + k]].
struct GroupQueries {
  std::uint32_t slot = 0;
  std::uint32_t first = 0, count = 0;
};
struct Queries {
  std::vector<GroupQueries> groups;
  std::vector<std::uint32_t> index, query;
};

// The overlaps of the queries of one group, skipping the candidates that are queries at a
// smaller index.
void find_overlaps(const BroadPhase& phase, const Queries& queries, const GroupQueries& group,
                   bool all_queries, const std::vector<std::uint32_t>& query_at, Scratch& scratch,
                   const ShellCheckOptions& options, std::vector<TetFindings>& found) {
  const std::uint32_t G = phase.group_size();
  const std::uint32_t* index = queries.index.data() + group.first;
  const std::uint32_t* query = queries.query.data() + group.first;
  std::vector<std::size_t>& candidates = scratch.candidates;  // counted here, not in `found`
  candidates.assign(group.count, 0);
  const BroadPhase::SlotBounds& bounds = phase.slot_bounds(group.slot);
  // With every tet a query, the smaller slots of a cell are skipped before they are visited.
  phase.for_each_group_near(
      group.slot, all_queries, scratch.groups, group.slot + 1, [&](std::uint32_t other) {
        if (!slot_bounds_overlap(bounds, phase.slot_bounds(other))) return;
        if (G > 1 && other != group.slot &&
            scratch.hull.separates(phase.slot_corners(other), phase.slot_corner_count(other)))
          return;
        for (std::uint32_t j = other * G; j < (other + 1) * G; ++j) {
          if (!phase.present_at(j)) continue;
          const BBox& box = phase.box_at(j);
          for (std::uint32_t q = 0; q < group.count; ++q) {
            const std::uint32_t i = index[q];
            if (j == i || (j < i && query_at[j] != 0)) continue;  // tested from j
            const TetGeometry& a = phase.geometry_at(i);
            if (!boxes_overlap(a.box, box)) continue;
            ++candidates[q];
            if (tets_intersect(a, phase.geometry_at(j), options.overlap_tolerance))
              found[query[q]].overlapping.push_back(phase.key_at(j));
          }
        }
      });
  for (std::uint32_t q = 0; q < group.count; ++q) found[query[q]].candidates = candidates[q];
}

// Which queries of one group reach outside the surface.
void find_leaks(const BroadPhase& phase, const Queries& queries, const GroupQueries& group,
                const InsideTester& inside, Scratch& scratch, const ShellCheckOptions& options,
                std::vector<TetFindings>& found) {
  const std::uint32_t* index = queries.index.data() + group.first;
  const std::uint32_t* query = queries.query.data() + group.first;
  std::uint32_t open = 0;  // queries not yet known to leak
  for (std::uint32_t q = 0; q < group.count; ++q) {
    const TetGeometry& a = phase.geometry_at(index[q]);
    found[query[q]].leaking = inside.outside((a.p[0] + a.p[1] + a.p[2] + a.p[3]) * 0.25);
    if (!found[query[q]].leaking) ++open;
  }
  const bool hull = phase.group_size() > 1;
  phase.for_each_triangle_near(group.slot, scratch.triangles, group.slot + 1, [&](std::uint32_t f) {
    if (open == 0) return;
    if (hull && scratch.hull.separates(triangle_corners(phase.surface(), f).data(), 3)) return;
    for (std::uint32_t q = 0; q < group.count; ++q) {
      TetFindings& out = found[query[q]];
      if (out.leaking) continue;
      if (surface_triangle_crosses(phase.surface(), f, phase.geometry_at(index[q]),
                                   options.overlap_tolerance)) {
        out.leaking = true;
        --open;
      }
    }
  });
}

}  // namespace

std::vector<TetFindings> find_intersections(const BroadPhase& phase,
                                            const std::vector<std::uint32_t>& queries,
                                            const InsideTester& inside,
                                            const ShellCheckOptions& options) {
  const std::uint32_t G = phase.group_size();
  // The queries by index, grouped by slot, so that consecutive groups read neighbouring lists
  // and geometry.
  std::vector<std::uint32_t> query_at(phase.slot_count() * G, 0);  // per index: query + 1, or 0
  for (std::uint32_t q = 0; q < queries.size(); ++q) query_at[phase.index(queries[q])] = q + 1;
  Queries by_group;
  std::vector<GroupQueries>& groups = by_group.groups;
  for (std::uint32_t i = 0; i < query_at.size(); ++i) {
    if (query_at[i] == 0) continue;
    if (groups.empty() || groups.back().slot != i / G)
      groups.push_back({i / G, static_cast<std::uint32_t>(by_group.index.size()), 0});
    by_group.index.push_back(i);
    by_group.query.push_back(query_at[i] - 1);
    ++groups.back().count;
  }
  const bool all_queries = queries.size() == phase.size();
  std::vector<TetFindings> found(queries.size());
  // Every chunk allocates marks over all slots and triangles: a grain of a 32nd of the groups
  // keeps the chunks few, and that cost a small multiple of one pass over them.
  for_each_chunk(
      groups.size(),
      [&](std::size_t begin, std::size_t end) {
        Scratch scratch;
        scratch.groups.assign(options.check_overlaps ? phase.slot_count() : 0, 0);
        scratch.triangles.assign(options.check_leaks ? phase.surface().triangles.size() : 0, 0);
        for (std::size_t g = begin; g != end; ++g) {
          if (G > 1)
            scratch.hull.build(phase, groups[g].slot, by_group.index.data() + groups[g].first,
                               groups[g].count);
          if (options.check_overlaps)
            find_overlaps(phase, by_group, groups[g], all_queries, query_at, scratch, options,
                          found);
          if (options.check_leaks)
            find_leaks(phase, by_group, groups[g], inside, scratch, options, found);
        }
      },
      std::max<std::size_t>(16, groups.size() / 32));
  return found;
}

}  // namespace vdb_shell

// tet_intersections.h — the narrow phase of the overlap and leak tests, shared by check_shell()
// (every tet is a query) and ShellChecker (the queries are the tets of the prisms that moved or
// offended; every other pair is trusted).
//
// The queries are tested group by group of the BroadPhase (tet_grid.h), in parallel:
//   * overlaps: every tet of a group sharing a cell with the query's group goes to
//     tets_intersect() (tet_predicates.h) when its box meets the query's and, for groups of more
//     than one tet, no face normal of the query group's tets separates the two groups (their
//     corners overlap by nothing along it: every pair of their tets is then apart, as
//     tets_intersect() would find too). A pair of two queries is tested once, from the smaller
//     index; a pair of two tets that are not queries is not tested at all;
//   * leaks: a query leaks when its centroid is outside the surface, or a surface triangle sharing
//     a cell with its group, and not separated from the group by those axes, crosses its interior
//     (surface_triangle_crosses()).
// Both use options.overlap_tolerance, relative to the longest edge involved. Deterministic: each
// query writes only its own result, which does not depend on the thread count.
//
// Internal to core/validity (not installed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/validity/inside_test.h"
#include "core/validity/shell_checks.h"
#include "core/validity/tet_grid.h"

namespace vdb_shell {

/// What the narrow phase found for one query tet.
struct TetFindings {
  std::vector<std::uint32_t> overlapping;  ///< keys of the tets it overlaps, in no fixed order
  bool leaking = false;                    ///< its centroid is outside, or a triangle crosses it
  std::size_t candidates = 0;              ///< tets that reached the overlap test
};

/// Tests the tets `queries` (distinct keys of tets in `phase`): for overlaps when
/// options.check_overlaps, for leaks (against `inside`, built on phase.surface()) when
/// options.check_leaks. One result per query, in the order of `queries`.
std::vector<TetFindings> find_intersections(const BroadPhase& phase,
                                            const std::vector<std::uint32_t>& queries,
                                            const InsideTester& inside,
                                            const ShellCheckOptions& options);

}  // namespace vdb_shell

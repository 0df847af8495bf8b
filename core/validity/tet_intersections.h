// tet_intersections.h — the narrow phase of the overlap and leak tests, shared by check_shell()
// (every tet is a query) and ShellChecker (the queries are the tets of the prisms that moved or
// offended; every other pair is trusted).
//
// Each query tet is tested, in parallel, against its candidates in a BroadPhase (tet_grid.h):
//   * overlaps: every tet sharing a cell with it whose box meets its own goes to tets_intersect()
//     (tet_predicates.h). A pair of two queries is tested once, from the smaller key; a pair of
//     two tets that are not queries is not tested at all;
//   * leaks: it leaks when its centroid is outside the surface, or a surface triangle sharing a
//     cell with it crosses its interior (surface_triangle_crosses()).
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

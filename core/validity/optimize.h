// optimize.h — raising the worst tets' quality of a valid shell by moving its inner vertices
// freely in 3D (--optimize; docs/validity.md, "Optimisation").
//
// Each sweep visits the inner vertices in index order and moves each towards the weighted mean
// of the apexes that would make its incident tets regular (weights favour the worst tets), by
// the first of the steps 1, 1/2, 1/4 that lowers neither the smallest volume-length ratio nor
// the smallest dihedral angle among those tets and raises one of them, never moves the vertex
// towards the surface vertices it belongs to, keeps it within their thickness limits, and
// keeps the volume all moves have lost within max_coverage_loss of the enclosed volume. The worst
// vertices go first, and a vertex moves only if no vertex moved in the same sweep shares a tet with
// it, so each move is judged on the tets as they end up: the shell's smallest ratio and smallest
// angle never fall, and its coverage falls by at most max_coverage_loss. After each sweep the shell
// is checked (ShellChecker: only the moved prisms' tets are retested); vertices of offending tets
// are moved back and frozen until the shell is valid again — moving every vertex back is the valid
// shell we started from, so this ends valid. Sequential: the same result for any thread count.
#pragma once

#include <cstddef>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/validity/search.h"

namespace vdb_shell {

struct OptimizeOptions {
  bool enabled = false;  ///< --optimize / --no-optimize
  int sweeps = 6;        ///< sweeps over the inner vertices
  /// Volume all moves together may lose, as a fraction of the enclosed volume (coverage).
  double max_coverage_loss = 0.01;
};

struct OptimizeReport {
  bool ran = false;
  int sweeps = 0;                  ///< sweeps that moved something and were kept
  int checks = 0;                  ///< shell checks (the first is a full one)
  std::size_t moved_vertices = 0;  ///< inner vertices at a new position in the end
  std::size_t reverted = 0;        ///< moves undone because the shell was no longer valid
  double seconds = 0;
};

/// Optimises the inner points of `valid`, a valid shell of `surface` (make_valid_shell()),
/// `limit` the thickness limit per surface vertex (InnerVertices::limit). Updates
/// valid.shell.mesh (points, quality, thickness), valid.input.inner_points and valid.checks.
/// Cap points are left where they are.
OptimizeReport optimize_shell(const SurfaceMesh& surface, const std::vector<double>& limit,
                              ValidShell& valid, const OptimizeOptions& options);

}  // namespace vdb_shell

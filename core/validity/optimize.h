// optimize.h — raising the worst tets' quality of a valid shell by moving its inner vertices
// freely in 3D and cutting prisms' side quads the other way (--optimize, on by default;
// docs/validity.md, "Optimisation").
//
// Each sweep takes the inner vertices and side quads with a tet among the worst
// (OptimizeOptions::worst_fraction of all tets by volume-length ratio), the worst first. A vertex
// moves towards the weighted mean of the apexes that would make its incident tets regular
// (weights favour the worst tets), by the first of the steps 1, 1/2, 1/4 that lowers neither the
// smallest volume-length ratio nor the smallest dihedral angle among those tets and raises one of
// them, never towards the surface vertices it belongs to, within their thickness limits, and
// keeping the volume all moves have lost within max_coverage_loss of the enclosed volume. A quad
// shared by two prisms whose six corners are distinct is then cut along its other diagonal when
// both prisms still have a 3-tet split (split_prism_cut(), assemble.h) and the same measures of
// their six tets rise as for a move; the points stay, and so does the volume.
//
// A vertex moves only if no vertex moved in the same sweep shares a tet with it, and a quad is
// recut only if no corner of its prisms moved and no other quad of them was recut in the sweep,
// so each change is judged on the tets as they end up: the shell's smallest ratio and smallest
// angle never fall, and its coverage falls by at most max_coverage_loss. After each sweep the
// shell is checked (ShellChecker: only the changed prisms' tets are retested); the moves and cuts
// of offending tets are undone and frozen until the shell is valid again — undoing every change
// is the valid shell we started from, so this ends valid. Sequential: the same result for any
// thread count.
#pragma once

#include <cstddef>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/validity/search.h"

namespace vdb_shell {

struct OptimizeOptions {
  bool enabled = true;  ///< --optimize (the default) / --no-optimize
  int sweeps = 4;       ///< sweeps over the inner vertices and side quads
  /// Volume all moves together may lose, as a fraction of the enclosed volume (coverage;
  /// --max-coverage-loss).
  double max_coverage_loss = 0.002;
  /// Only inner vertices and quads with a tet at or below the quality of this rank (a fraction
  /// of all tets, worst first) take part in a sweep.
  double worst_fraction = 0.1;
};

struct OptimizeReport {
  bool ran = false;
  int sweeps = 0;                  ///< sweeps that changed something and were kept
  int checks = 0;                  ///< shell checks (incremental: changed prisms only)
  std::size_t moved_vertices = 0;  ///< inner vertices at a new position in the end
  std::size_t reverted = 0;        ///< moves undone because the shell was no longer valid
  std::size_t recut_quads = 0;     ///< side quads cut otherwise than by the global-index rule
  std::size_t reverted_cuts = 0;   ///< recuts undone because the shell was no longer valid
  double seconds = 0;
};

/// Optimises the inner points of `valid`, a valid shell of `surface` (make_valid_shell()),
/// `limit` the thickness limit per surface vertex (InnerVertices::limit), checking with
/// `checker` (ShellCheckOptions::max_listed unlimited, as many layers as the shell), whose
/// previous check — of this shell, when it comes from make_valid_shell()'s BeforeFinalCheck —
/// makes the first one cheap. Leaves a shell the checker does not find valid as it is. Updates
/// valid.shell.mesh (points, tets of recut prisms — each in the place of the one it replaces —,
/// quality, thickness), valid.input.inner_points and valid.checks. Cap points are left where
/// they are.
OptimizeReport optimize_shell(const SurfaceMesh& surface, const std::vector<double>& limit,
                              ValidShell& valid, const OptimizeOptions& options,
                              ShellChecker& checker);

}  // namespace vdb_shell

// search.h — the thickest valid shell along the traces (docs/validity.md).
//
// Unknowns: t_v, the arc length at which surface vertex v's inner vertex sits on its own trace
// (0 = on the surface, full = the trace's end after thickness limits). Conditions: every tet of
// every prism positive (for the split actually used), no two tets intersecting, no tet leaving
// the surface, every inner vertex inside, every input triangle a boundary face.
//
// Method: start from the traced (and welded) end points. A step back moves t_v <- max(t_min_v,
// shrink * t_v) (a welded group leaves its weld instead). First settle the volumes locally: any
// prism with an inverted or flat tet steps back that tet's deepest movable inner vertex, and the
// prisms around it are tested again, until none is left (a tet's volume and the prism split
// depend on its own prism only). Then rounds: assemble and check everything; step back every
// pair of overlapping prisms, pair by pair and locally, until it is apart; step back the
// deepest movable vertex of every other offending element once; settle the volumes around
// every move; repeat until no element offends.
//
// Why it terminates with a valid shell: every step lowers one t_v by a fixed factor down to a
// floor t_min_v > 0 (or undoes a weld), and every round takes at least one step, so there are
// finitely many steps and rounds. The floor configuration
// (every vertex at t_min_v, no welds) is a thin offset along each trace's first, inward
// direction, bent where needed to point inward for every incident face (and the extra
// constraints of InnerVertices::constraints: a sector's, core/inner/sectors.h), so it is valid
// (a folded vertex, with no such direction, stays on the surface: t_v = 0 throughout; the
// pipeline splits folded vertices into sectors first, leaving only those with no split); an
// offending element whose vertices are all at the floor is an element of that configuration,
// which is impossible. So an offending element always has a vertex above its floor, and the
// loop ends with no offending element. The floor is "thin enough" only to first order: should a
// round find only floor elements offending (a crease sharper than the floor), their floors are
// divided by floor_drop (at most max_floor_drops times each) and the search goes on; after that
// the floor configuration is checked: sectors of folded vertices among its offenders (two
// sectors whose directions cross overlap at any depth) and vertices sharing their position with
// another (a pinch's copies, each with only its notch's faces) are kept on the surface from
// then on, each at most once, cap points among them move closer to their faces as floors do,
// and the search goes on; otherwise the run fails, naming what it broke.
// Vertices that were never involved keep their full depth: the shell stays as thick as the
// traces allow wherever it is already valid; the gentle shrink, applied locally until each
// offence is gone, takes little more than needed from those that were, and once the shell is
// valid, a ValidityOptions::give_back pass tries every moved-back vertex half a step deeper
// again: where that offends, the raised vertices involved go back to where they were, never
// lower, until the shell is valid again (docs/validity.md).
// Followers: a vertex m on the segment from a to b, next to a (an edge no longer than 1e-2 of
// the longest edge at each end joins m to a's cluster), or a cap's apex within 1e-2 |ab| of
// the segment ab (and the other vertices of a strip of caps, whose ends are a and b), has no
// unknown of its own: its inner vertex is a' + lambda (b' - a') plus its own offset from the
// segment, and stepping it back steps back a or b. The prisms then follow the split order
// (ShellInput::split_order: each follower right after a leader, each cap's leaders ordered by
// the twist of their side quad), in which the sliver prisms between a and m cut their two
// nearly coincident side quads alike and a cap's prism lies on the side its base quad bends
// to (details in docs/validity.md). A prism on a sliver face is settled only down to a quality
// in proportion to its face's shape, and a flat tet (far longer than deep, as under a coarse
// CAD face over a thin wall) only where stepping back can raise it to the quality.
// Last, inner vertices within 1e-8 of the surface's diagonal of each other (traces that met at
// one point and left their weld) step back apart, their floors dropped when at them, and the
// rounds run again: readers that weld duplicate positions would see non-manifold faces.
//
// Cost: one ShellChecker (shell_checks.h) serves every round, testing only the prisms that
// moved since the previous round (or still offend); the result gets one full check_shell().
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/assemble/assemble.h"
#include "core/base/run_control.h"
#include "core/inner/inner.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {

struct ValidityOptions {
  double shrink = 0.85;  ///< factor applied to t_v of a moved-back vertex, in (0, 1)
  /// Tets of a lower volume-length quality are settled like inverted ones (stepped back while a
  /// corner can move; a sliver left at the floor is no violation). 0: volumes only.
  double min_quality = 1e-3;
  double floor_fraction = 0.02;  ///< t_min_v = this * shortest incident edge (capped at full)
  double floor_drop = 0.25;      ///< factor on the floor of a vertex offending at its floor
  int max_floor_drops = 9;       ///< at most this many floor drops per vertex
  int max_rounds = 1000;         ///< safety net (rounds are cheap)
  /// Passes giving depth back once the shell is valid: every vertex below its traced depth half a
  /// step deeper (t / shrink^(1/2)), then a quarter, ...; the raised vertices of what then
  /// offends go back to where they were, never lower (0: none).
  int give_back = 1;
  /// Layers through the thickness (--layers, --layer-ratio; AssembleOptions): the search checks
  /// the layered shell, so the shell it ends with is valid layer by layer.
  int layers = 1;
  double layer_ratio = 1.0;
};

struct ValidShell {
  ShellInput input;             ///< final inner vertices (compact, order-preserving)
  AssembleOptions assemble;     ///< how `shell` was assembled (its layers)
  AssembleResult shell;         ///< the assembled shell
  ShellCheckResult checks;      ///< checks of the final shell (valid() unless floor fails)
  int rounds = 0;               ///< rounds of the moving-back search
  int checks_run = 0;           ///< shell checks run in all (the cost of this stage)
  std::size_t moved_back = 0;   ///< vertices whose final t_v is below their traced depth
  double moved_back_mean = 0;   ///< mean (traced - final) / traced over moved-back vertices
  std::size_t unwelded = 0;     ///< vertices that left their weld
  std::size_t floor_drops = 0;  ///< floors lowered where the floor itself offended
  std::size_t followers = 0;    ///< vertices whose inner vertex follows two others' (step 6)
  /// The search stopped with only elements at their floors offending (the floors as low as they
  /// go): `checks` is then invalid, and floor_valid says whether the floor configuration failed.
  bool stalled = false;
  bool floor_valid = true;     ///< false: the search stalled and the floor failed too
  std::string floor_problems;  ///< what the floor configuration broke, when it did
  /// Folded surface vertices kept on the surface (inner_id kOnSurface, depth 0): their incident
  /// face normals leave no inward direction with a margin of kFoldMargin (kSectorMargin for a
  /// sector), and every prism constrains each of its corners' inner directions against its face
  /// normal, so no thin shell has an inner vertex there. Their
  /// prisms become pyramids, which the same first-order argument allows (docs/validity.md).
  std::vector<std::uint32_t> on_surface;
  /// Faces whose three corners are folded: their prism is one tet to a cap point at the floor
  /// depth below the face (ShellInput::cap_faces).
  std::size_t cap_faces = 0;
  double seconds = 0;  ///< the search, without the final full check (checks.seconds)
};

/// Peak bytes per surface triangle of make_valid_shell(): the search's per-vertex state, the
/// assembled shell of each round (3 tets per prism), the ShellChecker's broad phase (312 bytes
/// of geometry per tet and its cells) and the final full check's own broad phase beside it.
/// Measured: 3.9-4.9 KiB per triangle (fandisk, fertility, spot, knight, sphere, torus, box,
/// bowl, propeller; independent of the resolution).
inline constexpr std::size_t kValidityBytesPerFace = 6656;

/// Estimated peak bytes of make_valid_shell() on `surface` with `layers` layers
/// (kValidityBytesPerFace per triangle and layer: nearly all of it is per tet).
inline std::size_t estimate_validity_bytes(const SurfaceMesh& surface, int layers = 1) {
  return surface.triangles.size() * kValidityBytesPerFace * static_cast<std::size_t>(layers);
}

/// Work on the valid shell before make_valid_shell()'s final full check — the optimisation
/// (optimize.h) — given the search's ShellChecker, whose last check was of that shell. It may
/// move points and recut prisms (keeping assemble_shell()'s layout of the tets); the final check
/// is then of the changed shell.
using BeforeFinalCheck = std::function<void(ValidShell&, ShellChecker&)>;

/// Finds the thickest valid inner vertices along the traces, starting from `start`. Reports to
/// `monitor` the share of the first round's offending elements gone (90% of the stage; the
/// final full check is the rest), runs `before_final_check` on a valid shell and checks it.
ValidShell make_valid_shell(const SurfaceMesh& surface, const TraceResult& traces,
                            const InnerVertices& start, const ValidityOptions& options = {},
                            const StageMonitor& monitor = StageMonitor(),
                            const BeforeFinalCheck& before_final_check = {});

}  // namespace vdb_shell

// shell_checks.h — verifying the invariants of a tet shell against its input surface (the
// conditions of docs/validity.md, "The unknowns and the conditions").
//
// check_shell() counts, for a TetMesh built on a SurfaceMesh:
//   * inverted tets: signed volume V < 0 (and not zero-volume, below);
//   * zero-volume tets: |V| <= zero_volume_tolerance * l^3, l the tet's longest edge (tets with
//     a repeated vertex index are zero-volume too);
//   * inner vertices outside the surface: points of the tet mesh flagged inner (TetMesh::inner,
//     or, without flags, every point after the surface's vertices) that lie outside the closed
//     surface. Points within on_surface_tolerance of the surface count as inside;
//   * surface points moved: the first num_vertices() points of the tet mesh must be the
//     surface's points, bit for bit;
//   * input triangles that are not a boundary face: every input triangle must be a face of
//     exactly one tet, as that tet's outward face (orientation included): "missing" (a face of
//     no tet), "shared" (a face of two or more tets), "misoriented" (a face of one tet, but that
//     tet's outward face runs the other way round);
//   * non-manifold faces: triangles that are a face of three or more tets;
//   * overlapping tet pairs: pairs whose interiors intersect (separating-axis test with a
//     tolerance). Tets that only touch — sharing a vertex, an edge or a face, or lying against
//     each other — are not counted;
//   * leaking tets: tets that reach outside the surface although their vertices may all be
//     inside or on it — a surface triangle crosses their interior (separating-axis test with
//     the same tolerance; touching does not count), or their centroid is outside;
//   * T <= 3F (3 K F with K layers, plus the tets of sector gaps: ShellCheckOptions).
// Lengths are world units; tolerances are relative (dimensionless), as documented per field.
//
// Not checked: thickness limits (they depend on the trace options).
//
// Deterministic: results (counts and listed elements) do not depend on the thread count.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

struct ShellCheckOptions {
  /// A tet is zero-volume when |V| <= this * l^3, l its longest edge (dimensionless).
  double zero_volume_tolerance = 1e-12;
  /// Points closer than this * (surface bounding-box diagonal) to the surface are on it, hence
  /// not outside (dimensionless).
  double on_surface_tolerance = 1e-9;
  /// Two tets overlap when every candidate separating axis sees their projections overlap by
  /// more than this * (longest edge of the two tets) (dimensionless).
  double overlap_tolerance = 1e-9;
  /// Run the tet-tet overlap test (the most expensive check).
  bool check_overlaps = true;
  /// Run the leak test (surface triangles crossing tets, centroids outside).
  bool check_leaks = true;
  /// Layers of prisms through the thickness (AssembleOptions::layers): a surface triangle has up
  /// to 3 * layers tets.
  int layers = 1;
  /// Tets allowed beyond 3 * layers per surface triangle (the gaps between sectors of folded
  /// vertices, sector_shell.h).
  std::size_t extra_tets = 0;
  /// The last this many tets are the flat tets of zero-area input faces (core/read/zero_area.h):
  /// four surface points each, of zero volume by construction. Their faces count as every tet's;
  /// the volume, overlap and leak tests leave them out.
  std::size_t flat_tets = 0;
  /// How many offending elements each list in the result keeps (lowest indices first);
  /// std::numeric_limits<std::size_t>::max() lists all of them.
  std::size_t max_listed = 5;
};

/// What check_shell() found. Lists hold the first offending elements in index order.
struct ShellCheckResult {
  std::size_t tets = 0;
  std::size_t faces = 0;  ///< triangles of the surface

  std::size_t inverted_tets = 0;
  std::vector<std::uint32_t> first_inverted_tets;
  std::size_t zero_volume_tets = 0;
  std::vector<std::uint32_t> first_zero_volume_tets;

  std::size_t checked_inner_vertices = 0;
  std::size_t outside_inner_vertices = 0;
  std::vector<std::uint32_t> first_outside_vertices;  ///< point indices of the tet mesh

  std::size_t moved_surface_points = 0;
  std::vector<std::uint32_t> first_moved_surface_points;

  std::size_t missing_triangles = 0;  ///< input triangles that are a face of no tet
  std::vector<std::uint32_t> first_missing_triangles;
  std::size_t shared_triangles = 0;  ///< input triangles that are a face of >= 2 tets
  std::vector<std::uint32_t> first_shared_triangles;
  std::size_t misoriented_triangles = 0;  ///< a face of one tet, but turned the wrong way
  std::vector<std::uint32_t> first_misoriented_triangles;

  std::size_t nonmanifold_faces = 0;  ///< triangles shared by three or more tets

  bool overlaps_checked = false;
  std::size_t overlapping_pairs = 0;
  std::vector<std::array<std::uint32_t, 2>> first_overlapping_pairs;  ///< (i, j), i < j
  std::size_t overlap_candidate_pairs = 0;  ///< pairs that reached the narrow phase

  bool leaks_checked = false;
  std::size_t leaking_tets = 0;  ///< tets crossed by a surface triangle or centroid outside
  std::vector<std::uint32_t> first_leaking_tets;

  bool too_many_tets = false;  ///< T > 3 layers F + ShellCheckOptions::extra_tets

  double seconds = 0.0;  ///< wall time of check_shell()

  /// True when no check failed.
  bool valid() const;
};

/// Checks the tet shell `mesh` built on `surface` (see the file comment).
/// \pre surface is closed and outward oriented (load_surface()).
/// \throw InputError if a tet refers to a point that does not exist, a point is not finite, or
///        mesh.inner is neither empty nor of one entry per point.
ShellCheckResult check_shell(const SurfaceMesh& surface, const TetMesh& mesh,
                             const ShellCheckOptions& options = {});

/// check_shell() of `mesh` in which only the tets flagged in `added` (one flag per tet) can
/// overlap or leak: every other tet passed an earlier check at the same corner positions against
/// a surface of the same geometry (the tets added to a checked shell: sector gaps,
/// sector_shell.h). Volumes, surface points, boundary faces and inner points are checked in full;
/// overlaps and leaks only for the added tets, against each other and the tets whose boxes meet
/// theirs (overlap_candidate_pairs counts those pairs only). Costs O(T) plus O(T) per added tet
/// for the boxes, instead of a whole grid of the tets.
/// \throw InputError as check_shell(), or unless `added` has one entry per tet.
ShellCheckResult check_added_tets(const SurfaceMesh& surface, const TetMesh& mesh,
                                  const std::vector<char>& added,
                                  const ShellCheckOptions& options = {});

/// Only the volume checks of check_shell() (inverted and zero-volume tets; the other counts
/// stay 0): the cheap first test of a candidate shell. \pre every tet index is in range.
ShellCheckResult check_volumes(const TetMesh& mesh, const ShellCheckOptions& options = {});

/// The volume test of check_volumes() for one tet.
enum class TetVolume : std::uint8_t { kPositive, kInverted, kZero };
TetVolume tet_volume_class(const std::array<Vec3d, 4>& p, double zero_volume_tolerance);

/// The overlap test of check_shell() for one pair of tets (options.overlap_tolerance).
bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b,
                  const ShellCheckOptions& options = {});

/// Checks a sequence of shells on one surface that differ from one call to the next in a few
/// prisms — the search of make_valid_shell() — at a cost that follows the prisms that changed.
///
/// Every mesh must be an assemble_shell() result (assemble.h): tets grouped by
/// TetMesh::source_triangle in triangle order, at most 3 * ShellCheckOptions::layers per triangle.
/// Volumes and surface points are checked in full on every call, boundary faces whenever the tets'
/// vertex indices changed (they depend on nothing else), inner points once per distinct position.
/// The overlap and leak tests only test the tets of "dirty" prisms — whose tets moved since the
/// previous call, or that offended in it — against all others, and trust every other pair: both its
/// tets are where they were when the pair last passed. The listed offenders therefore always
/// involve a dirty prism, and valid() is check_shell()'s verdict. A grid over the surface's box is
/// built once, at the first call, and the tets of a prism are moved in it when the prism moves.
class ShellChecker {
 public:
  explicit ShellChecker(const SurfaceMesh& surface, const ShellCheckOptions& options = {});
  ~ShellChecker();
  ShellChecker(const ShellChecker&) = delete;
  ShellChecker& operator=(const ShellChecker&) = delete;

  /// \throw InputError as check_shell(), or for a mesh that is not an assemble_shell() result.
  ShellCheckResult check(const TetMesh& mesh);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Pairs of surface triangles (i, j), i < j, whose interiors cross: the surface intersects
/// itself and bounds no single volume. Triangles that only touch (a shared vertex or edge
/// included) do not count; the two faces of an edge do where one folds back onto the other
/// (their third corners on one side of the edge, in one plane). At most `max_listed` pairs, by
/// ascending i, then j. Parallel over blocks of triangles; the same pairs for any thread count.
std::vector<std::array<std::uint32_t, 2>> surface_self_intersections(const SurfaceMesh& surface,
                                                                     std::size_t max_listed);

/// Where surface triangles f and g, with no corner in common, touch from inside: a corner or an
/// edge of one lies on the other (within the crossing test's tolerance of its plane) at least
/// `margin` world units inside its edges, and reaches below it. The solid then lies on both
/// sides of the face there (a wall of no thickness): any prism under the face holds some of the
/// space outside. Touching from outside (parts meeting at a point or along a line) does not
/// count, nor does a corner on or near the other's edge (a T-junction). std::nullopt when they
/// do not touch so.
std::optional<Vec3d> surface_triangles_touch_inside(const SurfaceMesh& surface, std::uint32_t f,
                                                    std::uint32_t g, double margin);

/// Pairs of surface triangles (i, j), i < j, that touch from inside
/// (surface_triangles_touch_inside()): at most `max_listed`, by ascending i, then j; the same
/// pairs for any thread count.
std::vector<std::array<std::uint32_t, 2>> surface_inside_contacts(const SurfaceMesh& surface,
                                                                  double margin,
                                                                  std::size_t max_listed);

/// A point where surface triangles f and g cross (as surface_self_intersections() lists them):
/// where an edge of one passes through the other, else (coplanar overlap) a corner of one inside
/// the other (not one they share), else the midpoint of their centroids.
Vec3d triangles_crossing_point(const SurfaceMesh& surface, std::uint32_t f, std::uint32_t g);

/// One line per failed check ("3 inverted tets (first: 12, 40, 41)"); "" when valid.
std::string describe_problems(const ShellCheckResult& result);

/// Whether `p` lies outside the closed surface (not counting points within `tolerance` world
/// units of it). Builds an index on every call: for many points use check_shell().
bool point_outside_surface(const SurfaceMesh& surface, const Vec3d& p, double tolerance);

/// Whether the interiors of tets (a0..a3) and (b0..b3) intersect: separating-axis test, where
/// projections overlapping by at most `tolerance` world units count as touching.
bool tets_overlap(const std::array<Vec3d, 4>& a, const std::array<Vec3d, 4>& b, double tolerance);

}  // namespace vdb_shell

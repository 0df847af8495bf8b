// check_steps.h — the steps check_shell() and ShellChecker::check() share: the checks of single
// elements (mesh sanity, T <= 3F, volumes, surface points kept, boundary faces, inner points),
// and the recording of what the narrow phase found (tet_intersections.h).
//
// Every step adds its counts to a ShellCheckResult, and its offenders to the result's lists in
// index order, up to options.max_listed per list. Internal to core/validity (not installed).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_faces.h"
#include "core/base/tet_mesh.h"
#include "core/validity/shell_checks.h"
#include "core/validity/tet_intersections.h"

namespace vdb_shell {

/// Appends `item` to `list` unless the list holds `max_listed` items already.
void list_item(std::vector<std::uint32_t>& list, std::size_t max_listed, std::size_t item);

/// The checks of single elements but for the boundary faces and the inner points' positions:
/// sanity (throws), result.tets, result.faces, T <= 3F, volumes and surface points kept. Returns
/// the indices of the inner points (TetMesh::inner, or without flags every point after the
/// surface's), and sets result.checked_inner_vertices.
/// \throw InputError as check_shell().
std::vector<std::uint32_t> check_elements(const SurfaceMesh& surface, const TetMesh& mesh,
                                          const ShellCheckOptions& options,
                                          ShellCheckResult& result);

/// Inverted and zero-volume tets. \pre every tet index is in range.
void count_volumes(const TetMesh& mesh, const ShellCheckOptions& options, ShellCheckResult& result);

/// Missing, shared and misoriented input triangles, and non-manifold faces: the 4T tet faces
/// sorted by their vertex triples, each input triangle looked up among them.
/// \pre every tet index is in range.
void check_boundary_faces(const SurfaceMesh& surface, const TetMesh& mesh,
                          const ShellCheckOptions& options, ShellCheckResult& result);

/// check_boundary_faces() over a sequence of meshes of one tet count that change a few tets at a
/// time (ShellChecker): the sorted faces, a verdict per input triangle and the non-manifold
/// count are kept, and a call sorts, looks up and counts again only the faces of the tets whose
/// corners changed, and the input triangles and vertex triples those faces had or have. The
/// results are check_boundary_faces()'s.
class BoundaryFaces {
 public:
  /// `surface` must outlive the object.
  explicit BoundaryFaces(const SurfaceMesh& surface) : surface_(surface) {}

  /// Brings the state to `mesh` and adds its counts and lists to `result`: from scratch at the
  /// first call, when the tet count changed, or when more than 1 / kRebuildShare of the tets
  /// changed. \pre every tet index is in range.
  void check(const TetMesh& mesh, const ShellCheckOptions& options, ShellCheckResult& result);

 private:
  static constexpr std::size_t kRebuildShare = 32;
  void rebuild(const TetMesh& mesh);
  void update(const TetMesh& mesh, const std::vector<std::uint32_t>& changed);

  const SurfaceMesh& surface_;
  std::vector<Tet> tets_;              // the tets the state is of
  FaceRecords faces_;                  // their faces, sorted
  std::vector<std::uint8_t> verdict_;  // per input triangle
  std::size_t nonmanifold_ = 0;        // vertex triples of more than two faces
  std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> triangle_keys_;  // sorted
};

/// The distance (world units) within which a point is on `surface`: options.on_surface_tolerance
/// times the diagonal of its bounding box.
double on_surface_distance(const SurfaceMesh& surface, const ShellCheckOptions& options);

/// Records the inner points `inner_points[i]` with outside[i] != 0 as outside.
void record_outside_points(const std::vector<std::uint32_t>& inner_points,
                           const std::vector<std::uint8_t>& outside,
                           const ShellCheckOptions& options, ShellCheckResult& result);

/// The offenders the narrow phase found, as tet indices.
struct Intersections {
  std::vector<std::array<std::uint32_t, 2>> pairs;  ///< overlapping tets (i, j), i < j, ascending
  std::vector<std::uint32_t> leaking;               ///< ascending
};

/// Records `findings` (those of find_intersections() for `queries`) in `result`: overlapping
/// pairs, leaking tets, candidate pairs, and whether each test ran (options.check_overlaps,
/// options.check_leaks). `tet_of` maps a key to its tet's index in the mesh. Returns every
/// offender, listed or not.
Intersections record_intersections(const std::vector<TetFindings>& findings,
                                   const std::vector<std::uint32_t>& queries,
                                   const std::function<std::uint32_t(std::uint32_t)>& tet_of,
                                   const ShellCheckOptions& options, ShellCheckResult& result);

}  // namespace vdb_shell

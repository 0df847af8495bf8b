// quality.h — shape quality of tetrahedra and the quality report of a tet shell (paper Fig. 10).
//
// Measures:
//   * volume-length ratio  Q = 6 sqrt(2) V / l_rms^3, with V the signed volume (vec3.h
//     tet_volume) and l_rms the root mean square of the six edge lengths. Dimensionless:
//     1 for the regular tet, 0 for a flat (zero-volume) one, negative for an inverted one.
//   * minimum dihedral angle, in degrees, in [0, 180); 70.53 for the regular tet, 0 for a flat
//     one. It does not see orientation (an inverted tet has the angles of its mirror image).
// Volumes are in world units cubed (the input's units).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"
#include "core/base/vec3.h"

namespace vdb_shell {

/// Volume-length ratio of tet (a, b, c, d): 1 regular, 0 flat, < 0 inverted. 0 when every edge
/// has zero length.
double tet_quality(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);

/// The six dihedral angles of tet (a, b, c, d), degrees in [0, 180), at the edges of kTetEdge in
/// order; all 0 when a face has zero area.
std::array<double, 6> tet_dihedrals_deg(const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                        const Vec3d& d);

/// Smallest of the six dihedral angles of tet (a, b, c, d), degrees in [0, 180). 0 when a face
/// has zero area.
double tet_min_dihedral_deg(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);

/// tet_quality() of every tet of `mesh`, in tet order (what TetMesh::quality holds).
/// \pre every tet index < mesh.points.size().
std::vector<double> tet_qualities(const TetMesh& mesh);

struct QualityOptions {
  /// Number of equal-width histogram bins over (0, 1]; tets with Q <= 0 are counted apart.
  std::size_t histogram_bins = 10;
  /// The last this many tets are left out (the flat tets of zero-area input faces,
  /// core/read/zero_area.h): every figure is over the others.
  std::size_t flat_tets = 0;
};

/// The quality report of a shell.
struct QualitySummary {
  std::size_t tets = 0;
  /// histogram[i] counts tets with Q in (i / n, (i + 1) / n] (n = histogram_bins); the first bin
  /// is (0, 1/n], Q = 1 falls in the last one.
  std::vector<std::size_t> histogram;
  std::size_t non_positive = 0;   ///< tets with Q <= 0 (flat or inverted), not in histogram
  double min_quality = 0.0;       ///< smallest Q (0 when there are no tets)
  double median_quality = 0.0;    ///< median Q (mean of the two middle values for even counts)
  double p5_quality = 0.0;        ///< 5th percentile of Q (the value at rank floor(0.05 T))
  double mean_quality = 0.0;      ///< arithmetic mean of Q
  double min_dihedral_deg = 0.0;  ///< smallest dihedral angle over all tets, degrees
  double shell_volume = 0.0;      ///< sum of signed tet volumes, world units cubed
  double enclosed_volume = 0.0;   ///< signed_volume(surface), world units cubed
  double coverage = 0.0;          ///< shell_volume / enclosed_volume (0 if that is <= 0)
};

/// Quality histogram and volumes of the shell `mesh` built on `surface`. Reads Q from
/// mesh.quality when it has one entry per tet, otherwise computes it.
/// \pre every tet index < mesh.points.size().
QualitySummary summarize_quality(const SurfaceMesh& surface, const TetMesh& mesh,
                                 const QualityOptions& options = {});

}  // namespace vdb_shell

// test_support.h — shared helpers of the test suite: temporary folders, the shared mesh corpus,
// running the built executables, reading a TetGen shell back, and checks of a shell computed here
// without core/'s checks.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell::test {

/// A fresh, empty folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// ../shared/meshes next to the repository, or empty when absent (tests then GTEST_SKIP).
std::filesystem::path shared_meshes_dir();
/// ../shared/eval/check_shell.py, or empty when absent.
std::filesystem::path shared_checker();

/// Result of running a command through the shell.
struct CommandResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};
/// Runs `command` (a shell command line) and captures its stdout and stderr.
CommandResult run_command(const std::string& command);

/// Paths of the built executables.
/// What run_cli() (cli/cli.h) did with `args` (without the program name), in this process.
struct CliRun {
  int code = -1;
  std::string out, err;
};
CliRun cli(std::vector<std::string> args);

std::string vdb_shell_bin();
std::string vdb_shell_shapes_bin();

/// The bytes of `path` ("" when it cannot be read).
std::string read_text(const std::string& path);

/// How often `what` occurs in `text` (overlapping occurrences too).
std::size_t count_of(const std::string& text, const std::string& what);

/// Writes `text` to `path` (binary, exact bytes).
void write_text(const std::string& path, const std::string& text);

/// Checks a shell against its surface with computations of its own (none of core/'s checks):
/// the surface's points come first, unchanged; T <= 3F + extra_tets (the gap tets of folded
/// vertices' sectors); every tet's signed volume is positive;
/// every surface triangle is the outward face of exactly one tet; no face is shared by more than
/// two tets, and two tets sharing a face lie on opposite sides of it; no two tets overlap (the
/// centroid of each tet and the midpoints between it and the corners lie strictly inside no
/// other tet); every other point lies inside the surface (winding number > 1/2) or on it.
/// The last `flat_tets` tets may be flat (zero-area input faces): four surface points each, of
/// volume within 1e-12 diagonal^3 (check_shell.py's "degenerate"), left out of the overlap test.
/// Returns "" or the first problem found.
std::string independent_shell_problems(const SurfaceMesh& surface, const TetMesh& shell,
                                       std::size_t extra_tets = 0, std::size_t flat_tets = 0);

/// Shell volume / enclosed volume, both computed here: the sum of the tets' signed volumes over
/// the volume the surface's triangles enclose (divergence theorem). 0 for an empty surface.
double independent_coverage(const SurfaceMesh& surface, const TetMesh& shell);

/// Volume-length ratio 6 sqrt(2) V / l_rms^3 of tet t of `mesh` (regular tet = 1), computed here.
double independent_quality(const TetMesh& mesh, const Tet& t);

/// The points and tets of a TetGen .node/.ele pair (`ele_path` names the .ele; the .node is
/// beside it), read by a parser of its own; 0- or 1-based, as the .node's first index says.
/// \throw std::runtime_error when either file is missing or malformed.
TetMesh read_tetgen_shell(const std::string& ele_path);

/// Whether triangles t and u cross, computed here (none of core/'s tests): an edge of one through
/// the other, or coplanar overlap. Shared vertices and edges do not count.
bool triangles_intersect(const std::array<Vec3d, 3>& t, const std::array<Vec3d, 3>& u);

/// Pairs of intersecting triangles of `mesh`, computed here (sweep and prune along x; pairs
/// sharing an edge are checked for a fold-over instead, pairs sharing a vertex with the full
/// test, which ignores contact at the shared vertex). Proper crossings only: a contact exactly
/// along an edge or at a vertex, within 1e-10 relative, is not reported.
std::vector<std::pair<std::size_t, std::size_t>> self_intersections(const SurfaceMesh& mesh);

/// A vertex with_vertices_near_edge_ends() inserted: on the edge (near, far), at `t` of its
/// length from `near`.
struct InsertedVertex {
  std::uint32_t vertex = 0, near = 0, far = 0;
  double t = 0;
};

/// `mesh` with vertices inserted on every `every`-th edge (in the order of first appearance,
/// skipping edges with a face already split), the two faces of each such edge fanned from their
/// third corners. The edges take turns: one vertex at `t` of the edge from its smaller end; two,
/// at t and 2t; one at t from each end. Appends the new vertices to `inserted`.
SurfaceMesh with_vertices_near_edge_ends(const SurfaceMesh& mesh, std::size_t every, double t,
                                         std::vector<InsertedVertex>& inserted);

/// `mesh` with a strip of caps on every `every`-th face (a, b, c): `vertices` new vertices m_i
/// at t_i along the edge (a, b) (evenly spread over 0.2-0.8, shifted by turns), each moved
/// `height` 4 t_i (1 - t_i) of the edge's length towards c in the face's plane; the face
/// becomes the caps (a, b, m_k), (a, m_i+1, m_i) and the fan (a, m_1, c), (m_i, m_i+1, c),
/// (m_k, b, c) (the edge taking turns among the face's three; a face whose edge has a strip
/// on its other side already is left as it is). Appends the new vertices to
/// `inserted` (near a, far b, t_i; each 4 height t_i (1 - t_i) |ab| off the edge).
SurfaceMesh with_caps(const SurfaceMesh& mesh, std::size_t every, double height,
                      std::size_t vertices, std::vector<InsertedVertex>& inserted);

/// `mesh` with a vertex m next to a corner a of every `every`-th face (a, b, c) whose corners
/// no split face has (the corner taking turns among the three): `distance` times the shorter
/// of the edges (a, b), (a, c) from a, into the face between them (the two edges' directions
/// mixed 0.3 / 0.7, 0.5 / 0.5, 0.7 / 0.3 by turns: off both edges' lines); the face becomes
/// (a, b, m), (b, c, m), (c, a, m). Appends the new vertices to `inserted` (near = far = a,
/// t = distance).
SurfaceMesh with_vertices_near_corners(const SurfaceMesh& mesh, std::size_t every, double distance,
                                       std::vector<InsertedVertex>& inserted);

/// The unit box with a sliver folded over its neighbour: a face (a, b, c) of its top side whose
/// neighbour (b, a, y) across ab lies in that side too becomes (a, b, m), (b, c, m), (c, a, m),
/// m next to the middle of ab, `across` |ab| over ab towards y in the side's plane: the sliver
/// (a, b, m) lies on (b, a, y) the wrong way round, a surface crossing itself, as rounding
/// leaves CAD exports. Then turned by `turn` radians about z and twice that about x. `flat` is
/// the flat tet a flip of ab would glue on: (a, b, y, m).
SurfaceMesh folded_sliver_box(double across, double turn, Tet& flat);

/// `points` turned by the angles `turn` (radians) about z, then x, then y.
void turn_points(std::vector<Vec3d>& points, const Vec3d& turn);

}  // namespace vdb_shell::test

// shell_writers.h — writing the tet shell (VTK, Gmsh, Medit, TetGen) and surfaces (OBJ, PLY, OFF).
//
// Units: coordinates are written as given, in world units (the input's), at full precision
// (17 significant digits: every double reads back bit for bit). Indices are 0-based in VTK and
// 1-based in Gmsh, Medit and TetGen files, as those formats define them.
//
// Orientation: TetMesh tets are positive, tet_volume(a, b, c, d) > 0 (vec3.h). VTK (cell type
// 10), Gmsh (element type 4), Medit and TetGen use that same convention — TetGen creates every
// tet with orient3d(a, b, c, d) < 0 in Shewchuk's sign, which is tet_volume > 0, and writes its
// four vertices in that order — so every format gets the tets in their stored order, unchanged.
// TetGen's `.face` lists the boundary faces of the tet mesh with normals (right-hand rule)
// pointing out of the mesh.
//
// Every file is written atomically (atomic_file.h): a failure leaves the previous file, or none,
// and no temporary file. A TetGen triple (.node, .ele, .face) is committed only once all three
// were written completely.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

/// The tet-mesh file formats write_tet_mesh() knows.
enum class TetFormat {
  Vtu,    ///< VTK XML UnstructuredGrid (.vtu), ASCII
  Vtk,    ///< legacy VTK UNSTRUCTURED_GRID (.vtk), ASCII, version 4.2
  Msh41,  ///< Gmsh MSH 4.1 (.msh), ASCII: one volume and two surface entities
  Msh22,  ///< Gmsh MSH 2.2 (.msh), ASCII
  Medit,  ///< Medit / INRIA (.mesh), MeshVersionFormatted 2 (double precision)
  TetGen  ///< TetGen X.node + X.ele + X.face, 1-based
};

/// Boundary tags, as every format carries them (Gmsh physical groups, Medit refs, TetGen boundary
/// markers): the outer surface, the inner boundary, the tets.
constexpr int kOuterTag = 1;
constexpr int kInnerTag = 2;
constexpr int kShellTag = 3;

/// The boundary of a shell, tagged: the faces of exactly one tet (tet_boundary_faces()), each
/// kOuterTag when none of its corners is an inner point (TetMesh::inner; every such face of a
/// shell is an input triangle: every other face has an inner corner) and kInnerTag otherwise
/// (the inner surface, and the sides of a shell that ends at the surface). Without `inner` data
/// every face is outer.
struct TaggedBoundary {
  std::vector<Triangle> faces;      ///< oriented out of the mesh
  std::vector<std::uint8_t> tag;    ///< kOuterTag or kInnerTag, per face
  std::vector<std::uint32_t> tet;   ///< per face: its tet
  std::vector<std::uint8_t> local;  ///< per face: the corner of its tet opposite it (0-3)
};
TaggedBoundary tagged_boundary(const TetMesh& mesh);

/// Extensions tet_format_from_path() accepts (lower case, with the dot).
const std::vector<std::string>& tet_mesh_extensions();

/// Chooses the format from `path`'s extension (case-insensitive): .vtu, .vtk, .msh, .mesh, .ele.
/// \param msh_version  Gmsh version for .msh files: 41 (MSH 4.1) or 22 (MSH 2.2).
/// \throw InputError for an unknown extension (the message lists the known ones) or a
///        msh_version other than 41 and 22.
TetFormat tet_format_from_path(const std::string& path, int msh_version = 41);

/// Writes `mesh` to `path` in `format`.
///
/// Optional data is written when present (non-empty): per tet `quality` (Float64) and
/// `source_triangle` (Int64), per point `inner` (UInt8), `thickness` (Float64, world units) and
/// `surface_vertex` (Int64) — as cell/point data in .vtu and .vtk (legacy: FIELD arrays), as
/// $ElementData (4.1 only) / $NodeData in .msh. The boundary (tagged_boundary()) is written in
/// every format: .msh triangles in physical surfaces "outer" (1) and "inner" (2) with the tets
/// in physical volume "shell" (3); Medit Triangles with refs 1/2 and tets with ref 3; the TetGen
/// .face with boundary markers 1/2; .vtu/.vtk per-tet bit masks `outer_faces` and `inner_faces`
/// (bit k: the face opposite corner k).
///
/// For TetFormat::TetGen, `path` names the .ele file (X.ele, or X.node, or the stem X); the
/// three files X.node, X.ele and X.face are written beside each other.
///
/// \pre every tet index < mesh.points.size(); each optional array empty or of full size.
/// \throw InternalError if the precondition is broken (nothing is written).
/// \throw ResourceError if a file cannot be written (nothing is left half written).
void write_tet_mesh(const std::string& path, const TetMesh& mesh, TetFormat format);

/// Peak bytes per tet that write_tet_mesh() allocates besides the mesh (every format): the 4
/// sorted face records of the boundary search (20 bytes each) and its flags, the tagged boundary
/// and the per-tet face masks; the text goes out in 64 KiB chunks. Measured: 95-107 bytes per
/// tet (fandisk, fertility, spot, knight, sphere, torus, bowl; .vtu, .msh, .ele).
inline constexpr std::size_t kWriteBytesPerTet = 160;
/// The same per point (the buckets of the face sort).
inline constexpr std::size_t kWriteBytesPerPoint = 16;

/// Estimated peak bytes write_tet_mesh() allocates for `mesh`.
inline std::size_t estimate_write_bytes(const TetMesh& mesh) {
  return mesh.tets.size() * kWriteBytesPerTet + mesh.points.size() * kWriteBytesPerPoint;
}

/// Extensions write_surface() accepts (lower case, with the dot).
const std::vector<std::string>& surface_output_extensions();

/// Writes a triangle surface (e.g. the inner surface for shell maps) as ASCII .obj, .ply or .off,
/// chosen by `path`'s extension (case-insensitive). Vertex order and triangle order and
/// orientation are kept; degenerate or non-manifold triangles are written as they are.
/// \throw InputError for an unknown extension (the message lists the known ones).
/// \throw InternalError if a triangle index is out of range (nothing is written).
/// \throw ResourceError if the file cannot be written.
void write_surface(const std::string& path, const SurfaceMesh& mesh);

/// The boundary faces of a tet mesh: faces that belong to exactly one tet, oriented so that their
/// normal (b - a) x (c - a) points out of that tet (and so out of the mesh). Ordered by tet, then
/// by the local index of the vertex the face is opposite to. Faces shared by three or more tets
/// (a non-manifold mesh) are not boundary faces.
/// \pre every tet index < mesh.points.size().
std::vector<Triangle> tet_boundary_faces(const TetMesh& mesh);

}  // namespace vdb_shell

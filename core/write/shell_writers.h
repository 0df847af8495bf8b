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

#include <string>
#include <vector>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

/// The tet-mesh file formats write_tet_mesh() knows.
enum class TetFormat {
  Vtu,    ///< VTK XML UnstructuredGrid (.vtu), ASCII
  Vtk,    ///< legacy VTK UNSTRUCTURED_GRID (.vtk), ASCII, version 4.2
  Msh41,  ///< Gmsh MSH 4.1 (.msh), ASCII, one volume entity
  Msh22,  ///< Gmsh MSH 2.2 (.msh), ASCII
  Medit,  ///< Medit / INRIA (.mesh), MeshVersionFormatted 2 (double precision)
  TetGen  ///< TetGen X.node + X.ele + X.face, 1-based
};

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
/// `source_triangle` (Int64), per point `inner` (UInt8) and `thickness` (Float64, world units) —
/// as cell/point data in .vtu and .vtk, as $ElementData/$NodeData in .msh. Medit and TetGen files
/// hold geometry only.
///
/// For TetFormat::TetGen, `path` names the .ele file (X.ele, or X.node, or the stem X); the
/// three files X.node, X.ele and X.face are written beside each other.
///
/// \pre every tet index < mesh.points.size(); each optional array empty or of full size.
/// \throw InternalError if the precondition is broken (nothing is written).
/// \throw ResourceError if a file cannot be written (nothing is left half written).
void write_tet_mesh(const std::string& path, const TetMesh& mesh, TetFormat format);

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

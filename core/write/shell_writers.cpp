// shell_writers.cpp — see shell_writers.h.
//
// All text is formatted with std::to_chars (locale-independent, 17 significant digits for
// doubles, the same as printf's %.17g) into a buffer that is handed to the stream in large
// chunks.
#include "core/write/shell_writers.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

#include "core/base/errors.h"
#include "core/base/file_name.h"
#include "core/base/tet_faces.h"
#include "core/write/atomic_file.h"
#include "core/write/format_writers.h"
#include "core/write/text_out.h"

namespace vdb_shell {
namespace {

constexpr int kVtkTetra = 10;  // VTK_TETRA

std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (const std::string& item : items) s += (s.empty() ? "" : " ") + item;
  return s;
}

// ---------------------------------------------------------------------------------------------
// Preconditions

void check_tet_mesh(const TetMesh& mesh) {
  const std::size_t np = mesh.points.size(), nt = mesh.tets.size();
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::uint32_t v : mesh.tets[t]) {
      if (v >= np) {
        throw InternalError("tet mesh writer: tet " + std::to_string(t) + " references vertex " +
                            std::to_string(v) + " but the mesh has " + std::to_string(np) +
                            " points");
      }
    }
  }
  const auto check_size = [](std::size_t size, std::size_t want, const char* name) {
    if (size != 0 && size != want) {
      throw InternalError(std::string("tet mesh writer: '") + name + "' has " +
                          std::to_string(size) + " entries, expected 0 or " + std::to_string(want));
    }
  };
  check_size(mesh.quality.size(), nt, "quality");
  check_size(mesh.source_triangle.size(), nt, "source_triangle");
  check_size(mesh.layer.size(), nt, "layer");
  check_size(mesh.inner.size(), np, "inner");
  check_size(mesh.thickness.size(), np, "thickness");
  check_size(mesh.surface_vertex.size(), np, "surface_vertex");
}

// ---------------------------------------------------------------------------------------------
// VTK XML (.vtu)

template <typename Values, typename Emit>
void vtu_data_array(TextOut& out, const char* type, const char* name, const Values& values,
                    Emit emit) {
  out.str("        <DataArray type=\"")
      .str(type)
      .str("\" Name=\"")
      .str(name)
      .str("\" format=\"ascii\">\n");
  for (std::size_t i = 0; i < values.size(); ++i) {
    out.str(i % 8 == 0 ? "          " : " ");
    emit(values[i]);
    if (i % 8 == 7 || i + 1 == values.size()) out.ch('\n');
  }
  out.str("        </DataArray>\n");
}

/// Per tet: a bit mask of its faces tagged `tag` (bit k: the face opposite corner k).
std::vector<std::uint8_t> face_mask(const TetMesh& mesh, const TaggedBoundary& boundary, int tag) {
  std::vector<std::uint8_t> mask(mesh.tets.size(), 0);
  for (std::size_t f = 0; f < boundary.faces.size(); ++f)
    if (boundary.tag[f] == tag) mask[boundary.tet[f]] |= std::uint8_t(1u << boundary.local[f]);
  return mask;
}

void write_vtu(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary) {
  TextOut out(os);
  const auto as_real = [&out](double v) { out.real(v); };
  const auto as_int = [&out](auto v) { out.integer(static_cast<long long>(v)); };
  out.str(
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n"
      "  <UnstructuredGrid>\n");
  out.str("    <Piece NumberOfPoints=\"")
      .integer(static_cast<long long>(mesh.points.size()))
      .str("\" NumberOfCells=\"")
      .integer(static_cast<long long>(mesh.tets.size()))
      .str("\">\n");
  if (!mesh.inner.empty() || !mesh.thickness.empty() || !mesh.surface_vertex.empty()) {
    out.str("      <PointData>\n");
    if (!mesh.inner.empty()) vtu_data_array(out, "UInt8", "inner", mesh.inner, as_int);
    if (!mesh.thickness.empty()) {
      vtu_data_array(out, "Float64", "thickness", mesh.thickness, as_real);
    }
    if (!mesh.surface_vertex.empty()) {
      vtu_data_array(out, "Int64", "surface_vertex", mesh.surface_vertex, as_int);
    }
    out.str("      </PointData>\n");
  }
  out.str("      <CellData>\n");
  if (!mesh.quality.empty()) vtu_data_array(out, "Float64", "quality", mesh.quality, as_real);
  if (!mesh.source_triangle.empty()) {
    vtu_data_array(out, "Int64", "source_triangle", mesh.source_triangle, as_int);
  }
  if (layered(mesh)) vtu_data_array(out, "UInt8", "layer", mesh.layer, as_int);
  vtu_data_array(out, "UInt8", "outer_faces", face_mask(mesh, boundary, kOuterTag), as_int);
  vtu_data_array(out, "UInt8", "inner_faces", face_mask(mesh, boundary, kInnerTag), as_int);
  out.str("      </CellData>\n");
  out.str(
      "      <Points>\n"
      "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" "
      "format=\"ascii\">\n");
  for (const Vec3d& p : mesh.points) out.str("          ").point(p).ch('\n');
  out.str(
      "        </DataArray>\n"
      "      </Points>\n"
      "      <Cells>\n"
      "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
  for (const Tet& t : mesh.tets) {
    out.str("          ")
        .integer(t[0])
        .ch(' ')
        .integer(t[1])
        .ch(' ')
        .integer(t[2])
        .ch(' ')
        .integer(t[3])
        .ch('\n');
  }
  out.str(
      "        </DataArray>\n"
      "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    out.str(i % 8 == 0 ? "          " : " ").integer(static_cast<long long>(4 * (i + 1)));
    if (i % 8 == 7 || i + 1 == mesh.tets.size()) out.ch('\n');
  }
  out.str(
      "        </DataArray>\n"
      "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    out.str(i % 16 == 0 ? "          " : " ").integer(kVtkTetra);
    if (i % 16 == 15 || i + 1 == mesh.tets.size()) out.ch('\n');
  }
  out.str(
      "        </DataArray>\n"
      "      </Cells>\n"
      "    </Piece>\n"
      "  </UnstructuredGrid>\n"
      "</VTKFile>\n");
  out.flush();
}

// ---------------------------------------------------------------------------------------------
// Legacy VTK (.vtk)

/// One array of a FIELD section: VTK's legacy reader loads every array of a FIELD, where it
/// keeps only the first of several SCALARS.
template <typename Values, typename Emit>
void vtk_field_array(TextOut& out, const char* name, const char* type, const Values& values,
                     Emit emit) {
  out.str(name).str(" 1 ").integer(static_cast<long long>(values.size())).ch(' ').str(type);
  out.ch('\n');
  for (const auto& v : values) {
    emit(v);
    out.ch('\n');
  }
}

void write_vtk(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary) {
  TextOut out(os);
  const auto as_real = [&out](double v) { out.real(v); };
  const auto as_int = [&out](auto v) { out.integer(static_cast<long long>(v)); };
  const auto np = static_cast<long long>(mesh.points.size());
  const auto nt = static_cast<long long>(mesh.tets.size());
  out.str(
      "# vtk DataFile Version 4.2\n"
      "vdb_shell tetrahedral shell\n"
      "ASCII\n"
      "DATASET UNSTRUCTURED_GRID\n");
  out.str("POINTS ").integer(np).str(" double\n");
  for (const Vec3d& p : mesh.points) out.point(p).ch('\n');
  out.str("CELLS ").integer(nt).ch(' ').integer(5 * nt).ch('\n');
  for (const Tet& t : mesh.tets) {
    out.str("4 ")
        .integer(t[0])
        .ch(' ')
        .integer(t[1])
        .ch(' ')
        .integer(t[2])
        .ch(' ')
        .integer(t[3])
        .ch('\n');
  }
  out.str("CELL_TYPES ").integer(nt).ch('\n');
  for (long long i = 0; i < nt; ++i) out.integer(kVtkTetra).ch('\n');
  out.str("CELL_DATA ").integer(nt).ch('\n');
  out.str("FIELD cell_data ")
      .integer(2 + !mesh.quality.empty() + !mesh.source_triangle.empty() + layered(mesh))
      .ch('\n');
  if (!mesh.quality.empty()) vtk_field_array(out, "quality", "double", mesh.quality, as_real);
  if (!mesh.source_triangle.empty()) {
    vtk_field_array(out, "source_triangle", "long", mesh.source_triangle, as_int);
  }
  if (layered(mesh)) vtk_field_array(out, "layer", "unsigned_char", mesh.layer, as_int);
  vtk_field_array(out, "outer_faces", "unsigned_char", face_mask(mesh, boundary, kOuterTag),
                  as_int);
  vtk_field_array(out, "inner_faces", "unsigned_char", face_mask(mesh, boundary, kInnerTag),
                  as_int);
  const int point_arrays =
      !mesh.inner.empty() + !mesh.thickness.empty() + !mesh.surface_vertex.empty();
  if (point_arrays > 0) {
    out.str("POINT_DATA ").integer(np).ch('\n');
    out.str("FIELD point_data ").integer(point_arrays).ch('\n');
    if (!mesh.inner.empty()) vtk_field_array(out, "inner", "unsigned_char", mesh.inner, as_int);
    if (!mesh.thickness.empty()) {
      vtk_field_array(out, "thickness", "double", mesh.thickness, as_real);
    }
    if (!mesh.surface_vertex.empty()) {
      vtk_field_array(out, "surface_vertex", "long", mesh.surface_vertex, as_int);
    }
  }
  out.flush();
}

// ---------------------------------------------------------------------------------------------
// Medit (.mesh)

void write_medit(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary) {
  TextOut out(os);
  out.str("MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n")
      .integer(static_cast<long long>(mesh.points.size()))
      .ch('\n');
  for (const Vec3d& p : mesh.points) out.point(p).str(" 0\n");
  out.str("\nTriangles\n").integer(static_cast<long long>(boundary.faces.size())).ch('\n');
  for (std::size_t f = 0; f < boundary.faces.size(); ++f) {
    for (std::uint32_t v : boundary.faces[f]) out.integer(static_cast<long long>(v) + 1).ch(' ');
    out.integer(boundary.tag[f]).ch('\n');
  }
  out.str("\nTetrahedra\n").integer(static_cast<long long>(mesh.tets.size())).ch('\n');
  for (const Tet& t : mesh.tets) {
    for (std::uint32_t v : t) out.integer(static_cast<long long>(v) + 1).ch(' ');
    out.integer(kShellTag).ch('\n');
  }
  out.str("\nEnd\n");
  out.flush();
}

// ---------------------------------------------------------------------------------------------
// TetGen (.node, .ele, .face)

void write_tetgen_node(std::ostream& os, const TetMesh& mesh) {
  TextOut out(os);
  out.integer(static_cast<long long>(mesh.points.size())).str(" 3 0 0\n");
  long long index = 1;
  for (const Vec3d& p : mesh.points) out.integer(index++).ch(' ').point(p).ch('\n');
  out.flush();
}

void write_tetgen_ele(std::ostream& os, const TetMesh& mesh) {
  TextOut out(os);
  const bool layers = layered(mesh);  // as the region attribute
  out.integer(static_cast<long long>(mesh.tets.size())).str(layers ? " 4 1\n" : " 4 0\n");
  for (std::size_t i = 0; i < mesh.tets.size(); ++i) {
    out.integer(static_cast<long long>(i) + 1);
    for (std::uint32_t v : mesh.tets[i]) out.ch(' ').integer(static_cast<long long>(v) + 1);
    if (layers) out.ch(' ').integer(mesh.layer[i]);
    out.ch('\n');
  }
  out.flush();
}

void write_tetgen_face(std::ostream& os, const TaggedBoundary& boundary) {
  TextOut out(os);
  out.integer(static_cast<long long>(boundary.faces.size())).str(" 1\n");  // with markers
  for (std::size_t f = 0; f < boundary.faces.size(); ++f) {
    out.integer(static_cast<long long>(f + 1));
    for (std::uint32_t v : boundary.faces[f]) out.ch(' ').integer(static_cast<long long>(v) + 1);
    out.ch(' ').integer(boundary.tag[f]).ch('\n');
  }
  out.flush();
}

/// X for X.ele, X.node or a path without one of those extensions.
std::string tetgen_stem(const std::string& path) {
  const std::string ext = lower_extension(path);
  const bool tetgen = ext == ".ele" || ext == ".node" || ext == ".face";
  return tetgen ? path.substr(0, path.size() - ext.size()) : path;
}

void write_tetgen(const std::string& path, const TetMesh& mesh, const TaggedBoundary& boundary) {
  const std::string stem = tetgen_stem(path);
  AtomicFile node(stem + ".node");
  AtomicFile ele(stem + ".ele");
  AtomicFile face(stem + ".face");
  write_tetgen_node(node.stream(), mesh);
  write_tetgen_ele(ele.stream(), mesh);
  write_tetgen_face(face.stream(), boundary);
  // All three complete before any replaces its target.
  node.finish();
  ele.finish();
  face.finish();
  node.commit();
  ele.commit();
  face.commit();
}

// ---------------------------------------------------------------------------------------------
// Surfaces

void write_obj(std::ostream& os, const SurfaceMesh& mesh) {
  TextOut out(os);
  out.str("# vdb_shell surface: ")
      .integer(static_cast<long long>(mesh.points.size()))
      .str(" vertices, ")
      .integer(static_cast<long long>(mesh.triangles.size()))
      .str(" triangles\n");
  for (const Vec3d& p : mesh.points) out.str("v ").point(p).ch('\n');
  for (const Triangle& t : mesh.triangles) {
    out.ch('f');
    for (std::uint32_t v : t) out.ch(' ').integer(static_cast<long long>(v) + 1);
    out.ch('\n');
  }
  out.flush();
}

void write_off(std::ostream& os, const SurfaceMesh& mesh) {
  TextOut out(os);
  out.str("OFF\n")
      .integer(static_cast<long long>(mesh.points.size()))
      .ch(' ')
      .integer(static_cast<long long>(mesh.triangles.size()))
      .str(" 0\n");
  for (const Vec3d& p : mesh.points) out.point(p).ch('\n');
  for (const Triangle& t : mesh.triangles) {
    out.ch('3');
    for (std::uint32_t v : t) out.ch(' ').integer(v);
    out.ch('\n');
  }
  out.flush();
}

void write_ply(std::ostream& os, const SurfaceMesh& mesh) {
  TextOut out(os);
  out.str("ply\nformat ascii 1.0\ncomment vdb_shell surface\nelement vertex ")
      .integer(static_cast<long long>(mesh.points.size()))
      .str("\nproperty double x\nproperty double y\nproperty double z\nelement face ")
      .integer(static_cast<long long>(mesh.triangles.size()))
      .str("\nproperty list uchar int vertex_indices\nend_header\n");
  for (const Vec3d& p : mesh.points) out.point(p).ch('\n');
  for (const Triangle& t : mesh.triangles) {
    out.ch('3');
    for (std::uint32_t v : t) out.ch(' ').integer(v);
    out.ch('\n');
  }
  out.flush();
}

/// ASCII STL, coordinates to full precision: a reader that welds corners by position gets the
/// mesh's vertices back exactly.
void write_stl(std::ostream& os, const SurfaceMesh& mesh) {
  TextOut out(os);
  out.str("solid vdb_shell\n");
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    out.str("facet normal ").point(normalized(face_normal_area(mesh, f))).str("\nouter loop\n");
    for (std::uint32_t v : mesh.triangles[f]) out.str("vertex ").point(mesh.points[v]).ch('\n');
    out.str("endloop\nendfacet\n");
  }
  out.str("endsolid vdb_shell\n");
  out.flush();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Public API

const std::vector<std::string>& tet_mesh_extensions() {
  static const std::vector<std::string> kExtensions = {".vtu", ".vtk", ".msh", ".mesh", ".ele"};
  return kExtensions;
}

TetFormat tet_format_from_path(const std::string& path, int msh_version) {
  const std::string ext = lower_extension(path);
  if (ext == ".vtu") return TetFormat::Vtu;
  if (ext == ".vtk") return TetFormat::Vtk;
  if (ext == ".mesh") return TetFormat::Medit;
  if (ext == ".ele") return TetFormat::TetGen;
  if (ext == ".msh") {
    if (msh_version == 41) return TetFormat::Msh41;
    if (msh_version == 22) return TetFormat::Msh22;
    throw InputError("unsupported Gmsh version " + std::to_string(msh_version) + " for " + path +
                     ": use 41 (MSH 4.1) or 22 (MSH 2.2)");
  }
  throw InputError("cannot tell the tet mesh format of " + path + " from its extension" +
                   (ext.empty() ? std::string() : " '" + ext + "'") + ": use one of " +
                   join(tet_mesh_extensions()) +
                   " (.ele writes the TetGen .node/.ele/.face triple)");
}

TaggedBoundary tagged_boundary(const TetMesh& mesh) {
  // A face no other tet shares is a boundary face; listed in (tet, local face) order.
  const FaceRecords sorted = sorted_tet_faces(mesh);
  std::vector<std::uint8_t> boundary(sorted.size(), 0);
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i + 1;
    while (j < sorted.size() && sorted[j].same_key(sorted[i])) ++j;
    if (j - i == 1) boundary[4 * std::size_t(sorted[i].tet) + sorted[i].face] = 1;
    i = j;
  }
  TaggedBoundary out;
  for (std::size_t slot = 0; slot < boundary.size(); ++slot) {
    if (!boundary[slot]) continue;
    const Tet& tet = mesh.tets[slot / 4];
    const int* f = kTetOutwardFace[slot % 4];
    const Triangle face = {tet[f[0]], tet[f[1]], tet[f[2]]};
    const bool inner =
        !mesh.inner.empty() && (mesh.inner[face[0]] || mesh.inner[face[1]] || mesh.inner[face[2]]);
    out.faces.push_back(face);
    out.tag.push_back(inner ? kInnerTag : kOuterTag);
    out.tet.push_back(static_cast<std::uint32_t>(slot / 4));
    out.local.push_back(static_cast<std::uint8_t>(slot % 4));
  }
  return out;
}

std::vector<Triangle> tet_boundary_faces(const TetMesh& mesh) {
  return tagged_boundary(mesh).faces;
}

void write_tet_mesh(const std::string& path, const TetMesh& mesh, TetFormat format) {
  check_tet_mesh(mesh);
  const TaggedBoundary boundary = tagged_boundary(mesh);
  const auto to = [&](auto writer) {
    write_file_atomically(path, [&](std::ostream& os) { writer(os, mesh, boundary); });
  };
  switch (format) {
    case TetFormat::Vtu:
      return to(write_vtu);
    case TetFormat::Vtk:
      return to(write_vtk);
    case TetFormat::Msh41:
      return to(write_msh41);
    case TetFormat::Msh22:
      return to(write_msh22);
    case TetFormat::Medit:
      return to(write_medit);
    case TetFormat::TetGen:
      return write_tetgen(path, mesh, boundary);
  }
  throw InternalError("write_tet_mesh: unknown TetFormat value");
}

const std::vector<std::string>& surface_output_extensions() {
  static const std::vector<std::string> kExtensions = {".obj", ".ply", ".off", ".stl"};
  return kExtensions;
}

void write_surface(const std::string& path, const SurfaceMesh& mesh) {
  const std::string ext = lower_extension(path);
  void (*writer)(std::ostream&, const SurfaceMesh&) = nullptr;
  if (ext == ".obj") writer = write_obj;
  if (ext == ".ply") writer = write_ply;
  if (ext == ".off") writer = write_off;
  if (ext == ".stl") writer = write_stl;
  if (writer == nullptr) {
    throw InputError("cannot tell the surface format of " + path + " from its extension" +
                     (ext.empty() ? std::string() : " '" + ext + "'") + ": use one of " +
                     join(surface_output_extensions()));
  }
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    for (std::uint32_t v : mesh.triangles[f]) {
      if (v >= mesh.points.size()) {
        throw InternalError("surface writer: triangle " + std::to_string(f) +
                            " references vertex " + std::to_string(v) + " but the mesh has " +
                            std::to_string(mesh.points.size()) + " points");
      }
    }
  }
  write_file_atomically(path, [&](std::ostream& os) { writer(os, mesh); });
}

}  // namespace vdb_shell

// shell_writers.cpp — see shell_writers.h.
//
// All text is formatted with std::to_chars (locale-independent, 17 significant digits for
// doubles, the same as printf's %.17g) into a buffer that is handed to the stream in large
// chunks. No OpenMesh here: its mesh types cannot hold the degenerate or non-manifold triangles an
// inner surface may have, and its writers print diagnostics instead of throwing.
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

namespace vdb_shell {
namespace {

constexpr int kVtkTetra = 10;      // VTK_TETRA
constexpr int kGmshTetra = 4;      // Gmsh element type: 4-node tetrahedron
constexpr int kGmshVolumeTag = 1;  // the single volume entity (and physical group) of .msh files
constexpr int kDoubleDigits = 17;  // %.17g: every double reads back exactly

// ---------------------------------------------------------------------------------------------
// Text formatting

/// Appends text to a buffer and hands it to the stream in chunks.
class TextOut {
 public:
  explicit TextOut(std::ostream& os) : os_(os) { buffer_.reserve(kChunk + 512); }
  TextOut(const TextOut&) = delete;
  TextOut& operator=(const TextOut&) = delete;

  TextOut& str(std::string_view s) {
    buffer_.append(s.data(), s.size());
    return maybe_flush();
  }
  TextOut& ch(char c) {
    buffer_.push_back(c);
    return maybe_flush();
  }
  TextOut& real(double v) {
    char tmp[64];
    const auto r =
        std::to_chars(tmp, tmp + sizeof(tmp), v, std::chars_format::general, kDoubleDigits);
    buffer_.append(tmp, r.ptr);
    return maybe_flush();
  }
  TextOut& integer(long long v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);
    buffer_.append(tmp, r.ptr);
    return maybe_flush();
  }
  TextOut& point(const Vec3d& p) { return real(p.x).ch(' ').real(p.y).ch(' ').real(p.z); }
  /// Writes everything buffered to the stream.
  void flush() {
    os_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;
  TextOut& maybe_flush() {
    if (buffer_.size() >= kChunk) flush();
    return *this;
  }
  std::ostream& os_;
  std::string buffer_;
};

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
  check_size(mesh.inner.size(), np, "inner");
  check_size(mesh.thickness.size(), np, "thickness");
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

void write_vtu(std::ostream& os, const TetMesh& mesh) {
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
  if (!mesh.inner.empty() || !mesh.thickness.empty()) {
    out.str("      <PointData>\n");
    if (!mesh.inner.empty()) vtu_data_array(out, "UInt8", "inner", mesh.inner, as_int);
    if (!mesh.thickness.empty()) {
      vtu_data_array(out, "Float64", "thickness", mesh.thickness, as_real);
    }
    out.str("      </PointData>\n");
  }
  if (!mesh.quality.empty() || !mesh.source_triangle.empty()) {
    out.str("      <CellData>\n");
    if (!mesh.quality.empty()) vtu_data_array(out, "Float64", "quality", mesh.quality, as_real);
    if (!mesh.source_triangle.empty()) {
      vtu_data_array(out, "Int64", "source_triangle", mesh.source_triangle, as_int);
    }
    out.str("      </CellData>\n");
  }
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

template <typename Values, typename Emit>
void vtk_scalars(TextOut& out, const char* name, const char* type, const Values& values,
                 Emit emit) {
  out.str("SCALARS ").str(name).ch(' ').str(type).str(" 1\nLOOKUP_TABLE default\n");
  for (const auto& v : values) {
    emit(v);
    out.ch('\n');
  }
}

void write_vtk(std::ostream& os, const TetMesh& mesh) {
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
  if (!mesh.quality.empty() || !mesh.source_triangle.empty()) {
    out.str("CELL_DATA ").integer(nt).ch('\n');
    if (!mesh.quality.empty()) vtk_scalars(out, "quality", "double", mesh.quality, as_real);
    if (!mesh.source_triangle.empty()) {
      vtk_scalars(out, "source_triangle", "long", mesh.source_triangle, as_int);
    }
  }
  if (!mesh.inner.empty() || !mesh.thickness.empty()) {
    out.str("POINT_DATA ").integer(np).ch('\n');
    if (!mesh.inner.empty()) vtk_scalars(out, "inner", "unsigned_char", mesh.inner, as_int);
    if (!mesh.thickness.empty()) {
      vtk_scalars(out, "thickness", "double", mesh.thickness, as_real);
    }
  }
  out.flush();
}

// ---------------------------------------------------------------------------------------------
// Gmsh (.msh 4.1 and 2.2)

/// $NodeData / $ElementData block (the same in MSH 2.2 and 4.1): one scalar per node/element,
/// tags 1-based.
template <typename Values, typename Emit>
void msh_data(TextOut& out, const char* section, const char* name, const Values& values,
              Emit emit) {
  out.ch('$').str(section).ch('\n');
  out.str("1\n\"").str(name).str("\"\n");  // one string tag: the name
  out.str("1\n0\n");                       // one real tag: the time
  out.str("3\n0\n1\n").integer(static_cast<long long>(values.size())).ch('\n');  // step, 1 comp
  for (std::size_t i = 0; i < values.size(); ++i) {
    out.integer(static_cast<long long>(i + 1)).ch(' ');
    emit(values[i]);
    out.ch('\n');
  }
  out.str("$End").str(section).ch('\n');
}

void msh_all_data(TextOut& out, const TetMesh& mesh) {
  const auto as_real = [&out](double v) { out.real(v); };
  const auto as_int = [&out](auto v) { out.integer(static_cast<long long>(v)); };
  if (!mesh.inner.empty()) msh_data(out, "NodeData", "inner", mesh.inner, as_int);
  if (!mesh.thickness.empty()) msh_data(out, "NodeData", "thickness", mesh.thickness, as_real);
  if (!mesh.quality.empty()) msh_data(out, "ElementData", "quality", mesh.quality, as_real);
  if (!mesh.source_triangle.empty()) {
    msh_data(out, "ElementData", "source_triangle", mesh.source_triangle, as_int);
  }
}

void msh_physical_names(TextOut& out) {
  out.str("$PhysicalNames\n1\n3 ").integer(kGmshVolumeTag).str(" \"shell\"\n$EndPhysicalNames\n");
}

void write_msh41(std::ostream& os, const TetMesh& mesh) {
  TextOut out(os);
  const auto np = static_cast<long long>(mesh.points.size());
  const auto nt = static_cast<long long>(mesh.tets.size());
  out.str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
  msh_physical_names(out);
  // One volume entity holding every node and element, in physical group 1.
  BBox box;
  for (const Vec3d& p : mesh.points) box.expand(p);
  if (box.empty()) box = BBox{Vec3d{}, Vec3d{}};
  out.str("$Entities\n0 0 0 1\n")
      .integer(kGmshVolumeTag)
      .ch(' ')
      .point(box.lo)
      .ch(' ')
      .point(box.hi)
      .str(" 1 ")
      .integer(kGmshVolumeTag)
      .str(" 0\n$EndEntities\n");
  out.str("$Nodes\n");
  if (np == 0) {
    out.str("0 0 0 0\n");
  } else {
    out.str("1 ").integer(np).str(" 1 ").integer(np).ch('\n');
    out.str("3 ").integer(kGmshVolumeTag).str(" 0 ").integer(np).ch('\n');
    for (long long i = 1; i <= np; ++i) out.integer(i).ch('\n');
    for (const Vec3d& p : mesh.points) out.point(p).ch('\n');
  }
  out.str("$EndNodes\n$Elements\n");
  if (nt == 0) {
    out.str("0 0 0 0\n");
  } else {
    out.str("1 ").integer(nt).str(" 1 ").integer(nt).ch('\n');
    out.str("3 ").integer(kGmshVolumeTag).ch(' ').integer(kGmshTetra).ch(' ').integer(nt).ch('\n');
    long long tag = 1;
    for (const Tet& t : mesh.tets) {
      out.integer(tag++);
      for (std::uint32_t v : t) out.ch(' ').integer(static_cast<long long>(v) + 1);
      out.ch('\n');
    }
  }
  out.str("$EndElements\n");
  msh_all_data(out, mesh);
  out.flush();
}

void write_msh22(std::ostream& os, const TetMesh& mesh) {
  TextOut out(os);
  out.str("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
  msh_physical_names(out);
  out.str("$Nodes\n").integer(static_cast<long long>(mesh.points.size())).ch('\n');
  long long tag = 1;
  for (const Vec3d& p : mesh.points) out.integer(tag++).ch(' ').point(p).ch('\n');
  out.str("$EndNodes\n$Elements\n").integer(static_cast<long long>(mesh.tets.size())).ch('\n');
  tag = 1;
  for (const Tet& t : mesh.tets) {
    // number, type, 2 tags (physical group, elementary entity), nodes
    out.integer(tag++)
        .ch(' ')
        .integer(kGmshTetra)
        .str(" 2 ")
        .integer(kGmshVolumeTag)
        .ch(' ')
        .integer(kGmshVolumeTag);
    for (std::uint32_t v : t) out.ch(' ').integer(static_cast<long long>(v) + 1);
    out.ch('\n');
  }
  out.str("$EndElements\n");
  msh_all_data(out, mesh);
  out.flush();
}

// ---------------------------------------------------------------------------------------------
// Medit (.mesh)

void write_medit(std::ostream& os, const TetMesh& mesh) {
  TextOut out(os);
  out.str("MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n")
      .integer(static_cast<long long>(mesh.points.size()))
      .ch('\n');
  for (const Vec3d& p : mesh.points) out.point(p).str(" 0\n");
  out.str("\nTetrahedra\n").integer(static_cast<long long>(mesh.tets.size())).ch('\n');
  for (const Tet& t : mesh.tets) {
    for (std::uint32_t v : t) out.integer(static_cast<long long>(v) + 1).ch(' ');
    out.str("1\n");
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
  out.integer(static_cast<long long>(mesh.tets.size())).str(" 4 0\n");
  long long index = 1;
  for (const Tet& t : mesh.tets) {
    out.integer(index++);
    for (std::uint32_t v : t) out.ch(' ').integer(static_cast<long long>(v) + 1);
    out.ch('\n');
  }
  out.flush();
}

void write_tetgen_face(std::ostream& os, const std::vector<Triangle>& faces) {
  TextOut out(os);
  out.integer(static_cast<long long>(faces.size())).str(" 0\n");
  long long index = 1;
  for (const Triangle& f : faces) {
    out.integer(index++);
    for (std::uint32_t v : f) out.ch(' ').integer(static_cast<long long>(v) + 1);
    out.ch('\n');
  }
  out.flush();
}

/// X for X.ele, X.node or a path without one of those extensions.
std::string tetgen_stem(const std::string& path) {
  const std::string ext = lower_extension(path);
  const bool tetgen = ext == ".ele" || ext == ".node" || ext == ".face";
  return tetgen ? path.substr(0, path.size() - ext.size()) : path;
}

void write_tetgen(const std::string& path, const TetMesh& mesh) {
  const std::string stem = tetgen_stem(path);
  const std::vector<Triangle> faces = tet_boundary_faces(mesh);
  AtomicFile node(stem + ".node");
  AtomicFile ele(stem + ".ele");
  AtomicFile face(stem + ".face");
  write_tetgen_node(node.stream(), mesh);
  write_tetgen_ele(ele.stream(), mesh);
  write_tetgen_face(face.stream(), faces);
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

std::vector<Triangle> tet_boundary_faces(const TetMesh& mesh) {
  // A face no other tet shares is a boundary face; listed in (tet, local face) order.
  const std::vector<FaceRecord> sorted = sorted_tet_faces(mesh);
  std::vector<std::uint8_t> boundary(sorted.size(), 0);
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i + 1;
    while (j < sorted.size() && sorted[j].same_key(sorted[i])) ++j;
    if (j - i == 1) boundary[4 * std::size_t(sorted[i].tet) + sorted[i].face] = 1;
    i = j;
  }
  std::vector<Triangle> faces;
  for (std::size_t slot = 0; slot < boundary.size(); ++slot) {
    if (!boundary[slot]) continue;
    const Tet& tet = mesh.tets[slot / 4];
    const int* f = kTetOutwardFace[slot % 4];
    faces.push_back({tet[f[0]], tet[f[1]], tet[f[2]]});
  }
  return faces;
}

void write_tet_mesh(const std::string& path, const TetMesh& mesh, TetFormat format) {
  check_tet_mesh(mesh);
  switch (format) {
    case TetFormat::Vtu:
      write_file_atomically(path, [&](std::ostream& os) { write_vtu(os, mesh); });
      return;
    case TetFormat::Vtk:
      write_file_atomically(path, [&](std::ostream& os) { write_vtk(os, mesh); });
      return;
    case TetFormat::Msh41:
      write_file_atomically(path, [&](std::ostream& os) { write_msh41(os, mesh); });
      return;
    case TetFormat::Msh22:
      write_file_atomically(path, [&](std::ostream& os) { write_msh22(os, mesh); });
      return;
    case TetFormat::Medit:
      write_file_atomically(path, [&](std::ostream& os) { write_medit(os, mesh); });
      return;
    case TetFormat::TetGen:
      write_tetgen(path, mesh);
      return;
  }
  throw InternalError("write_tet_mesh: unknown TetFormat value");
}

const std::vector<std::string>& surface_output_extensions() {
  static const std::vector<std::string> kExtensions = {".obj", ".ply", ".off"};
  return kExtensions;
}

void write_surface(const std::string& path, const SurfaceMesh& mesh) {
  const std::string ext = lower_extension(path);
  void (*writer)(std::ostream&, const SurfaceMesh&) = nullptr;
  if (ext == ".obj") writer = write_obj;
  if (ext == ".ply") writer = write_ply;
  if (ext == ".off") writer = write_off;
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

// gmsh_writer.cpp — Gmsh MSH 4.1 and 2.2 (see shell_writers.h): the tets in physical volume
// "shell" (tag 3), the boundary triangles in physical surfaces "outer" (1) and "inner" (2), the
// per-tet and per-point data as $ElementData / $NodeData. Element tags: the tets first (1..T),
// then the outer and the inner triangles; the element data lists every element (readers such as
// meshio need that), a boundary triangle with its tet's value. MSH 2.2 files have no element
// data: meshio 5.0 cannot read $ElementData in a 2.2 file with two element types (its reader
// splits the data by the length of (type, cells) pairs), and 2.2 is for solvers, which read
// the groups; use 4.1 for the per-tet data.
#include <cstdint>
#include <ostream>
#include <vector>

#include "core/write/format_writers.h"
#include "core/write/text_out.h"

namespace vdb_shell {
namespace {

constexpr int kGmshTriangle = 2;  // Gmsh element type: 3-node triangle
constexpr int kGmshTetra = 4;     // Gmsh element type: 4-node tetrahedron
constexpr int kVolume = 1;        // the volume entity (elementary tag)

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

/// Per-tet `values` extended to every element: the tets, then each boundary triangle (outer ones
/// first, as the elements are written) with its tet's value.
template <class T>
std::vector<T> per_element(const std::vector<T>& values, const TaggedBoundary& boundary) {
  std::vector<T> out = values;
  for (const int tag : {kOuterTag, kInnerTag})
    for (std::size_t f = 0; f < boundary.faces.size(); ++f)
      if (boundary.tag[f] == tag) out.push_back(values[boundary.tet[f]]);
  return out;
}

/// The per-point data, and the per-element data unless `elements` is false.
void msh_all_data(TextOut& out, const TetMesh& mesh, const TaggedBoundary& boundary,
                  bool elements) {
  const auto as_real = [&out](double v) { out.real(v); };
  const auto as_int = [&out](auto v) { out.integer(static_cast<long long>(v)); };
  if (!mesh.inner.empty()) msh_data(out, "NodeData", "inner", mesh.inner, as_int);
  if (!mesh.thickness.empty()) msh_data(out, "NodeData", "thickness", mesh.thickness, as_real);
  if (!mesh.surface_vertex.empty())
    msh_data(out, "NodeData", "surface_vertex", mesh.surface_vertex, as_int);
  if (!elements) return;
  if (!mesh.quality.empty()) {
    msh_data(out, "ElementData", "quality", per_element(mesh.quality, boundary), as_real);
  }
  if (!mesh.source_triangle.empty()) {
    msh_data(out, "ElementData", "source_triangle", per_element(mesh.source_triangle, boundary),
             as_int);
  }
  if (layered(mesh))
    msh_data(out, "ElementData", "layer", per_element(mesh.layer, boundary), as_int);
}

void msh_physical_names(TextOut& out) {
  out.str("$PhysicalNames\n3\n2 ")
      .integer(kOuterTag)
      .str(" \"outer\"\n2 ")
      .integer(kInnerTag)
      .str(" \"inner\"\n3 ")
      .integer(kShellTag)
      .str(" \"shell\"\n$EndPhysicalNames\n");
}

/// The nodes of a triangle or tet, 1-based, after a space each.
template <class Corners>
void msh_nodes(TextOut& out, const Corners& corners) {
  for (std::uint32_t v : corners) out.ch(' ').integer(static_cast<long long>(v) + 1);
  out.ch('\n');
}

}  // namespace

void write_msh41(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary) {
  TextOut out(os);
  const auto np = static_cast<long long>(mesh.points.size());
  const auto nt = static_cast<long long>(mesh.tets.size());
  long long count[3] = {0, 0, 0};  // triangles per tag
  for (const std::uint8_t tag : boundary.tag) ++count[tag];
  out.str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
  msh_physical_names(out);
  // Surfaces 1 (outer) and 2 (inner) bound volume 1; every node is classified on the volume.
  BBox box;
  for (const Vec3d& p : mesh.points) box.expand(p);
  if (box.empty()) box = BBox{Vec3d{}, Vec3d{}};
  out.str("$Entities\n0 0 2 1\n");
  for (const int tag : {kOuterTag, kInnerTag})
    out.integer(tag).ch(' ').point(box.lo).ch(' ').point(box.hi).str(" 1 ").integer(tag).str(
        " 0\n");
  out.integer(kVolume).ch(' ').point(box.lo).ch(' ').point(box.hi).str(" 1 ").integer(kShellTag);
  out.str(" 2 ").integer(kOuterTag).ch(' ').integer(kInnerTag).str("\n$EndEntities\n");
  out.str("$Nodes\n");
  if (np == 0) {
    out.str("0 0 0 0\n");
  } else {
    out.str("1 ").integer(np).str(" 1 ").integer(np).ch('\n');
    out.str("3 ").integer(kVolume).str(" 0 ").integer(np).ch('\n');
    for (long long i = 1; i <= np; ++i) out.integer(i).ch('\n');
    for (const Vec3d& p : mesh.points) out.point(p).ch('\n');
  }
  out.str("$EndNodes\n$Elements\n");
  const long long ne = nt + count[kOuterTag] + count[kInnerTag];
  const int blocks = (nt > 0) + (count[kOuterTag] > 0) + (count[kInnerTag] > 0);
  out.integer(blocks).ch(' ').integer(ne).str(ne ? " 1 " : " 0 ").integer(ne).ch('\n');
  long long element = 1;
  if (nt > 0) {
    out.str("3 ").integer(kVolume).ch(' ').integer(kGmshTetra).ch(' ').integer(nt).ch('\n');
    for (const Tet& t : mesh.tets) {
      out.integer(element++);
      msh_nodes(out, t);
    }
  }
  for (const int tag : {kOuterTag, kInnerTag}) {
    if (count[tag] == 0) continue;
    out.str("2 ").integer(tag).ch(' ').integer(kGmshTriangle).ch(' ').integer(count[tag]).ch('\n');
    for (std::size_t f = 0; f < boundary.faces.size(); ++f) {
      if (boundary.tag[f] != tag) continue;
      out.integer(element++);
      msh_nodes(out, boundary.faces[f]);
    }
  }
  out.str("$EndElements\n");
  msh_all_data(out, mesh, boundary, /*elements=*/true);
  out.flush();
}

void write_msh22(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary) {
  TextOut out(os);
  out.str("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
  msh_physical_names(out);
  out.str("$Nodes\n").integer(static_cast<long long>(mesh.points.size())).ch('\n');
  long long element = 1;
  for (const Vec3d& p : mesh.points) out.integer(element++).ch(' ').point(p).ch('\n');
  out.str("$EndNodes\n$Elements\n")
      .integer(static_cast<long long>(mesh.tets.size() + boundary.faces.size()))
      .ch('\n');
  element = 1;
  // number, type, 2 tags (physical group, elementary entity), nodes
  for (const Tet& t : mesh.tets) {
    out.integer(element++).ch(' ').integer(kGmshTetra).str(" 2 ").integer(kShellTag);
    out.ch(' ').integer(kVolume);
    msh_nodes(out, t);
  }
  for (const int tag : {kOuterTag, kInnerTag})
    for (std::size_t f = 0; f < boundary.faces.size(); ++f) {
      if (boundary.tag[f] != tag) continue;
      out.integer(element++).ch(' ').integer(kGmshTriangle).str(" 2 ").integer(tag);
      out.ch(' ').integer(tag);
      msh_nodes(out, boundary.faces[f]);
    }
  out.str("$EndElements\n");
  msh_all_data(out, mesh, boundary, /*elements=*/false);
  out.flush();
}

}  // namespace vdb_shell

// boundary_tags_test.cpp — the boundary tags of every tet format (shell_writers.h) on a real
// shell, read back by meshio and by Gmsh itself: the outer surface (the input triangles, tag 1),
// the inner boundary (tag 2), the tets (3), and each point's surface vertex. The expected faces
// are computed here from the tets. Skips what is not installed (meshio, gmsh).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {
namespace {

using test::TempDir;
using Key = std::array<long long, 3>;

Key key_of(long long a, long long b, long long c) {
  Key k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The flap's shell (a folded vertex: sectors and gap tets) and, computed here, its boundary
/// faces split into the input triangles and the rest.
struct Expected {
  ShellResult shell;
  std::set<Key> outer, inner;
};

const Expected& expected() {
  static const Expected e = [] {
    Expected out;
    ShellOptions o;
    o.fields.resolution = 32;
    out.shell = build_shell(make_shape("flap", 2), o);
    std::map<Key, int> count;
    for (const Tet& t : out.shell.mesh.tets)
      for (int skip = 0; skip < 4; ++skip) {
        std::vector<long long> f;
        for (int k = 0; k < 4; ++k)
          if (k != skip) f.push_back(t[k]);
        ++count[key_of(f[0], f[1], f[2])];
      }
    std::set<Key> input;
    for (const Triangle& t : out.shell.surface.triangles) input.insert(key_of(t[0], t[1], t[2]));
    for (const auto& [k, n] : count)
      if (n == 1) (input.count(k) ? out.outer : out.inner).insert(k);
    return out;
  }();
  return e;
}

TEST(BoundaryTags, TheExpectedBoundaryIsTheInputPlusTheInnerSide) {
  const Expected& e = expected();
  EXPECT_EQ(e.outer.size(), e.shell.surface.triangles.size());  // every input triangle
  EXPECT_GT(e.inner.size(), e.shell.surface.triangles.size() / 2);
  EXPECT_GT(e.shell.validity.gap_tets + e.shell.validity.sectors, 0u);
}

/// Reads `path` with meshio and prints, per cell block, its type, its tag (gmsh:physical or
/// medit:ref, -1 without) and its rows; then every point_data / cell_data array name.
constexpr const char* kMeshioScript = R"PY(
import sys
import meshio
import numpy as np
m = meshio.read(sys.argv[1])
tags = m.cell_data.get("gmsh:physical") or m.cell_data.get("medit:ref")
for i, block in enumerate(m.cells):
    t = np.asarray(tags[i]).reshape(-1) if tags is not None else np.full(len(block.data), -1)
    for row, tag in zip(np.asarray(block.data), t):
        print(block.type, int(tag), " ".join(str(int(x)) for x in row))
for name in m.point_data:
    print("point_data", name, " ".join(str(float(x)) for x in np.asarray(m.point_data[name]).reshape(-1)))
for name in m.cell_data:
    print("cell_data", name, " ".join(str(float(x)) for b in m.cell_data[name] for x in np.asarray(b).reshape(-1)))
)PY";

struct Read {
  std::map<int, std::set<Key>> triangles;  ///< by tag
  std::map<int, std::size_t> tets;         ///< count by tag
  std::map<std::string, std::vector<double>> point_data;
  std::map<std::string, std::vector<double>> cell_data;
};

bool read_with_meshio(const std::string& path, Read& out) {
  TempDir dir;
  test::write_text(dir.file("read.py"), kMeshioScript);
  const auto r = test::run_command("/usr/bin/python3 '" + dir.file("read.py") + "' '" + path + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  if (r.exit_code != 0) return false;
  std::istringstream in(r.out);
  std::string type;
  while (in >> type) {
    if (type == "point_data") {
      std::string name, line;
      in >> name;
      std::getline(in, line);
      std::istringstream values(line);
      for (double v; values >> v;) out.point_data[name].push_back(v);
    } else if (type == "cell_data") {
      std::string name, line;
      in >> name;
      std::getline(in, line);
      std::istringstream values(line);
      for (double v; values >> v;) out.cell_data[name].push_back(v);
    } else {
      int tag = 0;
      in >> tag;
      std::vector<long long> row(type == "tetra" ? 4 : 3);
      for (long long& v : row) in >> v;
      if (type == "triangle") out.triangles[tag].insert(key_of(row[0], row[1], row[2]));
      if (type == "tetra") ++out.tets[tag];
    }
  }
  return true;
}

bool meshio_available() {
  return test::run_command("/usr/bin/python3 -c 'import meshio'").exit_code == 0;
}

TEST(BoundaryTags, GmshAndMeditFilesCarryTheTaggedBoundary) {
  if (!meshio_available()) GTEST_SKIP() << "/usr/bin/python3 cannot import meshio";
  const Expected& e = expected();
  TempDir dir;
  for (const auto& [file, version] :
       std::vector<std::pair<std::string, int>>{{"s41.msh", 41}, {"s22.msh", 22}, {"s.mesh", 41}}) {
    SCOPED_TRACE(file);
    write_shell(dir.file(file), e.shell, version);
    Read r;
    if (!read_with_meshio(dir.file(file), r)) continue;
    EXPECT_EQ(r.triangles[kOuterTag], e.outer);
    EXPECT_EQ(r.triangles[kInnerTag], e.inner);
    EXPECT_EQ(r.tets[kShellTag], e.shell.mesh.tets.size());
    EXPECT_EQ(r.tets.size(), 1u);
  }
}

TEST(BoundaryTags, GmshReadsThePhysicalGroups) {
  if (test::run_command("command -v gmsh").exit_code != 0) GTEST_SKIP() << "gmsh not installed";
  const Expected& e = expected();
  TempDir dir;
  for (const int version : {41, 22}) {
    SCOPED_TRACE(version);
    write_shell(dir.file("s.msh"), e.shell, version);
    // Gmsh saves only the elements of physical groups (Mesh.SaveAll = 0), as MSH 2.2: what it
    // writes is what it read into each group.
    test::write_text(dir.file("resave.geo"), "Merge \"" + dir.file("s.msh") +
                                                 "\";\nMesh.MshFileVersion = 2.2;\n"
                                                 "Mesh.SaveAll = 0;\nSave \"" +
                                                 dir.file("out.msh") + "\";\n");
    const auto r = test::run_command("gmsh -nopopup -0 '" + dir.file("resave.geo") + "'");
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    const std::string saved = test::read_text(dir.file("out.msh"));
    EXPECT_NE(saved.find("2 1 \"outer\""), std::string::npos);
    EXPECT_NE(saved.find("2 2 \"inner\""), std::string::npos);
    EXPECT_NE(saved.find("3 3 \"shell\""), std::string::npos);
    std::map<std::pair<int, int>, std::size_t> count;  // (element type, physical tag)
    std::istringstream in(saved.substr(saved.find("$Elements\n") + 10));
    std::size_t n = 0;
    in >> n;
    for (std::size_t i = 0; i < n; ++i) {
      std::string line;
      long long number = 0;
      int type = 0, tags = 0, physical = 0;
      in >> number >> type >> tags >> physical;
      std::getline(in, line);
      ++count[{type, physical}];
    }
    EXPECT_EQ((count[{2, kOuterTag}]), e.outer.size());
    EXPECT_EQ((count[{2, kInnerTag}]), e.inner.size());
    EXPECT_EQ((count[{4, kShellTag}]), e.shell.mesh.tets.size());
  }
}

TEST(BoundaryTags, TetGenFaceMarkersTellOuterFromInner) {
  const Expected& e = expected();
  TempDir dir;
  write_shell(dir.file("s.ele"), e.shell);
  std::istringstream in(test::read_text(dir.file("s.face")));
  std::size_t n = 0;
  int markers = 0;
  in >> n >> markers;
  EXPECT_EQ(markers, 1);
  std::map<int, std::set<Key>> faces;
  for (std::size_t i = 0; i < n; ++i) {
    long long index = 0, a = 0, b = 0, c = 0;
    int marker = 0;
    in >> index >> a >> b >> c >> marker;
    faces[marker].insert(key_of(a - 1, b - 1, c - 1));  // TetGen is 1-based
  }
  EXPECT_EQ(faces[kOuterTag], e.outer);
  EXPECT_EQ(faces[kInnerTag], e.inner);
  EXPECT_EQ(faces.size(), 2u);
}

TEST(BoundaryTags, VtkFilesShowEveryArrayAndTheFaceMasks) {
  if (!meshio_available()) GTEST_SKIP() << "/usr/bin/python3 cannot import meshio";
  const Expected& e = expected();
  const TetMesh& mesh = e.shell.mesh;
  TempDir dir;
  for (const std::string file : {"s.vtu", "s.vtk"}) {
    SCOPED_TRACE(file);
    write_shell(dir.file(file), e.shell);
    Read r;
    if (!read_with_meshio(dir.file(file), r)) continue;
    for (const char* name : {"quality", "source_triangle", "outer_faces", "inner_faces"})
      EXPECT_EQ(r.cell_data.count(name), 1u) << name;
    for (const char* name : {"inner", "thickness", "surface_vertex"})
      EXPECT_EQ(r.point_data.count(name), 1u) << name;
    // The face masks (bit k: the face opposite corner k) count the outer and inner faces.
    for (const auto& [name, faces] :
         {std::pair{"outer_faces", e.outer.size()}, std::pair{"inner_faces", e.inner.size()}}) {
      std::size_t bits = 0;
      for (const double mask : r.cell_data[name])
        bits += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(mask)));
      EXPECT_EQ(bits, faces) << name;
    }
    // Each point's surface vertex: itself on the surface; for an inner point a corner of the
    // input triangle of every tet it is in (this shell welds no inner vertices).
    const std::vector<double>& owner = r.point_data["surface_vertex"];
    ASSERT_EQ(owner.size(), mesh.points.size());
    const std::size_t n = e.shell.surface.points.size();
    ASSERT_EQ(e.shell.counts.welded_vertices, 0u);
    for (std::size_t v = 0; v < n; ++v) EXPECT_EQ(owner[v], double(v));
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      const Triangle& source = e.shell.surface.triangles[mesh.source_triangle[t]];
      for (const std::uint32_t p : mesh.tets[t]) {
        if (p < n) continue;
        EXPECT_TRUE(std::count(source.begin(), source.end(), std::uint32_t(owner[p])))
            << "point " << p << " of tet " << t;
      }
    }
  }
}

}  // namespace
}  // namespace vdb_shell

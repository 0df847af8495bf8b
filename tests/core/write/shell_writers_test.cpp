// shell_writers_test.cpp — core/write/shell_writers.h and core/write/atomic_file.h.
//
// Every tet-mesh format is read back by a real reader (meshio through /usr/bin/python3; the
// TetGen triple also by a small parser here and by ../shared/eval/check_shell.py): the tet count,
// the coordinates (bit for bit), the connectivity and the data come back equal, and every tet is
// positive under the reader's convention. The meshio tests skip when meshio is not installed.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "core/base/tet_mesh.h"
#include "core/read/load_surface.h"
#include "core/write/atomic_file.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

constexpr const char* kPython = "/usr/bin/python3";

// ---------------------------------------------------------------------------------------------
// Meshes built by hand

double volume_of(const TetMesh& mesh, const Tet& t) {
  return tet_volume(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]);
}

/// One positive tet with coordinates that have no short decimal form.
TetMesh single_tet() {
  TetMesh mesh;
  const double third = 1.0 / 3.0;
  mesh.points = {{0.1, -third, 12345.678901234567},
                 {1.1 + 1e-15, -third, 12345.678901234567},
                 {0.1, 2.0 / 3.0, 12345.678901234567},
                 {0.1, -third, 12346.678901234567 + 1e-11}};
  mesh.tets = {{0, 1, 2, 3}};
  return mesh;
}

/// The cube [0, s]^3 shifted by `origin`, split into 5 positive tets (4 corners + the centre).
/// Corner i is at (i & 1, (i >> 1) & 1, (i >> 2) & 1).
TetMesh cube_5_tets(bool with_data) {
  TetMesh mesh;
  const Vec3d origin{1.0 / 7.0, -2.0 / 9.0, 1e-3 / 3.0};
  const double s = 0.1 * std::sqrt(2.0);
  for (int i = 0; i < 8; ++i) {
    mesh.points.push_back(origin + Vec3d{s * (i & 1), s * ((i >> 1) & 1), s * ((i >> 2) & 1)});
  }
  mesh.tets = {{0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}, {1, 2, 4, 7}};
  for (Tet& t : mesh.tets) {
    if (volume_of(mesh, t) < 0.0) std::swap(t[2], t[3]);
  }
  if (with_data) {
    mesh.quality = {0.1, 1.0 / 3.0, 2.0 / 3.0, 0.7071067811865476, 1.0};
    mesh.source_triangle = {0, 7, 4294967295u, 3, 11};
    mesh.layer = {1, 2, 3, 2, 1};
    mesh.inner = {0, 1, 0, 1, 1, 0, 1, 0};
    mesh.thickness = {0.0, 0.1, 1.0 / 3.0, 2.5e-7, 1e10 / 3.0, 0.0, 5.0, std::sqrt(3.0)};
  }
  return mesh;
}

/// The cube's surface: the boundary faces of its tets (12 triangles, outward).
SurfaceMesh cube_surface(const TetMesh& cube) {
  SurfaceMesh surface;
  surface.points = cube.points;
  surface.triangles = tet_boundary_faces(cube);
  return surface;
}

// ---------------------------------------------------------------------------------------------
// Reading back through meshio

bool meshio_available() {
  static const bool available =
      test::run_command(std::string(kPython) + " -c 'import meshio'").exit_code == 0;
  return available;
}

#define SKIP_WITHOUT_MESHIO()                                                    \
  do {                                                                           \
    if (!meshio_available()) GTEST_SKIP() << kPython << " cannot import meshio"; \
  } while (0)

// Prints what meshio read, exactly (repr of a float reads back bit for bit).
constexpr const char* kReadScript = R"PY(
import sys
import meshio
import numpy as np

m = meshio.read(sys.argv[1])
P = np.asarray(m.points, dtype=float)
print("points", len(P))
for p in P:
    print(" ".join(repr(float(x)) for x in p[:3]))
for block in m.cells:
    data = np.asarray(block.data)
    print("cells", block.type, len(data), data.shape[1] if data.ndim == 2 else 0)
    for row in data:
        print(" ".join(str(int(x)) for x in row))
    if block.type == "tetra" and len(data):
        a, b, c, d = (P[data[:, k]] for k in range(4))
        v = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0
        print("min_volume", repr(float(v.min())))
for name, arr in m.point_data.items():
    arr = np.asarray(arr).reshape(-1)
    print("point_data", name, len(arr))
    print(" ".join(repr(float(x)) for x in arr))
for name, blocks in m.cell_data.items():
    arr = np.concatenate([np.asarray(b).reshape(-1) for b in blocks])
    print("cell_data", name, len(arr))
    print(" ".join(repr(float(x)) for x in arr))
print("end")
)PY";

struct ReadBack {
  std::vector<Vec3d> points;
  std::map<std::string, std::vector<std::vector<long long>>> cells;  ///< by meshio cell type
  std::map<std::string, std::vector<double>> point_data, cell_data;
  double min_volume = std::numeric_limits<double>::quiet_NaN();  ///< meshio's, over tetra
};

/// Reads `path` with meshio; fails the test (and returns false) if meshio cannot.
bool read_with_meshio(const TempDir& dir, const std::string& path, ReadBack& out) {
  const std::string script = dir.file("read_back.py");
  if (!fs::exists(script)) test::write_text(script, kReadScript);
  const test::CommandResult r =
      test::run_command(std::string(kPython) + " '" + script + "' '" + path + "'");
  EXPECT_EQ(r.exit_code, 0) << "meshio could not read " << path << ":\n" << r.err;
  if (r.exit_code != 0) return false;
  std::istringstream in(r.out);
  std::string word;
  while (in >> word && word != "end") {
    if (word == "points") {
      std::size_t n = 0;
      in >> n;
      out.points.resize(n);
      for (Vec3d& p : out.points) {
        std::string x, y, z;
        in >> x >> y >> z;
        p = {std::stod(x), std::stod(y), std::stod(z)};
      }
    } else if (word == "cells") {
      std::string type;
      std::size_t n = 0, k = 0;
      in >> type >> n >> k;
      auto& rows = out.cells[type];
      for (std::size_t i = 0; i < n; ++i) {
        std::vector<long long> row(k);
        for (long long& v : row) in >> v;
        rows.push_back(row);
      }
    } else if (word == "min_volume") {
      std::string v;
      in >> v;
      out.min_volume = std::stod(v);
    } else if (word == "point_data" || word == "cell_data") {
      std::string name;
      std::size_t n = 0;
      in >> name >> n;
      std::vector<double>& values = (word == "point_data" ? out.point_data : out.cell_data)[name];
      values.resize(n);
      for (double& v : values) {
        std::string s;
        in >> s;
        v = std::stod(s);
      }
    } else {
      ADD_FAILURE() << "unexpected token '" << word << "' in the output of the read script";
      return false;
    }
  }
  return true;
}

/// Coordinates bit for bit, connectivity identical, every tet positive in meshio's (VTK) sense.
void expect_same_geometry(const TetMesh& mesh, const ReadBack& back) {
  ASSERT_EQ(back.points.size(), mesh.points.size());
  for (std::size_t i = 0; i < mesh.points.size(); ++i) {
    EXPECT_EQ(back.points[i], mesh.points[i]) << "point " << i;
  }
  ASSERT_EQ(back.cells.count("tetra"), 1u);
  const auto& tets = back.cells.at("tetra");
  ASSERT_EQ(tets.size(), mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    ASSERT_EQ(tets[t].size(), 4u);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(tets[t][k], mesh.tets[t][k]) << "tet " << t;
    const Tet read{static_cast<std::uint32_t>(tets[t][0]), static_cast<std::uint32_t>(tets[t][1]),
                   static_cast<std::uint32_t>(tets[t][2]), static_cast<std::uint32_t>(tets[t][3])};
    EXPECT_GT(tet_volume(back.points[read[0]], back.points[read[1]], back.points[read[2]],
                         back.points[read[3]]),
              0.0)
        << "tet " << t;
  }
  if (!mesh.tets.empty()) {
    EXPECT_GT(back.min_volume, 0.0) << "meshio's own volume";
  }
}

template <typename T>
void expect_data(const std::map<std::string, std::vector<double>>& data, const std::string& name,
                 const std::vector<T>& want) {
  ASSERT_EQ(data.count(name), 1u) << "missing data array '" << name << "'";
  const std::vector<double>& got = data.at(name);
  // .msh element data goes on over the boundary triangles, after the tets.
  ASSERT_GE(got.size(), want.size()) << name;
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(got[i], static_cast<double>(want[i])) << name << "[" << i << "]";
  }
}

struct FormatCase {
  TetFormat format;
  const char* file;
  bool has_data;       ///< the format carries inner / thickness per point
  bool has_cell_data;  ///< and quality / source_triangle per tet
};

const std::vector<FormatCase>& all_formats() {
  static const std::vector<FormatCase> kCases = {{TetFormat::Vtu, "shell.vtu", true, true},
                                                 {TetFormat::Vtk, "shell.vtk", true, true},
                                                 {TetFormat::Msh41, "shell.msh", true, true},
                                                 {TetFormat::Msh22, "shell.msh", true, false},
                                                 {TetFormat::Medit, "shell.mesh", false, false},
                                                 {TetFormat::TetGen, "shell.ele", false, false}};
  return kCases;
}

std::string format_name(TetFormat format) {
  switch (format) {
    case TetFormat::Vtu:
      return "vtu";
    case TetFormat::Vtk:
      return "vtk";
    case TetFormat::Msh41:
      return "msh41";
    case TetFormat::Msh22:
      return "msh22";
    case TetFormat::Medit:
      return "medit";
    case TetFormat::TetGen:
      return "tetgen";
  }
  return "?";
}

std::vector<std::string> folder_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// ---------------------------------------------------------------------------------------------
// A small TetGen parser (independent of meshio)

/// Rows of a TetGen table: header tokens, then `header[0]` rows; '#' starts a comment.
bool read_tetgen_table(const std::string& path, std::vector<long long>& header,
                       std::vector<std::vector<std::string>>& rows) {
  std::ifstream in(path);
  if (!in) return false;
  std::string line;
  header.clear();
  rows.clear();
  while (std::getline(in, line)) {
    line = line.substr(0, line.find('#'));
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (tokens.empty()) continue;
    if (header.empty()) {
      for (const std::string& t : tokens) header.push_back(std::stoll(t));
    } else {
      rows.push_back(tokens);
    }
  }
  return !header.empty() && static_cast<long long>(rows.size()) == header[0];
}

// ---------------------------------------------------------------------------------------------
// Format choice

TEST(WritersTest, FormatFromExtension) {
  EXPECT_EQ(tet_format_from_path("a/b/shell.vtu", 41), TetFormat::Vtu);
  EXPECT_EQ(tet_format_from_path("shell.VTK", 41), TetFormat::Vtk);
  EXPECT_EQ(tet_format_from_path("shell.msh", 41), TetFormat::Msh41);
  EXPECT_EQ(tet_format_from_path("shell.Msh", 22), TetFormat::Msh22);
  EXPECT_EQ(tet_format_from_path("shell.mesh", 41), TetFormat::Medit);
  EXPECT_EQ(tet_format_from_path("out.d/shell.ele", 41), TetFormat::TetGen);
  EXPECT_EQ(tet_format_from_path("shell.msh"), TetFormat::Msh41);
}

TEST(WritersTest, UnknownExtensionThrowsInputErrorListingKnownOnes) {
  for (const char* path : {"shell.stl", "shell", "folder.vtu/shell", "shell.node"}) {
    try {
      tet_format_from_path(path, 41);
      ADD_FAILURE() << "no error for " << path;
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(".vtu .vtk .msh .mesh .ele"), std::string::npos) << message;
    }
  }
  EXPECT_THROW(tet_format_from_path("shell.msh", 40), InputError);
  EXPECT_THROW(write_surface("surface.step", SurfaceMesh{}), InputError);
}

// ---------------------------------------------------------------------------------------------
// Round trips through meshio

TEST(WritersTest, MeshioReadsEveryFormatBack) {
  SKIP_WITHOUT_MESHIO();
  for (const bool with_data : {false, true}) {
    for (const TetMesh& mesh : {single_tet(), cube_5_tets(with_data)}) {
      for (const FormatCase& c : all_formats()) {
        SCOPED_TRACE(format_name(c.format) + (with_data ? " with data" : "") + ", " +
                     std::to_string(mesh.tets.size()) + " tets");
        TempDir dir;
        const std::string path = dir.file(c.file);
        write_tet_mesh(path, mesh, c.format);
        ReadBack back;
        if (!read_with_meshio(dir, path, back)) continue;
        expect_same_geometry(mesh, back);
        if (!c.has_data) continue;
        if (!mesh.quality.empty() && c.has_cell_data)
          expect_data(back.cell_data, "quality", mesh.quality);
        if (!mesh.source_triangle.empty() && c.has_cell_data) {
          expect_data(back.cell_data, "source_triangle", mesh.source_triangle);
        }
        if (!mesh.layer.empty() && c.has_cell_data)
          expect_data(back.cell_data, "layer", mesh.layer);
        if (!mesh.inner.empty()) expect_data(back.point_data, "inner", mesh.inner);
        if (!mesh.thickness.empty()) expect_data(back.point_data, "thickness", mesh.thickness);
        if (mesh.quality.empty()) {
          EXPECT_EQ(back.cell_data.count("quality"), 0u);
        }
        if (mesh.inner.empty()) {
          EXPECT_EQ(back.point_data.count("inner"), 0u);
        }
      }
    }
  }
}

TEST(WritersTest, MshFilesHaveTheRequestedVersionAndOneVolume) {
  TempDir dir;
  const TetMesh cube = cube_5_tets(true);
  write_tet_mesh(dir.file("a.msh"), cube, TetFormat::Msh41);
  write_tet_mesh(dir.file("b.msh"), cube, TetFormat::Msh22);
  const std::string v41 = slurp(dir.file("a.msh")), v22 = slurp(dir.file("b.msh"));
  EXPECT_EQ(v41.rfind("$MeshFormat\n4.1 0 8\n", 0), 0u);
  EXPECT_NE(v41.find("$Entities\n0 0 2 1\n"), std::string::npos);
  EXPECT_EQ(v22.rfind("$MeshFormat\n2.2 0 8\n", 0), 0u);
  EXPECT_EQ(v22.find("$Entities"), std::string::npos);
}

TEST(WritersTest, GmshReadsMshAndMeditWithPositiveJacobians) {
  if (test::run_command("command -v gmsh").exit_code != 0) GTEST_SKIP() << "gmsh not installed";
  const TetMesh cube = cube_5_tets(true);
  for (const FormatCase& c : all_formats()) {
    if (c.format != TetFormat::Msh41 && c.format != TetFormat::Msh22 &&
        c.format != TetFormat::Medit) {
      continue;
    }
    SCOPED_TRACE(format_name(c.format));
    TempDir dir;
    write_tet_mesh(dir.file(c.file), cube, c.format);
    // Gmsh's mesh-quality plugin reports the minimum Jacobian determinant: negative if inverted.
    test::write_text(dir.file("check.geo"),
                     "Merge \"" + dir.file(c.file) +
                         "\";\n"
                         "Plugin(AnalyseMeshQuality).JacobianDeterminant = 1;\n"
                         "Plugin(AnalyseMeshQuality).CreateView = 0;\n"
                         "Plugin(AnalyseMeshQuality).Run;\n");
    const test::CommandResult r =
        test::run_command("gmsh -nopopup -0 '" + dir.file("check.geo") + "'");
    const std::string log = r.out + r.err;
    ASSERT_EQ(r.exit_code, 0) << log;
    EXPECT_EQ(log.find("Error"), std::string::npos) << log;
    if (c.format != TetFormat::Medit) {
      EXPECT_NE(log.find(" 8 nodes"), std::string::npos) << log;
      EXPECT_NE(log.find(" 5 elements"), std::string::npos) << log;
    }
    const std::size_t at = log.find("minJ      =");
    ASSERT_NE(at, std::string::npos) << log;
    const double min_jacobian = std::stod(log.substr(at + 11));
    EXPECT_GT(min_jacobian, 0.0) << log.substr(at, 80);
  }
}

// meshio 5.0 cannot read empty .vtu, .msh or TetGen files (an IndexError in its readers), so
// only writing is checked here.
TEST(WritersTest, EmptyMeshesAreWritten) {
  const TetMesh empty;
  for (const FormatCase& c : all_formats()) {
    SCOPED_TRACE(format_name(c.format));
    TempDir dir;
    const std::string path = dir.file(c.file);
    ASSERT_NO_THROW(write_tet_mesh(path, empty, c.format));
    EXPECT_TRUE(fs::exists(path));
  }
}

TEST(WritersTest, SurfacesRoundTripThroughMeshio) {
  SKIP_WITHOUT_MESHIO();
  const SurfaceMesh surface = cube_surface(cube_5_tets(false));
  ASSERT_EQ(surface.triangles.size(), 12u);
  for (const char* name : {"inner.obj", "inner.ply", "inner.off", "INNER.OBJ"}) {
    SCOPED_TRACE(name);
    TempDir dir;
    const std::string path = dir.file(name);
    write_surface(path, surface);
    ReadBack back;
    if (!read_with_meshio(dir, path, back)) continue;
    ASSERT_EQ(back.points.size(), surface.points.size());
    for (std::size_t i = 0; i < surface.points.size(); ++i) {
      EXPECT_EQ(back.points[i], surface.points[i]) << "point " << i;
    }
    ASSERT_EQ(back.cells.count("triangle"), 1u);
    const auto& tris = back.cells.at("triangle");
    ASSERT_EQ(tris.size(), surface.triangles.size());
    for (std::size_t f = 0; f < tris.size(); ++f) {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(tris[f][k], surface.triangles[f][k]) << f;
    }
  }
}

TEST(WritersTest, StlSurfaceReadsBackWithTheSameCorners) {
  // STL stores corners, not vertices: read back (corners welded by position), every triangle
  // has the same corners in the same order, to the last bit.
  SurfaceMesh surface = cube_surface(cube_5_tets(false));
  for (Vec3d& p : surface.points) p = p * (1.0 / 3.0) + Vec3d{0.1, -1e-7, 12345.678};
  TempDir dir;
  write_surface(dir.file("s.stl"), surface);
  const SurfaceMesh back = load_surface(dir.file("s.stl")).mesh;
  ASSERT_EQ(back.triangles.size(), surface.triangles.size());
  EXPECT_EQ(back.points.size(), surface.points.size());
  for (std::size_t f = 0; f < surface.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(back.points[back.triangles[f][k]], surface.points[surface.triangles[f][k]]) << f;
}

TEST(WritersTest, SurfaceKeepsDegenerateTriangles) {
  SurfaceMesh surface;
  surface.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  surface.triangles = {{0, 1, 2}, {0, 1, 1}};
  TempDir dir;
  write_surface(dir.file("s.obj"), surface);
  EXPECT_EQ(slurp(dir.file("s.obj")).find("f 1 2 2\n") != std::string::npos, true);
}

// ---------------------------------------------------------------------------------------------
// TetGen

TEST(WritersTest, TetGenTripleReadsBackWithOutwardFaces) {
  const TetMesh cube = cube_5_tets(true);
  TempDir dir;
  write_tet_mesh(dir.file("cube.ele"), cube, TetFormat::TetGen);
  EXPECT_EQ(folder_entries(dir.path()),
            (std::vector<std::string>{"cube.ele", "cube.face", "cube.node"}));

  std::vector<long long> header;
  std::vector<std::vector<std::string>> rows;
  ASSERT_TRUE(read_tetgen_table(dir.file("cube.node"), header, rows));
  ASSERT_GE(header.size(), 2u);
  EXPECT_EQ(header[1], 3);
  ASSERT_EQ(rows.size(), cube.points.size());
  std::vector<Vec3d> points;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ASSERT_GE(rows[i].size(), 4u);
    EXPECT_EQ(std::stoll(rows[i][0]), static_cast<long long>(i) + 1);  // 1-based
    points.push_back({std::stod(rows[i][1]), std::stod(rows[i][2]), std::stod(rows[i][3])});
    EXPECT_EQ(points.back(), cube.points[i]);
  }

  ASSERT_TRUE(read_tetgen_table(dir.file("cube.ele"), header, rows));
  EXPECT_EQ(header[1], 4);
  ASSERT_EQ(header.size(), 3u);
  EXPECT_EQ(header[2], 1);  // one attribute: the layer
  ASSERT_EQ(rows.size(), cube.tets.size());
  for (std::size_t t = 0; t < rows.size(); ++t) {
    Tet tet{};
    for (int k = 0; k < 4; ++k) tet[k] = static_cast<std::uint32_t>(std::stoll(rows[t][k + 1]) - 1);
    EXPECT_EQ(tet, cube.tets[t]);
    ASSERT_EQ(rows[t].size(), 6u);
    EXPECT_EQ(std::stoi(rows[t][5]), cube.layer[t]);
    // TetGen's convention: orient3d(a, b, c, d) < 0, i.e. d above the CCW triangle (a, b, c).
    EXPECT_GT(tet_volume(points[tet[0]], points[tet[1]], points[tet[2]], points[tet[3]]), 0.0);
  }

  ASSERT_TRUE(read_tetgen_table(dir.file("cube.face"), header, rows));
  ASSERT_EQ(rows.size(), 12u);  // 2 triangles per side of the cube
  Vec3d centre;
  for (const Vec3d& p : points) centre += p / 8.0;
  std::set<std::array<std::uint32_t, 3>> seen;
  double area = 0.0;
  for (const auto& row : rows) {
    std::array<std::uint32_t, 3> f{};
    for (int k = 0; k < 3; ++k) f[k] = static_cast<std::uint32_t>(std::stoll(row[k + 1]) - 1);
    const Vec3d n = cross(points[f[1]] - points[f[0]], points[f[2]] - points[f[0]]);
    const Vec3d mid = (points[f[0]] + points[f[1]] + points[f[2]]) / 3.0;
    EXPECT_GT(dot(n, mid - centre), 0.0) << "face " << f[0] << " " << f[1] << " " << f[2];
    area += norm(n) / 2.0;
    std::sort(f.begin(), f.end());
    EXPECT_TRUE(seen.insert(f).second) << "face listed twice";
  }
  const double side = 0.1 * std::sqrt(2.0);
  EXPECT_NEAR(area, 6.0 * side * side, 1e-14);
}

TEST(WritersTest, OneLayerWritesNoLayerData) {
  TetMesh cube = cube_5_tets(true);
  cube.layer.assign(cube.tets.size(), 1);
  TempDir dir;
  for (const FormatCase& c : all_formats()) {
    SCOPED_TRACE(format_name(c.format));
    const std::string path = dir.file(c.file);
    write_tet_mesh(path, cube, c.format);
    const std::string text = slurp(path);
    EXPECT_EQ(text.find("layer"), std::string::npos);
    if (c.format == TetFormat::TetGen) {
      EXPECT_EQ(text.rfind("5 4 0\n", 0), 0u);
    }
  }
}

TEST(WritersTest, TetGenStemWithoutExtension) {
  TempDir dir;
  write_tet_mesh(dir.file("plain"), single_tet(), TetFormat::TetGen);
  EXPECT_EQ(folder_entries(dir.path()),
            (std::vector<std::string>{"plain.ele", "plain.face", "plain.node"}));
}

TEST(WritersTest, CheckShellAcceptsTheCubeInEveryFormat) {
  const fs::path checker = test::shared_checker();
  if (checker.empty()) GTEST_SKIP() << "../shared/eval/check_shell.py is absent";
  if (test::run_command(std::string(kPython) + " -c 'import numpy'").exit_code != 0) {
    GTEST_SKIP() << kPython << " cannot import numpy";
  }
  const TetMesh cube = cube_5_tets(true);
  TempDir dir;
  write_surface(dir.file("cube.obj"), cube_surface(cube));
  for (const FormatCase& c : all_formats()) {
    if (c.format != TetFormat::TetGen && !meshio_available()) continue;
    if (c.format == TetFormat::Medit) continue;  // check_shell reads .vtu/.vtk/.msh/TetGen
    SCOPED_TRACE(format_name(c.format));
    const std::string path = dir.file(format_name(c.format) + "_" + c.file);
    write_tet_mesh(path, cube, c.format);
    const test::CommandResult r = test::run_command(std::string(kPython) + " '" + checker.string() +
                                                    "' '" + dir.file("cube.obj") + "' '" + path +
                                                    "' --samples 4000 --orientation positive");
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("VERDICT: VALID"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("missing surface faces 0"), std::string::npos) << r.out;
  }
}

TEST(WritersTest, BoundaryFacesOfASingleTetPointOutward) {
  const TetMesh tet = single_tet();
  const std::vector<Triangle> faces = tet_boundary_faces(tet);
  ASSERT_EQ(faces.size(), 4u);
  for (std::size_t f = 0; f < 4; ++f) {
    // The vertex the face is opposite to lies behind it.
    const std::uint32_t opposite = tet.tets[0][f];
    EXPECT_LT(tet_volume(tet.points[faces[f][0]], tet.points[faces[f][1]], tet.points[faces[f][2]],
                         tet.points[opposite]),
              0.0);
  }
}

// ---------------------------------------------------------------------------------------------
// Failures

TEST(WritersTest, MissingFolderThrowsResourceErrorAndLeavesNothing) {
  TempDir dir;
  const TetMesh cube = cube_5_tets(true);
  for (const FormatCase& c : all_formats()) {
    SCOPED_TRACE(format_name(c.format));
    const std::string path = (dir.path() / "missing" / c.file).string();
    try {
      write_tet_mesh(path, cube, c.format);
      ADD_FAILURE() << "no error";
    } catch (const ResourceError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("cannot write " + (dir.path() / "missing").string()),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("check that the folder exists and is writable"), std::string::npos)
          << message;
    }
  }
  EXPECT_THROW(write_surface((dir.path() / "missing" / "s.obj").string(), cube_surface(cube)),
               ResourceError);
  EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(WritersTest, TetGenWritesAllThreeFilesOrNone) {
  TempDir dir;
  fs::create_directory(dir.path() / "cube.face");  // the third file cannot be written
  EXPECT_THROW(write_tet_mesh(dir.file("cube.ele"), cube_5_tets(false), TetFormat::TetGen),
               ResourceError);
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"cube.face"});
}

TEST(WritersTest, BadIndexThrowsInternalErrorAndWritesNothing) {
  TetMesh mesh = single_tet();
  mesh.tets.push_back({0, 1, 2, 4});
  TempDir dir;
  EXPECT_THROW(write_tet_mesh(dir.file("bad.vtu"), mesh, TetFormat::Vtu), InternalError);
  mesh = single_tet();
  mesh.quality = {1.0, 2.0};
  EXPECT_THROW(write_tet_mesh(dir.file("bad.vtk"), mesh, TetFormat::Vtk), InternalError);
  SurfaceMesh surface;
  surface.points = {{0, 0, 0}};
  surface.triangles = {{0, 0, 1}};
  EXPECT_THROW(write_surface(dir.file("bad.obj"), surface), InternalError);
  EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(WritersTest, ExistingFileIsReplaced) {
  TempDir dir;
  const std::string path = dir.file("shell.vtk");
  test::write_text(path, "old");
  write_tet_mesh(path, single_tet(), TetFormat::Vtk);
  EXPECT_EQ(slurp(path).rfind("# vtk DataFile Version", 0), 0u);
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"shell.vtk"});
}

// ---------------------------------------------------------------------------------------------
// AtomicFile

TEST(AtomicFileTest, CommitRenamesTheTempFileOntoTheTarget) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  AtomicFile file(path);
  EXPECT_EQ(file.temp_path().rfind(path + ".tmp.", 0), 0u) << file.temp_path();
  file.stream() << "hello\n";
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::exists(file.temp_path()));
  file.commit();
  EXPECT_TRUE(file.committed());
  EXPECT_EQ(slurp(path), "hello\n");
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFileTest, UncommittedFileLeavesNothing) {
  TempDir dir;
  std::string temp;
  {
    AtomicFile file(dir.file("out.txt"));
    file.stream() << "partial";
    temp = file.temp_path();
    EXPECT_TRUE(fs::exists(temp));
  }
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(AtomicFileTest, UncommittedFileKeepsTheOldContent) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  test::write_text(path, "old");
  {
    AtomicFile file(path);
    file.stream() << "new";
    file.finish();  // complete but not committed
  }
  EXPECT_EQ(slurp(path), "old");
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFileTest, ThrowingBodyLeavesNothing) {
  TempDir dir;
  EXPECT_THROW(write_file_atomically(dir.file("out.txt"),
                                     [](std::ostream& os) {
                                       os << "partial";
                                       throw InputError("stop");
                                     }),
               InputError);
  EXPECT_TRUE(folder_entries(dir.path()).empty());
  write_file_atomically(dir.file("out.txt"), [](std::ostream& os) { os << "done"; });
  EXPECT_EQ(slurp(dir.file("out.txt")), "done");
}

TEST(AtomicFileTest, MissingFolderThrowsResourceErrorNamingThePath) {
  TempDir dir;
  const std::string path = (dir.path() / "no" / "such" / "out.txt").string();
  try {
    AtomicFile file(path);
    ADD_FAILURE() << "no error";
  } catch (const ResourceError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("cannot write " + path + ": "), std::string::npos) << message;
    EXPECT_NE(message.find("No such file or directory"), std::string::npos) << message;
  }
  EXPECT_TRUE(folder_entries(dir.path()).empty());
}

TEST(AtomicFileTest, FolderInTheWayThrowsResourceError) {
  TempDir dir;
  fs::create_directory(dir.path() / "out.txt");
  EXPECT_THROW(AtomicFile file(dir.file("out.txt")), ResourceError);
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFileTest, PendingTempFilesAreRemovedOnRequest) {
  TempDir dir;
  std::vector<std::unique_ptr<AtomicFile>> files;
  for (int i = 0; i < kMaxPendingTempFiles + 4; ++i) {  // more than the registry holds
    files.push_back(std::make_unique<AtomicFile>(dir.file("f" + std::to_string(i))));
    files.back()->stream() << i;
  }
  files.front()->commit();  // committed files are no longer pending
  remove_pending_temp_files();
  std::size_t left = 0;
  for (std::size_t i = 1; i < files.size(); ++i) left += fs::exists(files[i]->temp_path());
  EXPECT_EQ(left, 4u);  // the 4 files beyond the registry's capacity
  EXPECT_TRUE(fs::exists(dir.file("f0")));
  files.clear();  // destructors remove whatever is left
  EXPECT_EQ(folder_entries(dir.path()), std::vector<std::string>{"f0"});
}

TEST(AtomicFileTest, TempNamesAreUnique) {
  TempDir dir;
  AtomicFile a(dir.file("x")), b(dir.file("x"));
  EXPECT_NE(a.temp_path(), b.temp_path());
  a.stream() << "a";
  b.stream() << "b";
  a.commit();
  b.commit();
  EXPECT_EQ(slurp(dir.file("x")), "b");
}

}  // namespace
}  // namespace vdb_shell

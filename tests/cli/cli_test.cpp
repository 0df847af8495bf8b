// cli_test.cpp — the vdb_shell command end to end: summary, help, version, exit codes, batch,
// contradictory options, progress, and interruption by a signal.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <array>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iterator>
#include <map>

#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "assets/shapes.h"
#include "cli/cli.h"
#include "core/base/errors.h"
#include "core/base/memory_budget.h"
#include "core/read/load_surface.h"
#include "core/write/atomic_file.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

using test::run_command;
using test::TempDir;

const char* kTetObj = "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";

/// Runs run_cli in-process and returns {exit code, stdout, stderr}.
using InProcess = test::CliRun;
using test::cli;

TEST(Cli, SummaryOfAValidSurface) {
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  const InProcess r = cli({dir.file("tet.obj")});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("vertices    4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("faces       4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("components  1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("genus       0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("volume      1.33333"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("bbox max    (2, 2, 2)"), std::string::npos) << r.out;
}

TEST(Cli, BadInputIsOneLineAndExitCode2) {
  TempDir dir;
  test::write_text(dir.file("open.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto r = run_command(test::vdb_shell_bin() + " '" + dir.file("open.obj") + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(r.out.empty());
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("boundary edges"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("open.obj"), std::string::npos) << r.err;
}

TEST(Cli, BadOptionValuesAreOneShortLineAndExitCode2) {
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  const std::vector<std::vector<std::string>> cases = {{"--max-thickness", "-1"},
                                                       {"--max-memory", "0"},
                                                       {"--layers", "0"},
                                                       {"--min-step", "2"},
                                                       {"--no-such-option"}};
  for (const auto& extra : cases) {
    std::vector<std::string> args = {dir.file("tet.obj"), "-o", dir.file("s.vtu")};
    args.insert(args.end(), extra.begin(), extra.end());
    const InProcess r = cli(args);
    EXPECT_EQ(r.code, 2) << extra[0];
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("vdb_shell: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(extra[0]), std::string::npos) << r.err;
    EXPECT_LT(r.err.size(), 160u) << r.err;  // no bound printed in 309 digits
    EXPECT_FALSE(std::filesystem::exists(dir.file("s.vtu")));
  }
}

TEST(Cli, HostileFilesExit2WithOneLineAndWriteNothing) {
  // Headers announcing more than the file holds, counts that are not counts, face lines that
  // end early, indices out of range, and every input the fuzz targets found: each is exit 2 with
  // one line on stderr and no output file (or, where what is left is a valid surface, exit 0).
  TempDir dir;
  const std::string tet_off = "OFF\n4 4 0\n0 0 0\n2 0 0\n0 2 0\n0 0 2\n";
  std::vector<std::pair<std::string, std::string>> files = {
      {"empty_header.off", "OFF\n"},
      {"huge_counts.off", "OFF\n100000000 100000000 0\n"},
      {"negative.off", "OFF\n-5 -3 0\n"},
      {"overflow.off", "OFF\n99999999999999999999999 1 0\n"},
      {"corners.off", tet_off + "2000000000 0 1 2\n"},
      {"index.obj", std::string(kTetObj) + "f 1 2 99999999999\n"},
      {"cut.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"},
      {"huge.ply",
       "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
       "property float x\nproperty float y\nproperty float z\nend_header\n"}};
  for (const char* format : {"obj", "off", "ply", "stl", "vdb"}) {
    const auto folder = std::filesystem::path(VDB_SHELL_FUZZ_REGRESSIONS) / format;
    if (!std::filesystem::is_directory(folder)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      std::ifstream in(entry.path(), std::ios::binary);
      files.emplace_back(entry.path().filename().string() + "." + format,
                         std::string(std::istreambuf_iterator<char>(in), {}));
    }
  }
  for (const auto& [name, text] : files) {
    test::write_text(dir.file(name), text);
    const std::string out = dir.file("out_" + name + ".vtu");
    const auto r = run_command(test::vdb_shell_bin() + " '" + dir.file(name) + "' -o '" + out +
                               "' --report '" + out + ".json' --resolution 16 -q");
    if (r.exit_code == 0) continue;  // what is left of a damaged file may be a valid surface
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << name << ": " << r.err;
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << name;
    EXPECT_FALSE(std::filesystem::exists(out + ".json")) << name;
  }
  EXPECT_GE(files.size(), 12u);
}

TEST(Cli, ACrossingSurfaceIsRefusedInEveryMode) {
  // Two tetrahedra through each other: closed, manifold and outward, but crossing.
  TempDir dir;
  std::string text = kTetObj;
  text += "v 0.5 0.5 0.5\nv 2.5 0.5 0.5\nv 0.5 2.5 0.5\nv 0.5 0.5 2.5\n";
  text += "f 5 7 6\nf 5 6 8\nf 6 7 8\nf 7 5 8\n";
  test::write_text(dir.file("two.obj"), text);
  for (const std::string& args : {std::string(), " -o '" + dir.file("two.vtu") + "' -r 16"}) {
    const auto r = run_command(test::vdb_shell_bin() + " '" + dir.file("two.obj") + "'" + args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("self-intersections"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(" cross at ("), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("two.vtu")));
  }
}

TEST(Cli, MissingAndEmptyFilesExit2) {
  TempDir dir;
  test::write_text(dir.file("empty.stl"), "");
  EXPECT_EQ(cli({dir.file("empty.stl")}).code, 2);
  EXPECT_EQ(cli({dir.file("nothere.obj")}).code, 2);
  EXPECT_EQ(cli({}).code, 2);
  EXPECT_EQ(cli({"--no-such-option", dir.file("empty.stl")}).code, 2);
}

TEST(Cli, HelpListsOptionsWithDefaultsAndVersion) {
  const auto help = run_command(test::vdb_shell_bin() + " --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("INPUT"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--quiet"), std::string::npos) << help.out;
  const auto version = run_command(test::vdb_shell_bin() + " --version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.out.find("vdb_shell"), std::string::npos);
}

TEST(Cli, InwardInputIsFlippedWithANotice) {
  TempDir dir;
  test::write_text(dir.file("in.obj"),
                   "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n");
  const InProcess r = cli({dir.file("in.obj")});
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.err.find("flipped"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("volume      1.33333"), std::string::npos) << r.out;
}

const char* kOpenObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Names of every file below `dir` (recursive).
std::vector<std::string> files_below(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  if (!std::filesystem::exists(dir)) return names;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.is_regular_file()) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(CliRepair, AHoleIsRefusedWithTheHintAndRepairedWithIt) {
  // A sphere with one face missing: without --repair exit 2 suggesting it; with it a shell of
  // the repaired surface (checked here against that surface, read back from --repaired), the
  // report's repair section, and every output written.
  TempDir dir;
  SurfaceMesh holed = make_shape("sphere");
  holed.triangles.erase(holed.triangles.begin() + 300);
  const std::string in = dir.file("holed.obj");
  write_surface(in, holed);
  const InProcess refused = cli({in, "-o", dir.file("refused.ele")});
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("boundary edges"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("rerun with --repair"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("refused.ele")));

  const InProcess r =
      cli({in, "--repair", "--repair-closing", "3", "-r", "48", "-o", dir.file("shell.ele"),
           "--repaired", dir.file("repaired.obj"), "--report", dir.file("r.json"), "-q"});
  ASSERT_EQ(r.code, 0) << r.err;
  const LoadedSurface repaired = load_surface(dir.file("repaired.obj"));
  EXPECT_EQ(repaired.stats.components, 1u);
  EXPECT_EQ(repaired.stats.genus, 0);
  const TetMesh shell = test::read_tetgen_shell(dir.file("shell.ele"));
  const auto report = nlohmann::json::parse(test::read_text(dir.file("r.json")));
  EXPECT_EQ(test::independent_shell_problems(repaired.mesh, shell,
                                             2 * report["validity"]["sectors"].get<std::size_t>()),
            "");
  const auto& repair = report["repair"];
  EXPECT_EQ(repair["holes_closed"], 1);
  EXPECT_EQ(repair["input_faces"], holed.triangles.size());
  EXPECT_EQ(repair["closing"], 3.0);
  EXPECT_GT(repair["distance_max"].get<double>(), 0.0);
  EXPECT_LT(repair["distance_max"].get<double>(), 4.0 * repair["voxel_size"].get<double>());
  EXPECT_LT(repair["input_distance_max"].get<double>(), repair["voxel_size"].get<double>());
  EXPECT_EQ(report["input"]["faces"], repaired.stats.faces);

  // --repair-voxel-size sets the repair volume's voxels (the report says so).
  const InProcess sized = cli({in, "--repair", "--repair-voxel-size", "0.04", "-o",
                               dir.file("sized.ele"), "--report", dir.file("s.json"), "-q"});
  ASSERT_EQ(sized.code, 0) << sized.err;
  EXPECT_EQ(nlohmann::json::parse(test::read_text(dir.file("s.json")))["repair"]["voxel_size"],
            0.04);

  // Repair options without --repair, and a repaired surface of no known format: exit 2.
  EXPECT_EQ(cli({in, "--repair-closing", "3"}).code, 2);
  EXPECT_EQ(cli({in, "--repaired", dir.file("x.obj")}).code, 2);
  const InProcess step = cli({in, "--repair", "--repaired", dir.file("x.step")});
  EXPECT_EQ(step.code, 2);
  EXPECT_NE(step.err.find(".obj, .ply, .off or .stl"), std::string::npos) << step.err;
}

TEST(CliRepair, ACleanInputIsKeptAndGivesThePlainShell) {
  TempDir dir;
  const std::string in = dir.file("horn.obj");
  write_surface(in, make_shape("horn"));
  ASSERT_EQ(cli({in, "-r", "48", "-o", dir.file("plain.vtu"), "-q"}).code, 0);
  const InProcess r = cli(
      {in, "-r", "48", "--repair", "-o", dir.file("repaired.vtu"), "--report", dir.file("r.json")});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("the input is already closed, 2-manifold and not crossing itself: --repair "
                       "kept it as it is"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(test::read_text(dir.file("plain.vtu")), test::read_text(dir.file("repaired.vtu")));
  const auto repair = nlohmann::json::parse(test::read_text(dir.file("r.json")))["repair"];
  EXPECT_EQ(repair["method"], "kept");
  EXPECT_EQ(repair["distance_max"], 0.0);
  EXPECT_EQ(repair["faces"], 408);
}

/// Runs the command on `in` at 48^3 into `dir`/shell.ele, expects exit 0 with `notice` on
/// stderr, and returns the shell read back (for the caller's independent check).
TetMesh shell_with_notice(const TempDir& dir, const std::string& in, const std::string& notice,
                          const char* resolution = "48") {
  const InProcess r = cli({in, "-r", resolution, "-o", dir.file("shell.ele")});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find(notice), std::string::npos) << r.err;
  return test::read_tetgen_shell(dir.file("shell.ele"));
}

/// Shells `in` (with shell_with_notice()) and checks the shell against the surface read back
/// with the tests' independent checker, and its coverage.
void expect_valid_shell(const TempDir& dir, const std::string& in, const LoadedSurface& loaded,
                        const std::string& notice, double min_coverage) {
  const TetMesh shell = shell_with_notice(dir, in, notice);
  EXPECT_EQ(test::independent_shell_problems(loaded.mesh, shell), "");
  EXPECT_GT(test::independent_coverage(loaded.mesh, shell), min_coverage);
}

TEST(CliRepair, SeamsWrittenTwiceAreWeldedNotRebuilt) {
  // The horn with every triangle's corners written apart, as an exporter splitting vertices
  // along seams writes them: welded with a notice, with or without --repair, and the shell is
  // built on the file's own triangles (checked here against the surface read back).
  TempDir dir;
  const SurfaceMesh horn = make_shape("horn");
  SurfaceMesh apart;
  for (const Triangle& t : horn.triangles) {
    Triangle u;
    for (int c = 0; c < 3; ++c) {
      apart.points.push_back(horn.points[t[std::size_t(c)]]);
      u[std::size_t(c)] = static_cast<std::uint32_t>(apart.points.size() - 1);
    }
    apart.triangles.push_back(u);
  }
  const std::string in = dir.file("apart.obj");
  write_surface(in, apart);
  const LoadedSurface welded = load_surface(in);
  EXPECT_EQ(welded.mesh.points.size(), horn.points.size());
  EXPECT_EQ(welded.seam_vertices, apart.points.size() - horn.points.size());

  EXPECT_EQ(test::independent_shell_problems(
                welded.mesh, shell_with_notice(dir, in, "(seams written twice) were welded")),
            "");
  const InProcess repaired = cli(
      {in, "-r", "48", "--repair", "-o", dir.file("repaired.ele"), "--report", dir.file("r.json")});
  ASSERT_EQ(repaired.code, 0) << repaired.err;
  // Kept, as mended: the seams welded.
  EXPECT_NE(repaired.err.find("the input, mended as the notes below say, is closed"),
            std::string::npos)
      << repaired.err;
  EXPECT_EQ(nlohmann::json::parse(test::read_text(dir.file("r.json")))["repair"]["method"], "kept");
  EXPECT_EQ(test::read_text(dir.file("shell.ele")), test::read_text(dir.file("repaired.ele")));
}

TEST(CliInput, VerticesNextToAnEdgesEndAreShelled) {
  // The horn with a vertex inserted on every 5th edge 1e-5 of its length from an end, written
  // to a file and read back (exit 3 before: the inserted vertices' own traces crossed their
  // neighbours'); the shell checked here against the surface read back.
  TempDir dir;
  std::vector<test::InsertedVertex> inserted;
  const SurfaceMesh mesh =
      test::with_vertices_near_edge_ends(make_shape("horn"), 5, 1e-5, inserted);
  ASSERT_GE(inserted.size(), 30u);
  const std::string in = dir.file("inserted.obj");
  write_surface(in, mesh);
  const InProcess r = cli({in, "-r", "48", "-o", dir.file("shell.ele")});
  ASSERT_EQ(r.code, 0) << r.err;
  const SurfaceMesh read_back = load_surface(in).mesh;
  ASSERT_EQ(read_back.points.size(), mesh.points.size());
  const TetMesh shell = test::read_tetgen_shell(dir.file("shell.ele"));
  EXPECT_EQ(test::independent_shell_problems(read_back, shell), "");
  EXPECT_GT(test::independent_coverage(read_back, shell), 0.8);
}

TEST(CliInput, AVertexNextToAnEdgesEndWhereTheEdgeLeavesAFaceIsShelled) {
  // An OpenSCAD union of a cylinder and a turned hexagonal cone (tests/data): where a cone edge
  // leaves the cylinder's cap, its vertex there lies on the edge next to its end. Following the
  // edge's ends, its inner vertex went out through the cap (the ends' directions point up
  // through it): exit 3. It follows them only where their directions go in at its faces.
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_union_rim.obj";
  expect_valid_shell(dir, in, load_surface(in), "", 0.6);
}

TEST(CliInput, SmallFacesNearACapsBaseKeepTheApexsInnerVertexInside) {
  // An OpenSCAD union of a sphere and a box whose top it pokes through (tests/data): a vertex of
  // the ring where they meet is the apex of a cap on a long edge of the top's triangles (from
  // the ring to a corner), and has small faces of the ring near that edge's line (within 1% of
  // its length) but not along it.
  // Counted as the cap's hair-thin neighbours, their normals went unchecked and the apex's
  // inner vertex went out through them: exit 3.
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_sphere_through_box_top.obj";
  expect_valid_shell(dir, in, load_surface(in), "", 0.6);
}

TEST(CliInput, VerticesNoDepthServesGoOnTheSurface) {
  // An OpenSCAD box less a turned box that cuts it 0.0027 from its bottom edge (tests/data): a
  // sliver 0.0027 high on a 12.6 long base along that edge, corners of a thin wall around it.
  // No floor serves them (the sliver's prism twists, then its tets fall under the zero-volume
  // tolerance as the floors drop) and the run ended in exit 3; the offending prisms' corners
  // now go on the surface, at any resolution.
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_thin_cut.obj";
  const LoadedSurface loaded = load_surface(in);
  expect_valid_shell(dir, in, loaded, "", 0.45);
  for (const char* resolution : {"24", "128"})
    EXPECT_EQ(
        test::independent_shell_problems(loaded.mesh, shell_with_notice(dir, in, "", resolution)),
        "")
        << resolution;
}

TEST(CliInput, ACapOnASliverIsDeepEnoughToHaveAVolume) {
  // An OpenSCAD part (tests/data, 56 faces) with a sliver whose corners all go on the surface at
  // the floor: its prism is one tet to a cap point at the floor depth, 0.02 of its shortest
  // edge (4e-5), and over a face 2.7 long and 1.3e-10 in area that tet has no volume the
  // checks see: exit 3 at every resolution. The cap point now goes deeper, until its tet has
  // one. (Two slivers folded over their neighbours are flipped when read: the last two tets
  // are their flat tets, beyond 3F.)
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_sliver_cap.obj";
  const LoadedSurface loaded = load_surface(in);
  for (const char* resolution : {"24", "48", "96"}) {
    const TetMesh shell = shell_with_notice(dir, in, "2 slivers", resolution);
    EXPECT_EQ(test::independent_shell_problems(loaded.mesh, shell, 2, 2), "") << resolution;
    EXPECT_GT(test::independent_coverage(loaded.mesh, shell), 0.6) << resolution;
  }
}

TEST(CliInput, AConesNeedlesStepBackOnlyWhereThatCuresThem) {
  // An OpenSCAD cone (tests/data, 64 segments, 20 across its base, 40 high, 0.5 across its top):
  // its side faces' prisms over the axis are needles whose quality levels off below
  // --min-quality as their corners step back. Stepped back all the same, they thinned the shell
  // to coverage 0.40 at 48^3 and 0.36 at 64^3 for no better tets; now a needle steps back only
  // where a few steps bring it to the demand.
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_cone.obj";
  const LoadedSurface loaded = load_surface(in);
  for (const auto& [resolution, coverage] : {std::pair{"48", 0.45}, std::pair{"64", 0.6}}) {
    const TetMesh shell = shell_with_notice(dir, in, "", resolution);
    EXPECT_EQ(test::independent_shell_problems(loaded.mesh, shell), "") << resolution;
    EXPECT_GT(test::independent_coverage(loaded.mesh, shell), coverage) << resolution;
  }
}

TEST(CliInput, ACutEndingOnAFaceIsRefusedAsTouchingItselfFromInside) {
  // An OpenSCAD box less a turned box whose top edge lies in the box's top face (tests/data): a
  // notch touching the top from inside along a line, a wall of no thickness through which every
  // prism under the top's faces reaches into the notch. The search ran down its floors and ended
  // in exit 3; the surface is refused when read instead (exit 2, nothing written), naming the
  // faces and where they touch.
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_notch_touching_top.obj";
  const InProcess refused = cli({in, "-r", "48", "-o", dir.file("refused.ele")});
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("places where the surface touches itself from inside"),
            std::string::npos)
      << refused.err;
  EXPECT_NE(refused.err.find(" touch at ("), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("refused.ele")));
}

TEST(CliInput, AWallAMillionthOfTheDiagonalThickIsShelled) {
  // The notch of tests/data/cad_notch_touching_top.obj with its edge 1e-5 below the box's top
  // (1e-6 of the diagonal): the top's prisms thin to that over it, their floors lowered up to 9
  // times (with 4, as before, the run ended in exit 3).
  TempDir dir;
  const std::string in = std::string(VDB_SHELL_TEST_DATA) + "/cad_notch_touching_top.obj";
  PolygonSoup soup = read_polygon_soup(in);
  SurfaceMesh lowered;
  for (Vec3d p : soup.points) {
    if (p.z == 10 && p.y == 5 && p.x > 0 && p.x < 10) p.z -= 1e-5;
    lowered.points.push_back(p);
  }
  EXPECT_EQ(std::count_if(lowered.points.begin(), lowered.points.end(),
                          [](const Vec3d& p) { return p.z == 10 - 1e-5; }),
            2);
  for (const auto& polygon : soup.polygons)
    lowered.triangles.push_back({static_cast<std::uint32_t>(polygon[0]),
                                 static_cast<std::uint32_t>(polygon[1]),
                                 static_cast<std::uint32_t>(polygon[2])});
  const std::string thin = dir.file("thin.obj");
  write_surface(thin, lowered);
  expect_valid_shell(dir, thin, load_surface(thin), "", 0.2);
}

TEST(CliInput, ANestedComponentFacingOutIsACavity) {
  // A sphere inside a sphere, both facing out (as parts are often exported): by the even-odd
  // rule the inner one bounds a cavity, so it is turned and the shell fills the space between,
  // checked here against the surface read back (its inner sphere facing in).
  TempDir dir;
  const SurfaceMesh sphere = make_shape("sphere");
  SurfaceMesh nested = sphere;
  const std::uint32_t n = static_cast<std::uint32_t>(sphere.points.size());
  for (const Vec3d& p : sphere.points) nested.points.push_back(p * 0.5);
  for (const Triangle& t : sphere.triangles)
    nested.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
  const std::string in = dir.file("nested.obj");
  write_surface(in, nested);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.flipped_components, 1u);
  // Independent of the loader: the inner sphere's triangles now enclose a negative volume.
  double inner = 0.0;
  for (std::size_t t = sphere.triangles.size(); t < loaded.mesh.triangles.size(); ++t) {
    const Triangle& v = loaded.mesh.triangles[t];
    inner +=
        dot(loaded.mesh.points[v[0]], cross(loaded.mesh.points[v[1]], loaded.mesh.points[v[2]]));
  }
  EXPECT_LT(inner, 0.0);

  const InProcess r =
      cli({in, "-r", "48", "-o", dir.file("shell.ele"), "--report", dir.file("r.json")});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("1 of 2 components faced into the solid"), std::string::npos) << r.err;
  EXPECT_EQ(
      nlohmann::json::parse(test::read_text(dir.file("r.json")))["input"]["flipped_components"], 1);
  const TetMesh shell = test::read_tetgen_shell(dir.file("shell.ele"));
  EXPECT_EQ(test::independent_shell_problems(loaded.mesh, shell), "");
  EXPECT_GT(test::independent_coverage(loaded.mesh, shell), 0.8);
}

TEST(CliInput, PartsMeetingAtOneVertexAreSplitThere) {
  // Two boxes sharing one corner vertex (the file indexes it from both): split, one vertex per
  // box, and the shell is checked here against the surface read back.
  TempDir dir;
  const SurfaceMesh box = make_shape("box", 2);
  SurfaceMesh pinched = box;
  const std::uint32_t n = static_cast<std::uint32_t>(box.points.size());
  std::uint32_t corner = 0, other = 0;  // (0.5, 0.5, 0.5) in the first box, (-0.5, ...) in it
  for (std::uint32_t i = 0; i < n; ++i) {
    if (box.points[i] == Vec3d{0.5, 0.5, 0.5}) corner = i;
    if (box.points[i] == Vec3d{-0.5, -0.5, -0.5}) other = i;
  }
  for (const Vec3d& p : box.points) pinched.points.push_back(p + Vec3d{1, 1, 1});
  for (const Triangle& t : box.triangles) {
    Triangle u;
    for (int c = 0; c < 3; ++c)
      u[std::size_t(c)] = t[std::size_t(c)] == other ? corner : t[std::size_t(c)] + n;
    pinched.triangles.push_back(u);
  }
  const std::string in = dir.file("pinched.obj");
  write_surface(in, pinched);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.pinched_vertices, 1u);
  EXPECT_EQ(loaded.stats.components, 2u);

  expect_valid_shell(dir, in, loaded, "meet only at that point were split", 0.8);
}

/// The boundary of a set of unit cubes (`cells`, integer corners), each square face between a
/// cube and no cube as two triangles, corners shared by position: cubes meeting only along an
/// edge make it an edge of four faces, cubes meeting only at a corner a pinched vertex. Then
/// turned by the rotation `turn` (angles about z, x and y, radians).
SurfaceMesh cube_cells(const std::vector<std::array<int, 3>>& cells, const Vec3d& turn = {}) {
  SurfaceMesh mesh;
  std::map<std::array<int, 3>, std::uint32_t> index;
  const auto point = [&](std::array<int, 3> p) {
    const auto [it, added] = index.emplace(p, static_cast<std::uint32_t>(mesh.points.size()));
    if (added) mesh.points.push_back(Vec3d{double(p[0]), double(p[1]), double(p[2])});
    return it->second;
  };
  const auto filled = [&](std::array<int, 3> c) {
    return std::find(cells.begin(), cells.end(), c) != cells.end();
  };
  for (const auto& c : cells)
    for (int axis = 0; axis < 3; ++axis)
      for (const int side : {1, -1}) {
        std::array<int, 3> next = c;
        next[std::size_t(axis)] += side;
        if (filled(next)) continue;
        // The face's corners counter-clockwise seen from outside.
        const std::size_t a = std::size_t(axis), u = (a + 1) % 3, v = (a + 2) % 3;
        std::array<int, 3> q[4] = {c, c, c, c};
        for (auto& corner : q) corner[a] += side > 0 ? 1 : 0;
        q[1][u] += 1;
        q[2][u] += 1;
        q[2][v] += 1;
        q[3][v] += 1;
        if (side < 0) std::swap(q[1], q[3]);
        const std::uint32_t i0 = point(q[0]), i1 = point(q[1]), i2 = point(q[2]), i3 = point(q[3]);
        mesh.triangles.push_back({i0, i1, i2});
        mesh.triangles.push_back({i0, i2, i3});
      }
  test::turn_points(mesh.points, turn);
  return mesh;
}

TEST(CliInput, PartsTouchingAlongAnEdgeAreSplitThere) {
  // Two cubes meeting along one edge: the edge (four faces) is split, its two vertices copied
  // for the second cube, every face kept as written; the shell is checked here against the
  // surface read back.
  TempDir dir;
  const SurfaceMesh two = cube_cells({{0, 0, 0}, {1, 1, 0}});
  ASSERT_EQ(two.points.size(), 14u);
  const std::string in = dir.file("two.obj");
  write_surface(in, two);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.touching_edges, 1u);
  EXPECT_EQ(loaded.pinched_vertices, 0u);
  EXPECT_EQ(loaded.stats.components, 2u);
  ASSERT_EQ(loaded.mesh.points.size(), 16u);
  ASSERT_EQ(loaded.mesh.triangles.size(), two.triangles.size());
  for (std::size_t t = 0; t < two.triangles.size(); ++t)
    for (std::size_t c = 0; c < 3; ++c)
      ASSERT_EQ(loaded.mesh.points[loaded.mesh.triangles[t][c]], two.points[two.triangles[t][c]])
          << t;
  // The copies are the edge's ends, and no vertex serves both cubes.
  EXPECT_EQ(loaded.mesh.points[14][0], 1.0);
  EXPECT_EQ(loaded.mesh.points[14][1], 1.0);
  EXPECT_EQ(loaded.mesh.points[15][0], 1.0);
  EXPECT_EQ(loaded.mesh.points[15][1], 1.0);
  std::vector<int> cube_of(16, -1);
  for (std::size_t t = 0; t < loaded.mesh.triangles.size(); ++t) {
    const int cube = t < two.triangles.size() / 2 ? 0 : 1;  // 12 faces each, in cell order
    for (const std::uint32_t v : loaded.mesh.triangles[t]) {
      EXPECT_NE(cube_of[v], 1 - cube) << v;
      cube_of[v] = cube;
    }
  }
  expect_valid_shell(dir, in, loaded, "1 edges where parts of the surface touch", 0.8);
}

TEST(CliInput, PartsTouchingAlongAnEdgeAreSplitInAnyUnit) {
  // The faces around the edge are sorted by direction alone: two cubes 1e-300 to 1e300 across
  // (where products of coordinates vanish or overflow) are split as at unit scale.
  TempDir dir;
  for (const double scale : {1e-300, std::ldexp(1.0, -700), std::ldexp(1.0, 700), 1e300}) {
    SurfaceMesh two = cube_cells({{0, 0, 0}, {1, 1, 0}});
    for (Vec3d& p : two.points) p = p * scale;
    const std::string in = dir.file("scaled.obj");
    write_surface(in, two);
    const LoadedSurface loaded = load_surface(in);
    EXPECT_EQ(loaded.touching_edges, 1u) << scale;
    EXPECT_EQ(loaded.mesh.points.size(), 16u) << scale;
  }
}

TEST(CliInput, CubesTouchingAlongEdgesAndAtACornerInAnyDirection) {
  // Four cubes of a 2 x 2 x 2 block, alternate ones, turned off the axes: each two meet along
  // an edge (6 edges), all four at the centre (on those edges: split with them).
  TempDir dir;
  const std::string in = dir.file("checker.obj");
  write_surface(in, cube_cells({{0, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}}, Vec3d{0.3, 0.7, 1.1}));
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.touching_edges, 6u);
  EXPECT_EQ(loaded.pinched_vertices, 0u);
  EXPECT_EQ(loaded.stats.components, 4u);
  EXPECT_EQ(loaded.mesh.points.size(), 4u * 8u);
  expect_valid_shell(dir, in, loaded, "6 edges where parts of the surface touch", 0.8);
}

TEST(CliInput, APartTouchingItselfAlongAnEdgeIsSplitUpToWhereItJoins) {
  // Two cubes meeting along an edge, bridged over by three more: the edge's lower end is split,
  // its upper end, where the part joins up again, stays one vertex (its faces wrap round the
  // edge). The shell is checked here against the surface read back.
  TempDir dir;
  const SurfaceMesh bridge = cube_cells({{0, 0, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}});
  const std::string in = dir.file("bridge.obj");
  write_surface(in, bridge);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.touching_edges, 1u);
  EXPECT_EQ(loaded.pinched_vertices, 0u);
  EXPECT_EQ(loaded.stats.components, 1u);
  ASSERT_EQ(loaded.mesh.points.size(), bridge.points.size() + 1);
  EXPECT_EQ(loaded.mesh.points.back(), (Vec3d{1, 1, 0}));
  expect_valid_shell(dir, in, loaded, "1 edges where parts of the surface touch", 0.8);
}

TEST(CliInput, CavitiesMeetingAlongAnEdgeAreSplitAcrossTheSpaceBetween) {
  // Two cavities meeting along an edge inside a block: the solid touches itself along the edge
  // and is one piece round both its ends, so pairing the faces across the solid splits neither
  // end; paired across the cavities, each cavity gets an edge (and both ends) of its own.
  TempDir dir;
  std::vector<std::array<int, 3>> block;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 3; ++k)
        if (!(k == 1 && ((i == 1 && j == 1) || (i == 2 && j == 2)))) block.push_back({i, j, k});
  const SurfaceMesh cavities = cube_cells(block);
  const std::string in = dir.file("cavities.obj");
  write_surface(in, cavities);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.touching_edges, 1u);
  EXPECT_EQ(loaded.pinched_vertices, 0u);
  EXPECT_EQ(loaded.stats.components, 3u);  // the block and each cavity
  ASSERT_EQ(loaded.mesh.points.size(), cavities.points.size() + 2);
  EXPECT_EQ(loaded.mesh.points[cavities.points.size()], (Vec3d{2, 2, 1}));
  EXPECT_EQ(loaded.mesh.points[cavities.points.size() + 1], (Vec3d{2, 2, 2}));
  expect_valid_shell(dir, in, loaded, "1 edges where parts of the surface touch", 0.5);
}

TEST(CliInput, NotchesMeetingAtAVertexKeepItOnTheSurface) {
  // A 2 x 2 x 2 block less two opposite cubes: two notches meeting at the centre, a pinch. Each
  // copy of the centre has only its notch's three faces, which point into the other notch: no
  // depth inward serves it, so the search keeps it on the surface (else the floor configuration
  // is invalid and the run ends in exit 3).
  TempDir dir;
  const std::string in = dir.file("notches.obj");
  write_surface(in, cube_cells({{0, 0, 1}, {0, 1, 0}, {0, 1, 1}, {1, 0, 0}, {1, 0, 1}, {1, 1, 0}},
                               Vec3d{0.2, 0.4, 0.6}));
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.pinched_vertices, 1u);
  expect_valid_shell(dir, in, loaded, "meet only at that point were split", 0.5);
}

TEST(CliInput, FacesRunningAgainstTheirNeighboursAreTurned) {
  // The horn with every 7th face written the other way round: turned back as it is loaded, and
  // the shell is checked here against the surface read back (every face as the horn's own).
  TempDir dir;
  const SurfaceMesh horn = make_shape("horn");
  SurfaceMesh mixed = horn;
  for (std::size_t f = 0; f < mixed.triangles.size(); f += 7)
    std::swap(mixed.triangles[f][1], mixed.triangles[f][2]);
  const std::string in = dir.file("mixed.obj");
  write_surface(in, mixed);
  const LoadedSurface loaded = load_surface(in);
  EXPECT_EQ(loaded.reoriented_faces, (horn.triangles.size() + 6) / 7);
  for (std::size_t f = 0; f < horn.triangles.size(); ++f) {
    const Triangle& t = loaded.mesh.triangles[f];
    const Triangle& h = horn.triangles[f];
    // The same corners in the same cyclic order as the horn's.
    const bool same = (t[0] == h[0] && t[1] == h[1] && t[2] == h[2]) ||
                      (t[0] == h[1] && t[1] == h[2] && t[2] == h[0]) ||
                      (t[0] == h[2] && t[1] == h[0] && t[2] == h[1]);
    ASSERT_TRUE(same) << f;
  }
  EXPECT_EQ(test::independent_shell_problems(
                loaded.mesh, shell_with_notice(dir, in, "ran against their neighbours")),
            "");
}

TEST(CliBatch, OneGoodOneBadInputExit2AndOneLineEach) {
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  test::write_text(dir.file("open.obj"), kOpenObj);
  const std::string out_dir = dir.file("shells");  // created because it is missing
  const InProcess r = cli({dir.file("tet.obj"), dir.file("open.obj"), "-o", out_dir, "-r", "32",
                           "--report", dir.file("reports")});
  EXPECT_EQ(r.code, 2) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 2u) << r.out;
  EXPECT_EQ(lines[0].rfind(dir.file("tet.obj") + "\tok\t4\t", 0), 0u) << lines[0];
  EXPECT_EQ(lines[1].rfind(dir.file("open.obj") + "\terror\t", 0), 0u) << lines[1];
  EXPECT_NE(lines[1].find("boundary edges"), std::string::npos) << lines[1];
  EXPECT_EQ(files_below(out_dir), std::vector<std::string>{"tet.vtu"});
  EXPECT_EQ(files_below(dir.file("reports")), std::vector<std::string>{"tet.json"});
}

TEST(CliBatch, AllGoodExit0AndFormatChoosesExtension) {
  TempDir dir;
  test::write_text(dir.file("a.obj"), kTetObj);
  test::write_text(dir.file("b.obj"), kTetObj);
  const InProcess r = cli({dir.file("a.obj"), dir.file("b.obj"), "-o", dir.file("out"), "--format",
                           "msh", "-r", "32", "-q"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines_of(r.out).size(), 2u) << r.out;
  EXPECT_EQ(files_below(dir.file("out")), (std::vector<std::string>{"a.msh", "b.msh"}));
}

TEST(CliBatch, Exit2IfEveryFailureIsBadInputElse3) {
  TempDir dir;
  test::write_text(dir.file("open.obj"), kOpenObj);
  test::write_text(dir.file("tet.obj"), kTetObj);
  InProcess r = cli({dir.file("open.obj"), dir.file("missing.obj"), "-o", dir.file("o")});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines_of(r.out).size(), 2u) << r.out;
  EXPECT_TRUE(files_below(dir.file("o")).empty());
  // A resource failure (memory budget) on the good input and bad input on the other: exit 3.
  r = cli(
      {dir.file("tet.obj"), dir.file("open.obj"), "-o", dir.file("o"), "--max-memory", "0.000001"});
  EXPECT_EQ(r.code, 3) << r.err;
  const auto lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 2u) << r.out;
  EXPECT_NE(lines[0].find("\terror\t"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("--max-memory"), std::string::npos) << lines[0];
  EXPECT_TRUE(files_below(dir.file("o")).empty());
}

TEST(CliMemory, AStageOverTheBudgetExits3NamingItAndWritesNothing) {
  TempDir dir;
  const std::string in = dir.file("sphere.obj");
  write_surface(in, make_shape("sphere", 1));
  // Long traces (an eighth of a voxel per step, shrinking with |grad phi|) on a small field: the
  // traces, then the --grids file's points, outgrow every stage before them.
  const std::vector<std::string> run = {in,
                                        "-r",
                                        "16",
                                        "--step",
                                        "0.0078125",
                                        "--min-step",
                                        "0",
                                        "-o",
                                        dir.file("s.vtu"),
                                        "--grids",
                                        dir.file("g.vdb"),
                                        "-q"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = run;
    args.insert(args.end(), extra.begin(), extra.end());
    return cli(args);
  };
  // A run within the budget reports every estimate, byte for byte (bytes / 2^30 are exact).
  ASSERT_EQ(with({"--report", dir.file("r.json")}).code, 0);
  const nlohmann::json memory =
      nlohmann::json::parse(test::read_text(dir.file("r.json")))["memory_gb"];
  for (const char* file : {"s.vtu", "g.vdb", "r.json"}) std::filesystem::remove(dir.file(file));
  ASSERT_EQ(files_below(dir.path()), std::vector<std::string>{"sphere.obj"});
  const auto bytes = [&](const char* key) {
    return static_cast<std::size_t>(memory[key].get<double>() * kBytesPerGiB);
  };
  // In the order the checks run; the two tested are each larger than every check before them.
  std::size_t earlier = 0;
  for (const char* key :
       {"surface", "fields", "trace", "inner", "validity", "write_shell", "write_fields"}) {
    const std::string stage = std::string(key) == "trace"          ? "trace"
                              : std::string(key) == "write_fields" ? "write"
                                                                   : "";
    if (!stage.empty()) {
      ASSERT_GT(bytes(key), earlier) << key << " does not outgrow the checks before it";
      std::ostringstream below;
      below.precision(17);
      below << double(bytes(key) - 1) / kBytesPerGiB;
      const InProcess r = with({"--max-memory", below.str()});
      EXPECT_EQ(r.code, 3) << key << ": " << r.err;
      EXPECT_EQ(r.err.rfind("vdb_shell: error: " + stage + ": about ", 0), 0u) << r.err;
      EXPECT_NE(r.err.find("more than --max-memory"), std::string::npos) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_EQ(files_below(dir.path()), std::vector<std::string>{"sphere.obj"}) << key;
    }
    earlier = std::max(earlier, bytes(key));
  }
}

TEST(CliBatch, OutputMustBeAFolder) {
  TempDir dir;
  test::write_text(dir.file("a.obj"), kTetObj);
  test::write_text(dir.file("b.obj"), kTetObj);
  InProcess r = cli({dir.file("a.obj"), dir.file("b.obj"), "-o", dir.file("shell.vtu")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("names a folder"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("shell.vtu")));
  test::write_text(dir.file("existing"), "x");
  r = cli({dir.file("a.obj"), dir.file("b.obj"), "-o", dir.file("existing")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("is a file"), std::string::npos) << r.err;
  r = cli({dir.file("a.obj"), dir.file("b.obj")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("-o DIR"), std::string::npos) << r.err;
  std::filesystem::create_directory(dir.file("sub"));
  test::write_text(dir.file("sub/a.off"), "");
  r = cli({dir.file("a.obj"), dir.file("sub/a.off"), "-o", dir.file("out")});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("collide"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
}

TEST(CliOptions, ContradictionsAreRejectedWithWhatToDo) {
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  const std::string in = dir.file("tet.obj"), vtu = dir.file("tet.vtu");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{in, "-o", vtu, "--voxel-size", "0.1", "--resolution", "64"}, "give only one"},
      {{in, "-o", vtu, "--grid", "surface"}, "--level-set FILE.vdb"},
      {{in, "-o", vtu, "--msh-version", "22"}, "FILE.msh"},
      {{in, in, "-o", dir.file("d"), "--msh-version", "22"}, "--format msh"},
      {{in, "-o", vtu, "--format", "vtk"}, "drop --format"},
      {{in, "--report", dir.file("r.json")}, "give -o OUTPUT"},
      {{in, "--inner", dir.file("i.obj")}, "give -o OUTPUT"},
      {{in, "--paths", dir.file("p.vtk")}, "give -o OUTPUT"},
      {{in, "-o", vtu, "--quiet", "--progress"}, "choose one"},
      {{in, dir.file("tet2.obj"), "-o", dir.file("d"), "--paths", dir.file("p.vtk")},
       "single input"},
  };
  for (const Case& c : cases) {
    const InProcess r = cli(c.args);
    EXPECT_EQ(r.code, 2) << c.message;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  EXPECT_FALSE(std::filesystem::exists(vtu));
  EXPECT_FALSE(std::filesystem::exists(dir.file("d")));
  // Not contradictions: an explicit --voxel-size 0 with --resolution, a matching --format.
  EXPECT_EQ(cli({in, "-o", vtu, "--voxel-size", "0", "-r", "32", "-q"}).code, 0);
  EXPECT_EQ(cli({in, "-o", vtu, "--format", "vtu", "-r", "32", "-q"}).code, 0);
  EXPECT_EQ(cli({in, "-o", dir.file("t.msh"), "--msh-version", "22", "-r", "32", "-q"}).code, 0);
}

TEST(CliProgress, StagesAndTimingsOnStderr) {
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  InProcess r = cli({dir.file("tet.obj"), "-o", dir.file("t.vtu"), "-r", "32", "--progress", "-v"});
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* stage : {"[1/6] read ...", "[2/6] fields ...", "[3/6] trace ...",
                            "[4/6] inner ...", "[5/6] validity ...", "[6/6] write ..."})
    EXPECT_NE(r.err.find(stage), std::string::npos) << stage << "\n" << r.err;
  EXPECT_NE(r.err.find("timings: read "), std::string::npos) << r.err;
  EXPECT_EQ(r.out.front(), '{');  // stdout still holds only the JSON report
  r = cli({dir.file("tet.obj"), "-o", dir.file("t.vtu"), "-r", "32"});
  EXPECT_EQ(r.err.find("[1/6]"), std::string::npos) << r.err;  // not a terminal: no progress
}

TEST(CliProgress, BarOnATerminalUnlessNoProgress) {
  // `script` runs the command on a pseudo-terminal: stderr is a terminal there.
  if (run_command("command -v script").exit_code != 0) GTEST_SKIP() << "script (util-linux)";
  TempDir dir;
  test::write_text(dir.file("tet.obj"), kTetObj);
  const std::string command = "'" + test::vdb_shell_bin() + "' '" + dir.file("tet.obj") + "' -o '" +
                              dir.file("t.vtu") + "' -r 64";
  auto on_terminal = [&](const std::string& args) {
    return run_command("script -qec \"" + command + " " + args + " >/dev/null\" /dev/null");
  };
  const auto bar = on_terminal("");
  ASSERT_EQ(bar.exit_code, 0) << bar.out << bar.err;
  // Each stage redrawn in place ("\r", erase line) and closed with its seconds.
  EXPECT_NE(bar.out.find("\r\033[K[2/6] fields"), std::string::npos) << bar.out;
  EXPECT_NE(bar.out.find("[5/6] validity ... "), std::string::npos) << bar.out;
  EXPECT_NE(bar.out.find("[6/6] write ..."), std::string::npos) << bar.out;
  const auto none = on_terminal("--no-progress");
  ASSERT_EQ(none.exit_code, 0) << none.out << none.err;
  EXPECT_EQ(none.out.find("[1/6]"), std::string::npos) << none.out;
  EXPECT_NE(none.out.find("coverage"), std::string::npos) << none.out;  // the summary line
  const auto quiet = on_terminal("-q");
  EXPECT_EQ(quiet.exit_code, 0);
  EXPECT_EQ(quiet.out, "") << quiet.out;
}

TEST(CliSignal, SigtermLeavesNoOutputAndNoTempFile) {
  TempDir dir;
  const auto shape = run_command(test::vdb_shell_shapes_bin() + " sphere --detail 8 -o '" +
                                 dir.file("x.obj") + "'");
  ASSERT_EQ(shape.exit_code, 0) << shape.err;
  std::filesystem::create_directory(dir.file("out"));
  const auto r = run_command("'" + test::vdb_shell_bin() + "' '" + dir.file("x.obj") + "' -o '" +
                             dir.file("out/x.vtu") + "' --report '" + dir.file("out/x.json") +
                             "' --resolution 256 & p=$!; sleep 0.8; kill -TERM $p; wait $p; "
                             "echo status=$?");
  EXPECT_NE(r.out.find("status=143"), std::string::npos) << r.out << r.err;
  EXPECT_TRUE(files_below(dir.file("out")).empty());
}

TEST(CliSignal, HandlerRemovesTheTempFileOfAWriteInFlight) {
  TempDir dir;
  const std::string target = dir.file("shell.vtu");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // the child: a write in flight when SIGTERM arrives
    install_signal_cleanup();
    AtomicFile file(target);
    file.stream() << "partial";
    file.stream().flush();
    std::raise(SIGTERM);
    _exit(0);  // not reached: the handler re-raises with the default action
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status));
  if (WIFSIGNALED(status)) {
    EXPECT_EQ(WTERMSIG(status), SIGTERM);
  }
  EXPECT_TRUE(files_below(dir.path()).empty());
}

}  // namespace
}  // namespace vdb_shell

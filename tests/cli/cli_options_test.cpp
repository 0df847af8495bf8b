// cli_options_test.cpp — every vdb_shell option reaches the pipeline: for each, a run on a small
// generated shape shows a difference the option causes, against a baseline run without it.
//
// Shapes: the star prism (assets/shapes.h; planar and non-planar vertices, every stop reason but
// the cap) at 32^3, and the sphere's level set at 12^3 for .vdb inputs. All runs are in-process
// (run_cli). Options whose effect another test already shows are listed in kShownElsewhere with
// that test; EveryOptionInTheHelpIsCovered fails when --help lists an option covered nowhere.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "cli/cli.h"
#include "core/read/load_surface.h"
#include "core/write/shell_writers.h"
#include "tests/test_support.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/trace_points.h"

namespace vdb_shell {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct CliRun : test::CliRun {
  json report;  ///< stdout parsed when it holds the JSON report, else null
};

CliRun cli(std::vector<std::string> args) {
  CliRun r{test::cli(std::move(args)), {}};
  if (r.code == 0 && !r.out.empty() && r.out.front() == '{') r.report = json::parse(r.out);
  return r;
}

/// The star (560 faces) and its baseline shell at 32^3, built once for the whole suite.
class CliOptionEffects : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    star_ = new SurfaceMesh(make_shape("star"));
    write_surface(dir_->file("star.obj"), *star_);
    baseline_ = new CliRun(cli({star(), "-o", dir_->file("base.vtu"), "-r", "32"}));
  }
  static void TearDownTestSuite() {
    delete baseline_;
    delete star_;
    delete dir_;
  }
  void SetUp() override { ASSERT_EQ(baseline_->code, 0) << baseline_->err; }

  static std::string star() { return dir_->file("star.obj"); }
  static const json& base() { return baseline_->report; }
  /// A fresh path in this test's folder.
  std::string file(const std::string& name) const { return local_.file(name); }

  static test::TempDir* dir_;
  static SurfaceMesh* star_;
  static CliRun* baseline_;
  test::TempDir local_;
};
test::TempDir* CliOptionEffects::dir_ = nullptr;
SurfaceMesh* CliOptionEffects::star_ = nullptr;
CliRun* CliOptionEffects::baseline_ = nullptr;

std::size_t stops(const json& j, const char* reason) {
  return j["stop_reasons"][reason].get<std::size_t>();
}
std::size_t samples(const json& j) { return j["trace"]["samples"].get<std::size_t>(); }

// --- options whose effect shows in the JSON report -----------------------------------------------

struct ReportCase {
  std::string option;             ///< as --help names it (long form)
  std::vector<std::string> args;  ///< added to the baseline's (which has -r 32 unless replaced)
  std::function<void(const json& base, const json& j)> expect;
};

const std::vector<ReportCase>& report_cases() {
  static const std::vector<ReportCase> cases = {
      {"--planar-angle",
       {"--planar-angle", "80"},
       [](const json& b, const json& j) {  // a wider cone of face normals counts as planar
         EXPECT_GT(j["trace"]["planar_vertices"], b["trace"]["planar_vertices"]);
         EXPECT_NE(j["stop_reasons"], b["stop_reasons"]);
       }},
      {"--step",
       {"--step", "0.005"},
       [](const json& b, const json& j) {
         EXPECT_DOUBLE_EQ(j["trace"]["step"].get<double>(), 0.005);
         EXPECT_GT(samples(j), 2 * samples(b));  // about a third of the default step
       }},
      {"--critical",
       {"--critical", "0.5"},
       [](const json& b, const json& j) {  // c = 0.5 stops wherever |grad phi| halves
         EXPECT_GT(stops(j, "critical"), 2 * stops(b, "critical"));
         EXPECT_LT(samples(j), samples(b));
       }},
      {"--point-size",
       {"--point-size", "0.001"},
       [](const json& b, const json& j) {
         EXPECT_DOUBLE_EQ(j["trace"]["point_size"].get<double>(), 0.001);
         EXPECT_GT(stops(b, "merge"), 0u);
         EXPECT_LT(stops(j, "merge"), stops(b, "merge"));
       }},
      {"--flux-threshold",
       {"--flux-threshold", "0.5"},
       [](const json& b, const json& j) {
         EXPECT_GT(stops(b, "flux"), 0u);
         EXPECT_LT(stops(j, "flux"), stops(b, "flux"));
       }},
      {"--merge-angle",
       {"--merge-angle", "89"},
       [](const json& b, const json& j) {  // more traces count as side by side: fewer merges
         EXPECT_LT(stops(j, "merge"), stops(b, "merge"));
       }},
      {"--integrator",
       {"--integrator", "euler"},
       [](const json& b, const json& j) {
         EXPECT_EQ(b["trace"]["integrator"], "rk2");
         EXPECT_EQ(j["trace"]["integrator"], "euler");
         EXPECT_NE(samples(j), samples(b));
       }},
      {"--min-step",
       {"--min-step", "0"},
       [](const json& b, const json& j) {  // the paper's steps: shorter where |grad phi| < 1
         EXPECT_DOUBLE_EQ(b["trace"]["min_step"].get<double>(), 0.25);
         EXPECT_DOUBLE_EQ(j["trace"]["min_step"].get<double>(), 0.0);
         EXPECT_GT(samples(j), samples(b));
       }},
      {"--resolution",
       {"-r", "24"},
       [](const json& b, const json& j) {  // voxel = longest side / resolution
         const double h24 = j["fields"]["voxel_size"].get<double>();
         const double h32 = b["fields"]["voxel_size"].get<double>();
         EXPECT_NEAR(24.0 * h24, 32.0 * h32, 1e-9);
         EXPECT_LT(j["fields"]["sdf_active_voxels"], b["fields"]["sdf_active_voxels"]);
       }},
      {"--min-quality",
       {"--min-quality", "0.01"},
       [](const json& b, const json& j) {  // steps back from tets below 0.01, not only 1e-3
         EXPECT_GE(b["quality"]["min"].get<double>(), 1e-3);
         EXPECT_LT(b["quality"]["min"].get<double>(), 1e-2);
         EXPECT_GE(j["quality"]["min"].get<double>(), 1e-2);
         EXPECT_GT(j["validity"]["moved_back_vertices"], b["validity"]["moved_back_vertices"]);
         EXPECT_LT(j["shell"]["coverage"], b["shell"]["coverage"]);
       }},
      {"--layers",
       {"--layers", "3"},
       [](const json& b, const json& j) {  // 3 prisms stacked on each: 3x the tets, more points
         EXPECT_EQ(b["shell"]["layers"], 1);
         EXPECT_EQ(j["shell"]["layers"], 3);
         EXPECT_GT(j["shell"]["tets"].get<double>(), 2.5 * b["shell"]["tets"].get<double>());
         EXPECT_GT(j["shell"]["points"].get<double>(), 1.5 * b["shell"]["points"].get<double>());
       }},
      {"--layer-ratio",
       {"--layers", "2", "--layer-ratio", "1.5"},
       [](const json& b, const json& j) {
         EXPECT_EQ(b["shell"]["layer_ratio"], 1.0);
         EXPECT_EQ(j["shell"]["layer_ratio"], 1.5);
         EXPECT_GT(j["shell"]["tets"].get<double>(), 1.5 * b["shell"]["tets"].get<double>());
       }},
      {"--max-coverage-loss",
       {"--max-coverage-loss", "0"},
       [](const json& b, const json& j) {  // no move may lose volume: coverage never falls
         EXPECT_EQ(b["optimize"]["max_coverage_loss"], 0.002);
         EXPECT_EQ(j["optimize"]["max_coverage_loss"], 0.0);
         EXPECT_LT(j["optimize"]["moved_vertices"], b["optimize"]["moved_vertices"]);
         EXPECT_GE(j["shell"]["coverage"].get<double>(),
                   j["optimize"]["coverage_before"].get<double>() - 1e-12);
       }},
      {"--voxel-size",
       {"--voxel-size", "0.05"},
       [](const json& b, const json& j) {
         EXPECT_NEAR(j["fields"]["voxel_size"].get<double>(), 0.05, 1e-12);
         EXPECT_LT(j["fields"]["sdf_active_voxels"], b["fields"]["sdf_active_voxels"]);
       }},
  };
  return cases;
}

TEST_F(CliOptionEffects, ReportShowsEveryFieldTracingAndShellOption) {
  const SurfaceMesh surface = load_surface(star()).mesh;
  for (const ReportCase& c : report_cases()) {
    SCOPED_TRACE(c.option);
    // The shell as a TetGen pair, read back by test_support's own parser and checked there.
    const std::string ele = file("s.ele");
    std::vector<std::string> args = {star(), "-o", ele};
    if (c.option != "--resolution" && c.option != "--voxel-size")
      args.insert(args.end(), {"-r", "32"});
    args.insert(args.end(), c.args.begin(), c.args.end());
    const CliRun r = cli(args);
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_FALSE(r.report.is_null()) << r.out;
    c.expect(base(), r.report);
    const TetMesh shell = test::read_tetgen_shell(ele);
    EXPECT_EQ(shell.tets.size(), r.report["shell"]["tets"].get<std::size_t>());
    const std::size_t layers = r.report["shell"]["layers"].get<std::size_t>();
    EXPECT_EQ(test::independent_shell_problems(surface, shell,
                                               3 * (layers - 1) * surface.triangles.size()),
              "");
  }
}

// --- options with an effect elsewhere than the report --------------------------------------------

TEST_F(CliOptionEffects, QuietPrintsOnlyErrors) {
  EXPECT_NE(baseline_->err.find("vdb_shell: " + dir_->file("base.vtu") + ": "), std::string::npos)
      << baseline_->err;
  const std::string report = file("s.json");
  const CliRun r = cli({star(), "-o", file("s.vtu"), "-r", "32", "-q", "--report", report});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(r.out, "");  // nothing but errors: not even the report on stdout
  EXPECT_EQ(json::parse(test::read_text(report))["shell"]["tets"], base()["shell"]["tets"]);
}

TEST_F(CliOptionEffects, MshVersionPicksTheGmshFormat) {
  // The default is 4.1; versions are accepted as users write them, 2.2 and 4.1, or 22 and 41.
  ASSERT_EQ(cli({star(), "-o", file("d.msh"), "-r", "32", "-q"}).code, 0);
  EXPECT_EQ(test::read_text(file("d.msh")).rfind("$MeshFormat\n4.1 0 8\n", 0), 0u);
  for (const auto& [given, header] : std::vector<std::pair<std::string, std::string>>{
           {"2.2", "2.2"}, {"22", "2.2"}, {"4.1", "4.1"}, {"41", "4.1"}}) {
    const std::string path = file("s" + given + ".msh");
    ASSERT_EQ(cli({star(), "-o", path, "-r", "32", "-q", "--msh-version", given}).code, 0);
    EXPECT_EQ(test::read_text(path).rfind("$MeshFormat\n" + header + " 0 8\n", 0), 0u) << given;
  }
  const CliRun bad = cli({star(), "-o", file("b.msh"), "-r", "32", "--msh-version", "3"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("must be 4.1 or 2.2"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(file("b.msh")));
}

TEST_F(CliOptionEffects, TimeoutGivesUpWithExit3AndNothingWritten) {
  // A run of well over a second at 256^3, given a millisecond: cancelled in its first stage.
  const CliRun r = cli({star(), "-o", file("s.vtu"), "-r", "256", "--timeout", "0.001"});
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_NE(r.err.find("timed out after 0.001 s"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(file("s.vtu")));
  // A generous timeout changes nothing.
  ASSERT_EQ(cli({star(), "-o", file("t.vtu"), "-r", "32", "-q", "--timeout", "600"}).code, 0);
  ASSERT_EQ(cli({star(), "-o", file("u.vtu"), "-r", "32", "-q"}).code, 0);
  EXPECT_EQ(test::read_text(file("t.vtu")), test::read_text(file("u.vtu")));
}

TEST_F(CliOptionEffects, MaxMemoryRefusesTheFieldBuild) {
  // A resource limit, not bad input: exit 3 (docs/usage.md), the fitting resolution named. The
  // budget holds the program and the surface (the check before the fields').
  const CliRun r = cli({star(), "-o", file("s.vtu"), "-r", "4096", "--max-memory", "0.1"});
  EXPECT_EQ(r.code, 3);
  EXPECT_NE(r.err.find("fields: about "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("more than --max-memory 0.1 GiB"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" fits)"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_TRUE(fs::is_empty(local_.path()));
  EXPECT_EQ(cli({star(), "-o", file("s.vtu"), "-r", "32", "--max-memory", "1", "-q"}).code, 0);
}

TEST_F(CliOptionEffects, PathsWritesOnePolylinePerVertex) {
  const std::string paths = file("p.vtk");
  const CliRun r = cli({star(), "-o", file("s.vtu"), "-r", "32", "-q", "--paths", paths});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string vtk = test::read_text(paths);
  const std::string lines = "\nLINES " + std::to_string(star_->points.size()) + " ";
  EXPECT_NE(vtk.find(lines), std::string::npos) << vtk.substr(0, 200);
  EXPECT_NE(vtk.find("SCALARS stop_reason int 1"), std::string::npos);
}

TEST_F(CliOptionEffects, GridsCarryFieldsAndTraces) {
  const std::string vdb = file("s.vdb");
  const CliRun r = cli({star(), "-o", file("s.vtu"), "-r", "32", "--grids", vdb});
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<std::string> names;
  for (const VdbGridInfo& g : read_vdb_grid_infos(vdb)) names.push_back(g.name);
  EXPECT_EQ(names, (std::vector<std::string>{"surface", "flux", "traces"}));

  // The points tell the report's story: one trace per vertex starting on it, the same stop
  // reasons and vertex classes, no more points than samples.
  const TracePoints p = read_trace_points(vdb);
  const json& j = r.report;
  EXPECT_LE(p.positions.size(), samples(j));
  std::map<int, int> stop_of, planar_of;
  for (std::size_t n = 0; n < p.vertex.size(); ++n) {
    stop_of[p.vertex[n]] = p.stop_reason[n];
    planar_of[p.vertex[n]] = p.planar[n];
    if (p.sample[n] == 0) {
      EXPECT_LE(distance(p.positions[n], star_->points.at(p.vertex[n])), 1e-6 * p.voxel_size);
    }
  }
  ASSERT_EQ(stop_of.size(), star_->points.size());
  const char* reasons[] = {"critical", "merge", "flux", "cap"};
  for (int s = 0; s < 4; ++s)
    EXPECT_EQ(std::count_if(stop_of.begin(), stop_of.end(),
                            [&](const auto& kv) { return kv.second == s; }),
              stops(j, reasons[s]))
        << reasons[s];
  EXPECT_EQ(std::count_if(planar_of.begin(), planar_of.end(),
                          [](const auto& kv) { return kv.second == 1; }),
            j["trace"]["planar_vertices"].get<long>());

  // --grids without -o traces too (4 stages, no report) and writes the same bytes; so does -j 2.
  const std::string alone = file("alone.vdb");
  const CliRun g = cli({star(), "-r", "32", "--grids", alone, "--progress", "-j", "2"});
  ASSERT_EQ(g.code, 0) << g.err;
  EXPECT_TRUE(g.out.empty()) << g.out;
  for (const char* stage : {"[1/4] read", "[2/4] fields", "[3/4] trace", "[4/4] write"})
    EXPECT_NE(g.err.find(stage), std::string::npos) << g.err;
  EXPECT_EQ(test::read_text(alone), test::read_text(vdb));
}

TEST_F(CliOptionEffects, ThreadCountKeepsEveryOutputByteIdentical) {
  std::vector<std::string> bytes;
  for (const char* j : {"1", "2"}) {
    const std::string vtu = file(std::string("s") + j + ".vtu"),
                      vdb = file(std::string("s") + j + ".vdb");
    ASSERT_EQ(cli({star(), "-o", vtu, "-r", "32", "-q", "-j", j, "--grids", vdb}).code, 0);
    bytes.push_back(test::read_text(vtu) + test::read_text(vdb));
  }
  EXPECT_FALSE(bytes[0].empty());
  EXPECT_TRUE(bytes[0] == bytes[1]);
}

/// The sphere's level set at 12^3 (radius 6 voxels), written by vdb_shell --grids.
std::string sphere_level_set(const test::TempDir& dir) {
  write_surface(dir.file("sphere.obj"), make_shape("sphere"));
  const CliRun r =
      cli({dir.file("sphere.obj"), "-r", "12", "-q", "--grids", dir.file("sphere.vdb")});
  EXPECT_EQ(r.code, 0) << r.err;
  return dir.file("sphere.vdb");
}

TEST_F(CliOptionEffects, AdaptivityLowersTheFaceCountOfAVdbInput) {
  const std::string vdb = sphere_level_set(local_);
  const CliRun fine = cli({vdb, "-o", file("a0.vtu"), "--adaptivity", "0"});
  const CliRun coarse = cli({vdb, "-o", file("a5.vtu"), "--adaptivity", "0.5"});
  ASSERT_EQ(fine.code, 0) << fine.err;
  ASSERT_EQ(coarse.code, 0) << coarse.err;
  EXPECT_LT(2 * coarse.report["input"]["faces"].get<long>(),
            fine.report["input"]["faces"].get<long>());
  EXPECT_LT(coarse.report["shell"]["tets"], fine.report["shell"]["tets"]);
}

TEST_F(CliOptionEffects, LevelSetReplacesTheBuiltField) {
  // A 24^3 level set of the star: its voxel size rules, not the resolution (default 128).
  const std::string vdb = file("star24.vdb");
  ASSERT_EQ(cli({star(), "-r", "24", "-q", "--grids", vdb}).code, 0);
  const CliRun r = cli({star(), "-o", file("s.vtu"), "--level-set", vdb});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(r.report["fields"]["voxel_size"].get<double>(),
              base()["fields"]["voxel_size"].get<double>() * 32.0 / 24.0, 1e-9);
  EXPECT_NE(r.report["fields"]["strategy"].get<std::string>().find("level set"), std::string::npos);
}

TEST_F(CliOptionEffects, GridSelectsTheNamedGrid) {
  const std::string vdb = file("star24.vdb");
  ASSERT_EQ(cli({star(), "-r", "24", "-q", "--grids", vdb}).code, 0);
  const std::vector<std::string> base_args = {star(),        "-o", file("s.vtu"), "-q",
                                              "--level-set", vdb,  "--grid"};
  auto with_grid = [&](const std::string& name) {
    std::vector<std::string> args = base_args;
    args.push_back(name);
    return cli(args);
  };
  EXPECT_EQ(with_grid("surface").code, 0);
  const CliRun flux = with_grid("flux");
  EXPECT_EQ(flux.code, 2);
  EXPECT_NE(flux.err.find("grid 'flux'"), std::string::npos) << flux.err;
  EXPECT_NE(flux.err.find("grid class to level set"), std::string::npos) << flux.err;
  const CliRun traces = with_grid("traces");
  EXPECT_EQ(traces.code, 2);
  EXPECT_NE(traces.err.find("grid 'traces'"), std::string::npos) << traces.err;

  // Two level sets in one .vdb INPUT: --grid chooses which one is meshed and shelled.
  if (test::run_command("command -v vdb_tool").exit_code != 0)
    GTEST_SKIP() << "vdb_tool (libopenvdb-tools) not installed";
  const std::string two = file("two.vdb");
  const test::CommandResult made = test::run_command(
      "vdb_tool -sphere voxel=0.05 radius=0.3 name=small -sphere voxel=0.05 radius=0.45 "
      "name=big -write '" +
      two + "'");
  ASSERT_EQ(made.exit_code, 0) << made.err;
  std::map<std::string, double> volume;
  for (const char* name : {"small", "big"}) {
    const CliRun r =
        cli({two, "-o", file(std::string(name) + ".vtu"), "--adaptivity", "0.5", "--grid", name});
    ASSERT_EQ(r.code, 0) << name << ": " << r.err;
    volume[name] = r.report["input"]["enclosed_volume"].get<double>();
  }
  // (0.45 / 0.3)^3 = 3.4 (adaptive polygons cut corners: 3.7 measured).
  EXPECT_GT(volume["big"], 2.5 * volume["small"]);
  EXPECT_LT(volume["big"], 4.5 * volume["small"]);
}

// --- coverage ------------------------------------------------------------------------------------

/// Options whose visible effect another test shows (option -> "Suite.Test").
const std::map<std::string, std::string>& shown_elsewhere() {
  static const std::map<std::string, std::string> m = {
      {"INPUT", "Cli.SummaryOfAValidSurface"},
      {"--help", "Cli.HelpListsOptionsWithDefaultsAndVersion"},
      {"--version", "Cli.HelpListsOptionsWithDefaultsAndVersion"},
      {"--output", "Pipeline.ReportHasEveryDocumentedKey"},
      {"--report", "Pipeline.ReportHasEveryDocumentedKey"},
      {"--format", "CliBatch.AllGoodExit0AndFormatChoosesExtension"},
      {"--progress", "CliProgress.StagesAndTimingsOnStderr"},
      {"--verbose", "CliProgress.StagesAndTimingsOnStderr"},
      {"--no-progress", "CliProgress.BarOnATerminalUnlessNoProgress"},
      {"--inner", "Pipeline.ThicknessLimitHolds"},
      {"--max-thickness", "Pipeline.ThicknessLimitHolds"},
      {"--thickness-edge-factor", "Pipeline.EdgeFactorThicknessLimitHolds"},
      {"--repair", "CliRepair.AHoleIsRefusedWithTheHintAndRepairedWithIt"},
      {"--repair-closing", "CliRepair.AHoleIsRefusedWithTheHintAndRepairedWithIt"},
      {"--repair-voxel-size", "CliRepair.AHoleIsRefusedWithTheHintAndRepairedWithIt"},
      {"--repaired", "CliRepair.AHoleIsRefusedWithTheHintAndRepairedWithIt"},
      {"--html", "CliHtml.APageWithEveryPictureNextToTheShell"},
      {"--optimize", "Optimize.ValidThickAndNeverWorseAtItsWorst"},
      {"--no-optimize", "Optimize.OnByDefaultAndReported"},
  };
  return m;
}

/// Options shown by the tests of this file (besides the report table).
const std::map<std::string, std::string>& shown_here() {
  static const std::map<std::string, std::string> m = {
      {"--quiet", "CliOptionEffects.QuietPrintsOnlyErrors"},
      {"--msh-version", "CliOptionEffects.MshVersionPicksTheGmshFormat"},
      {"--max-memory", "CliOptionEffects.MaxMemoryRefusesTheFieldBuild"},
      {"--paths", "CliOptionEffects.PathsWritesOnePolylinePerVertex"},
      {"--grids", "CliOptionEffects.GridsCarryFieldsAndTraces"},
      {"--threads", "CliOptionEffects.ThreadCountKeepsEveryOutputByteIdentical"},
      {"--adaptivity", "CliOptionEffects.AdaptivityLowersTheFaceCountOfAVdbInput"},
      {"--level-set", "CliOptionEffects.LevelSetReplacesTheBuiltField"},
      {"--grid", "CliOptionEffects.GridSelectsTheNamedGrid"},
      {"--timeout", "CliOptionEffects.TimeoutGivesUpWithExit3AndNothingWritten"},
  };
  return m;
}

bool test_exists(const std::string& full_name) {
  const ::testing::UnitTest& unit = *::testing::UnitTest::GetInstance();
  for (int s = 0; s < unit.total_test_suite_count(); ++s) {
    const ::testing::TestSuite& suite = *unit.GetTestSuite(s);
    for (int t = 0; t < suite.total_test_count(); ++t)
      if (std::string(suite.name()) + "." + suite.GetTestInfo(t)->name() == full_name) return true;
  }
  return false;
}

TEST(CliOptionCoverage, EveryOptionInTheHelpIsCovered) {
  // Option names of --help: the first word of each indented line, long form ("-r,--resolution").
  const CliRun help = cli({"--help"});
  ASSERT_EQ(help.code, 0);
  std::set<std::string> listed;
  std::istringstream lines(help.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  ", 0) != 0 || line.size() < 3 || line[2] == ' ') continue;
    std::string word = line.substr(2, line.find(' ', 2) - 2);
    word = word.substr(word.rfind(',') == std::string::npos ? 0 : word.rfind(',') + 1);
    listed.insert(word);
  }
  EXPECT_GE(listed.size(), 29u);  // INPUT, --help, --version and 26 options

  std::set<std::string> covered;
  for (const ReportCase& c : report_cases()) covered.insert(c.option);
  for (const auto* table : {&shown_here(), &shown_elsewhere()})
    for (const auto& [option, test_name] : *table) {
      EXPECT_TRUE(test_exists(test_name)) << option << ": no test " << test_name;
      covered.insert(option);
    }
  for (const std::string& option : listed)
    EXPECT_EQ(covered.count(option), 1u) << option << " has no test showing its effect";
  for (const std::string& option : covered)
    EXPECT_EQ(listed.count(option), 1u) << option << " is not in --help";
}

}  // namespace
}  // namespace vdb_shell

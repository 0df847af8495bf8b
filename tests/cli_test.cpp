// cli_test.cpp — the vdb_shell command end to end: summary, help, version, exit codes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

using test::run_command;
using test::TempDir;

const char* kTetObj = "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";

/// Runs run_cli in-process and returns {exit code, stdout, stderr}.
struct InProcess {
  int code;
  std::string out, err;
};
InProcess cli(std::vector<std::string> args) {
  args.insert(args.begin(), "vdb_shell");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int code = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return {code, out.str(), err.str()};
}

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

}  // namespace
}  // namespace vdb_shell

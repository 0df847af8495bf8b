// launcher_test.cpp — the vdb_shell command (cli/launcher.cpp): it starts the program found
// VDB_SHELL_PROGRAM_FROM_BINDIR from its own directory, with its arguments and exit code, and
// with glibc.malloc.hugetlb=1 added to GLIBC_TUNABLES unless that tunable is set already. A copy
// of the command starts a stand-in program that prints what it was given; the real command
// reaches the real program.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/test_support.h"

namespace vdb_shell {
namespace {

namespace fs = std::filesystem;
using test::CommandResult;
using test::count_of;
using test::run_command;
using test::TempDir;
using test::vdb_shell_bin;
using test::write_text;

// A copy of the command in <dir>/bin beside a stand-in program that prints GLIBC_TUNABLES and
// each argument on a line of its own, and exits with 7.
struct StandIn {
  TempDir dir;
  std::string command;
  StandIn() {
    const fs::path bin = fs::path(dir.file("bin"));
    fs::create_directories(bin);
    command = (bin / "vdb_shell").string();
    fs::copy_file(vdb_shell_bin(), command);
    const fs::path program = bin / VDB_SHELL_PROGRAM_FROM_BINDIR / "vdb_shell";
    fs::create_directories(program.parent_path());
    write_text(program.string(), "#!/bin/sh\nprintf '%s\\n' \"$GLIBC_TUNABLES\" \"$@\"\nexit 7\n");
    fs::permissions(program, fs::perms::owner_all);
  }
};

TEST(Launcher, StartsTheProgramWithItsArgumentsAndHugePagesForMalloc) {
  const StandIn s;
  const CommandResult r =
      run_command("env -u GLIBC_TUNABLES '" + s.command + "' in.obj 'two words' -r 64");
  EXPECT_EQ(r.exit_code, 7) << r.err;
  EXPECT_EQ(r.out, "glibc.malloc.hugetlb=1\nin.obj\ntwo words\n-r\n64\n");
}

TEST(Launcher, AddsTheTunableToOthersAndKeepsTheUsersOwnSetting) {
  const StandIn s;
  CommandResult r =
      run_command("GLIBC_TUNABLES=glibc.malloc.arena_max=2 '" + s.command + "' --version");
  EXPECT_EQ(r.exit_code, 7) << r.err;
  EXPECT_EQ(r.out, "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1\n--version\n");
  r = run_command("GLIBC_TUNABLES=glibc.malloc.hugetlb=0 '" + s.command + "'");
  EXPECT_EQ(r.exit_code, 7) << r.err;
  EXPECT_EQ(r.out, "glibc.malloc.hugetlb=0\n");
}

TEST(Launcher, FailsWithOneLineAndExitCode3WithoutItsProgram) {
  const StandIn s;
  fs::remove(fs::path(s.command).parent_path() / VDB_SHELL_PROGRAM_FROM_BINDIR / "vdb_shell");
  const CommandResult r = run_command("'" + s.command + "' --version");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(count_of(r.err, "\n"), 1u) << r.err;
  EXPECT_NE(r.err.find("cannot start"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("reinstall vdb_shell"), std::string::npos) << r.err;
}

TEST(Launcher, TheBuiltCommandRunsTheProgram) {
  const CommandResult r = run_command("'" + vdb_shell_bin() + "' --version");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("vdb_shell ", 0), 0u) << r.out;
}

}  // namespace
}  // namespace vdb_shell

// commit_group_test.cpp — CommitGroup (atomic_file.h): the outputs of a run appear together or
// not at all; and the CLI, which writes every output of an input in one group.
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "core/write/atomic_file.h"
#include "tests/test_support.h"

namespace vdb_shell {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

std::size_t files_in(const TempDir& dir) {
  return static_cast<std::size_t>(
      std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()));
}

TEST(CommitGroup, FilesAppearOnlyWhenTheGroupCommits) {
  TempDir dir;
  {
    CommitGroup group;
    write_file_atomically(dir.file("a.txt"), [](std::ostream& os) { os << "a"; });
    write_file_atomically(dir.file("b.txt"), [](std::ostream& os) { os << "b"; });
    EXPECT_FALSE(fs::exists(dir.file("a.txt")));  // complete, under temporary names
    EXPECT_EQ(files_in(dir), 2u);
    group.commit();
  }
  EXPECT_EQ(test::read_text(dir.file("a.txt")), "a");
  EXPECT_EQ(test::read_text(dir.file("b.txt")), "b");
  EXPECT_EQ(files_in(dir), 2u);  // no temporary file left
}

TEST(CommitGroup, AFailureOnTheWayLeavesNoneOfTheOutputs) {
  TempDir dir;
  try {
    CommitGroup group;
    write_file_atomically(dir.file("shell.vtu"), [](std::ostream& os) { os << "tets"; });
    write_file_atomically(dir.file("report.json"),
                          [](std::ostream&) { throw std::runtime_error("the report failed"); });
    group.commit();
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(files_in(dir), 0u);
  // Without a group, a file appears at once (as before).
  write_file_atomically(dir.file("alone.txt"), [](std::ostream& os) { os << "x"; });
  EXPECT_TRUE(fs::exists(dir.file("alone.txt")));
}

TEST(CommitGroup, TheCliChecksEveryOutputBeforeTheWork) {
  // --report naming a folder: refused before any work, nothing written.
  TempDir dir;
  test::write_text(dir.file("tet.obj"),
                   "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
  fs::create_directory(dir.file("taken"));
  const auto r =
      test::run_command(test::vdb_shell_bin() + " '" + dir.file("tet.obj") + "' -o '" +
                        dir.file("s.vtu") + "' -r 16 --report '" + dir.file("taken") + "'");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("taken"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.file("s.vtu")));
  EXPECT_EQ(files_in(dir), 2u);  // tet.obj and the folder
}

}  // namespace
}  // namespace vdb_shell

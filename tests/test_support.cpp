// test_support.cpp — see test_support.h.
#include "tests/test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace vdb_shell::test {
namespace fs = std::filesystem;

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          ("vdb_shell_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

fs::path shared_meshes_dir() {
  const fs::path dir = VDB_SHELL_SHARED_MESHES;
  return fs::is_directory(dir) ? fs::canonical(dir) : fs::path();
}

fs::path shared_checker() {
  const fs::path file = fs::path(VDB_SHELL_SHARED_EVAL) / "check_shell.py";
  return fs::is_regular_file(file) ? fs::canonical(file) : fs::path();
}

std::string read_text(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

CommandResult run_command(const std::string& command) {
  TempDir dir;
  const std::string out = dir.file("stdout"), err = dir.file("stderr");
  const std::string full = command + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(full.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(out);
  r.err = read_text(err);
  return r;
}

std::string vdb_shell_bin() { return VDB_SHELL_BIN; }
std::string vdb_shell_shapes_bin() { return VDB_SHELL_SHAPES_BIN; }

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << text;
}

}  // namespace vdb_shell::test

// launcher.cpp — the vdb_shell command: starts the program (main.cpp, installed as
// <libexecdir>/vdb_shell/vdb_shell) in its own place, with glibc's malloc asked to back its heaps
// with transparent huge pages: GLIBC_TUNABLES gains glibc.malloc.hugetlb=1 unless it already
// sets that tunable (=0 turns it off).
//
// Why: the program's fields and shells are millions of small blocks (OpenVDB's leaf buffers, the
// checks' lists), first touched 4 KiB at a time; on a virtual machine each page fault costs
// microseconds. The tunable can only be set before a process starts, and the program itself
// cannot start cheaply twice: loading libopenvdb takes ~40 ms. This launcher loads nothing but
// libc, so starting through it costs ~1 ms (docs/benchmarks.md, "Huge pages").
//
// The program replaces the launcher (execv: same process, arguments, streams and exit code).
// Only libc here: no C++ runtime is loaded.
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace {

constexpr const char kTunable[] = "glibc.malloc.hugetlb";

// Fails with one line on stderr and the exit code of an internal error.
[[noreturn]] void fail(const char* what, const char* path) {
  std::fprintf(stderr, "vdb_shell: %s %s: %s; reinstall vdb_shell\n", what, path,
               std::strerror(errno));
  std::exit(3);
}

}  // namespace

int main(int, char** argv) {
  // The program, VDB_SHELL_PROGRAM_FROM_BINDIR from this executable's directory.
  static char program[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", program, sizeof program);
  if (n <= 0 || n >= static_cast<ssize_t>(sizeof program)) fail("cannot read", "/proc/self/exe");
  program[n] = '\0';
  char* slash = std::strrchr(program, '/');
  const char tail[] = "/" VDB_SHELL_PROGRAM_FROM_BINDIR "/vdb_shell";
  if (!slash || static_cast<std::size_t>(slash - program) + sizeof tail > sizeof program) {
    errno = ENAMETOOLONG;
    fail("cannot find the program beside", program);
  }
  std::memcpy(slash, tail, sizeof tail);

  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (!tunables || !*tunables) {
    setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1", 1);
  } else if (!std::strstr(tunables, kTunable)) {  // (one too long to extend is left alone)
    static char joined[4096];
    if (std::snprintf(joined, sizeof joined, "%s:%s=1", tunables, kTunable) <
        static_cast<int>(sizeof joined))
      setenv("GLIBC_TUNABLES", joined, 1);
  }
  execv(program, argv);
  fail("cannot start", program);
}

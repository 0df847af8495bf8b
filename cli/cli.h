// cli.h — the vdb_shell command line, callable in-process (tests drive it without a shell).
#pragma once

#include <iosfwd>

namespace vdb_shell {

/// Exit codes of the vdb_shell command.
enum ExitCode : int {
  kExitOk = 0,        ///< success
  kExitBadInput = 2,  ///< bad input file or options; nothing was written
  kExitFailure = 3,   ///< resource or internal error; nothing was written
};

/// Runs the command with `argv`; writes results to `out` and messages to `err`.
int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);
/// Same, on std::cout / std::cerr.
int run_cli(int argc, const char* const* argv);

}  // namespace vdb_shell

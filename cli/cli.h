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

/// Runs the command with `argv`; writes results to `out` and messages to `err` (never treated as
/// a terminal: progress lines only with --progress).
int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);
/// Same, on std::cout / std::cerr (progress lines by default when stderr is a terminal).
int run_cli(int argc, const char* const* argv);

/// Installs SIGINT and SIGTERM handlers that remove every temporary output file in flight
/// (remove_pending_temp_files()) and then re-raise the signal with its default action, so an
/// interrupted run leaves no partial or temporary file and exits as killed by the signal (a shell
/// reports 130 for SIGINT, 143 for SIGTERM). A signal that is ignored on entry stays ignored.
/// For the executable's main(); tests do not call it.
void install_signal_cleanup();

}  // namespace vdb_shell

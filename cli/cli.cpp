#include "cli/cli.h"

#include <iostream>

namespace vdb_shell {
int run_cli(int, const char* const*, std::ostream&, std::ostream&) { return 0; }
int run_cli(int argc, const char* const* argv) { return run_cli(argc, argv, std::cout, std::cerr); }
}  // namespace vdb_shell

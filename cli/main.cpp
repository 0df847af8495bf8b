// main.cpp — the vdb_shell executable: everything lives in run_cli() (cli/cli.h).
#include "cli/cli.h"

int main(int argc, char** argv) {
  vdb_shell::install_signal_cleanup();
  return vdb_shell::run_cli(argc, argv);
}

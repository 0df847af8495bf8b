// cli_fuzz.cpp — libFuzzer target for the command line: the bytes, split at newlines, are the
// arguments of one `vdb_shell` run (in a scratch folder, output captured). Every outcome must be
// an exit code with a message; a crash, a sanitizer report or a hang is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char folder[] = "/tmp/vdb_shell_cli_fuzz_XXXXXX";
  if (mkdtemp(folder) == nullptr || chdir(folder) != 0) std::abort();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> args = {"vdb_shell"};
  std::string arg;
  for (std::size_t i = 0; i < size && args.size() < 24; ++i) {
    if (data[i] != '\n') {
      arg += static_cast<char>(data[i]);
      continue;
    }
    args.push_back(arg);
    arg.clear();
  }
  if (!arg.empty() && args.size() < 24) args.push_back(arg);
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  vdb_shell::run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return 0;
}

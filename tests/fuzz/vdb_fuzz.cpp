// vdb_fuzz.cpp — libFuzzer target for the .vdb input path: the bytes are written to a file and
// read as a level set, then as any float volume (OpenVDB's reader, the grid checks,
// volumeToMesh, at adaptivity 0 and 0.5 with its mending) and the surface meshed from it is
// validated, as `vdb_shell INPUT.vdb` does without and with --repair. Bad input must end in an
// InputError, or a
// ResourceError when OpenVDB's reader (the program vdb_shell_vdb_reader) runs out of memory on a
// size the file claims.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "vdb_ops/fields.h"

namespace {

// The file each input is written to, one per process, removed when the fuzzer exits.
struct InputFile {
  std::string path =
      "/tmp/vdb_shell_vdb_fuzz_" + std::to_string(static_cast<long>(getpid())) + ".vdb";
  ~InputFile() { std::remove(path.c_str()); }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const InputFile file;
  const std::string& path = file.path;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  for (const bool any_volume : {false, true})  // a .vdb input as it is, and with --repair
    for (const double adaptivity : {0.0, 0.5}) {
      try {
        vdb_shell::make_surface(vdb_shell::volume_to_soup(path, "", adaptivity, any_volume).soup,
                                path);
      } catch (const vdb_shell::InputError&) {
      } catch (const vdb_shell::ResourceError&) {
      }
    }
  return 0;
}

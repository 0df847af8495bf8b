// surface_fuzz.cpp — libFuzzer target for one surface reader (the format is the compile
// definition VDB_SHELL_FUZZ_EXT: ".obj", ".off", ".ply" or ".stl"): the bytes are parsed as a
// file of that format and, when they parse, validated as a surface. Bad input must end in an
// InputError; anything else (a crash, a sanitizer report, a hang, an allocation beyond
// libFuzzer's -rss_limit_mb) is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "core/read/polygon_soup.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const vdb_shell::PolygonSoup soup =
        vdb_shell::parse_polygon_soup(bytes, VDB_SHELL_FUZZ_EXT, "fuzz" VDB_SHELL_FUZZ_EXT);
    vdb_shell::make_surface(soup, "fuzz" VDB_SHELL_FUZZ_EXT);
  } catch (const vdb_shell::InputError&) {
  }
  return 0;
}

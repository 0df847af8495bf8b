// polygon_soup.cpp — reading a surface file whole and handing it to its format's reader.
#include "core/read/polygon_soup.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/base/errors.h"
#include "core/base/file_name.h"
#include "core/read/format_reader.h"

namespace vdb_shell {

const std::vector<std::string>& supported_surface_extensions() {
  static const std::vector<std::string> exts = {".obj", ".off", ".ply", ".stl"};
  return exts;
}

PolygonSoup parse_polygon_soup(std::string_view bytes, const std::string& ext,
                               const std::string& name) {
  PolygonSoup soup;
  if (ext == ".obj")
    soup = read_detail::read_obj(bytes, name);
  else if (ext == ".off")
    soup = read_detail::read_off(bytes, name);
  else if (ext == ".ply")
    soup = read_detail::read_ply(bytes, name);
  else if (ext == ".stl")
    soup = read_detail::read_stl(bytes, name);
  else
    throw InputError(name + ": unknown surface format '" + ext + "'; use .obj, .off, .ply or .stl");
  if (soup.polygons.empty())
    throw InputError(name + ": holds no faces (" + std::to_string(soup.points.size()) +
                     " vertices); vdb_shell needs a closed triangle surface");
  return soup;
}

PolygonSoup read_polygon_soup(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file; check the path");
  if (fs::is_directory(path, ec))
    throw InputError(path + ": is a directory, not a surface mesh file");
  const std::string ext = lower_extension(path);
  const auto& exts = supported_surface_extensions();
  if (std::find(exts.begin(), exts.end(), ext) == exts.end())
    throw InputError(path + ": unknown surface format '" + ext + "'; use .obj, .off, .ply or .stl");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read (" + ec.message() + ")");
  if (size == 0) throw InputError(path + ": the file is empty (0 bytes)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open for reading; check its permissions");
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size)
    throw InputError(path + ": cannot read all of its " + std::to_string(size) +
                     " bytes (it changed while being read?)");
  return parse_polygon_soup(bytes, ext, path);
}

}  // namespace vdb_shell

// polygon_soup.h — reading surface files: OBJ, OFF (ASCII and binary), PLY (ASCII and binary,
// faces or triangle strips), STL (ASCII and binary).
//
// The readers return the file's content untouched — positions and polygons with their indices as
// written — so that validation (load_surface.h) can name every problem instead of a reader
// silently repairing or dropping faces. Each reader holds the whole file in memory, checks the
// counts a header announces against the bytes that are there before it reserves anything (so no
// reader allocates more than a small multiple of the file's size), and refuses every
// inconsistency — a count, a line that ends early, an index out of range, a file cut short ("
// truncated") — as bad input naming the line. Coordinates are parsed in double precision.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/vec3.h"

namespace vdb_shell {

/// A file's faces as written: any polygon size, indices possibly out of range.
struct PolygonSoup {
  std::vector<Vec3d> points;                        ///< positions, file units
  std::vector<std::vector<std::int64_t>> polygons;  ///< 0-based vertex indices as read
};

/// Extensions read_polygon_soup() accepts (lower case, with the dot).
const std::vector<std::string>& supported_surface_extensions();

/// Reads `path` (format from its extension, case-insensitive).
/// \throw InputError if the file is missing, empty, truncated, inconsistent, of an unknown
///        format, or holds no faces; the message names the file, the line and what to do.
PolygonSoup read_polygon_soup(const std::string& path);

/// Parses `bytes`, the whole content of a file in the format of extension `ext` (".obj", ".off",
/// ".ply", ".stl"); `name` names it in messages. What read_polygon_soup() does after reading.
PolygonSoup parse_polygon_soup(std::string_view bytes, const std::string& ext,
                               const std::string& name);

}  // namespace vdb_shell

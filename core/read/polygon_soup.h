// polygon_soup.h — reading surface files (OBJ, OFF, PLY, STL ASCII/binary) through OpenMesh.
//
// The reader returns the file's content untouched — positions and polygons with their indices as
// written — so that validation (load_surface.h) can name every problem instead of OpenMesh silently
// repairing or dropping faces. OpenMesh's parsers do the reading; its diagnostics are captured and
// appended to the error message instead of being printed. Before them, what OpenMesh would trust
// is checked against the file: a binary STL's triangle count against its size; an ASCII OFF's
// counts (numbers >= 0 that the file's bytes can hold), its vertex and face lines (present, each
// face with the corners it announces); an OBJ's face indices (in range: OpenMesh drops a face
// with a bad index without a word). So no reader allocates more than a small multiple of the
// file's size, and each problem is bad input naming its line. A PLY file whose faces are
// triangle strips (element `tristrips`, which OpenMesh skips) is decoded here.
#pragma once

#include <cstdint>
#include <string>
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
/// \throw InputError if the file is missing, empty, truncated, of an unknown format, or holds
///        no faces; the message names the file and what to do.
PolygonSoup read_polygon_soup(const std::string& path);

}  // namespace vdb_shell

// read_obj.cpp — Wavefront OBJ: `v x y z` lines and `f` lines whose corners are `v`, `v/vt`,
// `v//vn` or `v/vt/vn` (1-based, or counting back from -1); every other line is ignored.
#include <algorithm>
#include <string>

#include "core/read/format_reader.h"

namespace vdb_shell::read_detail {
namespace {

/// The line's keyword: its first word (comments start with '#').
std::string_view keyword(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && is_blank(line[i])) ++i;
  std::size_t j = i;
  while (j < line.size() && !is_blank(line[j]) && line[j] != '#') ++j;
  return line.substr(i, j - i);
}

}  // namespace

PolygonSoup read_obj(std::string_view bytes, const std::string& name) {
  // Positive indices may name vertices further down the file: count them first.
  long long total = 0;
  {
    Lines lines(bytes);
    for (std::string_view line; lines.next(line);) total += keyword(line) == "v";
  }
  PolygonSoup soup;
  soup.points.reserve(static_cast<std::size_t>(total));  // >= 7 bytes each ("v 0 0 0")
  BadCoordinates bad;
  Lines lines(bytes);
  for (std::string_view line; lines.next(line);) {
    const std::string_view key = keyword(line);
    if (key == "v") {
      const std::vector<std::string_view> w = words(line, '#', 4);
      Vec3d p;
      bool readable = w.size() == 4;
      for (int k = 0; readable && k < 3; ++k) readable = parse_number(w[k + 1], p[k]);
      const std::string_view coords = line.substr(std::min(line.size(), line.find('v') + 1));
      bad.check(readable, p,
                "vertex " + std::to_string(soup.points.size()) + " (line " +
                    std::to_string(lines.line_no()) + ")",
                coords.substr(std::min(coords.size(), coords.find_first_not_of(" \t"))));
      soup.points.push_back(p);
      continue;
    }
    if (key != "f") continue;
    const std::size_t face = soup.polygons.size();
    const auto where = [&] {
      return "face " + std::to_string(face) + " (line " + std::to_string(lines.line_no()) + ")";
    };
    const std::vector<std::string_view> w = words(line);
    std::vector<std::int64_t> polygon;
    polygon.reserve(w.size() - 1);
    const long long so_far = static_cast<long long>(soup.points.size());
    for (std::size_t k = 1; k < w.size(); ++k) {
      long long index = 0;
      if (leading_integer(w[k], index) &&
          ((index > 0 && index <= total) || (index < 0 && index >= -so_far))) {
        polygon.push_back(index > 0 ? index - 1 : so_far + index);
        continue;
      }
      fail(name,
           where() + ": out-of-range vertex index " + quoted(w[k]) + " (the file has " +
               std::to_string(total) + " vertices, numbered from 1, or back from -1)",
           "the file is corrupt or truncated; re-export the mesh");
    }
    if (polygon.size() < 3)
      fail(name, where() + " has " + std::to_string(polygon.size()) +
                     " corners, a face needs 3 (a file cut short ends so)");
    soup.polygons.push_back(std::move(polygon));
  }
  bad.throw_if_any(name);
  return soup;
}

}  // namespace vdb_shell::read_detail

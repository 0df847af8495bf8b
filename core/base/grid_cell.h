// grid_cell.h — a cell of a uniform grid of cubes, and its hash: the key of hash grids over
// points (inner.cpp's welding) and the cells of the merge grid (merges.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/base/vec3.h"

namespace vdb_shell {

/// The cell of a uniform grid of cubes of side `side` that holds `p`.
struct GridCell {
  std::int64_t i, j, k;
  GridCell(std::int64_t i_, std::int64_t j_, std::int64_t k_) : i(i_), j(j_), k(k_) {}
  GridCell(const Vec3d& p, double side)
      : i(static_cast<std::int64_t>(std::floor(p.x / side))),
        j(static_cast<std::int64_t>(std::floor(p.y / side))),
        k(static_cast<std::int64_t>(std::floor(p.z / side))) {}
  bool operator==(const GridCell& o) const { return i == o.i && j == o.j && k == o.k; }
};
struct GridCellHash {
  std::size_t operator()(const GridCell& c) const {
    return static_cast<std::size_t>(c.i * 73856093LL ^ c.j * 19349663LL ^ c.k * 83492791LL);
  }
};

}  // namespace vdb_shell

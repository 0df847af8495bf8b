// point_index.h — fixed-radius neighbour queries over a point set (the paper's spatial hashing).
//
// core/ asks through this interface; vdb_ops/ implements it with OpenVDB's PointIndexGrid and
// core/ has a plain uniform hash grid (used by tests and as a reference). Both return the same
// indices for the same query.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/base/vec3.h"

namespace vdb_shell {

/// Queries over a fixed point set. Const queries are safe to run from several threads.
class PointIndex {
 public:
  virtual ~PointIndex() = default;
  /// Replaces `out` with the indices of the points within `radius` (world units) of `p`, in no
  /// particular order (for callers that filter the result and order what is left themselves).
  virtual void find_within_unordered(const Vec3d& p, double radius,
                                     std::vector<std::uint32_t>& out) const = 0;
  /// The same, sorted ascending.
  void find_within(const Vec3d& p, double radius, std::vector<std::uint32_t>& out) const {
    find_within_unordered(p, radius, out);
    std::sort(out.begin(), out.end());
  }
};

/// Builds an index over `points`; `radius` is the query radius the caller will use (a hint for
/// the cell size).
using PointIndexFactory =
    std::function<std::unique_ptr<PointIndex>(const std::vector<Vec3d>& points, double radius)>;

/// A cell of a uniform grid of cubes of side `side` (the one holding `p`), and its hash: the
/// key of hash grids over points.
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

/// Uniform hash grid with cells of side `radius`.
std::unique_ptr<PointIndex> make_hash_point_index(const std::vector<Vec3d>& points, double radius);

}  // namespace vdb_shell

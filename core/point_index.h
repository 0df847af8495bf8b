// point_index.h — fixed-radius neighbour queries over a point set (the paper's spatial hashing).
//
// core/ asks through this interface; vdb_ops/ implements it with OpenVDB's PointIndexGrid and
// core/ has a plain uniform hash grid (used by tests and as a reference). Both return the same
// indices for the same query.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/vec3.h"

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
using PointIndexFactory = std::function<std::unique_ptr<PointIndex>(
    const std::vector<Vec3d>& points, double radius)>;

/// Uniform hash grid with cells of side `radius`.
std::unique_ptr<PointIndex> make_hash_point_index(const std::vector<Vec3d>& points,
                                                  double radius);

}  // namespace vdb_shell

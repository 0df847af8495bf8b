// point_index.cpp — uniform hash grid implementation of PointIndex.
#include "core/trace/point_index.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vdb_shell {
namespace {

class HashPointIndex final : public PointIndex {
 public:
  HashPointIndex(const std::vector<Vec3d>& points, double radius)
      : points_(points), cell_(radius > 0 ? radius : 1.0) {
    for (std::uint32_t n = 0; n < points_.size(); ++n)
      cells_[GridCell(points_[n], cell_)].push_back(n);
  }
  void find_within_unordered(const Vec3d& p, double radius,
                             std::vector<std::uint32_t>& out) const override {
    out.clear();
    const GridCell lo(p - Vec3d(radius, radius, radius), cell_);
    const GridCell hi(p + Vec3d(radius, radius, radius), cell_);
    const double r2 = radius * radius;
    for (std::int64_t i = lo.i; i <= hi.i; ++i)
      for (std::int64_t j = lo.j; j <= hi.j; ++j)
        for (std::int64_t k = lo.k; k <= hi.k; ++k) {
          const auto it = cells_.find(GridCell(i, j, k));
          if (it == cells_.end()) continue;
          for (std::uint32_t n : it->second)
            if (norm2(points_[n] - p) <= r2) out.push_back(n);
        }
  }

 private:
  std::vector<Vec3d> points_;
  double cell_;
  std::unordered_map<GridCell, std::vector<std::uint32_t>, GridCellHash> cells_;
};

}  // namespace

std::unique_ptr<PointIndex> make_hash_point_index(const std::vector<Vec3d>& points, double radius) {
  return std::make_unique<HashPointIndex>(points, radius);
}

}  // namespace vdb_shell

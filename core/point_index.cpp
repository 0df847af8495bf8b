// point_index.cpp — uniform hash grid implementation of PointIndex.
#include "core/point_index.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace vdb_shell {
namespace {

struct CellKey {
  std::int64_t i, j, k;
  bool operator==(const CellKey& o) const { return i == o.i && j == o.j && k == o.k; }
};
struct CellHash {
  std::size_t operator()(const CellKey& c) const {
    return static_cast<std::size_t>(c.i * 73856093LL ^ c.j * 19349663LL ^ c.k * 83492791LL);
  }
};

class HashPointIndex final : public PointIndex {
 public:
  HashPointIndex(const std::vector<Vec3d>& points, double radius)
      : points_(points), cell_(radius > 0 ? radius : 1.0) {
    for (std::uint32_t n = 0; n < points_.size(); ++n) cells_[key(points_[n])].push_back(n);
  }
  void find_within_unordered(const Vec3d& p, double radius,
                             std::vector<std::uint32_t>& out) const override {
    out.clear();
    const CellKey lo = key(p - Vec3d(radius, radius, radius));
    const CellKey hi = key(p + Vec3d(radius, radius, radius));
    const double r2 = radius * radius;
    for (std::int64_t i = lo.i; i <= hi.i; ++i)
      for (std::int64_t j = lo.j; j <= hi.j; ++j)
        for (std::int64_t k = lo.k; k <= hi.k; ++k) {
          const auto it = cells_.find({i, j, k});
          if (it == cells_.end()) continue;
          for (std::uint32_t n : it->second)
            if (norm2(points_[n] - p) <= r2) out.push_back(n);
        }
  }

 private:
  CellKey key(const Vec3d& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x / cell_)),
            static_cast<std::int64_t>(std::floor(p.y / cell_)),
            static_cast<std::int64_t>(std::floor(p.z / cell_))};
  }
  std::vector<Vec3d> points_;
  double cell_;
  std::unordered_map<CellKey, std::vector<std::uint32_t>, CellHash> cells_;
};

}  // namespace

std::unique_ptr<PointIndex> make_hash_point_index(const std::vector<Vec3d>& points,
                                                  double radius) {
  return std::make_unique<HashPointIndex>(points, radius);
}

}  // namespace vdb_shell

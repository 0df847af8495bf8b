// point_index_vdb.cpp — PointIndex over tools::PointIndexGrid; see point_index_vdb.h.
#include "vdb_ops/point_index_vdb.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/PointIndexGrid.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/base/errors.h"

namespace vdb_shell {
namespace {

/// Largest |coordinate| / voxel accepted (OpenVDB index coordinates are 32-bit integers).
constexpr double kMaxIndexCoord = 1 << 29;
/// The radial search runs with radius + kSearchPad * voxel: OpenVDB tests points against a
/// centre converted to index space and back, so a point exactly on the sphere could be lost to
/// rounding; the exact world-space test below then decides.
constexpr double kSearchPad = 1e-3;

/// tools::PointIndexGrid's PointArray interface over a vector of world positions.
class PointList {
 public:
  using PosType = openvdb::Vec3d;
  explicit PointList(const std::vector<Vec3d>& points) : points_(points) {}
  std::size_t size() const { return points_.size(); }
  void getPos(std::size_t n, PosType& xyz) const {
    const Vec3d& p = points_[n];
    xyz = PosType(p.x, p.y, p.z);
  }

 private:
  const std::vector<Vec3d>& points_;
};

class VdbPointIndex final : public PointIndex {
 public:
  VdbPointIndex(const std::vector<Vec3d>& points, double voxel)
      : points_(points),
        list_(points_),
        transform_(openvdb::math::Transform::createLinearTransform(voxel)),
        voxel_(voxel) {
    grid_ =
        openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(list_, *transform_);
  }

  void find_within_unordered(const Vec3d& p, double radius,
                             std::vector<std::uint32_t>& out) const override {
    out.clear();
    if (points_.empty() || !(radius >= 0.0)) return;
    using Iterator = openvdb::tools::PointIndexIterator<openvdb::tools::PointIndexTree>;
    Iterator::ConstAccessor accessor(grid_->constTree());
    Iterator it;
    it.worldSpaceSearchAndUpdate(openvdb::Vec3d(p.x, p.y, p.z), radius + kSearchPad * voxel_,
                                 accessor, list_, *transform_, /*subvoxelAccuracy=*/true);
    const double r2 = radius * radius;
    for (; it; ++it) {
      const std::uint32_t n = *it;
      if (norm2(points_[n] - p) <= r2) out.push_back(n);
    }
  }

 private:
  std::vector<Vec3d> points_;
  PointList list_;
  openvdb::math::Transform::Ptr transform_;
  double voxel_;
  openvdb::tools::PointIndexGrid::Ptr grid_;
};

}  // namespace

std::unique_ptr<PointIndex> make_vdb_point_index(const std::vector<Vec3d>& points, double radius) {
  const double voxel = radius > 0.0 && std::isfinite(radius) ? radius : 1.0;
  for (std::size_t n = 0; n < points.size(); ++n) {
    const Vec3d& p = points[n];
    if (!is_finite(p))
      throw InputError("point index: point " + std::to_string(n) + " is not finite");
    if (std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) / voxel > kMaxIndexCoord)
      throw InputError("point index: point " + std::to_string(n) +
                       " lies too far from the origin for a grid of voxel size " +
                       std::to_string(voxel) + "; move the mesh nearer the origin");
  }
  openvdb::initialize();
  return std::make_unique<VdbPointIndex>(points, voxel);
}

}  // namespace vdb_shell

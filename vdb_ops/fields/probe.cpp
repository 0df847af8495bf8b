// probe.cpp — the FieldProbe of Fields: trilinear phi, gradient and flux at world points.
#include "vdb_ops/fields/fields_internal.h"

#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <memory>

namespace vdb_shell {

using namespace fields_detail;

namespace {

class VdbProbe final : public FieldProbe {
 public:
  explicit VdbProbe(const Fields::Impl& f)
      : f_(f),
        xform_(f.sdf->transform()),
        sdf_acc_(f.sdf->getConstAccessor()),
        flux_acc_(f.flux->getConstAccessor()) {
    if (f.gradient)
      grad_acc_ = std::make_unique<Vec3SGrid::ConstAccessor>(f.gradient->getConstAccessor());
  }

  double phi(const Vec3d& p) override {
    return openvdb::tools::BoxSampler::sample(sdf_acc_, to_index(p));
  }

  double flux(const Vec3d& p) override {
    return openvdb::tools::BoxSampler::sample(flux_acc_, to_index(p));
  }

  Vec3d gradient(const Vec3d& p) override {
    const openvdb::Vec3d xyz = to_index(p);
    if (grad_acc_) {
      const openvdb::Vec3s g = openvdb::tools::BoxSampler::sample(*grad_acc_, xyz);
      return {g[0], g[1], g[2]};
    }
    const Coord base(int(std::floor(xyz[0])), int(std::floor(xyz[1])), int(std::floor(xyz[2])));
    const openvdb::Vec3d t = xyz - base.asVec3d();
    // A trace asks several times in one voxel cell (RK2: its sample and the midpoint): the cell's
    // corner differences are kept until it leaves.
    if (!has_cell_ || base != cell_) {
      // phi over base + [-1, 2]^3 (only the 32 entries central differences need are read).
      float v[4][4][4];
      fetch_stencil(base, v);
      for (int cx = 0; cx < 2; ++cx)
        for (int cy = 0; cy < 2; ++cy)
          for (int cz = 0; cz < 2; ++cz) {
            const int x = cx + 1, y = cy + 1, z = cz + 1;
            openvdb::Vec3d& d = corner_diff_[cx][cy][cz];
            d[0] = 0.5 * double(v[x + 1][y][z] - v[x - 1][y][z]);
            d[1] = 0.5 * double(v[x][y + 1][z] - v[x][y - 1][z]);
            d[2] = 0.5 * double(v[x][y][z + 1] - v[x][y][z - 1]);
          }
      cell_ = base;
      has_cell_ = true;
    }
    openvdb::Vec3d g(0.0, 0.0, 0.0);
    for (int cx = 0; cx < 2; ++cx)
      for (int cy = 0; cy < 2; ++cy)
        for (int cz = 0; cz < 2; ++cz) {
          const double w =
              (cx ? t[0] : 1.0 - t[0]) * (cy ? t[1] : 1.0 - t[1]) * (cz ? t[2] : 1.0 - t[2]);
          g += w * corner_diff_[cx][cy][cz];
        }
    const openvdb::Vec3d w = apply_map(f_.gmap.g, g);
    return {w[0], w[1], w[2]};
  }

 private:
  openvdb::Vec3d to_index(const Vec3d& p) const {
    return xform_.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
  }

  /// Reads phi at base + (i-1, j-1, k-1) for the entries of the 4^3 block that central
  /// differences at the 8 inner corners use, through at most 8 leaf lookups.
  void fetch_stencil(const Coord& base, float (&v)[4][4][4]) {
    const Coord lo = base.offsetBy(-1);
    const FloatLeaf* leaves[2][2][2];
    float tiles[2][2][2];
    const Coord lo_leaf = lo & ~(kLeafDim - 1);
    // The block spans a second leaf along an axis only when it starts in the leaf's last 3.
    const int na = (lo[0] & 7) > 4 ? 2 : 1, nb = (lo[1] & 7) > 4 ? 2 : 1,
              nc = (lo[2] & 7) > 4 ? 2 : 1;
    for (int a = 0; a < na; ++a)
      for (int b = 0; b < nb; ++b)
        for (int c = 0; c < nc; ++c) {
          const Coord o = lo_leaf.offsetBy(a * kLeafDim, b * kLeafDim, c * kLeafDim);
          leaves[a][b][c] = sdf_acc_.probeConstLeaf(o);
          tiles[a][b][c] = leaves[a][b][c] ? 0.0f : sdf_acc_.getValue(o);
        }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int k = 0; k < 4; ++k) {
          const int inner = (i == 1 || i == 2) + (j == 1 || j == 2) + (k == 1 || k == 2);
          if (inner < 2) continue;  // corners and edges of the 4^3 block are not needed
          const int x = lo[0] + i, y = lo[1] + j, z = lo[2] + k;
          const int a = (x - lo_leaf[0]) >> 3, b = (y - lo_leaf[1]) >> 3, c = (z - lo_leaf[2]) >> 3;
          const FloatLeaf* leaf = leaves[a][b][c];
          v[i][j][k] =
              leaf ? leaf->getValue(((x & 7) << 6) | ((y & 7) << 3) | (z & 7)) : tiles[a][b][c];
        }
  }

  const Fields::Impl& f_;
  const openvdb::math::Transform& xform_;
  FloatGrid::ConstAccessor sdf_acc_;
  FloatGrid::ConstAccessor flux_acc_;
  std::unique_ptr<Vec3SGrid::ConstAccessor> grad_acc_;
  bool has_cell_ = false;
  Coord cell_;                           ///< the voxel cell of corner_diff_
  openvdb::Vec3d corner_diff_[2][2][2];  ///< central differences / 2 at its 8 corners
};

}  // namespace

std::unique_ptr<FieldProbe> Fields::probe() const { return std::make_unique<VdbProbe>(*impl_); }

}  // namespace vdb_shell

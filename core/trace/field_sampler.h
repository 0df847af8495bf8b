// field_sampler.h — the narrow interface through which core/ samples the distance and flux fields.
//
// Implemented in vdb_ops/ over OpenVDB grids, and in tests by exact analytic fields, so core/
// never includes OpenVDB. Conventions at this boundary:
//   * positions are world coordinates (the input mesh's units and frame);
//   * phi is the signed distance, negative inside the surface, in world units;
//   * gradient is grad(phi) by central differences of the sampled field, interpolated
//     trilinearly (unit length away from the medial surface, shorter near it);
//   * flux is the average outward flux of grad(phi) through the 26-neighbour cube around a
//     point (paper eq. 7 divided by 26), in [-1, 1]; positive near the medial surface, 0 where
//     the field stores nothing.
#pragma once

#include <memory>

#include "core/base/vec3.h"

namespace vdb_shell {

/// Point queries into the fields. Not thread-safe: each thread makes its own probe.
class FieldProbe {
 public:
  virtual ~FieldProbe() = default;
  /// Signed distance at `p` (world units, negative inside).
  virtual double phi(const Vec3d& p) = 0;
  /// grad(phi) at `p` (dimensionless).
  virtual Vec3d gradient(const Vec3d& p) = 0;
  /// Average outward flux at `p`, in [-1, 1].
  virtual double flux(const Vec3d& p) = 0;
};

/// The fields of one surface. Const and safe to share between threads.
class FieldSampler {
 public:
  virtual ~FieldSampler() = default;
  /// A new probe for the calling thread.
  virtual std::unique_ptr<FieldProbe> probe() const = 0;
  /// Edge length of a (cubic) voxel, world units.
  virtual double voxel_size() const = 0;
};

}  // namespace vdb_shell

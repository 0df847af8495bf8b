// analytic_field.h — exact signed distance functions as FieldSamplers, so core/ is tested
// without OpenVDB. phi is exact; gradient and flux are computed the way the paper computes them
// on a grid: central differences at the voxel spacing, and eq. (7) over the 26 neighbours.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "core/trace/field_sampler.h"

namespace vdb_shell::test {

class AnalyticField final : public FieldSampler {
 public:
  using Phi = std::function<double(const Vec3d&)>;
  AnalyticField(Phi phi, double voxel) : phi_(std::move(phi)), h_(voxel) {}

  std::unique_ptr<FieldProbe> probe() const override { return std::make_unique<Probe>(*this); }
  double voxel_size() const override { return h_; }

 private:
  class Probe final : public FieldProbe {
   public:
    explicit Probe(const AnalyticField& f) : f_(f) {}
    double phi(const Vec3d& p) override { return f_.phi_(p); }
    Vec3d gradient(const Vec3d& p) override {
      const double h = f_.h_;
      return {(f_.phi_(p + Vec3d(h, 0, 0)) - f_.phi_(p - Vec3d(h, 0, 0))) / (2 * h),
              (f_.phi_(p + Vec3d(0, h, 0)) - f_.phi_(p - Vec3d(0, h, 0))) / (2 * h),
              (f_.phi_(p + Vec3d(0, 0, h)) - f_.phi_(p - Vec3d(0, 0, h))) / (2 * h)};
    }
    double flux(const Vec3d& p) override {
      double sum = 0;
      for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
          for (int k = -1; k <= 1; ++k) {
            if (!i && !j && !k) continue;
            const Vec3d n = normalized(Vec3d(i, j, k));
            sum += dot(gradient(p + Vec3d(i, j, k) * f_.h_), n);
          }
      return sum / 26.0;
    }

   private:
    const AnalyticField& f_;
  };

  Phi phi_;
  double h_;
};

/// Sphere of radius r about the origin.
inline std::unique_ptr<AnalyticField> sphere_field(double r, double voxel) {
  return std::make_unique<AnalyticField>([r](const Vec3d& p) { return norm(p) - r; }, voxel);
}

/// Axis-aligned box with half-sides `half` about the origin (exact SDF).
inline std::unique_ptr<AnalyticField> box_field(const Vec3d& half, double voxel) {
  return std::make_unique<AnalyticField>(
      [half](const Vec3d& p) {
        const Vec3d d(std::fabs(p.x) - half.x, std::fabs(p.y) - half.y, std::fabs(p.z) - half.z);
        const Vec3d o(std::max(d.x, 0.0), std::max(d.y, 0.0), std::max(d.z, 0.0));
        return norm(o) + std::min(std::max(d.x, std::max(d.y, d.z)), 0.0);
      },
      voxel);
}

}  // namespace vdb_shell::test

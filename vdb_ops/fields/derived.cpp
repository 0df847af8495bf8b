// derived.cpp — the grids derived from the SDF in one pass over its leaves: the flux and, when
// stored, the gradient (finish_fields()), and the Fields object that holds them.
#include "vdb_ops/fields/fields_internal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include "core/base/run_control.h"
#include "core/base/timer.h"

namespace vdb_shell {
namespace fields_detail {

namespace {

// Gradient and flux: one pass over the SDF's leaves with a padded dense block per leaf.

constexpr int kPad = 2;                      // flux needs gradients at +-1, i.e. phi at +-2
constexpr int kBlock = kLeafDim + 2 * kPad;  // 12

/// Copies phi over [origin - 2, origin + 9]^3 into `block` (x-major), reading leaf buffers
/// directly and tile values where there is no leaf.
void gather_block(FloatGrid::ConstAccessor& acc, const Coord& origin, float* block) {
  for (int nx = -1; nx <= 1; ++nx)
    for (int ny = -1; ny <= 1; ++ny)
      for (int nz = -1; nz <= 1; ++nz) {
        const Coord nb_origin = origin.offsetBy(nx * kLeafDim, ny * kLeafDim, nz * kLeafDim);
        const FloatLeaf* leaf = acc.probeConstLeaf(nb_origin);
        const float tile = leaf ? 0.0f : acc.getValue(nb_origin);
        const float* data = leaf ? leaf->buffer().data() : nullptr;
        // Block index ranges covered by this neighbour along each axis.
        auto lo = [](int n) { return n < 0 ? 0 : (n == 0 ? kPad : kPad + kLeafDim); };
        auto hi = [](int n) { return n < 0 ? kPad : (n == 0 ? kPad + kLeafDim : kBlock); };
        for (int bx = lo(nx); bx < hi(nx); ++bx)
          for (int by = lo(ny); by < hi(ny); ++by) {
            float* row = block + (bx * kBlock + by) * kBlock;
            const int lxy =
                (((bx - kPad) & (kLeafDim - 1)) << 6) | (((by - kPad) & (kLeafDim - 1)) << 3);
            for (int bz = lo(nz); bz < hi(nz); ++bz) {
              row[bz] = data ? data[lxy | ((bz - kPad) & (kLeafDim - 1))] : tile;
            }
          }
      }
}

/// Average outward flux (eq. 7 / 26, index units: multiply by 1 / h) of the central-difference
/// gradient of `phi` (a 12^3 block, leaf at 2..9) at the 512 voxels of the leaf, into flux[512]
/// (x-major). The 26 terms g(c + d) . d / |d| are regrouped per axis: for x,
/// sum over (dy, dz) of (g_x(c + (1, dy, dz)) - g_x(c - (1, dy, dz))) / sqrt(1 + dy^2 + dz^2),
/// so the loops over z vectorise.
struct FluxScratch {
  float diff[3][10][10][10];
};

void flux_of_block(const float* phi, float* flux, FluxScratch& scratch) {
  constexpr int B = kBlock;
  auto& diff = scratch.diff;
  // diff[a][x + 1][y + 1][z + 1]: g_a at +1 minus g_a at -1 along axis a, where
  // g_a = (phi(+e_a) - phi(-e_a)) / 2, i.e. (phi(+2 e_a) + phi(-2 e_a)) / 2 - phi; needed with
  // the a-coordinate in [0, 7] and the other two in [-1, 8].
  for (int a = 0; a < 3; ++a) {
    const int s2 = a == 0 ? 2 * B * B : (a == 1 ? 2 * B : 2);
    for (int x = a == 0 ? 1 : 0; x < (a == 0 ? 9 : 10); ++x)
      for (int y = a == 1 ? 1 : 0; y < (a == 1 ? 9 : 10); ++y) {
        const float* c = phi + ((x + 1) * B + y + 1) * B + 1;
        float* out = diff[a][x][y];
        const int z0 = a == 2 ? 1 : 0, z1 = a == 2 ? 9 : 10;
        for (int z = z0; z < z1; ++z) out[z] = 0.5f * (c[z + s2] + c[z - s2]) - c[z];
      }
  }
  const float w1 = 1.0f, w2 = float(1.0 / std::sqrt(2.0)), w3 = float(1.0 / std::sqrt(3.0));
  const float w[3][3] = {{w3, w2, w3}, {w2, w1, w2}, {w3, w2, w3}};
  for (int x = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y) {
      float acc[8] = {0, 0, 0, 0, 0, 0, 0, 0};
      for (int u = 0; u < 3; ++u)
        for (int v = 0; v < 3; ++v) {
          const float wt = w[u][v];
          // x: offsets (dy, dz) = (u - 1, v - 1); y: (dx, dz); z: (dx, dy).
          const float* fx = &diff[0][x + 1][y + u][v];
          const float* fy = &diff[1][x + u][y + 1][v];
          const float* fz = &diff[2][x + u][y + v][1];
          for (int z = 0; z < 8; ++z) acc[z] += wt * (fx[z] + fy[z] + fz[z]);
        }
      for (int z = 0; z < 8; ++z) flux[(x << 6) | (y << 3) | z] = acc[z];
    }
}

struct DerivedLeaves {
  std::vector<FloatLeaf*> flux;  ///< one slot per SDF leaf, null when nothing is stored
  std::vector<Vec3SLeaf*> gradient;
  std::vector<std::size_t> interior;  ///< interior voxel count per SDF leaf
};

/// Builds the flux grid (and the gradient grid) of `sdf`.
void derive_fields(const FloatGrid& sdf, const GradientMap& gmap, double flux_min,
                   bool store_gradient, FloatGrid::Ptr& flux_out, Vec3SGrid::Ptr& gradient_out,
                   std::size_t& interior_voxels, double& seconds_flux, double& seconds_gradient,
                   const StageMonitor& monitor) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<const FloatLeaf*> leaves;
  leaves.reserve(sdf.tree().leafCount());
  sdf.tree().getNodes(leaves);
  DerivedLeaves out;
  out.flux.assign(leaves.size(), nullptr);
  out.interior.assign(leaves.size(), 0);
  if (store_gradient) out.gradient.assign(leaves.size(), nullptr);

  const double h = gmap.voxel_size;
  const float phi_limit = float(kFluxPhiLimitVoxels * h);
  const float inv_26h = float(1.0 / (26.0 * h));
  const float fmin = float(flux_min);

  monitor.begin_part(0.75, 1.0, leaves.size());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
      [&](const tbb::blocked_range<std::size_t>& range) {
        monitor.advance(range.size());
        FloatGrid::ConstAccessor acc = sdf.getConstAccessor();
        std::vector<float> phi(kBlock * kBlock * kBlock);
        float flux[512];
        auto scratch = std::make_unique<FluxScratch>();
        for (std::size_t li = range.begin(); li < range.end(); ++li) {
          const FloatLeaf& leaf = *leaves[li];
          const Coord origin = leaf.origin();
          const float* own = leaf.buffer().data();
          // Bit loops over the mask's words: the interior is dense, and OpenVDB's mask iterators
          // cost more than the flux itself there.
          std::uint64_t on[8];
          for (int w = 0; w < 8; ++w) on[w] = leaf.getValueMask().getWord<std::uint64_t>(w);
          std::size_t interior = 0;
          bool any_near = false;  // an active voxel with phi < phi_limit
          for (int pos = 0; pos < 512; ++pos) {
            const bool active = (on[pos >> 6] >> (pos & 63)) & 1u;
            interior += active && own[pos] < 0.0f;
            any_near |= active && own[pos] < phi_limit;
          }
          FloatLeaf* flux_leaf = nullptr;
          if (any_near || store_gradient) gather_block(acc, origin, phi.data());
          auto p_at = [&](int x, int y, int z) { return phi[(x * kBlock + y) * kBlock + z]; };
          if (any_near) {
            flux_of_block(phi.data(), flux, *scratch);
            for (int w = 0; w < 8; ++w)
              for (std::uint64_t bits = on[w]; bits; bits &= bits - 1) {
                const openvdb::Index pos = openvdb::Index(64 * w + __builtin_ctzll(bits));
                if (!(own[pos] < phi_limit)) continue;
                const float f = std::clamp(flux[pos] * inv_26h, -1.0f, 1.0f);
                if (std::abs(f) < fmin) continue;
                if (!flux_leaf) flux_leaf = new FloatLeaf(origin, 0.0f, false);
                flux_leaf->setValueOn(pos, f);
              }
          }
          out.flux[li] = flux_leaf;
          out.interior[li] = interior;
          if (store_gradient) {
            auto* gl = new Vec3SLeaf(origin, openvdb::Vec3s(0.0f), false);
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
              const Coord c = it.getCoord() - origin + Coord(kPad);
              // Central differences, index units (phi difference / 2).
              const openvdb::Vec3d g(
                  0.5 * double(p_at(c[0] + 1, c[1], c[2]) - p_at(c[0] - 1, c[1], c[2])),
                  0.5 * double(p_at(c[0], c[1] + 1, c[2]) - p_at(c[0], c[1] - 1, c[2])),
                  0.5 * double(p_at(c[0], c[1], c[2] + 1) - p_at(c[0], c[1], c[2] - 1)));
              const openvdb::Vec3d w = apply_map(gmap.g, g);
              gl->setValueOn(it.pos(), openvdb::Vec3s(w));
            }
            out.gradient[li] = gl;
          }
        }
      });

  flux_out = FloatGrid::create(0.0f);
  flux_out->setTransform(sdf.transform().copy());
  flux_out->setName("flux");
  flux_out->setGridClass(openvdb::GRID_UNKNOWN);
  interior_voxels = 0;
  for (std::size_t li = 0; li < leaves.size(); ++li) {
    interior_voxels += out.interior[li];
    if (out.flux[li]) flux_out->tree().addLeaf(out.flux[li]);
  }
  seconds_flux = seconds_since(t0);
  if (store_gradient) {
    const auto t1 = std::chrono::steady_clock::now();
    gradient_out = Vec3SGrid::create(openvdb::Vec3s(0.0f));
    gradient_out->setTransform(sdf.transform().copy());
    gradient_out->setName("gradient");
    gradient_out->setGridClass(openvdb::GRID_UNKNOWN);
    gradient_out->setVectorType(openvdb::VEC_COVARIANT);
    for (Vec3SLeaf* gl : out.gradient) gradient_out->tree().addLeaf(gl);
    seconds_gradient = seconds_since(t1);
  }
}

}  // namespace

std::unique_ptr<Fields> finish_fields(FloatGrid::Ptr sdf, const FieldOptions& options,
                                      FieldStats stats, std::chrono::steady_clock::time_point t0,
                                      const StageMonitor& monitor) {
  auto impl = std::make_unique<Fields::Impl>();
  impl->gmap = gradient_map(sdf->transform());
  sdf->setName("surface");
  sdf->setGridClass(openvdb::GRID_LEVEL_SET);
  derive_fields(*sdf, impl->gmap, options.flux_min, options.store_gradient, impl->flux,
                impl->gradient, stats.interior_voxels, stats.seconds_flux, stats.seconds_gradient,
                monitor);
  impl->sdf = std::move(sdf);
  stats.voxel_size = impl->gmap.voxel_size;
  const openvdb::Coord dim = impl->sdf->evalActiveVoxelBoundingBox().dim();
  stats.dims = {dim[0], dim[1], dim[2]};
  stats.sdf_active_voxels = impl->sdf->activeVoxelCount();
  stats.flux_active_voxels = impl->flux->activeVoxelCount();
  stats.grid_bytes = impl->sdf->memUsage() + impl->flux->memUsage();
  if (impl->gradient) {
    stats.gradient_active_voxels = impl->gradient->activeVoxelCount();
    stats.grid_bytes += impl->gradient->memUsage();
  }
  stats.seconds_total = seconds_since(t0);

  auto& p = impl->parameters;
  p["vdb_shell_voxel_size"] = format_double(stats.voxel_size);
  p["vdb_shell_exterior_band_voxels"] = format_double(kExteriorBandVoxels);
  p["vdb_shell_flux_min"] = format_double(options.flux_min);
  p["vdb_shell_flux_definition"] =
      "average outward flux of grad(phi) through the 26-neighbour cube, eq. 7 / 26";
  p["vdb_shell_sdf_strategy"] = stats.strategy;
  p["vdb_shell_source"] = stats.source;
  impl->stats = std::move(stats);
  return std::make_unique<Fields>(std::move(impl));
}

}  // namespace fields_detail
}  // namespace vdb_shell

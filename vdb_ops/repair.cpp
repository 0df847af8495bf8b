// repair.cpp — repair_surface(): dilate the input's unsigned distance, flood the outside, erode
// back by a Euclidean distance transform, mesh with volumeToMesh (see repair.h).
#include "vdb_ops/repair.h"

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "core/base/errors.h"
#include "core/base/geometry.h"
#include "core/base/memory_budget.h"
#include "core/base/timer.h"
#include "core/read/load_surface.h"
#include "core/read/tidy_surface.h"
#include "core/validity/shell_checks.h"
#include "vdb_ops/fields/fields_internal.h"

namespace vdb_shell {
namespace {

using fields_detail::format_double;
using fields_detail::IndexMesh;

/// Edges of the repaired surface shorter than this many voxels are collapsed
/// (tidy_contoured_surface()): a contour's vertices crowded onto a grid point.
constexpr double kTidyEdge = 0.1;

/// The clean repaired surface `soup` (voxels of side h) without its specks (parts of less than a
/// voxel's volume) and slivers (tidy_contoured_surface()).
/// Where the edits make faces cross (a collapse in a gap thinner than the edit), the points in
/// the voxels around the crossing faces' corners are left as they were and the rest is tidied
/// again; after three such rounds, or should a defect of another kind appear, `soup` as it was.
PolygonSoup without_slivers(const PolygonSoup& soup, double h, TidyCounts& counts) {
  TidyOptions options;
  options.min_edge = kTidyEdge * h;
  options.min_part_volume = h * h * h;
  std::set<std::array<long, 3>> near;  // voxels around the crossings so far
  const auto voxel = [&](const Vec3d& p) {
    return std::array<long, 3>{static_cast<long>(std::floor(p.x / h)),
                               static_cast<long>(std::floor(p.y / h)),
                               static_cast<long>(std::floor(p.z / h))};
  };
  for (int round = 0; round < 4; ++round) {
    PolygonSoup tidied = tidy_contoured_surface(soup, options, &counts);
    if (find_surface_problems(tidied).empty()) return tidied;
    if (round == 3) break;
    SurfaceMesh mesh;
    mesh.points = tidied.points;
    for (const std::vector<std::int64_t>& f : tidied.polygons)
      mesh.triangles.push_back({static_cast<std::uint32_t>(f[0]), static_cast<std::uint32_t>(f[1]),
                                static_cast<std::uint32_t>(f[2])});
    const std::size_t known = near.size();
    for (const auto& pair : surface_self_intersections(mesh, SIZE_MAX))
      for (const std::uint32_t f : pair)
        for (const std::uint32_t v : mesh.triangles[f]) {
          const std::array<long, 3> c = voxel(mesh.points[v]);
          for (int d = 0; d < 27; ++d)
            near.insert({c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1});
        }
    if (near.size() == known) break;  // not crossings, or none new
    options.frozen.assign(soup.points.size(), 0);
    for (std::size_t i = 0; i < soup.points.size(); ++i)
      options.frozen[i] = near.count(voxel(soup.points[i])) != 0;
  }
  counts = TidyCounts{};
  return soup;
}

/// Squared Euclidean distance transform of one line (Felzenszwalb and Huttenlocher's lower
/// envelope of parabolas): f holds 0 at the sites and kFar elsewhere on entry, the squared
/// distance to the nearest site on exit; `site` (the nearest site of each entry) follows.
constexpr double kFar = 1e30;
struct LineBuffers {
  std::vector<double> f, d, z;
  std::vector<int> v;
  std::vector<std::uint32_t> site, site_out;
};
void edt_line(LineBuffers& b) {
  const int n = static_cast<int>(b.f.size());
  const auto cross = [&](int q, int p) {
    return ((b.f[q] + double(q) * q) - (b.f[p] + double(p) * p)) / (2.0 * (q - p));
  };
  int k = 0;
  b.v[0] = 0;
  b.z[0] = -std::numeric_limits<double>::infinity();
  b.z[1] = std::numeric_limits<double>::infinity();
  for (int q = 1; q < n; ++q) {
    double s = cross(q, b.v[k]);
    while (s <= b.z[k]) s = cross(q, b.v[--k]);
    ++k;
    b.v[k] = q;
    b.z[k] = s;
    b.z[k + 1] = std::numeric_limits<double>::infinity();
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (b.z[k + 1] < q) ++k;
    b.d[q] = double(q - b.v[k]) * (q - b.v[k]) + b.f[b.v[k]];
    b.site_out[q] = b.site[b.v[k]];
  }
  b.f.swap(b.d);
  b.site.swap(b.site_out);
}

/// A dense box of voxels, x fastest.
struct Dense {
  int n[3] = {0, 0, 0};
  std::size_t index(int i, int j, int k) const { return (std::size_t(k) * n[1] + j) * n[0] + i; }
  std::size_t size() const { return std::size_t(n[0]) * n[1] * n[2]; }
};

/// In place: 0 at the sites, kFar elsewhere -> squared distance (in voxels) to the nearest
/// site; `nearest` receives that site's index.
void squared_distance_transform(const Dense& box, std::vector<float>& grid,
                                std::vector<std::uint32_t>& nearest) {
  nearest.resize(grid.size());
  for (std::size_t v = 0; v < grid.size(); ++v) nearest[v] = static_cast<std::uint32_t>(v);
  const int longest = std::max({box.n[0], box.n[1], box.n[2]});
  LineBuffers b;
  b.v.resize(longest);
  b.z.resize(longest + 1);
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (auto* line : {&b.f, &b.d}) line->resize(box.n[axis]);
    for (auto* line : {&b.site, &b.site_out}) line->resize(box.n[axis]);
    int c[3];
    for (c[a2] = 0; c[a2] < box.n[a2]; ++c[a2])
      for (c[a1] = 0; c[a1] < box.n[a1]; ++c[a1]) {
        for (c[axis] = 0; c[axis] < box.n[axis]; ++c[axis]) {
          const std::size_t at = box.index(c[0], c[1], c[2]);
          b.f[c[axis]] = grid[at];
          b.site[c[axis]] = nearest[at];
        }
        edt_line(b);
        for (c[axis] = 0; c[axis] < box.n[axis]; ++c[axis]) {
          const std::size_t at = box.index(c[0], c[1], c[2]);
          grid[at] = static_cast<float>(std::min(b.f[c[axis]], kFar));
          nearest[at] = b.site[c[axis]];
        }
      }
  }
}

/// Boundary loops of the input: the connected pieces of its edges used by one polygon.
std::size_t boundary_loops(const PolygonSoup& soup) {
  std::map<std::pair<std::int64_t, std::int64_t>, int> uses;
  for (const auto& poly : soup.polygons)
    for (std::size_t k = 0; k < poly.size(); ++k) {
      std::int64_t a = poly[k], b = poly[(k + 1) % poly.size()];
      if (a > b) std::swap(a, b);
      ++uses[{a, b}];
    }
  std::map<std::int64_t, std::int64_t> parent;
  const auto find = [&](std::int64_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto& [edge, count] : uses) {
    if (count != 1) continue;
    for (const std::int64_t v : {edge.first, edge.second})
      if (!parent.count(v)) parent[v] = v;
    parent[find(edge.first)] = find(edge.second);
  }
  std::size_t loops = 0;
  for (const auto& [v, p] : parent) loops += find(v) == v;
  return loops;
}

/// The usable triangles of `input` in the index space of `xform` (polygons fanned; corners out
/// of range or not finite drop their polygon).
IndexMesh usable_triangles(const PolygonSoup& input, const openvdb::math::Transform& xform) {
  IndexMesh m;
  m.points.reserve(input.points.size());
  for (const Vec3d& p : input.points)
    m.points.emplace_back(is_finite(p) ? xform.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z))
                                       : openvdb::Vec3d(0.0));
  const std::int64_t n = static_cast<std::int64_t>(input.points.size());
  for (const auto& poly : input.polygons) {
    const bool usable =
        poly.size() >= 3 && std::all_of(poly.begin(), poly.end(), [&](std::int64_t i) {
          return i >= 0 && i < n && is_finite(input.points[static_cast<std::size_t>(i)]);
        });
    if (!usable) continue;
    for (std::size_t k = 1; k + 1 < poly.size(); ++k)
      m.triangles.emplace_back(static_cast<openvdb::Index32>(poly[0]),
                               static_cast<openvdb::Index32>(poly[k]),
                               static_cast<openvdb::Index32>(poly[k + 1]));
  }
  return m;
}

/// Trilinear samples of `grid` at world points, clamped to its background.
struct Sampler {
  const FloatGrid& grid;
  double at(const Vec3d& p) const {
    const openvdb::Vec3d index = grid.transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
    return openvdb::tools::BoxSampler::sample(grid.tree(), index);
  }
};

/// A mesh's unsigned distance (meshToVolume, `band` voxels) and its closest triangles, for exact
/// point-to-mesh distances: the nearest of the triangles closest to the 8 voxels around a point.
struct MeshDistance {
  MeshDistance(const IndexMesh& m, const openvdb::math::Transform& x, float band_voxels)
      : mesh(m), xform(x), band(band_voxels), closest(openvdb::Int32Grid::create(-1)) {
    field = fields_detail::mesh_to_volume(mesh, xform, band, band, closest.get(),
                                          openvdb::tools::UNSIGNED_DISTANCE_FIELD);
  }
  /// World units; the band's width where no triangle is that near.
  double at(const Vec3d& p) const {
    const openvdb::Vec3d q = xform.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
    const Vec3d ip{q[0], q[1], q[2]};
    const openvdb::Coord base = openvdb::Coord::floor(q);
    const openvdb::Int32Grid::ConstAccessor acc = closest->getConstAccessor();
    double best = double(band) * band;
    for (int d = 0; d < 8; ++d) {
      int id = -1;
      if (!acc.probeValue(base.offsetBy(d & 1, (d >> 1) & 1, d >> 2), id) || id < 0) continue;
      const openvdb::Vec3I& t = mesh.triangles[std::size_t(id)];
      const auto corner = [&](int k) {
        const openvdb::Vec3s& c = mesh.points[t[k]];
        return Vec3d{c[0], c[1], c[2]};
      };
      best = std::min(best, point_triangle_distance2(ip, corner(0), corner(1), corner(2)));
    }
    return std::sqrt(best) * xform.voxelSize()[0];
  }
  const IndexMesh& mesh;
  const openvdb::math::Transform& xform;
  float band;
  openvdb::Int32Grid::Ptr closest;
  FloatGrid::Ptr field;
};

}  // namespace

PolygonSoup repair_surface(const PolygonSoup& input, const RepairOptions& options,
                           const std::string& name, RepairReport& report) {
  const auto start = Clock::now();
  fields_detail::init_openvdb();
  const double h = options.voxel_size;
  if (!(h > 0.0) || !std::isfinite(h))
    throw InputError("--repair-voxel-size must be a positive length; got " + format_double(h));
  if (!(options.closing >= 1.0) || !std::isfinite(options.closing))
    throw InputError("--repair-closing must be at least 1 voxel; got " +
                     format_double(options.closing));
  BBox box;
  for (const auto& poly : input.polygons)
    for (const std::int64_t i : poly)
      if (i >= 0 && i < static_cast<std::int64_t>(input.points.size()) &&
          is_finite(input.points[static_cast<std::size_t>(i)]))
        box.expand(input.points[static_cast<std::size_t>(i)]);
  if (box.empty())
    throw InputError(name + ": nothing to repair: no polygon has three usable corners");
  const double largest = 0.25 * box.max_side() / h;
  if (options.closing > largest)
    throw InputError(name + ": --repair-closing " + format_double(options.closing) +
                     " voxels would swallow the whole model; use at most " +
                     format_double(std::floor(largest)) + " (a quarter of its longest side)");

  // The frame: voxel (0, 0, 0) `pad` voxels below the box, the dense box `pad` voxels beyond.
  const int pad = static_cast<int>(std::ceil(options.closing)) + 4;
  fields_detail::GridFrame frame;
  frame.voxel_size = h;
  Dense dense;
  for (int a = 0; a < 3; ++a) {
    frame.origin[a] = h * (std::floor(box.lo[a] / h) - pad);
    const double span = (box.hi[a] - frame.origin[a]) / h + pad + 1;
    if (!(span < 1e6)) throw InputError(name + ": the repair volume is too large for its voxels");
    dense.n[a] = static_cast<int>(std::ceil(span));
  }
  const double voxels = double(dense.n[0]) * dense.n[1] * dense.n[2];
  // Dense arrays at their peak: state, two distances and the nearest sites, 13 bytes a voxel.
  check_memory_budget("repair", static_cast<std::size_t>(voxels * 16.0) + kProgramBytes,
                      budget_bytes(options.max_memory_gb),
                      "the repair volume (" + std::to_string(dense.n[0]) + " x " +
                          std::to_string(dense.n[1]) + " x " + std::to_string(dense.n[2]) +
                          " voxels)",
                      "raise --repair-voxel-size or lower --resolution, or raise --max-memory");
  const openvdb::math::Transform::Ptr xform = fields_detail::transform_of(frame);
  const IndexMesh mesh = usable_triangles(input, *xform);
  if (mesh.triangles.empty())
    throw InputError(name + ": nothing to repair: no polygon has three usable corners");
  double largest_area = 0.0;  // in voxels^2
  for (const openvdb::Vec3I& t : mesh.triangles) {
    const openvdb::Vec3s& a = mesh.points[t[0]];
    largest_area = std::max(
        largest_area, 0.5 * double((mesh.points[t[1]] - a).cross(mesh.points[t[2]] - a).length()));
  }
  if (largest_area < 1e-6)
    throw InputError(name +
                     ": nothing to repair: every polygon has zero area (its points lie on "
                     "a line or a point)");

  // The unsigned distance to the input, `band` voxels out, in world units.
  const float band = static_cast<float>(options.closing) + 3.0f;
  const MeshDistance to_input(mesh, *xform, band);
  const FloatGrid::Ptr& udf = to_input.field;
  const float r = static_cast<float>(options.closing * h);

  // The dilated band, and the outside: what a 6-connected flood from the box's faces reaches.
  std::vector<std::uint8_t> state(dense.size(), 0);  // 1 band, 2 outside
  for (auto it = udf->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    if (*it > r || c.x() < 0 || c.y() < 0 || c.z() < 0 || c.x() >= dense.n[0] ||
        c.y() >= dense.n[1] || c.z() >= dense.n[2])
      continue;
    state[dense.index(c.x(), c.y(), c.z())] = 1;
  }
  std::vector<std::size_t> queue;
  const auto visit = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i >= dense.n[0] || j >= dense.n[1] || k >= dense.n[2]) return;
    std::uint8_t& s = state[dense.index(i, j, k)];
    if (s != 0) return;
    s = 2;
    queue.push_back(dense.index(i, j, k));
  };
  for (int k = 0; k < dense.n[2]; ++k)
    for (int j = 0; j < dense.n[1]; ++j)
      for (int i = 0; i < dense.n[0]; ++i)
        if (i == 0 || j == 0 || k == 0 || i == dense.n[0] - 1 || j == dense.n[1] - 1 ||
            k == dense.n[2] - 1)
          visit(i, j, k);
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const std::size_t at = queue[q];
    const int i = static_cast<int>(at % dense.n[0]);
    const int j = static_cast<int>(at / dense.n[0] % dense.n[1]);
    const int k = static_cast<int>(at / (std::size_t(dense.n[0]) * dense.n[1]));
    visit(i - 1, j, k), visit(i + 1, j, k), visit(i, j - 1, k), visit(i, j + 1, k);
    visit(i, j, k - 1), visit(i, j, k + 1);
  }
  std::vector<std::size_t>().swap(queue);

  // Erode by `r`: the closed solid, phi_r = r - (distance to the outside) <= 0, where that
  // distance is the outside's own distance to the band (negative) or the inside's distance to
  // the nearest outside voxel less that voxel's own distance to the band. An open sheet's
  // dilated slab (2r thick) would erode away: what erodes by r / 3 but lies more than 2r + 1
  // voxels from the core (deeper than r + 1/2) is kept too, as a slab about 4r / 3 thick.
  const float rv = static_cast<float>(options.closing), ev = rv / 3.0f;  // voxels
  std::vector<float> to_outside(dense.size());
  std::vector<std::uint32_t> nearest;
  for (std::size_t v = 0; v < to_outside.size(); ++v)
    to_outside[v] = state[v] == 2 ? 0.0f : static_cast<float>(kFar);
  squared_distance_transform(dense, to_outside, nearest);
  const openvdb::FloatGrid::ConstAccessor distance = udf->getConstAccessor();
  const float hf = static_cast<float>(h);
  // An outside voxel's own distance to the band (voxels), from the input's distance.
  const auto beyond = [&](std::size_t v) {
    const int i = static_cast<int>(v % dense.n[0]);
    const int j = static_cast<int>(v / dense.n[0] % dense.n[1]);
    const int k = static_cast<int>(v / (std::size_t(dense.n[0]) * dense.n[1]));
    return (std::min(distance.getValue(openvdb::Coord(i, j, k)), band * hf) - r) / hf;
  };
  // Voxels from the outside's boundary, negative outside; inside, the distance to the nearest
  // outside voxel less that voxel's own distance to the band (the boundary lies between them).
  for (std::size_t v = 0; v < dense.size(); ++v)
    to_outside[v] = state[v] == 2 ? -beyond(v) : std::sqrt(to_outside[v]) - beyond(nearest[v]);
  std::vector<float> to_core(dense.size());
  for (std::size_t v = 0; v < to_core.size(); ++v)
    to_core[v] = to_outside[v] >= rv + 0.5f ? 0.0f : static_cast<float>(kFar);
  squared_distance_transform(dense, to_core, nearest);
  // The signed distance, world units, the surface at 0: the closed solid and the thin parts.
  std::vector<float> phi(dense.size());
  std::size_t inside = 0;
  for (std::size_t v = 0; v < dense.size(); ++v) {
    const float closed = rv - to_outside[v];
    const float thin = std::max(ev - to_outside[v], 2.0f * rv + 1.0f - std::sqrt(to_core[v]));
    phi[v] = std::min(closed, thin) * hf;
    inside += phi[v] < 0.0f;
  }
  std::vector<float>().swap(to_core);
  std::vector<std::uint8_t>().swap(state);
  // Squared voxels to the closed solid's voxels more than a voxel deep, for the report (input
  // vertices within 4.5 voxels lie on the enclosed solid; an open sheet's slab has no such
  // voxel: its own are at most rv + 0.87 from the outside).
  std::vector<float> to_deep(dense.size());
  for (std::size_t v = 0; v < dense.size(); ++v)
    to_deep[v] = to_outside[v] >= rv + 1.0f ? 0.0f : static_cast<float>(kFar);
  std::vector<float>().swap(to_outside);
  squared_distance_transform(dense, to_deep, nearest);
  std::vector<std::uint32_t>().swap(nearest);
  if (inside == 0)
    throw InputError(name + ": nothing solid is left after closing by " +
                     format_double(options.closing) +
                     " voxels (the input is degenerate: all its points on a line or a point)");
  // Smoothed (1-2-1 along each axis) only if the mesh of the distance as it is has a defect:
  // where the closed solid and a thin part meet, a crease can fold it. Smoothing also pulls the
  // rims of thin parts in by voxels, so it is the fallback, not the rule.
  const auto smooth = [&] {
    for (int axis = 0; axis < 3; ++axis) {
      const std::size_t stride = axis == 0   ? 1
                                 : axis == 1 ? std::size_t(dense.n[0])
                                             : std::size_t(dense.n[0]) * dense.n[1];
      std::vector<float> line(dense.n[axis]);
      int c[3];
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      for (c[a2] = 0; c[a2] < dense.n[a2]; ++c[a2])
        for (c[a1] = 0; c[a1] < dense.n[a1]; ++c[a1]) {
          c[axis] = 0;
          const std::size_t first = dense.index(c[0], c[1], c[2]);
          for (int q = 0; q < dense.n[axis]; ++q) line[q] = phi[first + q * stride];
          for (int q = 1; q + 1 < dense.n[axis]; ++q)
            phi[first + q * stride] = 0.25f * (line[q - 1] + 2.0f * line[q] + line[q + 1]);
        }
    }
  };
  const auto to_grid = [&] {
    const float background = 3.0f * hf;
    FloatGrid::Ptr sdf = FloatGrid::create(background);
    sdf->setTransform(xform->copy());
    sdf->setGridClass(openvdb::GRID_LEVEL_SET);
    {
      openvdb::FloatGrid::Accessor out = sdf->getAccessor();
      for (int k = 0; k < dense.n[2]; ++k)
        for (int j = 0; j < dense.n[1]; ++j)
          for (int i = 0; i < dense.n[0]; ++i) {
            const float value = phi[dense.index(i, j, k)];
            if (std::abs(value) < background)
              out.setValue(openvdb::Coord(i, j, k), value);
            else if (value < 0.0f)
              out.setValueOff(openvdb::Coord(i, j, k), -background);
          }
    }
    return sdf;
  };
  // Meshed slightly off zero: whole-voxel distances put exact zeros on grid points, where the
  // iso-surface would collapse triangles. An adaptive mesh is mended around its defects first
  // (mesh_volume()). Should the mesh still hold one (a zero-area triangle, two faces crossing),
  // the next of a few nearby iso-values is tried, then the same at half, a quarter of the
  // adaptivity and at 0, and then all of it once the distance is smoothed.
  fields_detail::VolumeMesh meshed;
  TidyCounts tidy;
  FloatGrid::Ptr sdf;
  bool clean = false;
  std::vector<double> adaptivities = {options.adaptivity};
  if (options.adaptivity > 0)
    adaptivities.insert(adaptivities.end(), {options.adaptivity / 2, options.adaptivity / 4, 0.0});
  for (int pass = 0; pass < 2 && !clean; ++pass) {
    if (pass == 1) smooth();
    sdf = to_grid();
    for (const double adaptivity : adaptivities) {
      for (const double iso : {1e-3, 0.0137, 0.0291, -0.0113, 0.0457}) {
        meshed = fields_detail::mesh_volume(*sdf, iso * h, adaptivity);  // facing outward
        if (!find_surface_problems(meshed.soup).empty()) continue;
        clean = true;
        meshed.soup = without_slivers(meshed.soup, h, tidy);
        break;
      }
      if (clean) break;
    }
  }
  PolygonSoup soup = std::move(meshed.soup);
  std::vector<float>().swap(phi);
  if (soup.polygons.empty())
    throw InputError(name + ": the repaired solid has no surface (nothing enclosed or thick)");

  // How far the repair strays: the repaired vertices' distance to the input, and the input
  // vertices' distance to the repaired surface, except those swallowed: inside the repaired
  // surface, more than a voxel from it, and on the enclosed solid (an overlapping part, a closed
  // gap; a sheet inside its own slab counts).
  report = RepairReport{};
  report.voxel_size = h;
  report.closing = options.closing;
  report.input_faces = input.polygons.size();
  report.faces = soup.polygons.size();
  report.dropped_parts = tidy.dropped_parts;
  report.collapsed_edges = tidy.collapsed;
  report.holes_closed = boundary_loops(input);
  for (const Vec3d& p : soup.points) {
    const double d = to_input.at(p);
    report.distance_max = std::max(report.distance_max, d);
    report.distance_mean += d / static_cast<double>(soup.points.size());
  }
  IndexMesh repaired;
  for (const Vec3d& p : soup.points)
    repaired.points.emplace_back(xform->worldToIndex(openvdb::Vec3d(p.x, p.y, p.z)));
  for (const std::vector<std::int64_t>& f : soup.polygons)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      repaired.triangles.emplace_back(f[0], f[k], f[k + 1]);
  const MeshDistance to_repaired(repaired, *xform, band);
  const Sampler side{*sdf};
  // Whether p lies on the enclosed solid: within 4.5 voxels of a voxel more than a voxel deep in
  // it, through one of the 8 voxels around p (a box's corner is, its nearest such voxel at most
  // sqrt(12) voxels away).
  const auto on_solid = [&](const Vec3d& p) {
    const openvdb::Vec3d ip = xform->worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
    const openvdb::Coord base = openvdb::Coord::floor(ip);
    for (int d = 0; d < 8; ++d) {
      const openvdb::Coord c = base.offsetBy(d & 1, (d >> 1) & 1, d >> 2);
      if (c.x() < 0 || c.y() < 0 || c.z() < 0 || c.x() >= dense.n[0] || c.y() >= dense.n[1] ||
          c.z() >= dense.n[2])
        continue;
      if (std::sqrt(to_deep[dense.index(c.x(), c.y(), c.z())]) + (c.asVec3d() - ip).length() <= 4.5)
        return true;
    }
    return false;
  };
  std::size_t counted = 0;
  for (const Vec3d& p : input.points) {
    if (!is_finite(p)) continue;
    const double d = to_repaired.at(p);
    const bool solid = on_solid(p);
    if (d > h && solid && side.at(p) < 0.0) continue;  // swallowed
    report.input_distance_max = std::max(report.input_distance_max, d);
    report.input_distance_mean += d;
    ++counted;
    if (!solid) continue;
    report.solid_input_distance_max = std::max(report.solid_input_distance_max, d);
    ++report.solid_input_points;
  }
  if (counted > 0) report.input_distance_mean /= static_cast<double>(counted);
  report.seconds = seconds_since(start);
  return soup;
}

}  // namespace vdb_shell

#include "core/render/sections.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "core/render/raster.h"

namespace vdb_shell {

namespace {

constexpr int kQualityClasses = 20;
constexpr double kMargin = 6;

/// Maps world points on the plane to SVG user units.
struct Frame {
  SectionAxes ax;
  double lo_u, hi_v, scale;
  void append(std::string& d, char op, const Vec3d& p) const {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%c%.1f %.1f", op, kMargin + (p[ax.u] - lo_u) * scale,
                  kMargin + (hi_v - p[ax.v]) * scale);
    d += buf;
  }
};

Vec3d crossing(const Vec3d& a, const Vec3d& b, double da, double db) {
  const double t = da / (da - db);
  return a + (b - a) * t;
}

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
}

/// The outline of `surface` on the plane as closed loops, one SVG subpath each.
std::string outline_path(const SurfaceMesh& surface, int axis, double at, const Frame& frame) {
  std::vector<double> d(surface.points.size());
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = surface.points[i][axis] - at;
  auto above = [&](std::uint32_t i) { return d[i] >= 0; };
  // Each triangle the plane cuts joins the crossings of two of its edges.
  std::vector<std::array<std::uint64_t, 2>> segments;
  for (const Triangle& t : surface.triangles) {
    std::array<std::uint64_t, 2> s{};
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (above(a) != above(b) && n < 2) s[n++] = edge_key(a, b);
    }
    if (n == 2) segments.push_back(s);
  }
  std::vector<std::uint64_t> nodes;
  for (const auto& s : segments) nodes.insert(nodes.end(), s.begin(), s.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  auto id = [&](std::uint64_t k) {
    return std::size_t(std::lower_bound(nodes.begin(), nodes.end(), k) - nodes.begin());
  };
  std::vector<std::array<std::int64_t, 2>> adj(nodes.size(), {-1, -1});
  for (const auto& s : segments) {
    const std::size_t a = id(s[0]), b = id(s[1]);
    (adj[a][0] < 0 ? adj[a][0] : adj[a][1]) = std::int64_t(b);
    (adj[b][0] < 0 ? adj[b][0] : adj[b][1]) = std::int64_t(a);
  }
  auto point = [&](std::size_t node) {
    const std::uint32_t a = std::uint32_t(nodes[node] >> 32), b = std::uint32_t(nodes[node]);
    return crossing(surface.points[a], surface.points[b], d[a], d[b]);
  };
  std::string path;
  std::vector<std::uint8_t> seen(nodes.size(), 0);
  for (std::size_t start = 0; start < nodes.size(); ++start) {
    if (seen[start]) continue;
    std::int64_t prev = -1, cur = std::int64_t(start);
    char op = 'M';
    while (cur >= 0 && !seen[cur]) {
      seen[cur] = 1;
      frame.append(path, op, point(std::size_t(cur)));
      op = 'L';
      const auto& next = adj[cur];
      const std::int64_t nxt = next[0] != prev ? next[0] : next[1];
      prev = cur;
      cur = nxt;
    }
    path += 'Z';
  }
  return path;
}

}  // namespace

SectionAxes section_axes(int axis) {
  if (axis == 0) return {1, 2};
  if (axis == 1) return {0, 2};
  return {0, 1};
}

std::string section_svg(const SurfaceMesh& surface, const TetMesh& mesh, int axis, double at,
                        const BBox& bounds, int width_px, int height_px) {
  Frame frame;
  frame.ax = section_axes(axis);
  const Vec3d extent = bounds.extent();
  const double eu = std::max(extent[frame.ax.u], 1e-30), ev = std::max(extent[frame.ax.v], 1e-30);
  frame.scale = std::min((width_px - 2 * kMargin) / eu, (height_px - 2 * kMargin) / ev);
  frame.lo_u = bounds.lo[frame.ax.u];
  frame.hi_v = bounds.hi[frame.ax.v];
  width_px = int(std::ceil(eu * frame.scale + 2 * kMargin));
  height_px = int(std::ceil(ev * frame.scale + 2 * kMargin));

  std::array<std::string, kQualityClasses> classes;
  const bool has_quality = mesh.quality.size() == mesh.tets.size();
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& tet = mesh.tets[t];
    std::array<double, 4> d;
    int n_above = 0;
    for (int k = 0; k < 4; ++k) {
      d[k] = mesh.points[tet[k]][axis] - at;
      n_above += d[k] >= 0;
    }
    if (n_above == 0 || n_above == 4) continue;
    const double q = has_quality ? mesh.quality[t] : 1.0;
    std::string& path = classes[std::clamp(int(q * kQualityClasses), 0, kQualityClasses - 1)];
    auto cut = [&](int i, int j) {
      return crossing(mesh.points[tet[i]], mesh.points[tet[j]], d[i], d[j]);
    };
    std::array<int, 4> up{}, down{};
    int nu = 0, nd = 0;
    for (int k = 0; k < 4; ++k) (d[k] >= 0 ? up[nu++] : down[nd++]) = k;
    if (nu == 2) {  // a quad: around the four crossing edges in cyclic order
      frame.append(path, 'M', cut(up[0], down[0]));
      frame.append(path, 'L', cut(up[0], down[1]));
      frame.append(path, 'L', cut(up[1], down[1]));
      frame.append(path, 'L', cut(up[1], down[0]));
    } else {  // a triangle around the lone corner
      const int lone = nu == 1 ? up[0] : down[0];
      const std::array<int, 4>& rest = nu == 1 ? down : up;
      frame.append(path, 'M', cut(lone, rest[0]));
      frame.append(path, 'L', cut(lone, rest[1]));
      frame.append(path, 'L', cut(lone, rest[2]));
    }
    path += 'Z';
  }

  const std::string outline = outline_path(surface, axis, at, frame);
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                    std::to_string(width_px) + "\" height=\"" + std::to_string(height_px) +
                    "\" viewBox=\"0 0 " + std::to_string(width_px) + " " +
                    std::to_string(height_px) + "\">\n";
  svg += "<path fill=\"" + std::string(kUncoveredColour) + "\" fill-rule=\"evenodd\" d=\"" +
         outline + "\"/>\n";
  const ColourMap& map = ColourMap::quality();
  for (int c = 0; c < kQualityClasses; ++c) {
    if (classes[c].empty()) continue;
    svg += "<path fill=\"" + hex(map((c + 0.5) / kQualityClasses)) +
           "\" stroke=\"#000\" stroke-opacity=\"0.3\" stroke-width=\"0.3\" d=\"" + classes[c] +
           "\"/>\n";
  }
  svg += "<path fill=\"none\" stroke=\"#222\" stroke-width=\"1\" d=\"" + outline + "\"/>\n</svg>";
  return svg;
}

}  // namespace vdb_shell

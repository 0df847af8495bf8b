// inner.cpp — thickness limits and welding; see inner.h.
#include "core/inner/inner.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "core/base/errors.h"
#include "core/base/grid_cell.h"

namespace vdb_shell {

Vec3d point_at_arc(const TraceResult& t, std::size_t v, double s) {
  const std::size_t first = t.offsets[v], last = first + t.end[v];
  if (s >= t.arc_length[last]) return t.samples[last];
  if (s <= 0.0) return t.samples[first];
  const auto begin = t.arc_length.begin() + static_cast<std::ptrdiff_t>(first);
  const auto end = t.arc_length.begin() + static_cast<std::ptrdiff_t>(last) + 1;
  const std::size_t i = static_cast<std::size_t>(std::upper_bound(begin, end, s) - begin) + first;
  const double a0 = t.arc_length[i - 1], a1 = t.arc_length[i];
  const double w = a1 > a0 ? (s - a0) / (a1 - a0) : 1.0;
  return t.samples[i - 1] * (1.0 - w) + t.samples[i] * w;
}

InnerVertices place_inner_vertices(const SurfaceMesh& mesh, const TraceResult& traces,
                                   const ThicknessOptions& options,
                                   const std::vector<std::uint32_t>& vertex) {
  if (!(options.max_thickness >= 0.0) || !std::isfinite(options.max_thickness))
    throw InputError("--max-thickness must be a finite length >= 0 (0: no limit)");
  if (!(options.edge_factor >= 0.0) || !std::isfinite(options.edge_factor))
    throw InputError("--thickness-edge-factor must be a finite number >= 0 (0: no limit)");
  const std::size_t n = mesh.points.size();

  std::vector<double> limit(n, INFINITY);
  if (options.max_thickness > 0.0) std::fill(limit.begin(), limit.end(), options.max_thickness);
  if (options.edge_factor > 0.0) {
    // Per vertex (copies count as their vertex): the sum and count of its incident edges.
    const auto of = [&](std::uint32_t v) { return vertex.empty() ? v : vertex[v]; };
    std::vector<double> sum(n, 0.0);
    std::vector<int> count(n, 0);
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {  // each edge is seen from both of its faces: halves cancel
        const double l = distance(mesh.points[t[k]], mesh.points[t[(k + 1) % 3]]);
        sum[of(t[k])] += l;
        sum[of(t[(k + 1) % 3])] += l;
        count[of(t[k])] += 1;
        count[of(t[(k + 1) % 3])] += 1;
      }
    for (std::uint32_t v = 0; v < n; ++v)
      if (count[of(v)])
        limit[v] = std::min(limit[v], options.edge_factor * sum[of(v)] / count[of(v)]);
  }

  InnerVertices out;
  out.limit = limit;
  out.arc.resize(n);
  std::vector<Vec3d> ends(n);
  for (std::size_t v = 0; v < n; ++v) {
    const double full = traces.end_arc(v);
    out.arc[v] = std::min(full, limit[v]);
    if (out.arc[v] < full) ++out.limited;
    ends[v] = point_at_arc(traces, v, out.arc[v]);
  }

  const double tol =
      options.weld_tolerance < 0.0 ? 0.5 * traces.parameters.point_size : options.weld_tolerance;
  std::vector<char> weldable(n);
  for (std::size_t v = 0; v < n; ++v)
    weldable[v] = out.arc[v] > 0.0 && out.arc[v] >= traces.end_arc(v);
  // Greedy, in vertex order: a weldable end joins the smallest earlier representative within
  // `tol`, or becomes one. Only representatives are indexed (cells of side `tol`, each listing
  // its representatives in increasing order): where thousands of traces end together, a query
  // meets the few representatives there, not every end.
  std::vector<std::uint32_t> rep(n);
  for (std::uint32_t v = 0; v < n; ++v) rep[v] = v;
  if (tol > 0.0 && n > 0) {
    std::unordered_map<GridCell, std::vector<std::uint32_t>, GridCellHash> reps;
    const double tol2 = tol * tol;
    for (std::uint32_t v = 0; v < n; ++v) {
      // Only trace ends weld: not the surface itself, and not points a thickness limit placed
      // mid-trace (welding could carry them past their limit).
      if (!weldable[v]) continue;
      const GridCell c(ends[v], tol);
      std::uint32_t best = v;
      for (std::int64_t i = c.i - 1; i <= c.i + 1; ++i)
        for (std::int64_t j = c.j - 1; j <= c.j + 1; ++j)
          for (std::int64_t k = c.k - 1; k <= c.k + 1; ++k) {
            const auto it = reps.find(GridCell(i, j, k));
            if (it == reps.end()) continue;
            for (const std::uint32_t u : it->second) {
              if (u >= best) break;
              // Within the weld distance, and not carrying v past its thickness limit.
              if (norm2(ends[u] - ends[v]) <= tol2 &&
                  distance(ends[u], mesh.points[v]) <= limit[v]) {
                best = u;
                break;
              }
            }
          }
      if (best != v) {
        rep[v] = best;
        ++out.welded;
      } else {
        reps[c].push_back(v);
      }
    }
  }
  out.input.inner_id.assign(n, 0);
  std::vector<std::uint32_t> compact(n, UINT32_MAX);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (rep[v] == v) {
      compact[v] = static_cast<std::uint32_t>(out.input.inner_points.size());
      out.input.inner_points.push_back(ends[v]);
    }
    out.input.inner_id[v] = compact[rep[v]];
  }
  return out;
}

}  // namespace vdb_shell

// assemble.cpp — see assemble.h.
#include "core/assemble/assemble.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/assemble/quality.h"
#include "core/base/errors.h"
#include "core/base/timer.h"

namespace vdb_shell {
namespace {

using LocalTet = std::array<int, 4>;  // corners of the prism: 0, 1, 2 outer; 3, 4, 5 inner
using LocalSplit = std::array<LocalTet, 3>;

// splits[m][cut]: the split when corner m has the smallest index; cut 0 cuts the third quad
// along V2-V6, cut 1 along V3-V5. Every tet listed in positive order.
struct SplitTable {
  LocalSplit splits[6][2];
};

// Corner positions of the reference right prism: the outer triangle counter-clockwise seen
// from +z (outside), the inner one a unit below it (inside).
constexpr Vec3d kReferenceCorner[6] = {{0, 0, 0},  {1, 0, 0},  {0, 1, 0},
                                       {0, 0, -1}, {1, 0, -1}, {0, 1, -1}};

// Corner V(i+1) of the prism whose smallest corner is m: the prism symmetry taking m to V1 is a
// rotation of the triangles, plus the exchange of outer and inner triangle when m is inner.
int corner_role(int m, int i) {
  const int r = m % 3;
  const int top = m < 3 ? 0 : 3;
  return (i < 3 ? top : 3 - top) + (r + i) % 3;
}

// The orientation of a tet follows from its place in the prism alone: its sign in the
// reference prism. Swapping the last two corners turns a negative order positive.
LocalTet oriented(LocalTet t) {
  const double v = tet_volume(kReferenceCorner[t[0]], kReferenceCorner[t[1]],
                              kReferenceCorner[t[2]], kReferenceCorner[t[3]]);
  if (v < 0.0) std::swap(t[2], t[3]);
  return t;
}

SplitTable make_split_table() {
  SplitTable table{};
  for (int m = 0; m < 6; ++m) {
    int v[6];  // v[i] is corner V(i+1) of assemble.h
    for (int i = 0; i < 6; ++i) v[i] = corner_role(m, i);
    table.splits[m][0] = {oriented({v[0], v[1], v[2], v[5]}), oriented({v[0], v[1], v[5], v[4]}),
                          oriented({v[0], v[4], v[5], v[3]})};
    table.splits[m][1] = {oriented({v[0], v[1], v[2], v[4]}), oriented({v[0], v[4], v[2], v[5]}),
                          oriented({v[0], v[4], v[5], v[3]})};
  }
  return table;
}

const SplitTable& split_table() {
  static const SplitTable table = make_split_table();
  return table;
}

// The tets of split_table().splits[m][cut] with the corners `ids`, without those with a repeated
// index.
PrismTets split_from_table(const std::array<std::uint32_t, 6>& ids, int m, int cut) {
  PrismTets out;
  for (const LocalTet& lt : split_table().splits[m][cut]) {
    const Tet t = {ids[lt[0]], ids[lt[1]], ids[lt[2]], ids[lt[3]]};
    const bool distinct = t[0] != t[1] && t[0] != t[2] && t[0] != t[3] && t[1] != t[2] &&
                          t[1] != t[3] && t[2] != t[3];
    if (distinct)
      out.tets[out.count++] = t;
    else
      ++out.dropped;
  }
  return out;
}

}  // namespace

PrismTets split_prism(const std::array<std::uint32_t, 6>& ids) {
  int m = 0;
  for (int k = 1; k < 6; ++k)
    if (ids[k] < ids[m]) m = k;
  const std::uint32_t v2 = ids[corner_role(m, 1)], v3 = ids[corner_role(m, 2)];
  const std::uint32_t v5 = ids[corner_role(m, 4)], v6 = ids[corner_role(m, 5)];
  return split_from_table(ids, m, std::min(v2, v6) < std::min(v3, v5) ? 0 : 1);
}

int prism_cuts(const std::array<std::uint32_t, 6>& ids) {
  int cuts = 0;
  for (int i = 0; i < 3; ++i) {  // the quad is cut through its smallest corner
    const int j = (i + 1) % 3;
    if (std::min(ids[i], ids[3 + j]) < std::min(ids[j], ids[3 + i])) cuts |= 1 << i;
  }
  return cuts;
}

PrismTets split_prism_cut(const std::array<std::uint32_t, 6>& ids, int cuts) {
  const auto bit = [&](int i) { return (cuts >> ((i + 3) % 3)) & 1; };
  // V1: a corner where two cuts meet. Outer corner j is on the cut of quad j when bit j is set
  // and on that of quad j - 1 when bit j - 1 is clear; inner corner j' the other way round.
  // Two corners qualify; the smaller id, as split_prism() picks it, gives the same tet order.
  int m = -1;
  for (int j = 0; j < 3; ++j)
    if (bit(j) != bit(j - 1)) {
      const int c = bit(j) ? j : 3 + j;
      if (m < 0 || ids[c] < ids[m]) m = c;
    }
  if (m < 0)
    throw InternalError("split_prism_cut: the cuts " + std::to_string(cuts) +
                        " form a cycle; no 3-tet split follows them");
  // The third quad, (V2, V3, V6, V5), is quad (m + 1) mod 3: its bit set cuts it from outer
  // corner (m + 1) mod 3 — V2 when V1 is outer (cut 0: V2-V6), V5 when inner (cut 1: V3-V5).
  const int third = bit(m % 3 + 1);
  return split_from_table(ids, m, m < 3 ? 1 - third : third);
}

std::vector<double> layer_fractions(int layers, double ratio) {
  std::vector<double> at(static_cast<std::size_t>(layers) + 1, 0.0);
  double thickness = 1, sum = 0;  // layer k is ratio^k thick, then all are scaled to sum to 1
  for (int k = 1; k <= layers; ++k, thickness *= ratio) at[k] = sum += thickness;
  for (double& a : at) a /= sum;
  at.back() = 1.0;
  return at;
}

AssembleResult assemble_shell(const SurfaceMesh& surface, const ShellInput& input,
                              const AssembleOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n_surface = surface.points.size();
  const std::size_t n_inner = input.inner_points.size();
  const int layers = options.layers;
  if (layers < 1 || layers > kMaxLayers || !(options.layer_ratio > 0) ||
      !std::isfinite(options.layer_ratio))
    throw InputError("assemble_shell: " + std::to_string(layers) + " layers of ratio " +
                     std::to_string(options.layer_ratio) + "; give 1 to " +
                     std::to_string(kMaxLayers) + " layers and a positive ratio");
  if (input.inner_id.size() != n_surface)
    throw InputError("assemble_shell: " + std::to_string(input.inner_id.size()) +
                     " inner ids for " + std::to_string(n_surface) +
                     " surface vertices; give one inner id per surface vertex");
  if (!input.split_order.empty()) {
    std::vector<char> seen(n_surface, 0);
    for (const std::uint32_t k : input.split_order)
      if (input.split_order.size() != n_surface || k >= n_surface || std::exchange(seen[k], 1))
        throw InputError("assemble_shell: the split order is not a permutation of the " +
                         std::to_string(n_surface) + " surface vertices; give one or none");
  }
  std::size_t off_surface = 0;
  for (const std::uint32_t i : input.inner_id) off_surface += i != kOnSurface;
  const std::size_t n_points =
      first_layer_point(surface, input) + off_surface * static_cast<std::size_t>(layers - 1);
  if (n_points > std::numeric_limits<std::uint32_t>::max())
    throw InputError("assemble_shell: " + std::to_string(n_points) +
                     " points do not fit 32-bit indices");
  for (std::size_t v = 0; v < n_surface; ++v)
    if (input.inner_id[v] >= n_inner && input.inner_id[v] != kOnSurface)
      throw InputError("assemble_shell: surface vertex " + std::to_string(v) +
                       " refers to inner vertex " + std::to_string(input.inner_id[v]) +
                       ", but there are only " + std::to_string(n_inner) + " inner points");
  const std::size_t n_caps = input.cap_faces.size();
  if (input.cap_points.size() != n_caps)
    throw InputError("assemble_shell: " + std::to_string(input.cap_points.size()) +
                     " cap points for " + std::to_string(n_caps) + " cap faces; give one each");
  std::vector<std::uint32_t> cap_of(surface.triangles.size(), UINT32_MAX);
  for (std::size_t k = 0; k < n_caps; ++k) {
    const std::uint32_t f = input.cap_faces[k];
    if (f >= surface.triangles.size() || (k > 0 && f <= input.cap_faces[k - 1]))
      throw InputError("assemble_shell: cap face " + std::to_string(f) +
                       " is out of range or order; list faces once, ascending");
    for (const std::uint32_t v : surface.triangles[f])
      if (v < n_surface && input.inner_id[v] != kOnSurface)
        throw InputError("assemble_shell: cap face " + std::to_string(f) + " has vertex " +
                         std::to_string(v) +
                         " off the surface; a cap face needs all three "
                         "corners kOnSurface");
    cap_of[f] = static_cast<std::uint32_t>(k);
  }
  for (std::size_t f = 0; f < surface.triangles.size(); ++f)
    for (const std::uint32_t v : surface.triangles[f])
      if (v >= n_surface)
        throw InputError("assemble_shell: triangle " + std::to_string(f) + " refers to vertex " +
                         std::to_string(v) + ", but the surface has " + std::to_string(n_surface) +
                         " vertices");

  AssembleResult result;
  TetMesh& mesh = result.mesh;
  mesh.points = surface.points;
  mesh.points.insert(mesh.points.end(), input.inner_points.begin(), input.inner_points.end());
  mesh.points.insert(mesh.points.end(), input.cap_points.begin(), input.cap_points.end());
  mesh.inner.assign(mesh.points.size(), 0);
  std::fill(mesh.inner.begin() + static_cast<std::ptrdiff_t>(n_surface), mesh.inner.end(), 1);

  // Per point its surface vertex: surface points themselves, an inner point the smallest surface
  // vertex ending there (set below, in vertex order), a cap point its face's first corner.
  mesh.surface_vertex.assign(mesh.points.size(), UINT32_MAX);
  for (std::uint32_t v = 0; v < n_surface; ++v) mesh.surface_vertex[v] = v;
  for (std::size_t k = 0; k < n_caps; ++k)
    mesh.surface_vertex[n_surface + n_inner + k] = surface.triangles[input.cap_faces[k]][0];
  // Thickness of an inner vertex: its distance to the farthest surface vertex that ends there.
  mesh.thickness.assign(mesh.points.size(), 0.0);
  std::vector<std::uint8_t> used(n_inner, 0);
  for (std::size_t v = 0; v < n_surface; ++v) {
    const std::uint32_t i = input.inner_id[v];
    if (i == kOnSurface) {
      ++result.on_surface_vertices;
      continue;
    }
    used[i] = 1;
    std::uint32_t& owner = mesh.surface_vertex[n_surface + i];
    owner = std::min(owner, static_cast<std::uint32_t>(v));
    double& t = mesh.thickness[n_surface + i];
    t = std::max(t, distance(surface.points[v], input.inner_points[i]));
  }
  // Layer points: vertex v's layer boundary k (0 < k < layers) is layer_point[v] + k - 1.
  std::vector<std::uint32_t> layer_point(n_surface, UINT32_MAX);
  if (layers > 1) {
    const std::vector<double> at = layer_fractions(layers, options.layer_ratio);
    mesh.points.reserve(n_points);
    for (std::uint32_t v = 0; v < n_surface; ++v) {
      const std::uint32_t i = input.inner_id[v];
      if (i == kOnSurface) continue;
      layer_point[v] = static_cast<std::uint32_t>(mesh.points.size());
      const Vec3d& s = surface.points[v];
      const Vec3d edge = input.inner_points[i] - s;
      for (int k = 1; k < layers; ++k) {
        mesh.points.push_back(s + edge * at[k]);
        mesh.inner.push_back(1);
        mesh.surface_vertex.push_back(v);
        mesh.thickness.push_back(norm(edge) * at[k]);
      }
    }
  }
  const std::size_t n_used = static_cast<std::size_t>(std::count(used.begin(), used.end(), 1));
  result.welded_inner_vertices = n_surface - result.on_surface_vertices - n_used;
  result.unused_inner_points = n_inner - n_used;

  const std::size_t n_faces = surface.triangles.size();
  const std::size_t max_tets = 3 * n_faces * static_cast<std::size_t>(layers);
  mesh.tets.reserve(max_tets);
  mesh.source_triangle.reserve(max_tets);
  mesh.layer.reserve(max_tets);
  std::vector<std::uint32_t> levels(3 * static_cast<std::size_t>(layers + 1));
  // Each prism's corners split as keys, ordered as the validity search's ids (its LocalPrism):
  // o(v) for a surface vertex (its place in ShellInput::split_order, or v), n + (layers - 1)
  // o(v) + k - 1 for a layer point, layers n + the inner point's own index (the search numbers
  // its slots in the split order). Deeper boundaries have larger keys, so every layer cuts its
  // side quads from the corner the outermost one cuts them from (split_layered_prism()).
  const std::vector<std::uint32_t>& order = input.split_order;
  const auto n = static_cast<std::uint32_t>(n_surface);
  std::vector<std::uint32_t> keys(order.empty() && layers == 1 ? 0 : levels.size());
  for (std::size_t f = 0; f < n_faces; ++f) {
    const Triangle& tri = surface.triangles[f];
    const std::uint32_t a = tri[0], b = tri[1], c = tri[2];
    const auto inner = [&](std::uint32_t v) {
      const std::uint32_t i = input.inner_id[v];
      return i == kOnSurface ? v : static_cast<std::uint32_t>(n_surface + i);
    };
    if (cap_of[f] != UINT32_MAX) {  // the face and its cap point, as a prism's first tet
      const std::uint32_t x = static_cast<std::uint32_t>(n_surface + n_inner + cap_of[f]);
      mesh.tets.push_back({a, b, x, c});
      mesh.source_triangle.push_back(static_cast<std::uint32_t>(f));
      mesh.layer.push_back(1);
      mesh.thickness[x] = std::max({distance(mesh.points[x], surface.points[a]),
                                    distance(mesh.points[x], surface.points[b]),
                                    distance(mesh.points[x], surface.points[c])});
      ++result.cap_tets;
      continue;
    }
    const std::uint32_t ai = inner(a), bi = inner(b), ci = inner(c);
    if (ai == bi && bi == ci) ++result.collapsed_prisms;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = tri[c];
      levels[c] = v;
      levels[3 * layers + c] = inner(v);
      for (int k = 1; k < layers; ++k)
        levels[3 * k + c] = layer_point[v] == UINT32_MAX ? v : layer_point[v] + k - 1;
    }
    const auto emit = [&](const Tet& t, int layer) {
      mesh.tets.push_back(t);
      mesh.source_triangle.push_back(static_cast<std::uint32_t>(f));
      mesh.layer.push_back(static_cast<std::uint8_t>(layer));
    };
    int dropped = 0;
    if (keys.empty()) {  // one layer in vertex order: the points' indices are such keys
      dropped = split_layered_prism(levels.data(), layers, emit);
    } else {  // split the keys, emit the points they stand for
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = tri[c];
        const std::uint32_t i = input.inner_id[v];
        const std::uint32_t o = order.empty() ? v : order[v];
        keys[c] = o;
        keys[3 * layers + c] = i == kOnSurface ? o : inner_point_key(n, layers, i);
        for (int k = 1; k < layers; ++k)
          keys[3 * k + c] = i == kOnSurface ? o : layer_point_key(n, layers, o, k);
      }
      dropped = split_layered_prism(keys.data(), layers, [&](const Tet& key_tet, int layer) {
        Tet t;
        for (int k = 0; k < 4; ++k)
          t[k] = levels[std::find(keys.begin(), keys.end(), key_tet[k]) - keys.begin()];
        emit(t, layer);
      });
    }
    result.dropped_degenerate_tets += static_cast<std::size_t>(dropped);
  }
  if (options.compute_quality) mesh.quality = tet_qualities(mesh);
  result.seconds = seconds_since(start);
  return result;
}

}  // namespace vdb_shell

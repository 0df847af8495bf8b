#include "core/read/zero_area.h"

#include <algorithm>
#include <numeric>
#include <set>
#include <unordered_map>

namespace vdb_shell {
namespace {

std::uint64_t edge_key(std::uint32_t u, std::uint32_t v) { return std::uint64_t(u) << 32 | v; }

}  // namespace

std::optional<ZeroAreaFlips> flip_zero_area_faces(const SurfaceMesh& mesh, double min_twice_area,
                                                  const SliverFlips& slivers) {
  ZeroAreaFlips out;
  out.triangles = mesh.triangles;
  std::vector<Triangle>& tris = out.triangles;
  const auto n = static_cast<std::uint32_t>(tris.size());
  const auto is_zero = [&](std::uint32_t f) {
    const Triangle& t = tris[f];
    const Vec3d& a = mesh.points[t[0]];
    return norm(cross(mesh.points[t[1]] - a, mesh.points[t[2]] - a)) <= min_twice_area;
  };
  for (const Triangle& t : tris)
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return std::nullopt;
  std::unordered_map<std::uint64_t, std::uint32_t> face_at;  // directed edge -> its face
  face_at.reserve(3 * std::size_t(n));
  const auto set_edges = [&](std::uint32_t f) {
    for (int k = 0; k < 3; ++k) face_at[edge_key(tris[f][k], tris[f][(k + 1) % 3])] = f;
  };
  for (std::uint32_t f = 0; f < n; ++f) set_edges(f);
  std::set<Triangle> seen;  // every face a flip removed or made, corners sorted
  const auto sorted = [](Triangle t) {
    std::sort(t.begin(), t.end());
    return t;
  };

  // The flip of zero-area face f: m its corner facing the longest edge ab (the widest angle; on
  // a line, the middle one), g the face across ab, y g's third corner.
  struct Flip {
    std::uint32_t g, m, a, b, y;
  };
  const auto plan = [&](std::uint32_t f) -> std::optional<Flip> {
    const Triangle& t = tris[f];
    const std::array<Vec3d, 3> c{mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]};
    int k = 0;
    double longest = -1;
    for (int i = 0; i < 3; ++i) {
      const double l = norm2(c[(i + 2) % 3] - c[(i + 1) % 3]);
      if (l > longest) longest = l, k = i;
    }
    Flip p{0, t[k], t[(k + 1) % 3], t[(k + 2) % 3], 0};
    const auto across = face_at.find(edge_key(p.b, p.a));
    if (across == face_at.end()) return std::nullopt;  // not closed
    p.g = across->second;
    for (const std::uint32_t v : tris[p.g])
      if (v != p.a && v != p.b) p.y = v;
    return p;
  };
  // A sliver flips soundly when m lies next to ab, between its ends as seen from g (the two
  // faces made then face as g does), and not above g's plane (the flat tet would be inverted).
  // Above or below a plane: by more than slivers.tolerance, the rounding of points that lie on it.
  const auto below = [&](const Vec3d& p, const Vec3d& o, const Vec3d& n) {
    return dot(p - o, n) < -slivers.tolerance * norm(n);
  };
  const auto is_sliver = [&](std::uint32_t f) {
    if (!(slivers.max_height > 0) ||
        std::none_of(tris[f].begin(), tris[f].end(),
                     [&](std::uint32_t v) { return v < slivers.near.size() && slivers.near[v]; }))
      return false;
    const std::optional<Flip> p = plan(f);
    if (!p || p->y == p->m) return false;
    const Vec3d &a = mesh.points[p->a], &b = mesh.points[p->b], &m = mesh.points[p->m],
                &y = mesh.points[p->y];
    const double ab = norm(b - a);
    if (!(norm(cross(b - a, m - a)) <= slivers.max_height * ab)) return false;
    const Vec3d n_g = cross(a - b, y - b);
    if (!(dot(cross(a - m, y - m), n_g) > 0 && dot(cross(y - m, b - m), n_g) > 0) ||
        below(b, m, n_g))  // m above g
      return false;
    // Nor may the sliver dip below the faces across its other edges: the flat tet would reach
    // into their prisms.
    for (const auto& [u, w, far] : {std::array<std::uint32_t, 3>{p->b, p->m, p->a},
                                    std::array<std::uint32_t, 3>{p->m, p->a, p->b}}) {
      const auto h = face_at.find(edge_key(w, u));
      if (h == face_at.end()) return false;
      const Triangle& t = tris[h->second];
      const Vec3d& o = mesh.points[t[0]];
      if (below(mesh.points[far], o, cross(mesh.points[t[1]] - o, mesh.points[t[2]] - o)))
        return false;
    }
    return true;
  };
  const auto needs_flip = [&](std::uint32_t f) { return is_zero(f) || is_sliver(f); };
  std::set<std::uint32_t> pending;  // the faces to flip away, by index
  for (std::uint32_t f = 0; f < n; ++f)
    if (needs_flip(f)) pending.insert(f);
  if (pending.empty()) return out;
  out.face_of.resize(n);
  std::iota(out.face_of.begin(), out.face_of.end(), 0u);
  // A few flips per zero-area face at most: more means corners of many faces on one line,
  // flipped round and round.
  std::size_t budget = 4 * pending.size() + 16;
  while (!pending.empty()) {
    // Flips onto a neighbour with an area first: they make faces no flip made before (a fan of
    // zero-area faces on one line is flipped from the end where it meets such a face). Only
    // when there are none, one onto a zero-area neighbour.
    bool flipped = false;
    for (const bool onto_zero : {false, true}) {
      for (const std::uint32_t f : std::vector<std::uint32_t>(pending.begin(), pending.end())) {
        const bool zero = is_zero(f);
        if (!zero && !is_sliver(f)) {
          pending.erase(f);
          continue;
        }
        const std::optional<Flip> p = plan(f);
        if (!p) return std::nullopt;
        if (!onto_zero && needs_flip(p->g)) continue;
        const auto [g, m, a, b, y] = *p;
        if (y == m || face_at.count(edge_key(m, y)) || face_at.count(edge_key(y, m)))
          return std::nullopt;
        // A face that was there before would be a face of two flat tets besides its own.
        const Triangle new_f{m, a, y}, new_g{m, y, b};
        if (seen.count(sorted(new_f)) || seen.count(sorted(new_g))) continue;
        if (budget-- == 0) return std::nullopt;
        for (const Triangle& t : {tris[f], tris[g], new_f, new_g}) seen.insert(sorted(t));
        face_at.erase(edge_key(a, b));
        face_at.erase(edge_key(b, a));
        out.tets.push_back({a, b, y, m});
        out.tet_face.push_back(f);
        out.slivers += !zero;
        tris[f] = new_f;
        tris[g] = new_g;
        out.face_of[f] = out.face_of[g];
        set_edges(f);
        set_edges(g);
        for (const std::uint32_t h : {f, g})
          if (needs_flip(h)) pending.insert(h);
        flipped = true;
        if (onto_zero) break;
      }
      if (flipped) break;
    }
    if (!flipped) return std::nullopt;
    for (auto it = pending.begin(); it != pending.end();)
      it = needs_flip(*it) ? std::next(it) : pending.erase(it);
  }
  return out;
}

SurfaceMesh flipped_surface(const SurfaceMesh& mesh, const ZeroAreaFlips& flips) {
  SurfaceMesh out;
  out.points = mesh.points;
  out.triangles = flips.triangles;
  return out;
}

}  // namespace vdb_shell

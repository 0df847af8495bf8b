// sectors.cpp — folded vertices split into sectors; see sectors.h.
#include "core/inner/sectors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "core/base/errors.h"
#include "core/base/geometry.h"
#include "core/base/index_lists.h"

namespace vdb_shell {

double inward_margin(const std::vector<Vec3d>& normals, const Vec3d& d) {
  double m = std::numeric_limits<double>::infinity();
  for (const Vec3d& nf : normals) m = std::min(m, -dot(nf, d));
  return m;
}

namespace {

/// The point of the simplex `s` (1 to 4 points) nearest the origin, by trying every face of it
/// (the affine nearest point with non-negative barycentric weights; the nearest over faces).
/// Keeps in `s` the corners of the face it lies on.
Vec3d nearest_on_simplex(std::vector<Vec3d>& s) {
  const std::size_t m = s.size();
  Vec3d best;
  double best_norm = std::numeric_limits<double>::infinity();
  unsigned best_mask = 0;
  for (unsigned mask = 1; mask < (1u << m); ++mask) {
    std::vector<Vec3d> q;
    for (std::size_t i = 0; i < m; ++i)
      if (mask & (1u << i)) q.push_back(s[i]);
    // Nearest point of the affine hull: p = q0 + sum w_i (q_i - q0), G w = -(q_i - q0).q0.
    const std::size_t r = q.size() - 1;
    double g[3][3] = {}, rhs[3] = {}, w[3] = {};
    for (std::size_t i = 0; i < r; ++i) {
      for (std::size_t j = 0; j < r; ++j) g[i][j] = dot(q[i + 1] - q[0], q[j + 1] - q[0]);
      rhs[i] = -dot(q[i + 1] - q[0], q[0]);
    }
    // Cramer's rule for r <= 3.
    const auto det3 = [](const double a[3][3], std::size_t n) {
      if (n == 1) return a[0][0];
      if (n == 2) return a[0][0] * a[1][1] - a[0][1] * a[1][0];
      return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
             a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
             a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    };
    bool ok = true;
    if (r > 0) {
      const double d = det3(g, r);
      if (!(std::abs(d) > 1e-30)) continue;  // a degenerate face: its sub-faces cover it
      for (std::size_t c = 0; c < r; ++c) {
        double a[3][3] = {};
        for (std::size_t i = 0; i < r; ++i)
          for (std::size_t j = 0; j < r; ++j) a[i][j] = j == c ? rhs[i] : g[i][j];
        w[c] = det3(a, r) / d;
      }
      double sum = 0;
      for (std::size_t c = 0; c < r; ++c) {
        ok = ok && w[c] >= 0;
        sum += w[c];
      }
      ok = ok && sum <= 1;
    }
    if (!ok) continue;
    Vec3d p = q[0];
    for (std::size_t c = 0; c < r; ++c) p += (q[c + 1] - q[0]) * w[c];
    if (norm2(p) < best_norm) {
      best_norm = norm2(p);
      best = p;
      best_mask = mask;
    }
  }
  std::vector<Vec3d> kept;
  for (std::size_t i = 0; i < m; ++i)
    if (best_mask & (1u << i)) kept.push_back(s[i]);
  s = kept;
  return best;
}

}  // namespace

Vec3d most_inward_direction(const std::vector<Vec3d>& normals) {
  // max over unit d of min_i (-n_i).d is the distance from the origin to the convex hull of the
  // -n_i, reached at d = p / |p| for p the hull's point nearest the origin (when the origin is
  // outside it). p by Gilbert's algorithm: grow a simplex towards the origin, one support point
  // at a time.
  if (normals.empty()) return {};
  std::vector<Vec3d> simplex = {-normals[0]};
  Vec3d p = simplex[0];
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Vec3d* support = &normals[0];
    for (const Vec3d& n : normals)
      if (dot(-n, p) < dot(-*support, p)) support = &n;
    // p is nearest when no point lies beyond the plane through p normal to p.
    if (norm2(p) - dot(-*support, p) <= 1e-15 * std::max(norm2(p), 1e-300)) break;
    if (std::find(simplex.begin(), simplex.end(), -*support) != simplex.end()) break;
    simplex.push_back(-*support);
    p = nearest_on_simplex(simplex);
    if (simplex.size() == 4 || norm2(p) < 1e-30) return {};  // the origin is in the hull
  }
  return norm2(p) > 0 ? normalized(p) : Vec3d{};
}

namespace {

/// The fan of one vertex: its faces in cyclic order, face i = (v, a_i, b_i) with b_i = a_{i+1}.
struct Fan {
  std::uint32_t v = 0;
  std::vector<std::uint32_t> faces;
  std::vector<std::uint32_t> a, b;
  std::vector<Vec3d> normal;  ///< unit outward normal per face
};

Fan fan_of(const SurfaceMesh& mesh, std::uint32_t v, const IndexLists& faces_of) {
  Fan fan;
  fan.v = v;
  std::vector<std::uint32_t> faces(faces_of[v].begin(), faces_of[v].end());
  const auto corners = [&](std::uint32_t f) {  // (a, b) of face f seen from v
    const Triangle& t = mesh.triangles[f];
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    return std::array<std::uint32_t, 2>{t[(k + 1) % 3], t[(k + 2) % 3]};
  };
  std::uint32_t f = faces.front();  // the smallest face first: a deterministic start
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto ab = corners(f);
    fan.faces.push_back(f);
    fan.a.push_back(ab[0]);
    fan.b.push_back(ab[1]);
    fan.normal.push_back(normalized(face_normal_area(mesh, f)));
    const auto next = std::find_if(faces.begin(), faces.end(),
                                   [&](std::uint32_t g) { return corners(g)[0] == ab[1]; });
    if (next == faces.end())
      throw InternalError("split_folded_vertices: the fan of vertex " + std::to_string(v) +
                          " is not closed; the surface must be a closed 2-manifold");
    f = *next;
  }
  return fan;
}

/// The constraint keeping a sector's direction on face `side`'s side of the plane that bisects
/// the interior angle at fan edge (v, b) between faces `side` and `other` (third corners c_side,
/// c_other), as a normal for inward_margin(): -n.d > 0 on the right side.
Vec3d bisector_constraint(const SurfaceMesh& mesh, std::uint32_t v, std::uint32_t b,
                          std::uint32_t c_side, std::uint32_t c_other, const Vec3d& n_side) {
  const Vec3d p = mesh.points[v];
  const Vec3d e = normalized(mesh.points[b] - p);
  const auto across = [&](std::uint32_t c) {  // unit direction from the edge into c's face
    const Vec3d w = mesh.points[c] - p;
    return normalized(w - e * dot(w, e));
  };
  const Vec3d x = across(c_side), y = -n_side, u = across(c_other);
  double theta = std::atan2(dot(u, y), dot(u, x));  // the interior angle at the edge
  if (theta <= 0) theta += 2 * kPi;
  const Vec3d m = x * std::sin(0.5 * theta) - y * std::cos(0.5 * theta);
  return -m;
}

/// Whether the great-circle arcs (p1, p2) and (q1, q2) (unit vectors, each shorter than pi)
/// cross at a point interior to both.
bool arcs_cross(const Vec3d& p1, const Vec3d& p2, const Vec3d& q1, const Vec3d& q2) {
  const Vec3d np = cross(p1, p2), nq = cross(q1, q2);
  if (!(dot(np, q1) * dot(np, q2) < 0 && dot(nq, p1) * dot(nq, p2) < 0)) return false;
  Vec3d t = cross(np, nq);
  if (dot(t, p1 + p2) < 0) t = -t;
  return dot(t, q1 + q2) > 0;
}

/// Whether a sector's prisms, seen from v (on a small sphere around it: its link), lie inside
/// the surface: the direction d points into the solid (the fan subtends a positive solid angle
/// from a point just off v along d: the tangent cone's inside, that minus 4 pi outside), and the
/// arc from d to every corner of the sector's faces crosses no other face's arc.
bool sector_sees_its_faces(const SurfaceMesh& mesh, const Fan& fan, std::size_t first,
                           std::size_t count, const Vec3d& d) {
  const std::size_t k = fan.faces.size();
  const Vec3d p = mesh.points[fan.v];
  double shortest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < k; ++i)
    shortest = std::min(shortest, distance(p, mesh.points[fan.a[i]]));
  const Vec3d q = p + d * (1e-6 * shortest);
  double winding = 0;
  for (std::size_t i = 0; i < k; ++i)
    winding += solid_angle(q, p, mesh.points[fan.a[i]], mesh.points[fan.b[i]]);
  if (!(winding > 0))
    return false;  // outside: the solid angle of the tangent cone, - 4 pi  // the fan's winding
                   // number around q is below 1/2
  const auto link = [&](std::uint32_t x) { return normalized(mesh.points[x] - p); };
  for (std::size_t i = 0; i <= count; ++i) {
    // Corner i of the sector's chain: a of its first face, then b of each face.
    const std::uint32_t c = i == 0 ? fan.a[first] : fan.b[(first + i - 1) % k];
    for (std::size_t j = count; j < k; ++j) {  // the faces outside the sector
      const std::size_t g = (first + j) % k;
      if (fan.a[g] == c || fan.b[g] == c) continue;
      if (arcs_cross(d, link(c), link(fan.a[g]), link(fan.b[g]))) return false;
    }
  }
  return true;
}

/// The constraints keeping the inner direction of b, the far end of the boundary edge (v, b)
/// between faces f (third corner c_f, unit normal n_f; its sector's direction d_f) and g (d_g),
/// between the two sectors' half-planes around the edge: whichever way the side quads are cut,
/// the triangle (v, b, b') then stays on its own prism's side (docs/validity.md).
std::array<Vec3d, 2> between(const SurfaceMesh& mesh, std::uint32_t v, std::uint32_t b,
                             std::uint32_t c_f, const Vec3d& n_f, const Vec3d& d_f,
                             const Vec3d& d_g) {
  const Vec3d p = mesh.points[v];
  const Vec3d e = normalized(mesh.points[b] - p);
  const Vec3d w = mesh.points[c_f] - p;
  const Vec3d x = normalized(w - e * dot(w, e)), y = -n_f;
  // The unit normal of the half-plane around e through d, towards growing angles from f.
  const auto towards_g = [&](const Vec3d& d) {
    const double phi = std::atan2(dot(d, y), dot(d, x));
    return y * std::cos(phi) - x * std::sin(phi);
  };
  // -n.d > 0: beyond d_f's half-plane, and short of d_g's.
  return {-towards_g(d_f), towards_g(d_g)};
}

/// Faces [first, first + count) of the fan (cyclic) as a sector: its direction and margin.
struct SectorFit {
  Vec3d direction;
  double margin = -1;
  std::vector<Vec3d> bisectors;  ///< the constraints of its boundary edges
};

SectorFit fit_sector(const SurfaceMesh& mesh, const Fan& fan, std::size_t first,
                     std::size_t count) {
  const std::size_t k = fan.faces.size();
  std::vector<Vec3d> normals;
  for (std::size_t i = 0; i < count; ++i) normals.push_back(fan.normal[(first + i) % k]);
  SectorFit fit;
  if (count < k) {
    // Before the sector: the edge (v, a_first) between the previous face and the first one;
    // after it: the edge (v, b_last) between the last face and the next one.
    const std::size_t prev = (first + k - 1) % k, last = (first + count - 1) % k;
    const std::size_t next = (first + count) % k;
    fit.bisectors = {
        bisector_constraint(mesh, fan.v, fan.a[first], fan.b[first], fan.a[prev],
                            fan.normal[first]),
        bisector_constraint(mesh, fan.v, fan.b[last], fan.a[last], fan.b[next], fan.normal[last])};
    normals.insert(normals.end(), fit.bisectors.begin(), fit.bisectors.end());
  }
  fit.direction = most_inward_direction(normals);
  fit.margin = norm2(fit.direction) > 0 ? inward_margin(normals, fit.direction) : -1.0;
  if (count < k && fit.margin >= kSectorMargin &&
      !sector_sees_its_faces(mesh, fan, first, count, fit.direction))
    fit.margin = -1.0;
  return fit;
}

/// A run of faces of the fan as a sector.
struct Sector {
  std::size_t first = 0, count = 0;
  SectorFit fit;
};

/// Margins above this count as fully inward when sectors are chosen.
constexpr double kGoodMargin = 0.1;

/// The sectors covering the fan that give its faces the most inward directions: the largest sum,
/// over faces, of the margin of their sector's direction (capped at kGoodMargin, so that runs
/// which are inward enough merge), then the fewest sectors, then the first start. A run is a
/// sector only with a margin of kSectorMargin. Dynamic programming over every cut of the cycle.
/// Empty when no cover exists.
std::vector<Sector> best_sectors(const SurfaceMesh& mesh, const Fan& fan) {
  const std::size_t k = fan.faces.size();
  std::vector<std::vector<SectorFit>> fits(k);  // fits[first][count - 1]
  for (std::size_t first = 0; first < k; ++first)
    for (std::size_t count = 1; count < k; ++count) {
      fits[first].push_back(fit_sector(mesh, fan, first, count));
      if (fits[first].back().margin < kSectorMargin) break;  // longer runs are not tried
    }
  const auto usable = [&](std::size_t first, std::size_t count) {
    return count <= fits[first].size() && fits[first][count - 1].margin >= kSectorMargin;
  };
  struct Best {
    double score = -1;
    std::size_t sectors = 0, last = 0;  ///< the count of the run ending here
  };
  const auto better = [](double score, std::size_t sectors, const Best& than) {
    return score > than.score + 1e-12 ||
           (std::abs(score - than.score) <= 1e-12 && sectors < than.sectors);
  };
  std::vector<Sector> out;
  Best overall;
  for (std::size_t start = 0; start < k; ++start) {
    std::vector<Best> best(k + 1);  // best[j]: faces start .. start + j - 1 covered
    best[0].score = 0;
    for (std::size_t j = 1; j <= k; ++j)
      for (std::size_t count = 1; count <= j && count < k; ++count) {
        const Best& before = best[j - count];
        const std::size_t first = (start + j - count) % k;
        if (before.score < 0 || !usable(first, count)) continue;
        const double score =
            before.score +
            static_cast<double>(count) * std::min(fits[first][count - 1].margin, kGoodMargin);
        if (better(score, before.sectors + 1, best[j]))
          best[j] = {score, before.sectors + 1, count};
      }
    if (best[k].score < 0 || !better(best[k].score, best[k].sectors, overall)) continue;
    overall = best[k];
    out.clear();
    for (std::size_t j = k; j > 0; j -= best[j].last) {
      Sector sector;
      sector.count = best[j].last;
      sector.first = (start + j - sector.count) % k;
      sector.fit = fits[sector.first][sector.count - 1];
      out.insert(out.begin(), sector);
    }
  }
  return out;
}

}  // namespace

SectorSplit split_folded_vertices(const SurfaceMesh& mesh) {
  SectorSplit out;
  const auto n = static_cast<std::uint32_t>(mesh.points.size());
  IndexLists faces_of;
  faces_of.build(n, [&](const auto& emit) {
    for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
      for (std::uint32_t v : mesh.triangles[f]) emit(v, f);
  });
  std::vector<Vec3d> normals;
  // Constraints on the far end b of a boundary edge, as {b, face f, normal}: resolved to b's
  // point in the split surface once every vertex is split.
  std::vector<std::tuple<std::uint32_t, std::uint32_t, Vec3d>> far_end;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (faces_of[v].begin() == faces_of[v].end()) continue;
    normals.clear();
    Vec3d sum;
    for (const std::uint32_t f : faces_of[v]) {
      normals.push_back(normalized(face_normal_area(mesh, f)));
      sum += normals.back();
    }
    // Most vertices: the mean inward normal already has the margin (the optimum has at least
    // as much), and the exact search is not needed.
    if (norm2(sum) > 0 && inward_margin(normals, -normalized(sum)) >= kFoldMargin) continue;
    const Vec3d d = most_inward_direction(normals);
    if (norm2(d) > 0 && inward_margin(normals, d) >= kFoldMargin) continue;
    const Fan fan = fan_of(mesh, v, faces_of);
    const std::vector<Sector> sectors = best_sectors(mesh, fan);
    if (sectors.empty()) {
      out.unsplit.push_back(v);
      continue;
    }
    if (out.folded.empty()) {
      out.surface = mesh;
      out.vertex.resize(n);
      for (std::uint32_t u = 0; u < n; ++u) out.vertex[u] = u;
      out.direction.assign(n, Vec3d{});
      out.constraints.resize(n);
    }
    out.folded.push_back(v);
    out.sectors += sectors.size();
    const std::size_t k = fan.faces.size();
    for (std::size_t j = 0; j < sectors.size(); ++j) {
      const Sector& s = sectors[j];
      std::uint32_t copy = v;
      if (j > 0) {
        copy = static_cast<std::uint32_t>(out.surface.points.size());
        out.surface.points.push_back(mesh.points[v]);
        out.vertex.push_back(v);
        out.direction.emplace_back();
        out.constraints.emplace_back();
      }
      out.direction[copy] = s.fit.direction;
      out.constraints[copy] = s.fit.bisectors;
      for (std::size_t i = 0; i < s.count; ++i) {
        Triangle& t = out.surface.triangles[fan.faces[(s.first + i) % k]];
        for (std::uint32_t& c : t)
          if (c == v) c = copy;
      }
      const std::size_t last = (s.first + s.count - 1) % k, next = (last + 1) % k;
      out.boundaries.push_back({v, fan.b[last], fan.faces[last], fan.faces[next]});
      const Vec3d d_next = sectors[(j + 1) % sectors.size()].fit.direction;
      for (const Vec3d& c :
           between(mesh, v, fan.b[last], fan.a[last], fan.normal[last], s.fit.direction, d_next))
        far_end.emplace_back(fan.b[last], fan.faces[last], c);
    }
  }
  for (const auto& [b, f, c] : far_end)
    for (const std::uint32_t u : out.surface.triangles[f])
      if (out.vertex[u] == b) out.constraints[u].push_back(c);
  return out;
}

}  // namespace vdb_shell

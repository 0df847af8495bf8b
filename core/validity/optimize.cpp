#include "core/validity/optimize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/assemble/quality.h"
#include "core/base/index_lists.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {

namespace {

/// The two measures a move must not lower, of the tets around one point: the smallest
/// volume-length ratio and the smallest dihedral angle (degrees).
struct Worst {
  double quality = std::numeric_limits<double>::infinity();
  double dihedral = std::numeric_limits<double>::infinity();
  double volume = 0;  ///< of all the tets around the point
  /// Neither measure lower than `o`'s and one of them higher: the shell's smallest ratio and
  /// smallest angle can then only rise.
  bool improves_on(const Worst& o) const {
    const bool q = quality >= o.quality, d = dihedral >= o.dihedral;
    return q && d &&
           (quality > o.quality * (1 + 1e-6) + 1e-12 || dihedral > o.dihedral * (1 + 1e-6) + 1e-9);
  }
};

/// Worst of the tets `ring`.
Worst worst_of(const TetMesh& mesh, IndexLists::Range ring) {
  Worst w;
  for (const std::uint32_t t : ring) {
    const Tet& tet = mesh.tets[t];
    const Vec3d &a = mesh.points[tet[0]], &b = mesh.points[tet[1]], &c = mesh.points[tet[2]],
                &d = mesh.points[tet[3]];
    w.quality = std::min(w.quality, tet_quality(a, b, c, d));
    w.dihedral = std::min(w.dihedral, tet_min_dihedral_deg(a, b, c, d));
    w.volume += tet_volume(a, b, c, d);
  }
  return w;
}

/// The layer points of a layered shell (assemble.h): each moves with an inner point, on the
/// straight edge from its surface vertex, at a fixed fraction of it.
struct LayerPoints {
  std::vector<std::uint32_t> point, vertex;  ///< per layer point: its index, its surface vertex
  std::vector<double> at;                    ///< its fraction of the edge
  IndexLists of;                             ///< inner point -> its layer points (indices here)
};

LayerPoints layer_points(const SurfaceMesh& surface, const ShellInput& input,
                         const AssembleOptions& assemble) {
  LayerPoints lp;
  const int K = assemble.layers;
  if (K > 1) {
    const std::vector<double> at = layer_fractions(K, assemble.layer_ratio);
    auto next = static_cast<std::uint32_t>(first_layer_point(surface, input));
    for (std::uint32_t v = 0; v < surface.points.size(); ++v)
      if (input.inner_id[v] != kOnSurface)
        for (int k = 1; k < K; ++k) {
          lp.point.push_back(next++);
          lp.vertex.push_back(v);
          lp.at.push_back(at[k]);
        }
  }
  lp.of.build(input.inner_points.size(), [&](auto emit) {
    for (std::uint32_t d = 0; d < lp.point.size(); ++d) emit(input.inner_id[lp.vertex[d]], d);
  });
  return lp;
}

}  // namespace

OptimizeReport optimize_shell(const SurfaceMesh& surface, const std::vector<double>& limit,
                              ValidShell& valid, const OptimizeOptions& options) {
  OptimizeReport report;
  if (!options.enabled || !valid.checks.valid()) return report;
  const auto t0 = std::chrono::steady_clock::now();
  report.ran = true;
  TetMesh& mesh = valid.shell.mesh;
  ShellInput& input = valid.input;
  const std::uint32_t n = static_cast<std::uint32_t>(surface.points.size());
  const std::size_t n_inner = input.inner_points.size();

  // Owners: the surface vertices whose inner vertex each inner point is; incident tets; the
  // layer points moving with each inner point and the ring of tets a move changes.
  IndexLists owners, around, ring;
  owners.build(n_inner, [&](auto emit) {
    for (std::uint32_t v = 0; v < n; ++v)
      if (input.inner_id[v] != kOnSurface) emit(input.inner_id[v], v);
  });
  around.build(mesh.points.size(), [&](auto emit) {
    for (std::uint32_t t = 0; t < mesh.tets.size(); ++t)
      for (const std::uint32_t v : mesh.tets[t]) emit(v, t);
  });
  const LayerPoints layer = layer_points(surface, input, valid.assemble);
  {
    std::vector<std::uint32_t> tets;
    ring.build(n_inner, [&](auto emit) {
      for (std::uint32_t i = 0; i < n_inner; ++i) {
        tets.assign(around[n + i].begin(), around[n + i].end());
        for (const std::uint32_t d : layer.of[i])
          tets.insert(tets.end(), around[layer.point[d]].begin(), around[layer.point[d]].end());
        std::sort(tets.begin(), tets.end());
        tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
        for (const std::uint32_t t : tets) emit(i, t);
      }
    });
  }
  // Inner point i at `at`, its layer points with it.
  const auto place = [&](std::uint32_t i, const Vec3d& at) {
    mesh.points[n + i] = at;
    for (const std::uint32_t d : layer.of[i]) {
      const Vec3d& s = surface.points[layer.vertex[d]];
      mesh.points[layer.point[d]] = s + (at - s) * layer.at[d];
    }
  };

  ShellCheckOptions check_options;
  check_options.max_listed = std::numeric_limits<std::size_t>::max();
  check_options.layers = valid.assemble.layers;
  ShellChecker checker(surface, check_options);
  ShellCheckResult checks = checker.check(mesh);
  ++report.checks;
  if (!checks.valid()) return report;  // cannot happen for a valid shell; leave it as it is

  const std::vector<Vec3d> start(mesh.points.begin(), mesh.points.end());
  std::vector<std::uint8_t> frozen(n_inner, 0);
  std::vector<std::uint32_t> moved;
  std::vector<Vec3d> before;  // position of moved[k] before this sweep
  constexpr double kSteps[] = {1.0, 0.5, 0.25};
  // Volume the moves may lose in all (gains are not counted back, and undoing a move only gives
  // back what it lost): the coverage falls by at most options.max_coverage_loss.
  const double budget = options.max_coverage_loss * std::max(0.0, signed_volume(surface));
  double spent = 0;

  std::vector<std::uint32_t> order(n_inner);
  std::vector<Worst> worst_before(n_inner);
  std::vector<std::uint8_t> taken(mesh.points.size());
  for (int sweep = 0; sweep < options.sweeps; ++sweep) {
    moved.clear();
    before.clear();
    // The worst vertices first; a vertex moves only if no vertex moved in this sweep shares a
    // tet with it, so every tet has at most one corner moved per sweep: each move was judged
    // on the tets as they end up, and any subset of the moves can be undone exactly.
    for (std::uint32_t i = 0; i < n_inner; ++i) worst_before[i] = worst_of(mesh, ring[i]);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return worst_before[a].quality < worst_before[b].quality;
    });
    std::fill(taken.begin(), taken.end(), 0);
    for (const std::uint32_t i : order) {
      const std::uint32_t pi = n + i;
      if (frozen[i] || owners[i].size() == 0 || taken[pi] ||
          std::any_of(layer.of[i].begin(), layer.of[i].end(),
                      [&](std::uint32_t d) { return taken[layer.point[d]] != 0; }))
        continue;
      const Vec3d p = mesh.points[pi];
      const Worst& worst = worst_before[i];
      Vec3d target{};
      double weights = 0;
      for (const std::uint32_t t : around[pi]) {
        const Tet& tet = mesh.tets[t];
        const double q = tet_quality(mesh.points[tet[0]], mesh.points[tet[1]], mesh.points[tet[2]],
                                     mesh.points[tet[3]]);
        const int k = int(std::find(tet.begin(), tet.end(), pi) - tet.begin());
        const int* f = kTetOutwardFace[k];
        const Vec3d &a = mesh.points[tet[f[0]]], &b = mesh.points[tet[f[1]]],
                    &c = mesh.points[tet[f[2]]];
        const Vec3d normal = cross(b - a, c - a);  // out of the tet, away from p
        const double len = norm(normal);
        if (!(len > 0)) continue;
        const double edge = (distance(a, b) + distance(b, c) + distance(c, a)) / 3;
        const Vec3d apex = (a + b + c) / 3.0 - normal * (std::sqrt(2.0 / 3.0) * edge / len);
        const double w = 1.0 / ((std::max(q, 0.0) + 0.02) * (std::max(q, 0.0) + 0.02));
        target += apex * w;
        weights += w;
      }
      if (!(weights > 0)) continue;
      target = target / weights;
      // No move outward: the component towards the surface vertices it belongs to is dropped,
      // so the shell keeps its thickness (its coverage) there.
      Vec3d owners_at{};
      for (const std::uint32_t v : owners[i]) owners_at += surface.points[v];
      const Vec3d inward = normalized(p - owners_at / double(owners[i].size()));
      const double outward = -dot(target - p, inward);
      if (outward > 0) target += inward * outward;
      for (const double step : kSteps) {
        const Vec3d candidate = p + (target - p) * step;
        bool within = true;
        for (const std::uint32_t v : owners[i])
          if (distance(candidate, surface.points[v]) > limit[v]) within = false;
        if (!within) continue;
        place(i, candidate);
        const Worst after = worst_of(mesh, ring[i]);
        const double lost = std::max(0.0, worst.volume - after.volume);
        if (after.improves_on(worst) && spent + lost <= budget) {
          spent += lost;
          moved.push_back(i);
          before.push_back(p);
          for (const std::uint32_t t : ring[i])
            for (const std::uint32_t v : mesh.tets[t]) taken[v] = 1;
          break;
        }
        place(i, p);
      }
    }
    if (moved.empty()) break;
    // Check; move back (and freeze) the vertices of whatever offends until the shell is valid.
    for (;;) {
      checks = checker.check(mesh);
      ++report.checks;
      if (checks.valid()) break;
      std::vector<std::uint8_t> bad(mesh.points.size(), 0);
      const auto mark_tet = [&](std::uint32_t t) {
        for (const std::uint32_t v : mesh.tets[t]) bad[v] = 1;
      };
      for (const std::uint32_t t : checks.first_inverted_tets) mark_tet(t);
      for (const std::uint32_t t : checks.first_zero_volume_tets) mark_tet(t);
      for (const std::uint32_t t : checks.first_leaking_tets) mark_tet(t);
      for (const auto& pair : checks.first_overlapping_pairs) mark_tet(pair[0]), mark_tet(pair[1]);
      for (const std::uint32_t v : checks.first_outside_vertices) bad[v] = 1;
      std::size_t undone = 0;
      for (std::size_t k = 0; k < moved.size(); ++k) {
        const std::uint32_t i = moved[k];
        const bool offends =
            bad[n + i] || std::any_of(layer.of[i].begin(), layer.of[i].end(),
                                      [&](std::uint32_t d) { return bad[layer.point[d]] != 0; });
        if (!offends || mesh.points[n + i] == before[k]) continue;
        place(i, before[k]);
        frozen[i] = 1;
        ++undone;
      }
      if (undone == 0) {  // offenders among no moved vertex: undo the whole sweep
        for (std::size_t k = 0; k < moved.size(); ++k) {
          report.reverted += mesh.points[n + moved[k]] != before[k];  // not counted again
          place(moved[k], before[k]);
        }
        checks = checker.check(mesh);
        ++report.checks;
        moved.clear();
        break;
      }
      report.reverted += undone;
    }
    if (!checks.valid()) {  // cannot happen: every move undone is the shell that was valid
      std::copy(start.begin(), start.end(), mesh.points.begin());
      checks = checker.check(mesh);
      ++report.checks;
      break;
    }
    if (moved.empty()) break;
    ++report.sweeps;
  }

  for (std::uint32_t i = 0; i < n_inner; ++i) {
    const std::uint32_t pi = n + i;
    if (mesh.points[pi] == start[pi]) continue;
    ++report.moved_vertices;
    input.inner_points[i] = mesh.points[pi];
    double t = 0;
    for (const std::uint32_t v : owners[i])
      t = std::max(t, distance(surface.points[v], mesh.points[pi]));
    if (mesh.thickness.empty()) continue;
    mesh.thickness[pi] = t;
    for (const std::uint32_t d : layer.of[i])
      mesh.thickness[layer.point[d]] =
          distance(surface.points[layer.vertex[d]], mesh.points[layer.point[d]]);
  }
  mesh.quality = tet_qualities(mesh);
  valid.checks = checks;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace vdb_shell

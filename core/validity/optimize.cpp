#include "core/validity/optimize.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

#include "core/assemble/assemble.h"
#include "core/assemble/quality.h"
#include "core/base/index_lists.h"
#include "core/base/parallel.h"
#include "core/validity/shell_checks.h"

namespace vdb_shell {

namespace {

/// The two measures a move must not lower, of the tets around one point: the smallest
/// volume-length ratio and the smallest dihedral angle (degrees).
struct Worst {
  double quality = std::numeric_limits<double>::infinity();
  double dihedral = std::numeric_limits<double>::infinity();
  double volume = 0;  ///< of all the tets around the point
  /// Takes in the tets [begin, end) (indices into mesh.tets, or tets; their corner v at at(v)),
  /// stopping with false at the first tet below `o`'s smallest ratio or angle (the ratios first:
  /// the angles cost more), when improves_on(o) can no longer hold.
  template <class It, class At>
  bool add_unless_below(const TetMesh& mesh, It begin, It end, const At& at, const Worst& o) {
    const auto corners = [&](It it) {
      const Tet& tet = tet_of(mesh, *it);
      return std::array<Vec3d, 4>{at(tet[0]), at(tet[1]), at(tet[2]), at(tet[3])};
    };
    for (It it = begin; it != end; ++it) {
      const std::array<Vec3d, 4> c = corners(it);
      quality = std::min(quality, tet_quality(c[0], c[1], c[2], c[3]));
      if (quality < o.quality) return false;
      volume += tet_volume(c[0], c[1], c[2], c[3]);
    }
    for (It it = begin; it != end; ++it) {
      const std::array<Vec3d, 4> c = corners(it);
      dihedral = std::min(dihedral, tet_min_dihedral_deg(c[0], c[1], c[2], c[3]));
      if (dihedral < o.dihedral) return false;
    }
    return true;
  }
  /// Takes in all the tets [begin, end), the corners where they are.
  template <class It>
  void add(const TetMesh& mesh, It begin, It end) {
    constexpr double kLowest = -std::numeric_limits<double>::infinity();
    add_unless_below(
        mesh, begin, end, [&](std::uint32_t v) { return mesh.points[v]; },
        Worst{kLowest, kLowest, 0});
  }
  static const Tet& tet_of(const TetMesh& mesh, std::uint32_t t) { return mesh.tets[t]; }
  static const Tet& tet_of(const TetMesh&, const Tet& tet) { return tet; }
  /// Neither measure lower than `o`'s and one of them higher: the shell's smallest ratio and
  /// smallest angle can then only rise.
  bool improves_on(const Worst& o) const {
    const bool q = quality >= o.quality, d = dihedral >= o.dihedral;
    return q && d &&
           (quality > o.quality * (1 + 1e-6) + 1e-12 || dihedral > o.dihedral * (1 + 1e-6) + 1e-9);
  }
};

/// The steps a vertex tries towards its target, largest first.
constexpr int kStepCount = 3;
constexpr double kSteps[kStepCount] = {1.0, 0.5, 0.25};

/// What moving one vertex by each step would do, its tets as they are.
struct MoveTrial {
  std::array<Vec3d, kStepCount> at{};               ///< where the step takes it
  std::array<std::uint8_t, kStepCount> improves{};  ///< within the limits, and improves its tets
  std::array<double, kStepCount> lost{};            ///< volume its tets lose
};

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

/// One prism of one layer whose side quads may be cut otherwise: its six distinct corners (as
/// split_prism() takes them), their keys in assemble_shell()'s split, its cuts (assemble.h) and
/// its 3 tets, mesh.tets[first_tet, + 3).
struct CutPrism {
  std::array<std::uint32_t, 6> ids, keys;
  std::uint32_t first_tet;
  int cuts;
};

/// `split`, a split of the corners `keys`, with each key replaced by its corner's id.
PrismTets with_ids(PrismTets split, const std::array<std::uint32_t, 6>& keys,
                   const std::array<std::uint32_t, 6>& ids) {
  for (int i = 0; i < split.count; ++i)
    for (std::uint32_t& corner : split.tets[i])
      corner = ids[std::find(keys.begin(), keys.end(), corner) - keys.begin()];
  return split;
}

/// The 3 tets of `prism` cut as `cuts`, in the order assemble_shell() gives them.
PrismTets split_cut(const CutPrism& prism, int cuts) {
  return with_ids(split_prism_cut(prism.keys, cuts), prism.keys, prism.ids);
}

/// A side quad between two CutPrisms: quad side[k] of prism[k].
struct Quad {
  std::array<std::uint32_t, 2> prism;
  std::array<int, 2> side;
};

bool is_cyclic(int cuts) { return cuts == kCyclicCuts[0] || cuts == kCyclicCuts[1]; }

struct CutPrisms {
  std::vector<CutPrism> prisms;
  std::vector<Quad> quads;
};

/// The prisms of the shell `mesh` (assemble_shell() of surface and input, its layer points
/// `layer`) whose 3 tets are those of the global-index rule on six distinct corners, layer by
/// layer, and the quads two such prisms share. Prisms with welded or on-surface corners and cap
/// tets are left out, and so are the quads they touch.
CutPrisms cut_prisms(const SurfaceMesh& surface, const ShellInput& input, int layers,
                     const LayerPoints& layer, const TetMesh& mesh) {
  const std::size_t n = surface.points.size(), K = static_cast<std::size_t>(layers);
  // level[(K + 1) v + k]: vertex v's point on layer boundary k (0 the surface, K the inner one;
  // v itself at every level when it stays on the surface).
  // key: the same points' keys in assemble_shell()'s splits.
  std::vector<std::uint32_t> level((K + 1) * n), key((K + 1) * n);
  const auto nk = static_cast<std::uint32_t>(n);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t i = input.inner_id[v];
    const std::uint32_t o = input.split_order.empty() ? v : input.split_order[v];
    std::fill_n(level.begin() + std::ptrdiff_t((K + 1) * v), K + 1, v);
    std::fill_n(key.begin() + std::ptrdiff_t((K + 1) * v), K + 1, o);
    if (i == kOnSurface) continue;
    level[(K + 1) * v + K] = nk + i;
    key[(K + 1) * v + K] = inner_point_key(nk, layers, i);
    for (int k = 1; k < layers; ++k) key[(K + 1) * v + k] = layer_point_key(nk, layers, o, k);
  }
  for (std::size_t d = 0; d < layer.point.size();
       ++d)  // K - 1 in a row per vertex, outermost first
    level[(K + 1) * layer.vertex[d] + 1 + d % (K - 1)] = layer.point[d];
  std::vector<std::uint32_t> first(surface.triangles.size() + 1, 0);
  for (const std::uint32_t f : mesh.source_triangle) ++first[f + 1];
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) first[f + 1] += first[f];

  CutPrisms out;
  for (std::uint32_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& tri = surface.triangles[f];
    std::uint32_t t = first[f];
    for (std::size_t k = 0; k < K; ++k) {
      std::array<std::uint32_t, 6> ids{}, keys{};
      for (int c = 0; c < 3; ++c) {
        ids[c] = level[(K + 1) * tri[c] + k];
        ids[3 + c] = level[(K + 1) * tri[c] + k + 1];
        keys[c] = key[(K + 1) * tri[c] + k];
        keys[3 + c] = key[(K + 1) * tri[c] + k + 1];
      }
      const PrismTets split = with_ids(split_prism(keys), keys, ids);
      const auto layer_of = [&](std::uint32_t u) {
        return mesh.layer.empty() ? std::size_t(1) : std::size_t(mesh.layer[u]);
      };
      const std::uint32_t begin = t;
      while (t < first[f + 1] && layer_of(t) == k + 1) ++t;
      if (split.count != 3 || t - begin != 3 ||
          !std::equal(split.tets.begin(), split.tets.end(), mesh.tets.begin() + begin))
        continue;
      out.prisms.push_back({ids, keys, begin, prism_cuts(keys)});
    }
  }
  // The quads, found by their outer edge: (edge key, prism, side), sorted.
  std::vector<std::tuple<std::uint64_t, std::uint32_t, int>> sides;
  for (std::uint32_t p = 0; p < out.prisms.size(); ++p)
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = out.prisms[p].ids[i], b = out.prisms[p].ids[(i + 1) % 3];
      sides.emplace_back(std::uint64_t(std::min(a, b)) << 32 | std::max(a, b), p, i);
    }
  parallel_sort(sides.begin(), sides.end());  // distinct tuples: one order for any thread count
  for (std::size_t s = 0; s + 1 < sides.size(); ++s) {
    const auto& [key, p, i] = sides[s];
    const auto& [key2, q, j] = sides[s + 1];
    if (key != key2 || (s + 2 < sides.size() && std::get<0>(sides[s + 2]) == key) ||
        (s > 0 && std::get<0>(sides[s - 1]) == key))
      continue;
    // The same four corners, seen the other way round: q's corner j is p's corner i + 1.
    const auto& a = out.prisms[p].ids;
    const auto& b = out.prisms[q].ids;
    if (a[i] == b[(j + 1) % 3] && a[3 + i] == b[3 + (j + 1) % 3] && a[3 + (i + 1) % 3] == b[3 + j])
      out.quads.push_back({{p, q}, {i, j}});
  }
  return out;
}

}  // namespace

OptimizeReport optimize_shell(const SurfaceMesh& surface, const std::vector<double>& limit,
                              ValidShell& valid, const OptimizeOptions& options,
                              ShellChecker& checker) {
  OptimizeReport report;
  if (!options.enabled || !valid.checks.valid() || valid.shell.mesh.tets.empty()) return report;
  const auto t0 = std::chrono::steady_clock::now();
  report.ran = true;
  TetMesh& mesh = valid.shell.mesh;
  ShellInput& input = valid.input;
  const std::uint32_t n = static_cast<std::uint32_t>(surface.points.size());
  const std::size_t n_inner = input.inner_points.size();

  // Owners: the surface vertices whose inner vertex each inner point is; the layer points
  // moving with each inner point; the prisms whose side quads may be cut the other way.
  IndexLists owners;
  owners.build(n_inner, [&](auto emit) {
    for (std::uint32_t v = 0; v < n; ++v)
      if (input.inner_id[v] != kOnSurface) emit(input.inner_id[v], v);
  });
  const LayerPoints layer = layer_points(surface, input, valid.assemble);
  CutPrisms cp = cut_prisms(surface, input, valid.assemble.layers, layer, mesh);
  std::vector<std::int32_t> prism_of_tet(mesh.tets.size(), -1);
  for (std::uint32_t p = 0; p < cp.prisms.size(); ++p)
    for (int k = 0; k < 3; ++k) prism_of_tet[cp.prisms[p].first_tet + k] = std::int32_t(p);

  // Incident tets of every point and the ring of tets a move of each inner point changes;
  // built again after sweeps that cut quads the other way.
  IndexLists around, ring;
  const auto index_rings = [&] {
    invert_lists(
        mesh.tets.size(),
        [&](std::size_t t) {
          return std::pair{mesh.tets[t].data(), mesh.tets[t].data() + 4};
        },
        mesh.points.size(), around.start, around.items);
    ring.build_each(n_inner, [&](std::size_t i, std::vector<std::uint32_t>& tets) {
      const std::size_t at = tets.size();
      tets.insert(tets.end(), around[n + i].begin(), around[n + i].end());
      for (const std::uint32_t d : layer.of[i])
        tets.insert(tets.end(), around[layer.point[d]].begin(), around[layer.point[d]].end());
      std::sort(tets.begin() + std::ptrdiff_t(at), tets.end());
      tets.erase(std::unique(tets.begin() + std::ptrdiff_t(at), tets.end()), tets.end());
    });
  };
  // Inner point i at `at`, its layer points with it.
  const auto place = [&](std::uint32_t i, const Vec3d& at) {
    mesh.points[n + i] = at;
    for (const std::uint32_t d : layer.of[i]) {
      const Vec3d& s = surface.points[layer.vertex[d]];
      mesh.points[layer.point[d]] = s + (at - s) * layer.at[d];
    }
  };
  // Prism p cut as `cuts`; quad q cut the other way.
  const auto cut = [&](std::uint32_t p, int cuts) {
    CutPrism& prism = cp.prisms[p];
    prism.cuts = cuts;
    const PrismTets split = split_cut(prism, cuts);
    std::copy(split.tets.begin(), split.tets.end(), mesh.tets.begin() + prism.first_tet);
  };
  const auto flip = [&](const Quad& q) {
    for (int k = 0; k < 2; ++k) cut(q.prism[k], cp.prisms[q.prism[k]].cuts ^ (1 << q.side[k]));
  };
  const auto worst_of_cuts = [&](const Quad& q, const std::array<int, 2>& cuts) {
    Worst w;
    for (int k = 0; k < 2; ++k) {
      const PrismTets split = split_cut(cp.prisms[q.prism[k]], cuts[k]);
      w.add(mesh, split.tets.begin(), split.tets.end());
    }
    return w;
  };

  ShellCheckResult checks = checker.check(mesh);
  ++report.checks;
  if (!checks.valid()) return report;

  const std::vector<Vec3d> start(mesh.points.begin(), mesh.points.end());
  const std::vector<Tet> start_tets = mesh.tets;
  std::vector<std::uint8_t> frozen(n_inner, 0), frozen_quad(cp.quads.size(), 0);
  std::vector<std::uint32_t> moved, flipped;
  std::vector<Vec3d> before;  // position of moved[k] before this sweep
  // Volume the moves may lose in all (gains are not counted back, and undoing a move only gives
  // back what it lost): the coverage falls by at most options.max_coverage_loss. Cuts keep the
  // volume: the two prisms of a quad trade what one gains for what the other loses.
  const double budget = options.max_coverage_loss * std::max(0.0, signed_volume(surface));
  double spent = 0;

  std::vector<std::uint32_t> order;
  std::vector<MoveTrial> trials;
  std::vector<std::uint8_t> improves;  // per candidate quad: recutting it would improve
  std::vector<double> ring_quality(n_inner), quad_quality(cp.quads.size());
  std::vector<std::uint8_t> taken(mesh.points.size()), moved_point(mesh.points.size()),
      cut_prism(cp.prisms.size());
  bool rings_current = false;
  for (int sweep = 0; sweep < options.sweeps; ++sweep) {
    if (!rings_current) index_rings();
    rings_current = true;
    moved.clear();
    before.clear();
    flipped.clear();
    // Only what touches the worst tets takes part: those at or below the quality of rank
    // options.worst_fraction.
    const std::vector<double> quality = tet_qualities(mesh);
    std::vector<double> ranked = quality;
    const double fraction = std::clamp(options.worst_fraction, 0.0, 1.0);
    const auto rank = ranked.begin() + std::ptrdiff_t(fraction * double(ranked.size() - 1));
    std::nth_element(ranked.begin(), rank, ranked.end());
    const double threshold = *rank;

    // Moves: the worst vertices first; a vertex moves only if no vertex moved in this sweep
    // shares a tet with it, so every tet has at most one corner moved per sweep: each move was
    // judged on the tets as they end up, and any subset of the moves can be undone exactly.
    for_each_index(n_inner, [&](std::size_t i) {
      ring_quality[i] = std::numeric_limits<double>::infinity();
      for (const std::uint32_t t : ring[i]) ring_quality[i] = std::min(ring_quality[i], quality[t]);
    });
    order.clear();
    for (std::uint32_t i = 0; i < n_inner; ++i)
      if (!frozen[i] && owners[i].size() > 0 && ring_quality[i] <= threshold) order.push_back(i);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return ring_quality[a] < ring_quality[b];
    });
    // Every candidate's steps are tried in parallel on the tets as they are: a vertex that moves
    // has no tet in common with one moved before it in the sweep, so its tets are still as they
    // were, and the sequential pass below takes the same moves as trying each in turn would.
    trials.resize(order.size());
    for_each_index(order.size(), [&](std::size_t k) {
      const std::uint32_t i = order[k], pi = n + i;
      MoveTrial& trial = trials[k];
      trial = MoveTrial{};
      const Vec3d p = mesh.points[pi];
      Worst worst;
      worst.add(mesh, ring[i].begin(), ring[i].end());
      Vec3d target{};
      double weights = 0;
      for (const std::uint32_t t : around[pi]) {
        const Tet& tet = mesh.tets[t];
        const double q = quality[t];
        const int c = int(std::find(tet.begin(), tet.end(), pi) - tet.begin());
        const int* f = kTetOutwardFace[c];
        const Vec3d &a = mesh.points[tet[f[0]]], &b = mesh.points[tet[f[1]]],
                    &d = mesh.points[tet[f[2]]];
        const Vec3d normal = cross(b - a, d - a);  // out of the tet, away from p
        const double len = norm(normal);
        if (!(len > 0)) continue;
        const double edge = (distance(a, b) + distance(b, d) + distance(d, a)) / 3;
        const Vec3d apex = (a + b + d) / 3.0 - normal * (std::sqrt(2.0 / 3.0) * edge / len);
        const double w = 1.0 / ((std::max(q, 0.0) + 0.02) * (std::max(q, 0.0) + 0.02));
        target += apex * w;
        weights += w;
      }
      if (!(weights > 0)) return;
      target = target / weights;
      // No move outward: the component towards the surface vertices it belongs to is dropped,
      // so the shell keeps its thickness (its coverage) there.
      Vec3d owners_at{};
      for (const std::uint32_t v : owners[i]) owners_at += surface.points[v];
      const Vec3d inward = normalized(p - owners_at / double(owners[i].size()));
      const double outward = -dot(target - p, inward);
      if (outward > 0) target += inward * outward;
      for (int step = 0; step < kStepCount; ++step) {
        const Vec3d candidate = p + (target - p) * kSteps[step];
        bool within = true;
        for (const std::uint32_t v : owners[i])
          if (distance(candidate, surface.points[v]) > limit[v]) within = false;
        if (!within) continue;
        Worst after;
        const auto at = [&](std::uint32_t v) {
          if (v == pi) return candidate;
          for (const std::uint32_t d : layer.of[i])
            if (v == layer.point[d]) {
              const Vec3d& s = surface.points[layer.vertex[d]];
              return s + (candidate - s) * layer.at[d];
            }
          return mesh.points[v];
        };
        if (!after.add_unless_below(mesh, ring[i].begin(), ring[i].end(), at, worst) ||
            !after.improves_on(worst))
          continue;
        trial.at[step] = candidate;
        trial.improves[step] = 1;
        trial.lost[step] = std::max(0.0, worst.volume - after.volume);
      }
    });
    std::fill(taken.begin(), taken.end(), 0);
    std::fill(moved_point.begin(), moved_point.end(), 0);
    for (std::size_t k = 0; k < order.size(); ++k) {
      const std::uint32_t i = order[k], pi = n + i;
      if (taken[pi] || std::any_of(layer.of[i].begin(), layer.of[i].end(),
                                   [&](std::uint32_t d) { return taken[layer.point[d]] != 0; }))
        continue;
      const MoveTrial& trial = trials[k];
      for (int step = 0; step < kStepCount; ++step) {
        if (!trial.improves[step] || spent + trial.lost[step] > budget) continue;
        spent += trial.lost[step];
        moved.push_back(i);
        before.push_back(mesh.points[pi]);
        place(i, trial.at[step]);
        for (const std::uint32_t t : ring[i])
          for (const std::uint32_t v : mesh.tets[t]) taken[v] = 1;
        moved_point[pi] = 1;
        for (const std::uint32_t d : layer.of[i]) moved_point[layer.point[d]] = 1;
        break;
      }
    }

    // Cuts: the worst quads first, of prisms none of whose corners moved in this sweep and no
    // two of one prism, so each cut too was judged on the tets as they end up.
    for_each_index(cp.quads.size(), [&](std::size_t q) {
      quad_quality[q] = std::numeric_limits<double>::infinity();
      for (const std::uint32_t p : cp.quads[q].prism)
        for (int k = 0; k < 3; ++k)
          quad_quality[q] = std::min(quad_quality[q], quality[cp.prisms[p].first_tet + k]);
    });
    order.clear();
    for (std::uint32_t q = 0; q < cp.quads.size(); ++q)
      if (!frozen_quad[q] && quad_quality[q] <= threshold) order.push_back(q);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return quad_quality[a] < quad_quality[b];
    });
    // Judged in parallel on the cuts as they are (a quad recut only if neither prism was before
    // it in the sweep), taken in order after.
    const auto moved_corner = [&](std::uint32_t p) {
      const auto& ids = cp.prisms[p].ids;
      return std::any_of(ids.begin(), ids.end(), [&](std::uint32_t v) { return moved_point[v]; });
    };
    const auto other_cuts = [&](const Quad& quad) {
      return std::array<int, 2>{cp.prisms[quad.prism[0]].cuts ^ (1 << quad.side[0]),
                                cp.prisms[quad.prism[1]].cuts ^ (1 << quad.side[1])};
    };
    improves.assign(order.size(), 0);
    for_each_index(order.size(), [&](std::size_t k) {
      const Quad& quad = cp.quads[order[k]];
      const std::array<int, 2> other = other_cuts(quad);
      improves[k] = !moved_corner(quad.prism[0]) && !moved_corner(quad.prism[1]) &&
                    !is_cyclic(other[0]) && !is_cyclic(other[1]) &&
                    worst_of_cuts(quad, other)
                        .improves_on(worst_of_cuts(
                            quad, {cp.prisms[quad.prism[0]].cuts, cp.prisms[quad.prism[1]].cuts}));
    });
    std::fill(cut_prism.begin(), cut_prism.end(), 0);
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Quad& quad = cp.quads[order[k]];
      if (!improves[k] || cut_prism[quad.prism[0]] || cut_prism[quad.prism[1]]) continue;
      flip(quad);
      cut_prism[quad.prism[0]] = cut_prism[quad.prism[1]] = 1;
      flipped.push_back(order[k]);
    }
    if (moved.empty() && flipped.empty()) break;
    rings_current = flipped.empty();

    // Check; undo (and freeze) the moves and cuts of whatever offends until the shell is valid.
    for (;;) {
      checks = checker.check(mesh);
      ++report.checks;
      if (checks.valid()) break;
      std::vector<std::uint8_t> bad(mesh.points.size(), 0), bad_prism(cp.prisms.size(), 0);
      const auto mark_tet = [&](std::uint32_t t) {
        for (const std::uint32_t v : mesh.tets[t]) bad[v] = 1;
        if (prism_of_tet[t] >= 0) bad_prism[std::size_t(prism_of_tet[t])] = 1;
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
        if (!offends || frozen[i]) continue;
        place(i, before[k]);
        frozen[i] = 1;
        ++report.reverted;
        ++undone;
      }
      for (const std::uint32_t q : flipped) {
        const Quad& quad = cp.quads[q];
        if (frozen_quad[q] || !(bad_prism[quad.prism[0]] || bad_prism[quad.prism[1]])) continue;
        flip(quad);
        frozen_quad[q] = 1;
        ++report.reverted_cuts;
        ++undone;
      }
      if (undone == 0) {  // offenders among no moved vertex or cut prism: undo the whole sweep
        for (std::size_t k = 0; k < moved.size(); ++k)
          if (!frozen[moved[k]])
            place(moved[k], before[k]), frozen[moved[k]] = 1, ++report.reverted;
        for (const std::uint32_t q : flipped)
          if (!frozen_quad[q]) flip(cp.quads[q]), frozen_quad[q] = 1, ++report.reverted_cuts;
        checks = checker.check(mesh);
        ++report.checks;
        break;
      }
    }
    if (!checks.valid()) {  // cannot happen: every move and cut undone is the valid shell
      std::copy(start.begin(), start.end(), mesh.points.begin());
      mesh.tets = start_tets;
      for (CutPrism& p : cp.prisms) p.cuts = prism_cuts(p.keys);
      checks = checker.check(mesh);
      ++report.checks;
      break;
    }
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
  for (const Quad& q : cp.quads) {
    const CutPrism& p = cp.prisms[q.prism[0]];
    report.recut_quads += ((p.cuts ^ prism_cuts(p.keys)) >> q.side[0]) & 1;
  }
  mesh.quality = tet_qualities(mesh);
  valid.checks = checks;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace vdb_shell

// validity.cpp — moving inner vertices back along their traces until the shell is valid; see
// validity.h for the method and why it terminates.
#include "core/validity.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace vdb_shell {
namespace {

/// Smallest -n.d over the unit face normals `normals` (> 0: d points inward for every face).
double inward_margin(const std::vector<Vec3d>& normals, const Vec3d& d) {
  double m = std::numeric_limits<double>::infinity();
  for (const Vec3d& nf : normals) m = std::min(m, -dot(nf, d));
  return m;
}

/// The unit direction that (approximately) maximises inward_margin, by projected subgradient
/// steps from `start`; deterministic.
Vec3d most_inward_direction(const std::vector<Vec3d>& normals, Vec3d start) {
  Vec3d d = normalized(start), best = d;
  double best_margin = inward_margin(normals, d);
  for (int k = 0; k < 200 && !normals.empty(); ++k) {
    const Vec3d* worst = &normals[0];
    for (const Vec3d& nf : normals)
      if (-dot(nf, d) < -dot(*worst, d)) worst = &nf;
    d = normalized(d - *worst * (0.5 / (k + 1.0)));
    const double m = inward_margin(normals, d);
    if (m > best_margin) {
      best_margin = m;
      best = d;
    }
  }
  return best;
}

/// First directions with a smaller inward margin (sine of the angle to the nearest incident
/// face plane) are bent towards the most inward direction.
constexpr double kMinMargin = 0.1;

/// Per-vertex state of the search.
struct State {
  std::vector<double> t;        ///< current arc length; 0: on the surface (folded vertices)
  std::vector<char> welded;     ///< still sharing its start weld group's point
};

class ShellSearch {
 public:
  ShellSearch(const SurfaceMesh& surface, const TraceResult& traces, const InnerVertices& start,
              const ValidityOptions& options)
      : surface_(surface), traces_(traces), start_(start) {
    const std::size_t n = surface.points.size();
    full_.resize(n);
    floor_.assign(n, std::numeric_limits<double>::infinity());
    fallback_.resize(n);
    std::vector<Vec3d> normal(n);
    for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
      const Triangle& tri = surface.triangles[f];
      const Vec3d nf = face_normal_area(surface, f);
      for (int k = 0; k < 3; ++k) {
        normal[tri[k]] += nf;
        const double l = distance(surface.points[tri[k]], surface.points[tri[(k + 1) % 3]]);
        floor_[tri[k]] = std::min(floor_[tri[k]], l);
        floor_[tri[(k + 1) % 3]] = std::min(floor_[tri[(k + 1) % 3]], l);
      }
    }
    group_size_.assign(n, 0);
    for (std::size_t v = 0; v < n; ++v) ++group_size_[start.input.inner_id[v]];
    std::vector<std::vector<Vec3d>> face_normals(n);
    for (std::size_t f = 0; f < surface.triangles.size(); ++f)
      for (std::uint32_t v : surface.triangles[f])
        face_normals[v].push_back(normalized(face_normal_area(surface, f)));
    correction_.assign(n, Vec3d{});
    for (std::size_t v = 0; v < n; ++v) {
      floor_[v] *= options.floor_fraction;
      full_[v] = std::max(start.arc[v], floor_[v]);
      // Beyond the trace's end (only for traces shorter than the floor): continue straight
      // along its first step, or inward along the vertex normal for a trace that never moved.
      fallback_[v] = traces.end[v] > 0 ? normalized(traces.sample(v, 1) - traces.sample(v, 0))
                                       : -normalized(normal[v]);
      // The first direction must point inward for every incident face, with a margin, or the
      // thinnest shell already folds: bend the start of such a trace (within the floor depth)
      // into the most inward direction.
      const Vec3d first = fallback_[v];
      const double margin = inward_margin(face_normals[v], first);
      if (margin >= kMinMargin) continue;
      const Vec3d safe = most_inward_direction(face_normals[v], -normalized(normal[v]));
      if (inward_margin(face_normals[v], safe) > margin) correction_[v] = safe - first;
      if (std::max(margin, inward_margin(face_normals[v], safe)) <= 0.0)
        folded_.push_back(static_cast<std::uint32_t>(v));
    }
    // Folded vertices stay on the surface, but a face needs one corner off it to keep a prism
    // (a tet): should all three of its corners be folded, its last one stays at the floor.
    std::vector<char> on_surface(n, 0);
    for (std::uint32_t v : folded_) on_surface[v] = 1;
    for (const Triangle& tri : surface.triangles)
      if (on_surface[tri[0]] && on_surface[tri[1]] && on_surface[tri[2]])
        on_surface[std::max({tri[0], tri[1], tri[2]})] = 0;
    for (std::uint32_t v : folded_)
      if (on_surface[v]) on_surface_.push_back(v);
  }

  /// Vertices whose incident faces admit no common inward direction (none found), in order.
  const std::vector<std::uint32_t>& folded() const { return folded_; }
  /// The folded vertices kept on the surface (t_v = 0), in order.
  const std::vector<std::uint32_t>& on_surface() const { return on_surface_; }

  const std::vector<double>& full() const { return full_; }
  const std::vector<double>& floor() const { return floor_; }

  State initial() const {
    State s;
    s.t = full_;
    s.welded.resize(full_.size());
    for (std::size_t v = 0; v < full_.size(); ++v)
      s.welded[v] = group_size_[start_.input.inner_id[v]] > 1 && start_.arc[v] >= floor_[v];
    for (std::uint32_t v : on_surface_) {
      s.t[v] = 0;
      s.welded[v] = 0;
    }
    return s;
  }
  State floor_state() const {
    State s{floor_, std::vector<char>(floor_.size(), 0)};
    for (std::uint32_t v : on_surface_) s.t[v] = 0;
    return s;
  }

  Vec3d position(std::size_t v, double t) const {
    const double end = traces_.end_arc(v);
    const Vec3d bend = correction_[v] * std::min(t, floor_[v]);
    if (t <= end) return point_at_arc(traces_, v, t) + bend;
    return traces_.end_point(v) + fallback_[v] * (t - end) + bend;
  }

  /// Inner vertices of `s` (slots in order of their smallest member) and each slot's members.
  ShellInput build(const State& s, std::vector<std::vector<std::uint32_t>>& members) const {
    const std::size_t n = full_.size();
    ShellInput in;
    in.inner_id.resize(n);
    members.clear();
    std::vector<std::uint32_t> group_slot(start_.input.inner_points.size(), UINT32_MAX);
    for (std::uint32_t v = 0; v < n; ++v) {
      std::uint32_t slot;
      if (s.t[v] == 0) {
        in.inner_id[v] = kOnSurface;
        continue;
      } else if (s.welded[v]) {
        const std::uint32_t g = start_.input.inner_id[v];
        if (group_slot[g] == UINT32_MAX) {
          group_slot[g] = static_cast<std::uint32_t>(in.inner_points.size());
          in.inner_points.push_back(start_.input.inner_points[g]);
          members.emplace_back();
        }
        slot = group_slot[g];
      } else {
        slot = static_cast<std::uint32_t>(in.inner_points.size());
        in.inner_points.push_back(position(v, s.t[v]));
        members.emplace_back();
      }
      in.inner_id[v] = slot;
      members[slot].push_back(v);
    }
    return in;
  }

 private:
  const SurfaceMesh& surface_;
  const TraceResult& traces_;
  const InnerVertices& start_;
  std::vector<double> full_, floor_;
  std::vector<Vec3d> fallback_, correction_;
  std::vector<std::uint32_t> group_size_;
  std::vector<std::uint32_t> folded_, on_surface_;
};

/// Offending tets and inner slots of a check.
void collect_offenders(const SurfaceMesh& surface, const ShellInput& in,
                       const ShellCheckResult& c, std::vector<std::uint32_t>& tets,
                       std::vector<std::uint32_t>& slots) {
  const std::uint32_t n = static_cast<std::uint32_t>(surface.points.size());
  tets.clear();
  slots.clear();
  tets.insert(tets.end(), c.first_inverted_tets.begin(), c.first_inverted_tets.end());
  tets.insert(tets.end(), c.first_zero_volume_tets.begin(), c.first_zero_volume_tets.end());
  tets.insert(tets.end(), c.first_leaking_tets.begin(), c.first_leaking_tets.end());
  for (const auto& pair : c.first_overlapping_pairs) {
    tets.push_back(pair[0]);
    tets.push_back(pair[1]);
  }
  for (std::uint32_t p : c.first_outside_vertices)
    if (p >= n) slots.push_back(p - n);
  for (const auto* list : {&c.first_missing_triangles, &c.first_shared_triangles,
                           &c.first_misoriented_triangles})
    for (std::uint32_t f : *list)
      for (std::uint32_t v : surface.triangles[f])
        if (in.inner_id[v] != kOnSurface) slots.push_back(in.inner_id[v]);
  std::sort(tets.begin(), tets.end());
  tets.erase(std::unique(tets.begin(), tets.end()), tets.end());
}

}  // namespace

ValidShell make_valid_shell(const SurfaceMesh& surface, const TraceResult& traces,
                            const InnerVertices& start, const ValidityOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint32_t n = static_cast<std::uint32_t>(surface.points.size());
  ShellSearch search(surface, traces, start, options);
  ValidShell out;
  std::vector<std::vector<std::uint32_t>> members;
  AssembleOptions no_quality;
  no_quality.compute_quality = false;

  ShellCheckOptions check_options;
  check_options.max_listed = std::numeric_limits<std::size_t>::max();
  ShellChecker checker(surface, check_options);
  // Inverted tets first: they are found in O(T) and a shell with any is not worth the rest.
  auto check = [&](const TetMesh& mesh) {
    ShellCheckResult volumes = check_volumes(mesh, check_options);
    if (!volumes.valid()) return volumes;
    ++out.checks_run;
    return checker.check(mesh);
  };

  State s = search.initial();
  std::vector<std::uint32_t> bad_tets, bad_slots;
  std::vector<char> lowered(n);
  for (;; ++out.rounds) {
    out.input = search.build(s, members);
    out.shell = assemble_shell(surface, out.input, no_quality);
    out.checks = check(out.shell.mesh);
    if (out.checks.valid() || out.rounds >= options.max_rounds) break;
    collect_offenders(surface, out.input, out.checks, bad_tets, bad_slots);
    std::fill(lowered.begin(), lowered.end(), 0);
    bool progress = false;
    auto slot_depth = [&](std::uint32_t slot) {
      double d = 0;
      for (std::uint32_t v : members[slot])
        if (s.welded[v] || s.t[v] > search.floor()[v]) d = std::max(d, s.t[v]);
      return d;  // 0: every member at its floor, nothing to move
    };
    auto lower = [&](std::uint32_t slot) {
      for (std::uint32_t v : members[slot]) {
        if (lowered[v]) continue;
        lowered[v] = 1;
        if (s.welded[v]) {
          s.welded[v] = 0;
          ++out.unwelded;
        } else {
          s.t[v] = std::max(search.floor()[v], s.t[v] * options.shrink);
        }
        progress = true;
      }
    };
    for (std::uint32_t t : bad_tets) {
      std::uint32_t best = UINT32_MAX;
      double best_depth = 0;
      for (std::uint32_t p : out.shell.mesh.tets[t]) {
        if (p < n) continue;
        const double d = slot_depth(p - n);
        if (d > best_depth) {
          best_depth = d;
          best = p - n;
        }
      }
      if (best != UINT32_MAX) lower(best);
    }
    for (std::uint32_t slot : bad_slots)
      if (slot_depth(slot) > 0) lower(slot);
    if (!progress) {
      // Only elements at the floor offend: the floor configuration itself must be invalid.
      const ShellInput in = search.build(search.floor_state(), members);
      const ShellCheckResult c = check_shell(surface, assemble_shell(surface, in, no_quality).mesh);
      out.floor_valid = c.valid();
      if (!out.floor_valid) out.floor_problems = describe_problems(c);
      out.folded_vertices = search.folded();
      break;
    }
  }

  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // The incremental checks trusted unchanged tets; the result carries one full check (the
  // confirmation every run gets, valid search or not: out.checks.seconds, not out.seconds).
  out.shell = assemble_shell(surface, out.input);  // with quality for the report and writers
  {
    ShellCheckOptions o;
    out.checks = check_shell(surface, out.shell.mesh, o);
  }
  out.depth = s.t;
  out.on_surface = search.on_surface();
  double sum = 0;
  for (std::uint32_t v = 0; v < n; ++v)
    if (!s.welded[v] && s.t[v] < search.full()[v] * (1.0 - 1e-12)) {
      ++out.moved_back;
      sum += (search.full()[v] - s.t[v]) / search.full()[v];
    }
  out.moved_back_mean = out.moved_back ? sum / static_cast<double>(out.moved_back) : 0.0;
  ++out.checks_run;  // the final full check
  return out;
}

}  // namespace vdb_shell

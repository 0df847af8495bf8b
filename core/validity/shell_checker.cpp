// shell_checker.cpp — ShellChecker (shell_checks.h): check_shell()'s checks, repeated on shells
// that change a few prisms at a time.
//
// One BroadPhase (tet_grid.h) over the surface's box, grown to hold the first shell, is built at
// the first call, with the surface triangles entered once and tet k of prism f entered under the
// key P f + k, P = 3 * ShellCheckOptions::layers the most tets of a prism (a prism is one group of
// the phase). A call moves the tets of
// the prisms that changed and runs the narrow phase (tet_intersections.h) for the "dirty" prisms —
// changed since the previous call, or offending in it — only; every other pair is trusted: both its
// tets are where they were when the pair was last tested, and it passed. The element checks are
// check_shell()'s (check_steps.h), with two caches: the boundary faces (BoundaryFaces: those of the
// tets whose vertex indices changed are looked up again), and whether each distinct inner point
// position is outside.
#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "core/assemble/assemble.h"
#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/base/timer.h"
#include "core/validity/check_steps.h"
#include "core/validity/inside_test.h"
#include "core/validity/shell_checks.h"
#include "core/validity/tet_grid.h"
#include "core/validity/tet_intersections.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// Per prism f (its source triangle): its first tet in the mesh, first[f]; first[F] = T.
// \throw InputError unless the tets are grouped by source triangle in order, at most
//        `per_prism` each.
std::vector<std::uint32_t> prism_starts(const TetMesh& mesh, std::size_t n_faces,
                                        std::uint32_t per_prism) {
  const std::size_t n = mesh.tets.size();
  if (mesh.source_triangle.size() != n)
    throw InputError(
        "ShellChecker: the tet mesh has no source triangle per tet; pass an "
        "assemble_shell() result");
  std::vector<std::uint32_t> first(n_faces + 1, 0);
  for (std::size_t t = 0; t < n; ++t) {
    const std::uint32_t f = mesh.source_triangle[t];
    if (f >= n_faces || (t > 0 && f < mesh.source_triangle[t - 1]))
      throw InputError("ShellChecker: tet " + std::to_string(t) + " has source triangle " +
                       std::to_string(f) +
                       " out of order or range; pass an assemble_shell() result");
    ++first[f + 1];
  }
  for (std::size_t f = 0; f < n_faces; ++f) {
    if (first[f + 1] > per_prism)
      throw InputError("ShellChecker: triangle " + std::to_string(f) + " has more than " +
                       std::to_string(per_prism) +
                       " tets; pass an assemble_shell() result of as many layers as "
                       "ShellCheckOptions::layers");
    first[f + 1] += first[f];
  }
  return first;
}

}  // namespace

struct ShellChecker::Impl {
  Impl(const SurfaceMesh& s, const ShellCheckOptions& o)
      : surface(s),
        options(o),
        per_prism(3 * static_cast<std::uint32_t>(o.layers)),
        inside(s, on_surface_distance(s, o)),
        tet_count(s.triangles.size(), 0),
        offended(s.triangles.size(), 0),
        faces(s) {
    if (o.layers < 1 || o.layers > kMaxLayers ||
        std::uint64_t(per_prism) * s.triangles.size() > UINT32_MAX)
      throw InputError("ShellChecker: " + std::to_string(o.layers) + " layers of " +
                       std::to_string(s.triangles.size()) + " prisms; give 1 to " +
                       std::to_string(kMaxLayers) + " layers and fewer than " +
                       std::to_string(UINT32_MAX / std::max<std::uint32_t>(per_prism, 3)) +
                       " triangles");
  }

  const SurfaceMesh& surface;
  ShellCheckOptions options;
  std::uint32_t per_prism;  // P: the most tets of a prism
  InsideTester inside;
  std::unique_ptr<BroadPhase> phase;    // from the first call on
  std::vector<std::uint8_t> tet_count;  // per prism: its tets in `phase`
  std::vector<std::uint8_t> offended;   // per prism, in the previous call
  BoundaryFaces faces;                  // the boundary faces of the previous call's tets
  std::map<std::array<double, 3>, bool> outside_cache;

  void check_inner_points(const TetMesh& mesh, const std::vector<std::uint32_t>& inner_points,
                          ShellCheckResult& result);
  std::vector<std::uint8_t> changed_prisms(const TetMesh& mesh,
                                           const std::vector<std::uint32_t>& first) const;
  std::vector<std::uint32_t> keys_of(const std::vector<std::uint32_t>& prisms) const;
  template <class Set>
  void tet_geometries(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                      const std::vector<std::uint32_t>& prisms, const Set& set);
  void build_phase(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                   const std::vector<std::uint32_t>& all);
  void move_prisms(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                   const std::vector<std::uint32_t>& moved);
  void check_intersections(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                           const std::vector<std::uint32_t>& dirty, ShellCheckResult& result);
};

// Inner points inside, each position tested once over all calls.
void ShellChecker::Impl::check_inner_points(const TetMesh& mesh,
                                            const std::vector<std::uint32_t>& inner_points,
                                            ShellCheckResult& result) {
  // Per point, in parallel (finds only): 0 inside, 1 outside, 2 not tested yet.
  std::vector<std::uint8_t> outside(inner_points.size(), 0);
  for_each_chunk(
      inner_points.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i != end; ++i) {
          const Vec3d& p = mesh.points[inner_points[i]];
          const auto it = outside_cache.find({p.x, p.y, p.z});
          outside[i] = it == outside_cache.end() ? 2 : (it->second ? 1 : 0);
        }
      },
      1024);
  std::vector<std::size_t> unknown;
  for (std::size_t i = 0; i < inner_points.size(); ++i)
    if (outside[i] == 2) unknown.push_back(i);
  for_each_index(unknown.size(), [&](std::size_t j) {
    outside[unknown[j]] = inside.outside(mesh.points[inner_points[unknown[j]]]) ? 1 : 0;
  });
  for (const std::size_t i : unknown) {
    const Vec3d& p = mesh.points[inner_points[i]];
    outside_cache.emplace(std::array<double, 3>{p.x, p.y, p.z}, outside[i] != 0);
  }
  record_outside_points(inner_points, outside, options, result);
}

// Per prism: 1 when its tets' corners differ from those in the phase (every prism at the first
// call).
std::vector<std::uint8_t> ShellChecker::Impl::changed_prisms(
    const TetMesh& mesh, const std::vector<std::uint32_t>& first) const {
  const std::size_t n_faces = first.size() - 1;
  std::vector<std::uint8_t> changed(n_faces, 1);
  if (!phase) return changed;
  for_each_index(n_faces, [&](std::size_t f) {
    bool same = tet_count[f] == first[f + 1] - first[f];
    for (std::uint32_t t = first[f]; same && t < first[f + 1]; ++t)
      same = tet_corners(mesh, t) == phase->geometry(per_prism * f + (t - first[f])).p;
    changed[f] = same ? 0 : 1;
  });
  return changed;
}

// The keys in `phase` of the tets of `prisms` (tet_count of each).
std::vector<std::uint32_t> ShellChecker::Impl::keys_of(
    const std::vector<std::uint32_t>& prisms) const {
  std::vector<std::uint32_t> keys;
  for (const std::uint32_t f : prisms)
    for (std::uint32_t k = 0; k < tet_count[f]; ++k) keys.push_back(per_prism * f + k);
  return keys;
}

// Calls set(key, geometry) for every tet of `prisms` in `mesh`, in parallel (distinct keys), and
// makes tet_count theirs.
template <class Set>
void ShellChecker::Impl::tet_geometries(const TetMesh& mesh,
                                        const std::vector<std::uint32_t>& first,
                                        const std::vector<std::uint32_t>& prisms, const Set& set) {
  for_each_index(prisms.size(), [&](std::size_t i) {
    const std::uint32_t f = prisms[i];
    for (std::uint32_t t = first[f]; t < first[f + 1]; ++t)
      set(per_prism * f + (t - first[f]), tet_geometry(tet_corners(mesh, t)));
  });
  for (const std::uint32_t f : prisms)
    tet_count[f] = static_cast<std::uint8_t>(first[f + 1] - first[f]);
}

// The phase, over the surface's box and the tets of the first shell `mesh` (`all` its prisms),
// with a 5% margin, and those tets in it.
void ShellChecker::Impl::build_phase(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                                     const std::vector<std::uint32_t>& all) {
  TetGeometries by_key(per_prism * all.size());  // `all` holds every prism: each key set here
  tet_geometries(mesh, first, all,
                 [&](std::uint32_t key, const TetGeometry& g) { by_key[key] = g; });
  for_each_index(all.size(), [&](std::size_t f) {  // absent keys: empty boxes
    for (std::uint32_t j = first[f + 1] - first[f]; j < per_prism; ++j)
      by_key[per_prism * f + j] = TetGeometry{};
  });
  BBox box = bounding_box(surface);
  const BBox tets = bounding_box_of(by_key);
  box.expand(tets.lo);
  box.expand(tets.hi);
  const double margin = 0.05 * box.diagonal();
  box.expand(box.lo - Vec3d{margin, margin, margin});
  box.expand(box.hi + Vec3d{margin, margin, margin});
  phase = std::make_unique<BroadPhase>(surface, box, grid_cell_size(by_key, box), std::move(by_key),
                                       options.check_leaks, per_prism);
  phase->insert(keys_of(all));
}

// The tets of the prisms `moved` to their new places: out of the phase, their new geometry set in
// parallel (straight into the phase's own), back in.
void ShellChecker::Impl::move_prisms(const TetMesh& mesh, const std::vector<std::uint32_t>& first,
                                     const std::vector<std::uint32_t>& moved) {
  phase->remove(keys_of(moved));
  tet_geometries(mesh, first, moved,
                 [&](std::uint32_t key, const TetGeometry& g) { phase->set_geometry(key, g); });
  phase->insert(keys_of(moved));
}

// The narrow phase for the tets of the prisms `dirty`; remembers the prisms offending now, to be
// tested again at the next call whether they move or not.
void ShellChecker::Impl::check_intersections(const TetMesh& mesh,
                                             const std::vector<std::uint32_t>& first,
                                             const std::vector<std::uint32_t>& dirty,
                                             ShellCheckResult& result) {
  const std::vector<std::uint32_t> queries = keys_of(dirty);
  const std::vector<TetFindings> found = find_intersections(*phase, queries, inside, options);
  const Intersections offenders = record_intersections(
      found, queries, [&](std::uint32_t key) { return first[key / per_prism] + key % per_prism; },
      options, result);
  std::fill(offended.begin(), offended.end(), 0);
  const auto offend = [&](std::uint32_t t) { offended[mesh.source_triangle[t]] = 1; };
  for (const auto& pair : offenders.pairs) {
    offend(pair[0]);
    offend(pair[1]);
  }
  for (const std::uint32_t t : offenders.leaking) offend(t);
}

ShellChecker::ShellChecker(const SurfaceMesh& surface, const ShellCheckOptions& options)
    : impl_(std::make_unique<Impl>(surface, options)) {}

ShellChecker::~ShellChecker() = default;

ShellCheckResult ShellChecker::check(const TetMesh& mesh) {
  Impl& m = *impl_;
  const auto start = Clock::now();
  ShellCheckResult result;
  const std::vector<std::uint32_t> inner_points =
      check_elements(m.surface, mesh, m.options, result);
  m.faces.check(mesh, m.options, result);
  m.check_inner_points(mesh, inner_points, result);
  if (m.options.check_overlaps || m.options.check_leaks) {
    const std::vector<std::uint32_t> first =
        prism_starts(mesh, m.surface.triangles.size(), m.per_prism);
    const std::vector<std::uint8_t> changed = m.changed_prisms(mesh, first);
    std::vector<std::uint32_t> moved, dirty;
    for (std::uint32_t f = 0; f < changed.size(); ++f) {
      if (changed[f]) moved.push_back(f);
      if (changed[f] || m.offended[f]) dirty.push_back(f);
    }
    if (m.phase)
      m.move_prisms(mesh, first, moved);
    else  // the first call: every prism moved
      m.build_phase(mesh, first, moved);
    m.check_intersections(mesh, first, dirty, result);
  }
  result.seconds = seconds_since(start);
  return result;
}

}  // namespace vdb_shell

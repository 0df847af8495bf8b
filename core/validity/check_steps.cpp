// check_steps.cpp — see check_steps.h.
#include "core/validity/check_steps.h"

#include <algorithm>
#include <functional>
#include <string>

#include "core/base/errors.h"
#include "core/base/parallel.h"
#include "core/base/tet_faces.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// Throws InputError unless every tet index is in range, every point finite and the inner flags
// empty or one per point.
void validate_tet_mesh(const TetMesh& mesh) {
  const std::size_t n_points = mesh.points.size();
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    for (const std::uint32_t v : mesh.tets[t])
      if (v >= n_points)
        throw InputError("check_shell: tet " + std::to_string(t) + " refers to point " +
                         std::to_string(v) + ", but the tet mesh has " + std::to_string(n_points) +
                         " points");
  for (std::size_t v = 0; v < n_points; ++v)
    if (!is_finite(mesh.points[v]))
      throw InputError("check_shell: point " + std::to_string(v) +
                       " of the tet mesh has a NaN or infinite coordinate");
  if (!mesh.inner.empty() && mesh.inner.size() != n_points)
    throw InputError("check_shell: " + std::to_string(mesh.inner.size()) + " inner flags for " +
                     std::to_string(n_points) + " points; give one per point or none");
}

// The first surface.points.size() points of the mesh must be the surface's, bit for bit.
void count_moved_surface_points(const SurfaceMesh& surface, const TetMesh& mesh,
                                const ShellCheckOptions& options, ShellCheckResult& result) {
  for (std::size_t v = 0; v < surface.points.size(); ++v) {
    if (v >= mesh.points.size() || mesh.points[v] != surface.points[v]) {
      ++result.moved_surface_points;
      list_item(result.first_moved_surface_points, options.max_listed, v);
    }
  }
}

// Whether x is y or one of its rotations (same orientation).
bool same_cycle(const std::array<std::uint32_t, 3>& x, const Triangle& y) {
  for (int r = 0; r < 3; ++r)
    if (x[0] == y[r] && x[1] == y[(r + 1) % 3] && x[2] == y[(r + 2) % 3]) return true;
  return false;
}

// The records of `faces` (sorted) on the vertex triple `key`.
struct RecordRange {
  FaceRecords::const_iterator begin, end;
  std::size_t size() const { return static_cast<std::size_t>(end - begin); }
};
RecordRange records_of(const FaceRecords& faces, const std::array<std::uint32_t, 3>& key) {
  const FaceRecord probe{key, 0, 0};
  const auto lo = std::lower_bound(faces.begin(), faces.end(), probe);
  auto hi = lo;
  while (hi != faces.end() && hi->same_key(probe)) ++hi;
  return {lo, hi};
}

enum BoundaryVerdict : std::uint8_t { kBoundaryFace, kMissing, kShared, kMisoriented };

// Input triangle `tri` among the sorted faces of `mesh`: one face, outward as the triangle turns.
BoundaryVerdict boundary_verdict(const Triangle& tri, const FaceRecords& faces,
                                 const TetMesh& mesh) {
  const RecordRange r = records_of(faces, sorted3(tri[0], tri[1], tri[2]));
  if (r.size() == 0) return kMissing;
  if (r.size() > 1) return kShared;
  const Tet& v = mesh.tets[r.begin->tet];
  const int* k = kTetOutwardFace[r.begin->face];
  return same_cycle({v[k[0]], v[k[1]], v[k[2]]}, tri) ? kBoundaryFace : kMisoriented;
}

}  // namespace

void list_item(std::vector<std::uint32_t>& list, std::size_t max_listed, std::size_t item) {
  if (list.size() < max_listed) list.push_back(static_cast<std::uint32_t>(item));
}

std::vector<std::uint32_t> check_elements(const SurfaceMesh& surface, const TetMesh& mesh,
                                          const ShellCheckOptions& options,
                                          ShellCheckResult& result) {
  validate_tet_mesh(mesh);
  result.tets = mesh.tets.size();
  result.faces = surface.triangles.size();
  result.too_many_tets =
      result.tets > 3 * result.faces * std::size_t(options.layers) + options.extra_tets;
  count_volumes(mesh, options, result);
  count_moved_surface_points(surface, mesh, options, result);
  std::vector<std::uint32_t> inner_points;
  const std::size_t n_surface = surface.points.size();
  for (std::size_t v = 0; v < mesh.points.size(); ++v)
    if (mesh.inner.empty() ? v >= n_surface : mesh.inner[v] != 0)
      inner_points.push_back(static_cast<std::uint32_t>(v));
  result.checked_inner_vertices = inner_points.size();
  return inner_points;
}

void count_volumes(const TetMesh& mesh, const ShellCheckOptions& options,
                   ShellCheckResult& result) {
  std::vector<TetVolume> sign(mesh.tets.size(), TetVolume::kPositive);
  for_each_chunk(
      mesh.tets.size() - std::min(options.flat_tets, mesh.tets.size()),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t != end; ++t)
          sign[t] = tet_volume_class(tet_corners(mesh, t), options.zero_volume_tolerance);
      },
      4096);
  for (std::size_t t = 0; t < sign.size(); ++t) {
    if (sign[t] == TetVolume::kInverted) {
      ++result.inverted_tets;
      list_item(result.first_inverted_tets, options.max_listed, t);
    } else if (sign[t] == TetVolume::kZero) {
      ++result.zero_volume_tets;
      list_item(result.first_zero_volume_tets, options.max_listed, t);
    }
  }
}

void check_boundary_faces(const SurfaceMesh& surface, const TetMesh& mesh,
                          const ShellCheckOptions& options, ShellCheckResult& result) {
  BoundaryFaces(surface).check(mesh, options, result);
}

void BoundaryFaces::check(const TetMesh& mesh, const ShellCheckOptions& options,
                          ShellCheckResult& result) {
  if (mesh.tets.size() == tets_.size() && verdict_.size() == surface_.triangles.size()) {
    std::vector<std::uint32_t> changed;
    for (std::uint32_t t = 0; t < tets_.size(); ++t)
      if (mesh.tets[t] != tets_[t]) changed.push_back(t);
    if (changed.size() * kRebuildShare <= tets_.size())
      update(mesh, changed);
    else
      rebuild(mesh);
  } else {
    rebuild(mesh);
  }
  result.nonmanifold_faces += nonmanifold_;
  const std::size_t max_listed = options.max_listed;
  for (std::size_t f = 0; f < verdict_.size(); ++f) {
    if (verdict_[f] == kMissing) {
      ++result.missing_triangles;
      list_item(result.first_missing_triangles, max_listed, f);
    } else if (verdict_[f] == kShared) {
      ++result.shared_triangles;
      list_item(result.first_shared_triangles, max_listed, f);
    } else if (verdict_[f] == kMisoriented) {
      ++result.misoriented_triangles;
      list_item(result.first_misoriented_triangles, max_listed, f);
    }
  }
}

void BoundaryFaces::rebuild(const TetMesh& mesh) {
  tets_ = mesh.tets;
  faces_ = sorted_tet_faces(mesh);
  nonmanifold_ = reduce_in_blocks(
      faces_.size(), std::size_t{0},
      [&](std::size_t i) -> std::size_t {
        return (i == 0 || !faces_[i].same_key(faces_[i - 1])) && i + 2 < faces_.size() &&
               faces_[i + 2].same_key(faces_[i]);
      },
      std::plus<>());
  verdict_.resize(surface_.triangles.size());
  for_each_chunk(
      verdict_.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f != end; ++f)
          verdict_[f] = boundary_verdict(surface_.triangles[f], faces_, mesh);
      },
      1024);
}

void BoundaryFaces::update(const TetMesh& mesh, const std::vector<std::uint32_t>& changed) {
  if (changed.empty()) return;
  if (triangle_keys_.empty()) {  // the surface's: built once
    triangle_keys_.reserve(surface_.triangles.size());
    for (std::uint32_t f = 0; f < surface_.triangles.size(); ++f) {
      const Triangle& t = surface_.triangles[f];
      triangle_keys_.emplace_back(sorted3(t[0], t[1], t[2]), f);
    }
    std::sort(triangle_keys_.begin(), triangle_keys_.end());
  }
  // The faces the changed tets had and have, and the vertex triples of either.
  FaceRecords removed(4 * changed.size()), added(4 * changed.size());
  for (std::size_t i = 0; i < changed.size(); ++i) {
    const std::uint32_t t = changed[i];
    for (int k = 0; k < 4; ++k) {
      removed[4 * i + k] = face_of_tet(tets_[t], t, k);
      added[4 * i + k] = face_of_tet(mesh.tets[t], t, k);
    }
    tets_[t] = mesh.tets[t];
  }
  parallel_sort(removed.begin(), removed.end());
  parallel_sort(added.begin(), added.end());
  std::vector<std::array<std::uint32_t, 3>> keys;
  keys.reserve(removed.size() + added.size());
  for (const FaceRecords* records : {&removed, &added})
    for (const FaceRecord& r : *records) keys.push_back(r.key);
  parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  // The non-manifold triples among them counted again; the faces edited in one pass.
  const auto nonmanifold_among_keys = [&] {
    return reduce_in_blocks(
        keys.size(), std::size_t{0},
        [&](std::size_t i) -> std::size_t { return records_of(faces_, keys[i]).size() > 2; },
        std::plus<>());
  };
  nonmanifold_ -= nonmanifold_among_keys();
  FaceRecords kept(faces_.size() - removed.size());
  const auto kept_end = std::set_difference(faces_.begin(), faces_.end(), removed.begin(),
                                            removed.end(), kept.begin());
  if (kept_end != kept.end())
    throw InternalError("BoundaryFaces: the faces kept do not hold the changed tets' old faces");
  faces_.resize(kept.size() + added.size());
  std::merge(kept.begin(), kept.end(), added.begin(), added.end(), faces_.begin());
  nonmanifold_ += nonmanifold_among_keys();
  // The input triangles on those triples judged again.
  for_each_index(keys.size(), [&](std::size_t i) {  // one key's triangles each: distinct writes
    const auto range = std::equal_range(
        triangle_keys_.begin(), triangle_keys_.end(), std::pair{keys[i], std::uint32_t{0}},
        [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto it = range.first; it != range.second; ++it)
      verdict_[it->second] = boundary_verdict(surface_.triangles[it->second], faces_, mesh);
  });
}

double on_surface_distance(const SurfaceMesh& surface, const ShellCheckOptions& options) {
  return options.on_surface_tolerance * bounding_box(surface).diagonal();
}

void record_outside_points(const std::vector<std::uint32_t>& inner_points,
                           const std::vector<std::uint8_t>& outside,
                           const ShellCheckOptions& options, ShellCheckResult& result) {
  for (std::size_t i = 0; i < inner_points.size(); ++i) {
    if (outside[i]) {
      ++result.outside_inner_vertices;
      list_item(result.first_outside_vertices, options.max_listed, inner_points[i]);
    }
  }
}

Intersections record_intersections(const std::vector<TetFindings>& findings,
                                   const std::vector<std::uint32_t>& queries,
                                   const std::function<std::uint32_t(std::uint32_t)>& tet_of,
                                   const ShellCheckOptions& options, ShellCheckResult& result) {
  Intersections found;
  for (std::size_t i = 0; i < findings.size(); ++i) {
    const TetFindings& f = findings[i];
    const std::uint32_t a = tet_of(queries[i]);
    result.overlap_candidate_pairs += f.candidates;
    for (const std::uint32_t other : f.overlapping) {
      const std::uint32_t b = tet_of(other);
      found.pairs.push_back({std::min(a, b), std::max(a, b)});
    }
    if (f.leaking) found.leaking.push_back(a);
  }
  std::sort(found.pairs.begin(), found.pairs.end());
  std::sort(found.leaking.begin(), found.leaking.end());
  result.overlaps_checked = options.check_overlaps;
  result.overlapping_pairs = found.pairs.size();
  for (const auto& pair : found.pairs)
    if (result.first_overlapping_pairs.size() < options.max_listed)
      result.first_overlapping_pairs.push_back(pair);
  result.leaks_checked = options.check_leaks;
  result.leaking_tets = found.leaking.size();
  for (const std::uint32_t t : found.leaking)
    list_item(result.first_leaking_tets, options.max_listed, t);
  return found;
}

}  // namespace vdb_shell

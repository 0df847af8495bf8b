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
  const FaceRecords faces = sorted_tet_faces(mesh);
  // A face is non-manifold where more than two tets share it: counted at its first record.
  result.nonmanifold_faces += reduce_in_blocks(
      faces.size(), std::size_t{0},
      [&](std::size_t i) -> std::size_t {
        return (i == 0 || !faces[i].same_key(faces[i - 1])) && i + 2 < faces.size() &&
               faces[i + 2].same_key(faces[i]);
      },
      std::plus<>());
  // Per input triangle, in parallel; counted and listed in triangle order after.
  enum Verdict : std::uint8_t { kBoundaryFace, kMissing, kShared, kMisoriented };
  const std::size_t n_triangles = surface.triangles.size();
  std::vector<std::uint8_t> verdict(n_triangles, kBoundaryFace);
  for_each_chunk(
      n_triangles,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t f = begin; f != end; ++f) {
          const Triangle& tri = surface.triangles[f];
          const FaceRecord probe{sorted3(tri[0], tri[1], tri[2]), 0, 0};
          const auto lo = std::lower_bound(faces.begin(), faces.end(), probe);
          auto hi = lo;
          while (hi != faces.end() && hi->same_key(probe)) ++hi;
          const std::ptrdiff_t count = hi - lo;
          if (count == 0) {
            verdict[f] = kMissing;
          } else if (count > 1) {
            verdict[f] = kShared;
          } else {
            const Tet& v = mesh.tets[lo->tet];
            const int* k = kTetOutwardFace[lo->face];
            if (!same_cycle({v[k[0]], v[k[1]], v[k[2]]}, tri)) verdict[f] = kMisoriented;
          }
        }
      },
      1024);
  const std::size_t max_listed = options.max_listed;
  for (std::size_t f = 0; f < n_triangles; ++f) {
    if (verdict[f] == kMissing) {
      ++result.missing_triangles;
      list_item(result.first_missing_triangles, max_listed, f);
    } else if (verdict[f] == kShared) {
      ++result.shared_triangles;
      list_item(result.first_shared_triangles, max_listed, f);
    } else if (verdict[f] == kMisoriented) {
      ++result.misoriented_triangles;
      list_item(result.first_misoriented_triangles, max_listed, f);
    }
  }
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

// sector_shell.cpp — joining a split surface's shell and filling its sector gaps; see
// sector_shell.h.
#include "core/validity/sector_shell.h"

#include <algorithm>
#include <limits>
#include <utility>

#include "core/assemble/quality.h"
#include "core/base/errors.h"

namespace vdb_shell {
namespace {

/// Renumbers `mesh`, a shell of split.surface, as a shell of the input: copies become their
/// vertex, the points after the split surface's move down.
void join_points(const SectorSplit& split, std::size_t n, TetMesh& mesh) {
  const std::size_t n_split = split.surface.points.size(), shift = n_split - n;
  const auto join = [&](std::uint32_t p) {
    return p < n ? p : p < n_split ? split.vertex[p] : static_cast<std::uint32_t>(p - shift);
  };
  for (Tet& t : mesh.tets)
    for (std::uint32_t& p : t) p = join(p);
  const auto drop_copies = [&](auto& per_point) {
    if (per_point.size() == mesh.points.size())
      per_point.erase(per_point.begin() + static_cast<std::ptrdiff_t>(n),
                      per_point.begin() + static_cast<std::ptrdiff_t>(n_split));
  };
  drop_copies(mesh.inner);
  drop_copies(mesh.thickness);
  drop_copies(mesh.surface_vertex);
  for (std::uint32_t& v : mesh.surface_vertex) v = join(v);
  drop_copies(mesh.points);
}

/// The gap tets of every sector boundary (sector_shell.h), each with the face whose prism it
/// follows, in the joined mesh's numbering.
std::vector<std::pair<std::uint32_t, Tet>> gap_tets(const SectorSplit& split,
                                                    const ShellInput& input, std::size_t n,
                                                    const TetMesh& mesh, double min_quality) {
  // Per face: its tets [first[f], first[f + 1]) (assemble_shell() groups them by face).
  std::vector<std::size_t> first(split.surface.triangles.size() + 1, 0);
  for (const std::uint32_t f : mesh.source_triangle) ++first[f + 1];
  for (std::size_t f = 0; f + 1 < first.size(); ++f) first[f + 1] += first[f];
  // The inner vertex of input vertex x's corner in face f, joined.
  const auto inner_of = [&](std::uint32_t f, std::uint32_t x) {
    for (const std::uint32_t c : split.surface.triangles[f])
      if (split.vertex[c] == x)
        return input.inner_id[c] == kOnSurface ? x
                                               : static_cast<std::uint32_t>(n + input.inner_id[c]);
    throw InternalError("join_sectors: face " + std::to_string(f) + " has no corner " +
                        std::to_string(x));
  };
  // Whether face f's prism cuts its side quad at (v, b) from v: some tet has v and b'.
  const auto cut_from_v = [&](std::uint32_t f, std::uint32_t v, std::uint32_t b_inner) {
    for (std::size_t t = first[f]; t < first[f + 1]; ++t) {
      const Tet& tet = mesh.tets[t];
      if (std::count(tet.begin(), tet.end(), v) && std::count(tet.begin(), tet.end(), b_inner))
        return true;
    }
    return false;
  };
  std::vector<std::pair<std::uint32_t, Tet>> out;
  for (const auto& [v, b, f, g] : split.boundaries) {
    const std::uint32_t pf = inner_of(f, v), pg = inner_of(g, v), bi = inner_of(f, b);
    if (bi != inner_of(g, b) || pf == pg || pf == v || pg == v) continue;
    std::vector<Tet> tets;
    if (bi == b) {
      tets = {{v, b, pf, pg}};
    } else {
      const bool f_from_v = cut_from_v(f, v, bi), g_from_v = cut_from_v(g, v, bi);
      if (f_from_v && g_from_v) tets = {{v, bi, pf, pg}};
      if (!f_from_v && !g_from_v) tets = {{b, v, pf, pg}, {b, bi, pf, pg}};
      if (f_from_v && !g_from_v) tets = {{v, b, bi, pg}, {v, bi, pf, pg}};
      if (!f_from_v && g_from_v) tets = {{v, b, bi, pf}, {v, bi, pf, pg}};
    }
    for (Tet t : tets) {
      const auto& p = mesh.points;
      if (tet_volume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0) std::swap(t[2], t[3]);
      if (tet_quality(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) >= min_quality) out.push_back({f, t});
    }
  }
  return out;
}

/// `mesh` with `gaps` inserted after the tets of their faces (source_triangle stays sorted);
/// marks the gap tets in `is_gap`.
void insert_gaps(const std::vector<std::pair<std::uint32_t, Tet>>& gaps, TetMesh& mesh,
                 std::vector<char>& is_gap) {
  std::vector<std::pair<std::uint32_t, Tet>> sorted = gaps;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Tet> tets;
  std::vector<std::uint32_t> source;
  std::vector<std::uint8_t> layer;
  is_gap.clear();
  std::size_t next = 0;
  for (std::size_t t = 0; t <= mesh.tets.size(); ++t) {
    const bool end_of_face =
        t == mesh.tets.size() || (t > 0 && mesh.source_triangle[t] != mesh.source_triangle[t - 1]);
    if (t > 0 && end_of_face)
      for (; next < sorted.size() && sorted[next].first == mesh.source_triangle[t - 1]; ++next) {
        tets.push_back(sorted[next].second);
        source.push_back(sorted[next].first);
        layer.push_back(1);
        is_gap.push_back(1);
      }
    if (t == mesh.tets.size()) break;
    tets.push_back(mesh.tets[t]);
    source.push_back(mesh.source_triangle[t]);
    layer.push_back(mesh.layer.empty() ? 1 : mesh.layer[t]);
    is_gap.push_back(0);
  }
  mesh.tets = std::move(tets);
  mesh.source_triangle = std::move(source);
  mesh.layer = std::move(layer);
}

/// Removes the tets flagged in `remove` (and their flags in `is_gap`).
void remove_tets(const std::vector<char>& remove, TetMesh& mesh, std::vector<char>& is_gap) {
  std::size_t k = 0;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (remove[t]) continue;
    mesh.tets[k] = mesh.tets[t];
    mesh.source_triangle[k] = mesh.source_triangle[t];
    if (!mesh.layer.empty()) mesh.layer[k] = mesh.layer[t];
    is_gap[k] = is_gap[t];
    ++k;
  }
  mesh.tets.resize(k);
  mesh.source_triangle.resize(k);
  if (!mesh.layer.empty()) mesh.layer.resize(k);
  is_gap.resize(k);
}

}  // namespace

SectorShell join_sectors(const SurfaceMesh& surface, const SectorSplit& split, ValidShell& valid,
                         double min_quality) {
  const std::size_t n = surface.points.size();
  TetMesh& mesh = valid.shell.mesh;
  SectorShell out;
  // Layered side quads have layer points the gap tets would not share: gaps stay open then.
  const int layers = valid.assemble.layers;
  const auto gaps = layers > 1 ? std::vector<std::pair<std::uint32_t, Tet>>()
                               : gap_tets(split, valid.input, n, mesh, min_quality);
  join_points(split, n, mesh);
  std::vector<char> is_gap;
  insert_gaps(gaps, mesh, is_gap);

  ShellCheckOptions options;
  options.max_listed = std::numeric_limits<std::size_t>::max();
  options.extra_tets = 2 * split.sectors;
  options.layers = layers;
  // The split surface's shell passed a full check (valid.checks): joining the copies moves no
  // point, so only the gap tets need the overlap and leak tests.
  ShellCheckResult c;
  double seconds = valid.checks.seconds;
  for (;;) {
    c = check_added_tets(surface, mesh, is_gap, options);
    seconds += c.seconds;
    if (c.valid()) break;
    std::vector<char> remove(mesh.tets.size(), 0);
    for (const auto* list :
         {&c.first_inverted_tets, &c.first_zero_volume_tets, &c.first_leaking_tets})
      for (const std::uint32_t t : *list) remove[t] = is_gap[t];
    for (const auto& [s, t] : c.first_overlapping_pairs) {
      remove[s] = remove[s] || is_gap[s];
      remove[t] = remove[t] || is_gap[t];
    }
    // Whatever else offends is not the gaps' doing, but without them the shell is the split
    // surface's valid one: remove them all.
    if (std::find(remove.begin(), remove.end(), 1) == remove.end()) remove = is_gap;
    if (std::find(remove.begin(), remove.end(), 1) == remove.end()) break;  // nothing to remove
    out.dropped_gaps += static_cast<std::size_t>(std::count(remove.begin(), remove.end(), 1));
    remove_tets(remove, mesh, is_gap);
  }
  out.gap_tets = static_cast<std::size_t>(std::count(is_gap.begin(), is_gap.end(), 1));
  mesh.quality = tet_qualities(mesh);
  c.seconds = seconds;  // the full check's and these
  valid.checks = std::move(c);
  return out;
}

void join_zero_area_faces(const SurfaceMesh& surface, const ZeroAreaFlips& flips,
                          std::size_t gap_tets, ValidShell& valid) {
  TetMesh& mesh = valid.shell.mesh;
  const bool with_quality = mesh.quality.size() == mesh.tets.size();
  for (std::uint32_t& f : mesh.source_triangle) f = flips.face_of[f];
  mesh.tets.insert(mesh.tets.end(), flips.tets.begin(), flips.tets.end());
  mesh.source_triangle.insert(mesh.source_triangle.end(), flips.tet_face.begin(),
                              flips.tet_face.end());
  if (!mesh.layer.empty()) mesh.layer.resize(mesh.tets.size(), 1);
  if (with_quality) {  // the shell's tets keep theirs
    for (const Tet& t : flips.tets)
      mesh.quality.push_back(
          tet_quality(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]));
  } else {
    mesh.quality = tet_qualities(mesh);
  }
  ShellCheckOptions options;
  options.layers = valid.assemble.layers;
  options.extra_tets = gap_tets + flips.tets.size();
  options.flat_tets = flips.tets.size();
  const double seconds = valid.checks.seconds;
  valid.checks = check_shell(surface, mesh, options);
  valid.checks.seconds += seconds;
}

}  // namespace vdb_shell

// quality.cpp — see quality.h.
#include "core/assemble/quality.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/base/parallel.h"

namespace vdb_shell {
namespace {}  // namespace

double tet_quality(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  const double sum2 =
      norm2(b - a) + norm2(c - a) + norm2(d - a) + norm2(c - b) + norm2(d - b) + norm2(d - c);
  if (!(sum2 > 0.0)) return 0.0;
  const double l_rms = std::sqrt(sum2 / 6.0);
  return 6.0 * std::sqrt(2.0) * tet_volume(a, b, c, d) / (l_rms * l_rms * l_rms);
}

namespace {

// The cosines of the six dihedral angles of (a, b, c, d), in kTetEdge order; false for a flat
// tet (a face without area).
bool tet_dihedral_cosines(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d,
                          std::array<double, 6>& cosines) {
  // n[k]: normal of the face opposite corner k, pointing away from corner k.
  const std::array<Vec3d, 4> p = {a, b, c, d};
  std::array<Vec3d, 4> n;
  for (int k = 0; k < 4; ++k) {
    const Vec3d& u = p[(k + 1) % 4];
    const Vec3d& v = p[(k + 2) % 4];
    const Vec3d& w = p[(k + 3) % 4];
    Vec3d m = cross(v - u, w - u);
    if (dot(m, p[k] - u) > 0.0) m = -m;
    const double len = norm(m);
    if (!(len > 0.0)) return false;
    n[k] = m / len;
  }
  // The dihedral angle at the edge shared by the faces opposite k and l is pi minus the angle
  // between their outward normals; edge e of kTetEdge joins corners i and j, so its faces are
  // the ones opposite the other two corners.
  for (int e = 0; e < 6; ++e) {
    int k = -1, l = -1;
    for (int m = 0; m < 4; ++m)
      if (m != kTetEdge[e][0] && m != kTetEdge[e][1]) (k < 0 ? k : l) = m;
    cosines[e] = std::clamp(-dot(n[k], n[l]), -1.0, 1.0);
  }
  return true;
}

}  // namespace

std::array<double, 6> tet_dihedrals_deg(const Vec3d& a, const Vec3d& b, const Vec3d& c,
                                        const Vec3d& d) {
  std::array<double, 6> angles;
  if (!tet_dihedral_cosines(a, b, c, d, angles)) return {};
  for (double& x : angles) x = std::acos(x) * 180.0 / kPi;
  return angles;
}

double tet_min_dihedral_deg(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  std::array<double, 6> cosines;
  if (!tet_dihedral_cosines(a, b, c, d, cosines)) return 0.0;
  // The smallest angle has the largest cosine (acos falls): one acos, the same value.
  return std::acos(*std::max_element(cosines.begin(), cosines.end())) * 180.0 / kPi;
}

std::vector<double> tet_qualities(const TetMesh& mesh) {
  std::vector<double> q(mesh.tets.size());
  for_each_index(q.size(), [&](std::size_t t) {
    const Tet& v = mesh.tets[t];
    q[t] = tet_quality(mesh.points[v[0]], mesh.points[v[1]], mesh.points[v[2]], mesh.points[v[3]]);
  });
  return q;
}

QualitySummary summarize_quality(const SurfaceMesh& surface, const TetMesh& mesh,
                                 const QualityOptions& options) {
  QualitySummary s;
  const std::size_t n = mesh.tets.size() - std::min(options.flat_tets, mesh.tets.size());
  s.tets = n;
  const std::size_t bins = std::max<std::size_t>(options.histogram_bins, 1);
  s.histogram.assign(bins, 0);
  s.enclosed_volume = signed_volume(surface);

  std::vector<double> q =
      mesh.quality.size() == mesh.tets.size() ? mesh.quality : tet_qualities(mesh);
  q.resize(std::min(q.size(), n));
  // Per tet in parallel; the volume summed in tet order after (the same sum for any thread
  // count).
  std::vector<double> volumes(n), dihedrals(n);
  for_each_index(n, [&](std::size_t t) {
    const Tet& v = mesh.tets[t];
    const Vec3d &a = mesh.points[v[0]], &b = mesh.points[v[1]], &c = mesh.points[v[2]],
                &d = mesh.points[v[3]];
    volumes[t] = tet_volume(a, b, c, d);
    dihedrals[t] = tet_min_dihedral_deg(a, b, c, d);
  });
  double volume = 0.0, min_dihedral = 180.0;
  for (std::size_t t = 0; t < volumes.size(); ++t) {
    volume += volumes[t];
    min_dihedral = std::min(min_dihedral, dihedrals[t]);
  }
  s.shell_volume = volume;
  s.coverage = s.enclosed_volume > 0.0 ? volume / s.enclosed_volume : 0.0;
  if (q.empty()) return s;
  s.min_dihedral_deg = min_dihedral;

  double sum = 0.0;
  for (const double x : q) {
    sum += x;
    if (!(x > 0.0)) {
      ++s.non_positive;
      continue;
    }
    // (i/n, (i+1)/n] -> i; values above 1 (rounding) go to the last bin.
    const double scaled = std::ceil(x * static_cast<double>(bins)) - 1.0;
    const std::size_t bin =
        static_cast<std::size_t>(std::clamp(scaled, 0.0, static_cast<double>(bins - 1)));
    ++s.histogram[bin];
  }
  s.mean_quality = sum / static_cast<double>(q.size());
  // The order statistics by selection (what a full sort would give at those ranks): the 5th
  // percentile first, then the median among the values above it.
  const auto at_rank = [&](std::size_t k, std::size_t from) {
    std::nth_element(q.begin() + static_cast<std::ptrdiff_t>(from),
                     q.begin() + static_cast<std::ptrdiff_t>(k), q.end());
    return q[k];
  };
  s.min_quality = *std::min_element(q.begin(), q.end());
  const std::size_t p5 = q.size() / 20, mid = q.size() / 2;
  s.p5_quality = at_rank(p5, 0);
  const double upper = at_rank(mid, p5);
  // For an even count, the value below the median's rank: the largest of the ranks before it.
  s.median_quality =
      q.size() % 2 == 1
          ? upper
          : 0.5 * (*std::max_element(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(mid)) +
                   upper);
  return s;
}

}  // namespace vdb_shell

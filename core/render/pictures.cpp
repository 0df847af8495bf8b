#include "core/render/pictures.h"

#include <algorithm>

#include "core/base/tet_faces.h"

namespace vdb_shell {

namespace {

/// Light from over the viewer's left shoulder.
Vec3d light_of(const Camera& c) { return c.up * 0.45 - c.right * 0.35 - c.forward; }

}  // namespace

ShellFaces shell_faces(const TetMesh& mesh, const SurfaceMesh& surface) {
  ShellFaces f;
  f.neighbour.assign(4 * mesh.tets.size(), -1);
  f.outer.assign(4 * mesh.tets.size(), 0);
  const FaceRecords records = sorted_tet_faces(mesh);
  std::vector<std::array<std::uint32_t, 3>> triangles;
  triangles.reserve(surface.triangles.size());
  for (const Triangle& t : surface.triangles) triangles.push_back(sorted3(t[0], t[1], t[2]));
  std::sort(triangles.begin(), triangles.end());
  for (std::size_t i = 0; i < records.size();) {
    std::size_t j = i + 1;
    while (j < records.size() && records[j].same_key(records[i])) ++j;
    const FaceRecord& a = records[i];
    if (j - i == 2) {
      const FaceRecord& b = records[i + 1];
      f.neighbour[4 * a.tet + a.face] = b.tet;
      f.neighbour[4 * b.tet + b.face] = a.tet;
    } else if (j - i == 1) {
      f.outer[4 * a.tet + a.face] =
          std::binary_search(triangles.begin(), triangles.end(), a.key) ? 1 : 0;
    }
    i = j;
  }
  return f;
}

Image render_cut_away(const TetMesh& mesh, const ShellFaces& faces, const Camera& camera,
                      const Vec3d& at, const Vec3d& cut, int supersample) {
  Canvas canvas(camera, supersample, kBackground);
  const Vec3d light = light_of(camera);
  const std::size_t n = mesh.tets.size();
  std::vector<std::uint8_t> kept(n);
  for (std::size_t t = 0; t < n; ++t) {
    const Tet& v = mesh.tets[t];
    const Vec3d centroid =
        (mesh.points[v[0]] + mesh.points[v[1]] + mesh.points[v[2]] + mesh.points[v[3]]) * 0.25;
    kept[t] = dot(centroid - at, cut) < 0 ? 1 : 0;
  }
  const ColourMap& quality = ColourMap::quality();
  for (std::size_t t = 0; t < n; ++t) {
    if (!kept[t]) continue;
    const Tet& v = mesh.tets[t];
    for (int k = 0; k < 4; ++k) {
      const std::int64_t other = faces.neighbour[4 * t + k];
      if (other >= 0 && kept[other]) continue;
      const int* f = kTetOutwardFace[k];
      const Vec3d& a = mesh.points[v[f[0]]];
      const Vec3d& b = mesh.points[v[f[1]]];
      const Vec3d& c = mesh.points[v[f[2]]];
      const Vec3d normal = cross(b - a, c - a);
      Rgb base;
      double wire = 0.82;
      if (other >= 0) {  // exposed by the cut
        base = quality(mesh.quality.size() == n ? mesh.quality[t] : 1.0);
        wire = 0.5;
      } else {
        base = faces.outer[4 * t + k] ? kOuterColour : kInnerColour;
      }
      const Rgb col = shade(base, normal, light);
      canvas.triangle(a, b, c, {col, col, col}, wire);
    }
  }
  return canvas.resolve();
}

Image render_surface(const SurfaceMesh& surface, const std::vector<Rgb>& corner_colour,
                     const Camera& camera, int supersample) {
  Canvas canvas(camera, supersample, kBackground);
  const Vec3d light = light_of(camera);
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    const Vec3d& a = surface.points[tri[0]];
    const Vec3d& b = surface.points[tri[1]];
    const Vec3d& c = surface.points[tri[2]];
    const Vec3d normal = cross(b - a, c - a);
    canvas.triangle(
        a, b, c,
        {shade(corner_colour[3 * t], normal, light), shade(corner_colour[3 * t + 1], normal, light),
         shade(corner_colour[3 * t + 2], normal, light)},
        0.85);
  }
  return canvas.resolve();
}

Image render_traces(const SurfaceMesh& surface, const TraceResult& traces, const Camera& camera,
                    std::size_t max_traces, int supersample) {
  Canvas canvas(camera, supersample, kBackground);
  const Vec3d light = light_of(camera);
  for (const Triangle& tri : surface.triangles) {
    const Vec3d& a = surface.points[tri[0]];
    const Vec3d& b = surface.points[tri[1]];
    const Vec3d& c = surface.points[tri[2]];
    const Rgb col = shade({200, 200, 200}, cross(b - a, c - a), light);
    canvas.triangle(a, b, c, {col, col, col});
  }
  canvas.fade(kBackground, 0.6);
  const std::size_t n = traces.num_traces();
  const std::size_t every = trace_stride(n, max_traces);
  for (std::size_t v = 0; v < n; v += every) {
    const Rgb col = kStopColour[static_cast<std::size_t>(traces.stop[v])];
    for (std::size_t i = 0; i < traces.end[v]; ++i)
      canvas.line(traces.sample(v, i), traces.sample(v, i + 1), col, 1.2);
  }
  return canvas.resolve();
}

}  // namespace vdb_shell

// --layers end to end (build_shell(), ValidityOptions::layers): layered shells valid by the
// independent checks at 1, 2 and 5 layers and ratios 1 and 1.5, within T <= 3KF, every prism
// in every layer, thickness limits kept, layers through the thickness less elongated than one,
// with --optimize too, and the same for any thread count.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "tests/test_support.h"
#include "vdb_shell/vdb_shell.h"

namespace vdb_shell {
namespace {

ShellOptions layered(int resolution, int layers, double ratio) {
  ShellOptions o;
  o.fields.resolution = resolution;
  o.validity.layers = layers;
  o.validity.layer_ratio = ratio;
  return o;
}

/// The shell's problems by test_support's own checks, with the layered tet bound.
std::string problems(const ShellResult& r, int layers) {
  const std::size_t faces = r.surface.triangles.size();
  return test::independent_shell_problems(r.surface, r.mesh,
                                          3 * (layers - 1) * faces + 2 * r.validity.sectors);
}

/// Volume-length ratio of every tet (test_support's), ascending.
std::vector<double> qualities(const TetMesh& m) {
  std::vector<double> q;
  for (const Tet& t : m.tets) q.push_back(test::independent_quality(m, t));
  std::sort(q.begin(), q.end());
  return q;
}

TEST(Layers, ValidAtOneTwoAndFiveLayersAndBothRatios) {
  for (const char* name : {"torus", "horn", "flap"}) {
    const SurfaceMesh surface = make_shape(name, name == std::string("flap") ? 2 : 1);
    const std::size_t faces = surface.triangles.size();
    for (const int K : {1, 2, 5})
      for (const double ratio : {1.0, 1.5}) {
        if (K == 1 && ratio != 1.0) continue;
        const std::string what =
            std::string(name) + " " + std::to_string(K) + " layers, ratio " + std::to_string(ratio);
        const ShellResult r = build_shell(surface, layered(48, K, ratio));
        ASSERT_EQ(problems(r, K), "") << what;
        EXPECT_LE(r.mesh.tets.size(), 3 * K * faces + 2 * r.validity.sectors) << what;
        EXPECT_GT(test::independent_coverage(r.surface, r.mesh), 0.8) << what;
        // Every tet in a layer of 1..K, and every prism (its source triangle) in each of them
        // unless it is a cap or has all three corners on the surface.
        ASSERT_EQ(r.mesh.layer.size(), r.mesh.tets.size()) << what;
        std::map<std::uint32_t, std::set<int>> layers_of;
        for (std::size_t t = 0; t < r.mesh.tets.size(); ++t) {
          ASSERT_GE(r.mesh.layer[t], 1) << what;
          ASSERT_LE(r.mesh.layer[t], K) << what;
          layers_of[r.mesh.source_triangle[t]].insert(r.mesh.layer[t]);
        }
        std::size_t full = 0;
        for (const auto& [f, set] : layers_of) full += set.size() == std::size_t(K);
        EXPECT_GE(full, faces - r.validity.cap_faces - 3 * r.validity.on_surface_vertices) << what;
        const nlohmann::json j = nlohmann::json::parse(report_json(r));
        EXPECT_EQ(j["shell"]["layers"], K) << what;
      }
  }
}

TEST(Layers, ThicknessLimitsHoldAtEveryLayerPoint) {
  ShellOptions o = layered(64, 3, 1.5);
  o.thickness.max_thickness = 0.1;
  const ShellResult r = build_shell(make_shape("sphere", 1), o);
  ASSERT_EQ(problems(r, 3), "");
  // Every point's distance to its surface vertex, computed here: within the limit, and the
  // layer points strictly inside it.
  std::size_t between = 0;
  for (std::size_t p = 0; p < r.mesh.points.size(); ++p) {
    const double d = distance(r.mesh.points[p], r.surface.points[r.mesh.surface_vertex[p]]);
    EXPECT_LE(d, 0.1 * (1 + 1e-9)) << p;
    between += d > 0 && d < 0.1 * 0.99;
  }
  EXPECT_GE(between, 2 * r.surface.points.size());
}

TEST(Layers, LayersMakeTheNeedlesOfAFineSphereLessElongated) {
  // A finely tessellated sphere's traces converge on the centre: one layer gives needles, five
  // layers cut each into five shorter tets (the innermost layer keeps the tips).
  const SurfaceMesh sphere = make_shape("sphere", 2);
  const ShellResult one = build_shell(sphere, layered(48, 1, 1.0));
  const ShellResult five = build_shell(sphere, layered(48, 5, 1.0));
  ASSERT_EQ(problems(one, 1), "");
  ASSERT_EQ(problems(five, 5), "");
  const std::vector<double> q1 = qualities(one.mesh), q5 = qualities(five.mesh);
  const auto median = [](const std::vector<double>& q) { return q[q.size() / 2]; };
  EXPECT_GT(median(q5), 1.5 * median(q1));
}

TEST(Layers, OptimizeKeepsALayeredShellValidAndTheSameForAnyThreadCount) {
  test::TempDir dir;
  std::string bytes[2];
  for (const int threads : {1, 2}) {
    ShellOptions o = layered(48, 3, 1.3);
    o.optimize.enabled = true;
    o.threads = threads;
    const ShellResult r = build_shell(make_shape("star", 1), o);
    ASSERT_EQ(problems(r, 3), "") << threads;
    EXPECT_TRUE(r.optimize.report.ran);
    write_shell(dir.file("s.vtu"), r);
    bytes[threads - 1] = test::read_text(dir.file("s.vtu"));
  }
  EXPECT_NE(bytes[0].find("Name=\"layer\""), std::string::npos);
  EXPECT_TRUE(bytes[0] == bytes[1]);
}

}  // namespace
}  // namespace vdb_shell

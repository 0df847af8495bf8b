// tet_faces_test.cpp — sorted_tet_faces() (tet_faces.h): every face of every tet once, in
// FaceRecord order (a sort of all of them, here), on one thread and on four.
#include "core/base/tet_faces.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <random>
#include <vector>

namespace vdb_shell {
namespace {

TEST(TetFaces, EveryFaceOnceInRecordOrderForAnyThreadCount) {
  // 40,000 random tets over 3,000 points: buckets of every size, shared and repeated faces, ten
  // blocks of tets and twelve ranges of points (sorted_tet_faces() splits at 4,096 and 256).
  TetMesh mesh;
  mesh.points.resize(3000);
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::uint32_t> point(0, 2999);
  for (int t = 0; t < 40000; ++t) {
    Tet v;
    do {
      for (std::uint32_t& p : v) p = point(rng);
    } while (v[0] == v[1] || v[0] == v[2] || v[0] == v[3] || v[1] == v[2] || v[1] == v[3] ||
             v[2] == v[3]);
    mesh.tets.push_back(v);
  }
  std::vector<FaceRecord> expected;
  for (std::uint32_t t = 0; t < mesh.tets.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      const int* f = kTetOutwardFace[k];
      const Tet& v = mesh.tets[t];
      expected.push_back({sorted3(v[f[0]], v[f[1]], v[f[2]]), t, static_cast<std::uint8_t>(k)});
    }
  std::sort(expected.begin(), expected.end());
  const auto same = [](const FaceRecords& a, const std::vector<FaceRecord>& b) {
    return a.size() == b.size() &&
           std::equal(a.begin(), a.end(), b.begin(), [](const FaceRecord& x, const FaceRecord& y) {
             return x.key == y.key && x.tet == y.tet && x.face == y.face;
           });
  };
  for (const int threads : {1, 4}) {
    SCOPED_TRACE(threads);
    tbb::task_arena arena(threads);
    FaceRecords faces;
    arena.execute([&] { faces = sorted_tet_faces(mesh); });
    EXPECT_TRUE(same(faces, expected));
  }
}

}  // namespace
}  // namespace vdb_shell

// tet_faces.h — the faces of a tet mesh grouped by vertex triple: what the boundary-face check
// (core/validity) and the boundary faces a writer lists (core/write) are computed from.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/base/parallel.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

/// One tet face: its sorted vertex triple, the tet and the corner opposite the face.
struct FaceRecord {
  std::array<std::uint32_t, 3> key;  // sorted vertex indices
  std::uint32_t tet;
  std::uint8_t face;                           // corner of the tet opposite the face
  bool operator<(const FaceRecord& o) const {  // element by element: no memcmp calls
    if (key[0] != o.key[0]) return key[0] < o.key[0];
    if (key[1] != o.key[1]) return key[1] < o.key[1];
    if (key[2] != o.key[2]) return key[2] < o.key[2];
    return tet != o.tet ? tet < o.tet : face < o.face;
  }
  bool same_key(const FaceRecord& o) const {
    return key[0] == o.key[0] && key[1] == o.key[1] && key[2] == o.key[2];
  }
};

/// a, b and c in ascending order.
inline std::array<std::uint32_t, 3> sorted3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::array<std::uint32_t, 3> k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The 4T faces of the tets in FaceRecord order (equal faces next to each other), sorted in two
/// steps: by smallest vertex (counting sort), then within each (small) bucket, the buckets in
/// parallel (each its own range: the same order for any thread count).
inline std::vector<FaceRecord> sorted_tet_faces(const TetMesh& mesh) {
  const std::size_t n_points = mesh.points.size();
  std::vector<std::uint32_t> bucket(n_points + 1, 0);
  for (const Tet& v : mesh.tets)
    for (const int* f : kTetOutwardFace) ++bucket[std::min({v[f[0]], v[f[1]], v[f[2]]}) + 1];
  for (std::size_t p = 0; p < n_points; ++p) bucket[p + 1] += bucket[p];
  std::vector<FaceRecord> faces(4 * mesh.tets.size());
  std::vector<std::uint32_t> fill(bucket.begin(), bucket.end() - 1);
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& v = mesh.tets[t];
    for (int k = 0; k < 4; ++k) {
      const int* f = kTetOutwardFace[k];
      const std::array<std::uint32_t, 3> key = sorted3(v[f[0]], v[f[1]], v[f[2]]);
      faces[fill[key[0]]++] = {key, static_cast<std::uint32_t>(t), static_cast<std::uint8_t>(k)};
    }
  }
  for_each_chunk(
      n_points,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p != end; ++p)
          if (bucket[p + 1] - bucket[p] > 1)
            std::sort(faces.begin() + bucket[p], faces.begin() + bucket[p + 1]);
      },
      4096);
  return faces;
}

}  // namespace vdb_shell

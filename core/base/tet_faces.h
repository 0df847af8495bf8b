// tet_faces.h — the faces of a tet mesh grouped by vertex triple: what the boundary-face check
// (core/validity) and the boundary faces a writer lists (core/write) are computed from.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/base/tet_mesh.h"
#include "core/base/uninitialized_allocator.h"

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

/// Faces in a buffer a parallel loop fills (no pass of its own to initialise it).
using FaceRecords = std::vector<FaceRecord, UninitializedAllocator<FaceRecord>>;

/// a, b and c in ascending order.
inline std::array<std::uint32_t, 3> sorted3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  std::array<std::uint32_t, 3> k = {a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

/// The face of tet `t` (corners `v`) opposite its corner k.
inline FaceRecord face_of_tet(const Tet& v, std::uint32_t t, int k) {
  const int* f = kTetOutwardFace[k];
  return {sorted3(v[f[0]], v[f[1]], v[f[2]]), t, static_cast<std::uint8_t>(k)};
}

/// The 4T faces of the tets in FaceRecord order (equal faces next to each other). Every step runs
/// in parallel over fixed blocks; since FaceRecord's order is total, the result is the same for
/// any thread count.
FaceRecords sorted_tet_faces(const TetMesh& mesh);

}  // namespace vdb_shell

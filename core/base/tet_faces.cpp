// tet_faces.cpp — sorted_tet_faces(): a bucket sort of the tets' faces on their smallest vertex,
// in two levels so that every step runs in parallel.
#include "core/base/tet_faces.h"

#include <algorithm>
#include <utility>

#include "core/base/parallel.h"

namespace vdb_shell {

FaceRecords sorted_tet_faces(const TetMesh& mesh) {
  const std::size_t n_tets = mesh.tets.size();
  // Blocks of tets and ranges of points (by smallest vertex), at most 1024 and 4096 of them: the
  // counts per block and range stay small.
  const std::size_t block = std::max<std::size_t>(4096, (n_tets + 1023) / 1024);
  const std::size_t span = std::max<std::size_t>(256, (mesh.points.size() + 4095) / 4096);
  const std::size_t n_blocks = (n_tets + block - 1) / block;
  const std::size_t n_ranges = std::max<std::size_t>(1, (mesh.points.size() + span - 1) / span);
  const auto for_each_block = [&](const auto& body) {
    for_each_index(
        n_blocks,
        [&](std::size_t b) {
          for (std::size_t t = b * block; t < std::min(n_tets, (b + 1) * block); ++t) body(b, t);
        },
        2);
  };

  // 1. Each block counts its faces per range; the counts become the block's first slot in each
  //    range (ranges in order, within a range the blocks in order).
  std::vector<std::size_t> slot(n_blocks * n_ranges, 0);
  for_each_block([&](std::size_t b, std::size_t t) {
    const Tet& v = mesh.tets[t];
    for (const int* f : kTetOutwardFace)
      ++slot[b * n_ranges + std::min({v[f[0]], v[f[1]], v[f[2]]}) / span];
  });
  std::vector<std::size_t> range_start(n_ranges + 1, 0);
  for (std::size_t r = 0, at = 0; r < n_ranges; ++r) {
    for (std::size_t b = 0; b < n_blocks; ++b) at += std::exchange(slot[b * n_ranges + r], at);
    range_start[r + 1] = at;
  }
  // 2. Each block writes its faces to its slots.
  FaceRecords faces(4 * n_tets);  // every element written below
  for_each_block([&](std::size_t b, std::size_t t) {
    for (int k = 0; k < 4; ++k) {
      const FaceRecord face = face_of_tet(mesh.tets[t], static_cast<std::uint32_t>(t), k);
      faces[slot[b * n_ranges + face.key[0] / span]++] = face;
    }
  });
  // 3. Each range sorts its faces by smallest vertex (a counting sort), then each vertex's few
  //    faces by FaceRecord's order.
  for_each_index(
      n_ranges,
      [&](std::size_t r) {
        const std::size_t begin = range_start[r];
        const std::size_t end = range_start[r + 1];
        if (end - begin < 2) return;
        const std::size_t first = r * span;
        std::vector<std::size_t> start(span + 1, 0);
        for (std::size_t i = begin; i != end; ++i) ++start[faces[i].key[0] - first + 1];
        for (std::size_t p = 0; p < span; ++p) start[p + 1] += start[p];
        FaceRecords sorted(end - begin);
        std::vector<std::size_t> fill(start.begin(), start.end() - 1);
        for (std::size_t i = begin; i != end; ++i)
          sorted[fill[faces[i].key[0] - first]++] = faces[i];
        for (std::size_t p = 0; p < span; ++p)
          if (start[p + 1] - start[p] > 1)
            std::sort(sorted.begin() + start[p], sorted.begin() + start[p + 1]);
        std::copy(sorted.begin(), sorted.end(), faces.begin() + begin);
      },
      2);
  return faces;
}

}  // namespace vdb_shell

// tet_intersections.cpp — see tet_intersections.h.
#include "core/validity/tet_intersections.h"

#include <algorithm>

#include "core/base/parallel.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// Per chunk of queries: marks of the tets and triangles met by the current query (entries equal
// to its key + 1), so that one met in several cells is tested once.
struct Marks {
  std::vector<std::uint32_t> tets, triangles;
};

// The overlaps of query `key`, skipping the candidates that are queries with a smaller key.
void find_overlaps(const BroadPhase& phase, std::uint32_t key, bool all_queries,
                   const std::vector<std::uint8_t>& is_query, Marks& marks,
                   const ShellCheckOptions& options, TetFindings& out) {
  const TetGeometry& a = phase.geometry(key);
  std::size_t candidates = 0;  // counted here, not in `out`, which the compiler must reload
  // With every tet a query, the smaller keys of a cell are skipped before they are visited.
  phase.for_each_tet_near(key, all_queries, marks.tets, key + 1, [&](std::uint32_t other) {
    if (other == key || (other < key && is_query[other])) return;  // tested from `other`
    if (!boxes_overlap(a.box, phase.box(other))) return;
    ++candidates;
    if (tets_intersect(a, phase.geometry(other), options.overlap_tolerance))
      out.overlapping.push_back(other);
  });
  out.candidates = candidates;
}

// Whether query `key` reaches outside the surface.
bool leaks(const BroadPhase& phase, std::uint32_t key, const InsideTester& inside, Marks& marks,
           const ShellCheckOptions& options) {
  const TetGeometry& a = phase.geometry(key);
  if (inside.outside((a.p[0] + a.p[1] + a.p[2] + a.p[3]) * 0.25)) return true;
  bool crossed = false;
  phase.for_each_triangle_near(key, marks.triangles, key + 1, [&](std::uint32_t f) {
    if (!crossed && surface_triangle_crosses(phase.surface(), f, a, options.overlap_tolerance))
      crossed = true;
  });
  return crossed;
}

}  // namespace

std::vector<TetFindings> find_intersections(const BroadPhase& phase,
                                            const std::vector<std::uint32_t>& queries,
                                            const InsideTester& inside,
                                            const ShellCheckOptions& options) {
  std::vector<std::uint8_t> is_query(phase.key_count(), 0);
  for (const std::uint32_t key : queries) is_query[key] = 1;
  const bool all_queries = queries.size() == phase.size();
  std::vector<TetFindings> found(queries.size());
  // Every chunk allocates marks over all keys and triangles: a grain of a 32nd of the queries
  // keeps the chunks few, and that cost a small multiple of one pass over them.
  for_each_chunk(
      queries.size(),
      [&](std::size_t begin, std::size_t end) {
        Marks marks{std::vector<std::uint32_t>(options.check_overlaps ? phase.key_count() : 0, 0),
                    std::vector<std::uint32_t>(
                        options.check_leaks ? phase.surface().triangles.size() : 0, 0)};
        for (std::size_t i = begin; i != end; ++i) {
          const std::uint32_t key = queries[i];
          if (options.check_overlaps)
            find_overlaps(phase, key, all_queries, is_query, marks, options, found[i]);
          if (options.check_leaks) found[i].leaking = leaks(phase, key, inside, marks, options);
        }
      },
      std::max<std::size_t>(16, queries.size() / 32));
  return found;
}

}  // namespace vdb_shell

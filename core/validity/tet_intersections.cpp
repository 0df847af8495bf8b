// tet_intersections.cpp — see tet_intersections.h.
#include "core/validity/tet_intersections.h"

#include <algorithm>
#include <utility>

#include "core/base/parallel.h"
#include "core/validity/tet_predicates.h"

namespace vdb_shell {
namespace {

// Per chunk of queries: marks of the tets (by slot) and triangles met by the current query
// (entries equal to its slot + 1), so that one met in several cells is tested once.
struct Marks {
  std::vector<std::uint32_t> tets, triangles;
};

// The overlaps of the query in `slot`, skipping the candidates that are queries in a smaller
// slot.
void find_overlaps(const BroadPhase& phase, std::uint32_t slot, bool all_queries,
                   const std::vector<std::uint8_t>& is_query, Marks& marks,
                   const ShellCheckOptions& options, TetFindings& out) {
  const TetGeometry& a = phase.slot_geometry(slot);
  std::size_t candidates = 0;  // counted here, not in `out`, which the compiler must reload
  // With every tet a query, the smaller slots of a cell are skipped before they are visited.
  phase.for_each_tet_near(slot, all_queries, marks.tets, slot + 1, [&](std::uint32_t other) {
    if (other == slot || (other < slot && is_query[other])) return;  // tested from `other`
    if (!boxes_overlap(a.box, phase.slot_box(other))) return;
    ++candidates;
    if (tets_intersect(a, phase.slot_geometry(other), options.overlap_tolerance))
      out.overlapping.push_back(phase.key(other));
  });
  out.candidates = candidates;
}

// Whether the query in `slot` reaches outside the surface.
bool leaks(const BroadPhase& phase, std::uint32_t slot, const InsideTester& inside, Marks& marks,
           const ShellCheckOptions& options) {
  const TetGeometry& a = phase.slot_geometry(slot);
  if (inside.outside((a.p[0] + a.p[1] + a.p[2] + a.p[3]) * 0.25)) return true;
  bool crossed = false;
  phase.for_each_triangle_near(slot, marks.triangles, slot + 1, [&](std::uint32_t f) {
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
  // The queries by slot, so that consecutive queries read neighbouring lists and geometry.
  std::vector<std::uint32_t> index_of(phase.key_count(), 0);  // per slot: query index + 1, or 0
  for (std::uint32_t i = 0; i < queries.size(); ++i) index_of[phase.slot(queries[i])] = i + 1;
  std::vector<std::uint8_t> is_query(phase.key_count(), 0);    // per slot
  std::vector<std::pair<std::uint32_t, std::uint32_t>> order;  // (slot, query index)
  order.reserve(queries.size());
  for (std::uint32_t slot = 0; slot < index_of.size(); ++slot)
    if (index_of[slot] != 0) {
      is_query[slot] = 1;
      order.emplace_back(slot, index_of[slot] - 1);
    }
  const bool all_queries = queries.size() == phase.size();
  std::vector<TetFindings> found(queries.size());
  // Every chunk allocates marks over all slots and triangles: a grain of a 32nd of the queries
  // keeps the chunks few, and that cost a small multiple of one pass over them.
  for_each_chunk(
      queries.size(),
      [&](std::size_t begin, std::size_t end) {
        Marks marks{std::vector<std::uint32_t>(options.check_overlaps ? phase.key_count() : 0, 0),
                    std::vector<std::uint32_t>(
                        options.check_leaks ? phase.surface().triangles.size() : 0, 0)};
        for (std::size_t i = begin; i != end; ++i) {
          const auto [slot, index] = order[i];
          if (options.check_overlaps)
            find_overlaps(phase, slot, all_queries, is_query, marks, options, found[index]);
          if (options.check_leaks)
            found[index].leaking = leaks(phase, slot, inside, marks, options);
        }
      },
      std::max<std::size_t>(16, queries.size() / 32));
  return found;
}

}  // namespace vdb_shell

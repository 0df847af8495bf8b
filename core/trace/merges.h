// merges.h — order-independent merge resolution (criterion 1 of trace.h; paper eq. 3, Fig. 3).
//
// A trace merges at its first sample (by arc length) that lies within the point size of an
// *eligible* sample of another trace, where
//   * a sample is eligible unless it lies within the last two point sizes of its trace (traces
//     arriving together at a critical point end there and are welded, they do not stop short);
//   * traces that started within the point size of each other never merge (side by side);
//   * two samples whose directions (sample_direction) lie within the merge angle of each other
//     never merge (traces running the same way, not a junction);
// and its partner is the nearest such sample, ties going to the smallest (trace, sample). The trace
// then ends at its merge point: of its samples from that first one to one point size of arc
// past it, the one nearest the partner's sample (the first of equals), where it passes the
// partner's path. Ending at the first one instead would stop it up to a point size short: where
// the traces of a thin part's two sides meet traces running along its medial surface, that
// leaves a slab about the point size thick uncovered.
//
// The queries run against a grid of the eligible samples: cubic cells of side the point size
// (larger only where the samples' extent would overflow 18 bits of cell index), each cell's
// samples grouped by direction bin (a cube map of 6 x 8 x 8 bins) with the group's bounding box.
// A querying sample first asks which bins occur around it (one lookup: per block of 2 x 2 x 2
// cells, the bins of the 27 blocks around it): when none of them can hold a direction at the
// merge angle from its own, it is done.
// Otherwise it visits only the groups within the point size whose bin is not entirely within the
// merge angle of its direction, and tests their samples one by one with the rule above. Where
// thousands of traces converge on one path, or run side by side down a fine mesh, the samples
// near a query run its own way and are never read, so the work follows the crossings, not the
// crowd.
#pragma once

#include <cstdint>
#include <vector>

#include "core/trace/trace.h"

namespace vdb_shell {

/// Ends every trace of `which` at its first merge (rule above) with an eligible sample of the
/// `indexed` traces, given each indexed trace's current end; sets end, stop (kMerge) and
/// merged_with of the traces that merge. `indexed` must be ascending. Parallel over `which`;
/// the result is the same for any thread count.
void resolve_merges(TraceResult& r, const std::vector<std::uint32_t>& which,
                    const std::vector<std::uint32_t>& indexed);

}  // namespace vdb_shell

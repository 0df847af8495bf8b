// sector_shell.h — the valid shell of a split surface (core/inner/sectors.h) as a shell of the
// input: the vertex copies joined back into their vertex, and the wedge-shaped gaps between
// neighbouring sectors filled with tets (docs/validity.md, "Folded vertices").
//
// At a sector boundary, the fan edge e = (v, b) between faces f and g, the prisms of f and g
// have the side quads (v, b, b', p_f) and (v, b, b', p_g), with p_f and p_g the inner vertices
// of v's two sectors and b' the inner vertex of b. Between them lies a gap of five vertices,
// filled with one or two tets joining the surface vertex v (or b) to the inner vertices, as the
// cuts of the two quads (from v or from b, assemble.h) dictate:
//     both from v:           (v, b', p_f, p_g)
//     both from b:           (b, v, p_f, p_g), (b, b', p_f, p_g)
//     f's from v, g's from b: (v, b, b', p_g), (v, b', p_f, p_g)   (and mirrored)
// Gaps whose b is split at the same edge, or whose two sectors share an inner vertex, are left
// open, and so are gap tets below the search's minimum quality. Each gap tet is oriented by its
// volume; the shell is then checked on the input surface (check_added_tets(): every check in
// full but overlaps and leaks, which only gap tets can add: joining the copies moves no point)
// and every gap tet that offends (flat, inverted, overlapping, leaking) is removed until it
// passes: the shell without gap tets is the split surface's valid shell, so this ends valid.
// At most 2 tets per sector boundary: T <= 3F + 2 * sectors. A layered shell (--layers K > 1)
// cuts the side quads at layer points the gap tets would not share, so its gaps stay open:
// T <= 3 K F.
//
// join_zero_area_faces() does the same for the shell of a surface whose zero-area faces were
// flipped away (core/read/zero_area.h): each flip's flat tet glued on, the tets' source
// triangles those of the input faces whose ground they cover.
#pragma once

#include <cstddef>

#include "core/inner/sectors.h"
#include "core/read/zero_area.h"
#include "core/validity/search.h"

namespace vdb_shell {

struct SectorShell {
  std::size_t gap_tets = 0;      ///< tets filling gaps between sectors, in the shell
  std::size_t dropped_gaps = 0;  ///< gap tets removed because they offended
};

/// Turns `valid`, the valid shell of split.surface, into a shell of `surface`: joins the copies
/// (points and tets renumbered), fills the sector gaps and checks the result on `surface`
/// (valid.checks). valid.input stays on the split surface.
/// Gap tets of a volume-length quality below `min_quality` are not added (the search does not
/// leave such slivers where it can move a corner either).
SectorShell join_sectors(const SurfaceMesh& surface, const SectorSplit& split, ValidShell& valid,
                         double min_quality);

/// Turns `valid`, the valid shell of `surface` with `flips` made (of its sectors joined, with
/// `gap_tets` tets filling their gaps), into a shell of `surface`: the flat tets appended (the
/// last flips.tets.size() tets, layer 1), the source triangles mapped to the input's, checked in
/// full on `surface` (valid.checks; ShellCheckOptions::flat_tets).
void join_zero_area_faces(const SurfaceMesh& surface, const ZeroAreaFlips& flips,
                          std::size_t gap_tets, ValidShell& valid);

}  // namespace vdb_shell

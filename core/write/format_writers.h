// format_writers.h — the tet-mesh formats written in their own files (internal to core/write;
// write_tet_mesh() in shell_writers.h is the public entry).
#pragma once

#include <algorithm>
#include <ostream>

#include "core/write/shell_writers.h"

namespace vdb_shell {

/// Whether `mesh` has more than one layer (--layers): only then is TetMesh::layer written.
inline bool layered(const TetMesh& mesh) {
  return std::any_of(mesh.layer.begin(), mesh.layer.end(), [](std::uint8_t k) { return k > 1; });
}

void write_msh41(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary);
void write_msh22(std::ostream& os, const TetMesh& mesh, const TaggedBoundary& boundary);

}  // namespace vdb_shell

// html_report.h — what pipeline.cpp needs of html_report.cpp.
#pragma once

#include <cstddef>

#include "core/base/surface_mesh.h"
#include "core/base/tet_mesh.h"

namespace vdb_shell {

/// The working memory of report_html() on a shell, bytes, beyond the result itself: the tet
/// face table, the dihedral angles, one picture's canvas, the sections (from the tets each
/// middle plane cuts) and the page.
std::size_t estimate_html_bytes(const SurfaceMesh& surface, const TetMesh& mesh);

}  // namespace vdb_shell

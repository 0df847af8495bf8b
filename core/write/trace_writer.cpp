// trace_writer.cpp — see trace_writer.h.
#include "core/write/trace_writer.h"

#include <cstdio>
#include <ostream>

#include "core/write/atomic_file.h"

namespace vdb_shell {

void write_paths_vtk(const std::string& path, const TraceResult& t) {
  write_file_atomically(path, [&](std::ostream& os) {
    const std::size_t n = t.num_traces();
    std::size_t points = 0;
    for (std::size_t v = 0; v < n; ++v) points += t.end[v] + 1;
    char buf[96];
    os << "# vtk DataFile Version 4.2\nvdb_shell traces\nASCII\nDATASET POLYDATA\n";
    os << "POINTS " << points << " double\n";
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t i = 0; i <= t.end[v]; ++i) {
        const Vec3d& p = t.sample(v, i);
        std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", p.x, p.y, p.z);
        os << buf;
      }
    os << "LINES " << n << " " << (n + points) << "\n";
    std::size_t next = 0;
    for (std::size_t v = 0; v < n; ++v) {
      os << (t.end[v] + 1);
      for (std::size_t i = 0; i <= t.end[v]; ++i) os << " " << next++;
      os << "\n";
    }
    os << "POINT_DATA " << points << "\nSCALARS arc_length double 1\nLOOKUP_TABLE default\n";
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t i = 0; i <= t.end[v]; ++i) {
        std::snprintf(buf, sizeof buf, "%.17g\n", t.arc_length[t.offsets[v] + i]);
        os << buf;
      }
    os << "CELL_DATA " << n << "\nSCALARS stop_reason int 1\nLOOKUP_TABLE default\n";
    for (std::size_t v = 0; v < n; ++v) os << static_cast<int>(t.stop[v]) << "\n";
    os << "SCALARS planar int 1\nLOOKUP_TABLE default\n";
    for (std::size_t v = 0; v < n; ++v) os << static_cast<int>(t.planar[v]) << "\n";
  });
}

}  // namespace vdb_shell

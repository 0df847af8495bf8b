// optimize_bench.cpp — what --optimize (core/validity/optimize.h) gains and costs: quality,
// smallest dihedral angle and coverage before and after, and its seconds beside the validity
// stage's, on the shared clean meshes and a few shapes. Not part of the test run. Usage:
//   vdb_shell_bench_optimize [RESOLUTION ...]     (default: 128 256)
// One run per input and resolution (the "before" figures are the same run's, before the moves).
// Prints Markdown.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "vdb_shell/vdb_shell.h"

int main(int argc, char** argv) {
  std::vector<int> resolutions;
  for (int i = 1; i < argc; ++i) resolutions.push_back(std::atoi(argv[i]));
  if (resolutions.empty()) resolutions = {128, 256};
  std::vector<std::pair<std::string, vdb_shell::SurfaceMesh>> inputs;
  for (const char* name : {"fandisk.obj", "fertility.off", "spot.obj", "decimated-knight.off"}) {
    const std::filesystem::path path = std::filesystem::path(VDB_SHELL_SHARED_MESHES) / name;
    if (std::filesystem::exists(path))
      inputs.emplace_back(name, vdb_shell::load_surface(path.string()).mesh);
  }
  for (const char* name : {"star", "propeller", "horn", "torus"})
    inputs.emplace_back(name, vdb_shell::make_shape(name));
  std::printf(
      "| input | res | min Q | p5 Q | min dihedral deg | coverage | moved | recut | optimize s | "
      "validity s |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (const int res : resolutions)
    for (const auto& [name, mesh] : inputs) {
      vdb_shell::ShellOptions o;
      o.fields.resolution = res;
      try {
        const vdb_shell::ShellResult r = vdb_shell::build_shell(mesh, o, {}, name);
        const vdb_shell::OptimizeSummary& b = r.optimize;
        const vdb_shell::QualitySummary& q = r.quality;
        std::printf(
            "| %s | %d | %.4f -> %.4f | %.4f -> %.4f | %.3f -> %.3f | %.4f -> %.4f | %zu | %zu | "
            "%.2f | %.2f |\n",
            name.c_str(), res, b.min_quality_before, q.min_quality, b.p5_quality_before,
            q.p5_quality, b.min_dihedral_deg_before, q.min_dihedral_deg, b.coverage_before,
            q.coverage, b.report.moved_vertices, b.report.recut_quads, b.report.seconds,
            r.timings.validity - b.report.seconds);
      } catch (const std::exception& e) {
        std::printf("| %s | %d | failed: %s |\n", name.c_str(), res, e.what());
      }
      std::fflush(stdout);
    }
  return 0;
}

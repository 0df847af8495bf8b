// check_bench.cpp — the full shell check (check_shell(), core/validity/shell_checks.h) on the
// shells of the shared meshes and of finer versions of them: seconds (median of --runs N, default
// 5), candidate pairs of the overlap test per tet, tets per second. The check runs twice per
// default run (the validity search's first incremental check is a full one, and the final
// confirmation); this isolates it. Not part of the test run. Usage:
//   vdb_shell_bench_check [--runs N] [--resolution R] [MESH ...]
// Without MESH: fandisk, spot and fertility from ../shared/meshes. Prints Markdown.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "vdb_shell/vdb_shell.h"

int main(int argc, char** argv) {
  int runs = 5, resolution = 128;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc)
      runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--resolution" && i + 1 < argc)
      resolution = std::atoi(argv[++i]);
    else
      paths.push_back(a);
  }
  if (paths.empty())
    for (const char* name : {"fandisk.obj", "spot.obj", "fertility.off"}) {
      const std::filesystem::path path = std::filesystem::path(VDB_SHELL_SHARED_MESHES) / name;
      if (std::filesystem::exists(path)) paths.push_back(path.string());
    }
  std::printf(
      "| input | res | faces | tets | candidate pairs / tet | check s (median of %d) | "
      "tets / s |\n|---|---|---|---|---|---|---|\n",
      runs);
  for (const std::string& path : paths) {
    try {
      const vdb_shell::SurfaceMesh surface = vdb_shell::load_surface(path).mesh;
      vdb_shell::ShellOptions o;
      o.fields.resolution = resolution;
      const vdb_shell::ShellResult r = vdb_shell::build_shell(surface, o, {}, path);
      std::vector<double> seconds;
      vdb_shell::ShellCheckResult c;
      for (int k = 0; k < runs; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        c = vdb_shell::check_shell(surface, r.mesh);
        seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      std::sort(seconds.begin(), seconds.end());
      const double median = seconds[seconds.size() / 2];
      const double tets = double(r.mesh.tets.size());
      std::printf("| %s | %d | %zu | %zu | %.1f | %.3f | %.0f |%s\n",
                  std::filesystem::path(path).filename().string().c_str(), resolution,
                  surface.triangles.size(), r.mesh.tets.size(),
                  double(c.overlap_candidate_pairs) / tets, median, tets / median,
                  c.valid() ? "" : " (invalid!)");
    } catch (const std::exception& e) {
      std::printf("| %s | %d | failed: %s |\n", path.c_str(), resolution, e.what());
    }
    std::fflush(stdout);
  }
  return 0;
}

// html_bench.cpp — how long report_html() (the --html page) takes and how large the page is, on
// shells from a few hundred to 250k tets. Not part of the test run. Usage:
//   vdb_shell_bench_html [--runs N]
// Each shell is built once at 128^3 (all threads); the page is then made N times (default 5)
// and the median printed, with html_thumbnail() beside it. Prints Markdown.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "assets/shapes.h"
#include "vdb_shell/vdb_shell.h"

namespace {

template <class F>
double median_seconds(int runs, F&& f) {
  std::vector<double> s;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(s.begin(), s.end());
  return s[s.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
  const std::vector<std::pair<std::string, int>> shapes = {
      {"horn", 1}, {"sphere", 4}, {"torus", 6}, {"torus", 12}};
  std::printf("| shape | faces | tets | page MB | report_html s (median of %d) | thumbnail s |\n",
              runs);
  std::printf("|---|---|---|---|---|---|\n");
  for (const auto& [name, detail] : shapes) {
    vdb_shell::ShellOptions o;
    o.fields.resolution = 128;
    const vdb_shell::ShellResult r =
        vdb_shell::build_shell(vdb_shell::make_shape(name, detail), o, {}, name);
    std::size_t bytes = 0;
    const double page = median_seconds(runs, [&] { bytes = vdb_shell::report_html(r).size(); });
    const double thumb = median_seconds(runs, [&] { vdb_shell::html_thumbnail(r); });
    std::printf("| %s (detail %d) | %zu | %zu | %.2f | %.3f | %.3f |\n", name.c_str(), detail,
                r.surface.triangles.size(), r.mesh.tets.size(), bytes / 1e6, page, thumb);
    std::fflush(stdout);
  }
  return 0;
}

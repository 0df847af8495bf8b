// fields_bench.cpp — time and peak memory of the field build (vdb_ops/fields.h), beside OpenVDB's
// plain narrow-band meshToLevelSet (half-width 3) of the same mesh at the same voxel size.
//
// Not part of the test run. Usage:
//   vdb_shell_bench_fields [--max-resolution N] [--repeat N] [--skip-sweeping] [--skip-queries]
//                          [MESH ...]
//   vdb_shell_bench_fields --floor MESH [--resolution R] [--threads N] [--json]
//       only the floor (meshToLevelSet, half-width 3) of MESH at R (default 128), in this process,
//       once; one JSON object (or one Markdown row) on stdout. For run_benchmarks.py, which
//       measures the process's wall time and peak RSS itself.
//   vdb_shell_bench_fields --write-subdivided IN OUT [--levels N]
//       midpoint-subdivide IN N times (default 2: 4^N times the faces) and write OUT (.obj .off
//       .ply, full precision); e.g. fertility.off -> the 144,000-face "fertility x16".
// Without MESH it uses ../shared/meshes/fandisk.obj and fertility.off subdivided to 144k faces.
// With --repeat N every build runs N times (floor and fields alternating) and each row shows the
// run with the median total time.
// Every measurement runs in a forked child, so "peak" is that build's own maximum resident set
// (VmHWM, after resetting it through /proc/self/clear_refs where the kernel allows) minus the
// resident set at fork time. Where the reset is refused the column cannot go below the parent's
// own peak (~ tens of MB): small values at 128/256 are that floor. Prints Markdown.
#include <sys/wait.h>
#include <unistd.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "core/write/shell_writers.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/fields_diagnostics.h"

namespace vdb_shell {
namespace {

/// What a child reports back through its pipe.
struct Sample {
  double seconds = 0.0;   ///< total build time
  double sdf = 0.0;       ///< SDF (incl. interior fill)
  double refine = 0.0;    ///< interior fill or refinement pass (part of sdf)
  double flux = 0.0;      ///< flux grid
  double gradient = 0.0;  ///< gradient grid
  double active = 0.0;    ///< SDF active voxels
  double flux_active = 0.0;
  double grid_mb = 0.0;  ///< memory held by the grids
  double estimate_mb = 0.0;
  double peak_mb = 0.0;  ///< child's peak RSS minus the parent's RSS at fork
  bool ok = false;
};

double rss_mb_now() {
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return double(resident) * double(::sysconf(_SC_PAGE_SIZE)) / (1024.0 * 1024.0);
}

/// VmHWM (peak resident set) of this process, MB.
double peak_mb_now() {
  double kb = 0.0;
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    while (std::fgets(line, sizeof(line), f)) {
      if (std::strncmp(line, "VmHWM:", 6) == 0) kb = std::atof(line + 6);
    }
    std::fclose(f);
  }
  return kb / 1024.0;
}

/// Runs f() in a forked child and returns its result R (Sample, or any trivially copyable type
/// with `ok` and `peak_mb`), with the child's own peak memory.
template <typename F, typename R = std::invoke_result_t<F>>
R in_child(F&& f) {
  static_assert(std::is_trivially_copyable_v<R>, "results travel through a pipe");
  int fds[2];
  if (::pipe(fds) != 0) return {};
  std::cout.flush();  // or the child would print the parent's buffered output again
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    // Reset the peak to the current resident set (Linux >= 4.0), then measure from there.
    if (FILE* c = std::fopen("/proc/self/clear_refs", "w")) {
      std::fputs("5", c);
      std::fclose(c);
    }
    const double base = rss_mb_now();
    R s;
    try {
      s = f();
      s.ok = true;
    } catch (const std::exception& e) {
      std::cerr << "  (failed: " << e.what() << ")\n";
    }
    s.peak_mb = peak_mb_now() - base;
    if (::write(fds[1], &s, sizeof(s)) != ssize_t(sizeof(s))) ::_exit(1);
    ::_exit(0);
  }
  ::close(fds[1]);
  R s;
  if (::read(fds[0], &s, sizeof(s)) != ssize_t(sizeof(s))) s.ok = false;
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return s;
}

Sample from_stats(const FieldStats& st) {
  Sample s;
  s.seconds = st.seconds_total;
  s.sdf = st.seconds_sdf;
  s.refine = st.seconds_fill + st.seconds_refine;
  s.flux = st.seconds_flux;
  s.gradient = st.seconds_gradient;
  s.active = double(st.sdf_active_voxels);
  s.flux_active = double(st.flux_active_voxels);
  s.grid_mb = double(st.grid_bytes) / (1024.0 * 1024.0);
  s.estimate_mb = double(st.estimated_bytes) / (1024.0 * 1024.0);
  return s;
}

/// Midpoint subdivision: every triangle into 4 (same surface, 4x the faces).
SurfaceMesh subdivide(const SurfaceMesh& in) {
  SurfaceMesh out;
  out.points = in.points;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
  auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const auto key = std::minmax(a, b);
    auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    const auto id = std::uint32_t(out.points.size());
    out.points.push_back((in.points[a] + in.points[b]) * 0.5);
    mid.emplace(key, id);
    return id;
  };
  for (const Triangle& t : in.triangles) {
    const std::uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]),
                        ca = midpoint(t[2], t[0]);
    out.triangles.push_back({t[0], ab, ca});
    out.triangles.push_back({ab, t[1], bc});
    out.triangles.push_back({ca, bc, t[2]});
    out.triangles.push_back({ab, bc, ca});
  }
  return out;
}

/// The sample with the median total time (the lower middle one for an even count).
Sample median_of(std::vector<Sample> v) {
  std::sort(v.begin(), v.end(), [](const Sample& a, const Sample& b) {
    return a.ok != b.ok ? a.ok : a.seconds < b.seconds;
  });
  return v.empty() ? Sample{} : v[(v.size() - 1) / 2];
}

void print_row(const std::string& mesh, int res, const std::string& what, const Sample& s,
               double floor_seconds, double floor_peak) {
  char line[512];
  if (!s.ok) {
    std::snprintf(line, sizeof(line), "| %s | %d | %s | failed | | | | | | | | |", mesh.c_str(),
                  res, what.c_str());
  } else {
    std::snprintf(line, sizeof(line),
                  "| %s | %d | %s | %.2f | %.2f (%.2f) | %.2f | %.2f | %.1fM | %.2fM | %.0f | %.0f "
                  "| %.0f | %.2fx / %.2fx |",
                  mesh.c_str(), res, what.c_str(), s.seconds, s.sdf, s.refine, s.flux, s.gradient,
                  s.active / 1e6, s.flux_active / 1e6, s.grid_mb, s.estimate_mb, s.peak_mb,
                  floor_seconds > 0 ? s.seconds / floor_seconds : 0.0,
                  floor_peak > 0 ? s.peak_mb / floor_peak : 0.0);
  }
  std::cout << line << std::endl;
}

/// ns per gradient + flux query along trace-like paths (one thread): from every 4th vertex,
/// 400 steps of half a voxel against the gradient (paper eq. 1-2), and at random points.
std::pair<double, double> query_ns(const Fields& fields, const SurfaceMesh& mesh) {
  auto probe = fields.probe();
  const double step = 0.5 * fields.voxel_size();
  std::size_t n = 0;
  double sink = 0.0;
  auto t0 = std::chrono::steady_clock::now();
  for (std::size_t v = 0; v < mesh.num_vertices(); v += 4) {
    Vec3d q = mesh.points[v];
    for (int i = 0; i < 400; ++i, ++n) {
      Vec3d g = probe->gradient(q);
      sink += probe->flux(q);
      const double len = norm(g);
      if (len > 1.0) g = g / len;
      q -= step * g;
    }
  }
  const double trace =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e9 /
      double(n);
  const BBox box = bounding_box(mesh);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vec3d> pts(static_cast<std::size_t>(1000000));
  for (Vec3d& p : pts) {
    p = {box.lo.x + u(rng) * box.extent().x, box.lo.y + u(rng) * box.extent().y,
         box.lo.z + u(rng) * box.extent().z};
  }
  t0 = std::chrono::steady_clock::now();
  for (const Vec3d& p : pts) sink += probe->gradient(p).x;
  const double random =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e9 /
      double(pts.size());
  if (sink == 12345.678) std::cout << "";  // keep the loops
  return {trace, random};
}

/// Sphere of radius 0.5 at `res`: worst |phi - (|x| - R)| inside, voxels.
void sphere_accuracy(SdfMethod method, int res) {
  const SurfaceMesh mesh = make_shape("sphere", 8);
  FieldOptions options;
  options.resolution = res;
  options.sdf_method = method;
  const auto t0 = std::chrono::steady_clock::now();
  const auto fields = build_fields(mesh, options);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double h = fields->voxel_size();
  const IndexBox b = fields->active_index_box();
  double worst = 0.0, sum = 0.0;
  std::size_t n = 0;
  for (int i = b.lo[0]; i <= b.hi[0]; ++i)
    for (int j = b.lo[1]; j <= b.hi[1]; ++j)
      for (int k = b.lo[2]; k <= b.hi[2]; ++k) {
        const double r = norm(fields->voxel_center(i, j, k));
        if (r >= 0.5) continue;
        const double e = std::abs(fields->phi_at_voxel(i, j, k) - (r - 0.5)) / h;
        worst = std::max(worst, e);
        sum += e;
        ++n;
      }
  std::cout << "| sphere R=" << 0.5 / h << " voxels, " << mesh.num_faces() << " faces | " << res
            << " | " << fields->stats().strategy << " | " << s << " | " << worst << " | "
            << sum / double(n) << " |" << std::endl;
}

/// JSON string literal (paths only: escapes quotes, backslashes and control characters).
std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

/// --floor: one narrow-band meshToLevelSet of `path` at `res`, in this process.
int floor_only(const std::string& path, int res, int threads, bool json) {
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(threads));
  const auto t0 = std::chrono::steady_clock::now();
  const SurfaceMesh mesh = load_surface(path).mesh;
  const double load_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  FieldOptions options;
  options.resolution = res;
  options.max_memory_gb = 64.0;
  const FieldStats st = build_narrow_band_reference(mesh, options);
  char line[4096];
  if (json) {
    std::snprintf(line, sizeof line,
                  "{\"mesh\": %s, \"faces\": %zu, \"resolution\": %d, \"threads\": %d, "
                  "\"strategy\": %s, \"voxel_size\": %.17g, \"load_s\": %.6f, \"floor_s\": %.6f, "
                  "\"active_voxels\": %zu, \"grid_mb\": %.3f, \"peak_rss_mb\": %.3f}",
                  json_string(path).c_str(), mesh.num_faces(), res, threads,
                  json_string(st.strategy).c_str(), st.voxel_size, load_s, st.seconds_total,
                  st.sdf_active_voxels, double(st.grid_bytes) / (1024.0 * 1024.0), peak_mb_now());
  } else {
    std::snprintf(line, sizeof line, "| %s | %zu | %d | %.3f | %zu | %.1f | %.0f |", path.c_str(),
                  mesh.num_faces(), res, st.seconds_total, st.sdf_active_voxels,
                  double(st.grid_bytes) / (1024.0 * 1024.0), peak_mb_now());
    std::cout << "| mesh | faces | res | floor s | active voxels | grid MB | peak RSS MB |\n"
              << "|---|---|---|---|---|---|---|\n";
  }
  std::cout << line << std::endl;
  return 0;
}

/// --write-subdivided: `levels` midpoint subdivisions of `in`, written to `out`.
int write_subdivided(const std::string& in, const std::string& out, int levels) {
  SurfaceMesh mesh = load_surface(in).mesh;
  const std::size_t before = mesh.num_faces();
  for (int l = 0; l < levels; ++l) mesh = subdivide(mesh);
  write_surface(out, mesh);
  std::cout << in << " (" << before << " faces) subdivided " << levels
            << "x: " << mesh.num_vertices() << " vertices, " << mesh.num_faces() << " faces -> "
            << out << std::endl;
  return 0;
}

}  // namespace
}  // namespace vdb_shell

int main(int argc, char** argv) {
  using namespace vdb_shell;
  int max_res = 1024;
  int repeat = 1;
  bool sweeping = true;
  bool queries = true;
  std::vector<std::string> paths;
  std::string floor_mesh, subdivide_in, subdivide_out;
  int resolution = 128, threads = 0, levels = 2;
  bool json = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--floor" && i + 1 < argc) {
      floor_mesh = argv[++i];
    } else if (a == "--resolution" && i + 1 < argc) {
      resolution = std::atoi(argv[++i]);
    } else if ((a == "--threads" || a == "-j") && i + 1 < argc) {
      threads = std::max(0, std::atoi(argv[++i]));
    } else if (a == "--json") {
      json = true;
    } else if (a == "--write-subdivided" && i + 2 < argc) {
      subdivide_in = argv[++i];
      subdivide_out = argv[++i];
    } else if (a == "--levels" && i + 1 < argc) {
      levels = std::max(0, std::atoi(argv[++i]));
    } else if (a == "--max-resolution" && i + 1 < argc) {
      max_res = std::atoi(argv[++i]);
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--skip-sweeping") {
      sweeping = false;
    } else if (a == "--skip-queries") {
      queries = false;
    } else {
      paths.push_back(a);
    }
  }
  if (!floor_mesh.empty() || !subdivide_in.empty()) {
    try {
      return !floor_mesh.empty() ? floor_only(floor_mesh, resolution, threads, json)
                                 : write_subdivided(subdivide_in, subdivide_out, levels);
    } catch (const InputError& e) {
      std::cerr << "fields_bench: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "fields_bench: " << e.what() << "\n";
      return 3;
    }
  }
  std::vector<std::pair<std::string, SurfaceMesh>> meshes;
  try {
    const std::string dir = VDB_SHELL_SHARED_MESHES;
    if (paths.empty()) {
      meshes.emplace_back("fandisk", load_surface(dir + "/fandisk.obj").mesh);
      SurfaceMesh fert = load_surface(dir + "/fertility.off").mesh;
      meshes.emplace_back("fertility x16", subdivide(subdivide(fert)));
    } else {
      for (const std::string& p : paths) {
        meshes.emplace_back(std::filesystem::path(p).filename().string(), load_surface(p).mesh);
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "fields_bench: " << e.what() << "\n";
    return 2;
  }

  std::cout << "## SDF accuracy (sphere, analytic reference)\n\n"
            << "| shape | res | strategy | seconds | max error (voxels) | mean error |\n"
            << "|---|---|---|---|---|---|\n";
  // In children too, so that the parent's peak stays low for the memory columns below.
  in_child([] {
    sphere_accuracy(SdfMethod::kExactInterior, 128);
    return Sample{};
  });
  in_child([] {
    sphere_accuracy(SdfMethod::kMeshToVolumeInterior, 128);
    return Sample{};
  });
  in_child([] {
    sphere_accuracy(SdfMethod::kFastSweeping, 128);
    return Sample{};
  });

  std::cout
      << "\n## Build time and peak memory\n\n"
      << "peak = the build's own peak RSS (MB); ratio = time / floor time, peak / floor "
         "peak.\n\n"
      << "| mesh | res | build | total s | sdf s (fill or refine) | flux s | grad s | sdf active "
         "| flux active | grids MB | estimate MB | peak MB | ratio |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [name, mesh] : meshes) {
    const std::string label = name + " (" + std::to_string(mesh.num_faces()) + " f)";
    for (int res = 128; res <= max_res; res *= 2) {
      FieldOptions options;
      options.resolution = res;
      FieldOptions old_method = options;
      old_method.sdf_method = SdfMethod::kMeshToVolumeInterior;
      const bool with_old = res <= 512;
      std::vector<Sample> floors, fields, olds;
      for (int r = 0; r < repeat; ++r) {
        floors.push_back(
            in_child([&] { return from_stats(build_narrow_band_reference(mesh, options)); }));
        fields.push_back(
            in_child([&] { return from_stats(build_fields(mesh, options)->stats()); }));
        if (with_old) {
          olds.push_back(
              in_child([&] { return from_stats(build_fields(mesh, old_method)->stats()); }));
        }
      }
      const Sample floor = median_of(floors);
      print_row(label, res, "floor: meshToLevelSet hw 3", floor, floor.seconds, floor.peak_mb);
      print_row(label, res, "fields (exact interior)", median_of(fields), floor.seconds,
                floor.peak_mb);
      if (with_old) {
        print_row(label, res, "fields (meshToVolume interior)", median_of(olds), floor.seconds,
                  floor.peak_mb);
      }
      if (res <= 512) {
        FieldOptions g = options;
        g.store_gradient = true;
        const Sample s = in_child([&] { return from_stats(build_fields(mesh, g)->stats()); });
        print_row(label, res, "fields + gradient grid", s, floor.seconds, floor.peak_mb);
      }
      if (sweeping && res <= 512 && (res <= 256 || name == "fandisk")) {
        FieldOptions sw = options;
        sw.sdf_method = SdfMethod::kFastSweeping;
        const Sample s = in_child([&] { return from_stats(build_fields(mesh, sw)->stats()); });
        print_row(label, res, "fields (fast sweeping)", s, floor.seconds, floor.peak_mb);
      }
    }
  }

  std::cout << "\n## Seed band: own voxelization against meshToVolume\n\n"
            << "The exact-interior build's band (widths 2) as build_fields() makes it and by "
               "OpenVDB's meshToVolume alone, in one child process (median of the runs by our "
               "time); differing = voxels whose distance, triangle or state differ.\n\n"
            << "| mesh | res | band voxels | ours s | meshToVolume s | ratio | flood-filled "
               "triangles | differing |\n|---|---|---|---|---|---|---|---|\n";
  struct BandSample {
    SeedBandComparison c;
    bool ok = false;
    double peak_mb = 0.0;
  };
  for (const auto& [name, mesh] : meshes) {
    for (int res = 128; res <= max_res; res *= 2) {
      FieldOptions options;
      options.resolution = res;
      std::vector<BandSample> runs;
      for (int r = 0; r < repeat; ++r) {
        runs.push_back(in_child([&] { return BandSample{compare_seed_band(mesh, options)}; }));
      }
      std::sort(runs.begin(), runs.end(), [](const BandSample& a, const BandSample& b) {
        return a.ok != b.ok ? a.ok : a.c.seconds < b.c.seconds;
      });
      const BandSample& m = runs[(runs.size() - 1) / 2];
      if (!m.ok) continue;
      std::printf("| %s (%zu f) | %d | %.2fM | %.3f | %.3f | %.2fx | %s | %zu |\n", name.c_str(),
                  mesh.num_faces(), res, double(m.c.band_voxels) / 1e6, m.c.seconds,
                  m.c.seconds_mesh_to_volume, m.c.seconds / m.c.seconds_mesh_to_volume,
                  m.c.voxelized_here ? std::to_string(m.c.flood_filled).c_str() : "(all OpenVDB)",
                  m.c.differing_voxels);
    }
  }

  if (!queries) return 0;
  std::cout << "\n## Probe queries at 512 (one thread)\n\n"
            << "trace = gradient + flux per step along trace-like paths; random = gradient at "
               "random points of the bbox.\n\n"
            << "| mesh | gradient | trace ns / step | random ns / query | all grids MB | build "
               "peak MB |\n|---|---|---|---|---|---|\n";
  for (const auto& [name, mesh] : meshes) {
    for (bool stored : {false, true}) {
      FieldOptions options;
      options.resolution = std::min(512, max_res);
      options.store_gradient = stored;
      const Sample s = in_child([&] {
        const auto fields = build_fields(mesh, options);
        Sample r;
        const auto ns = query_ns(*fields, mesh);
        r.seconds = ns.first;
        r.sdf = ns.second;
        r.grid_mb = double(fields->stats().grid_bytes) / (1024.0 * 1024.0);
        return r;
      });
      std::cout << "| " << name << " | " << (stored ? "stored Vec3SGrid" : "SDF stencil") << " | "
                << s.seconds << " | " << s.sdf << " | " << s.grid_mb << " | " << s.peak_mb << " |"
                << std::endl;
    }
  }
  return 0;
}

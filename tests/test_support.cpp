// test_support.cpp — see test_support.h.
#include "tests/test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace vdb_shell::test {
namespace fs = std::filesystem;

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = fs::temp_directory_path() /
          ("vdb_shell_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

fs::path shared_meshes_dir() {
  const fs::path dir = VDB_SHELL_SHARED_MESHES;
  return fs::is_directory(dir) ? fs::canonical(dir) : fs::path();
}

fs::path shared_checker() {
  const fs::path file = fs::path(VDB_SHELL_SHARED_EVAL) / "check_shell.py";
  return fs::is_regular_file(file) ? fs::canonical(file) : fs::path();
}

std::string read_text(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

CommandResult run_command(const std::string& command) {
  TempDir dir;
  const std::string out = dir.file("stdout"), err = dir.file("stderr");
  const std::string full = command + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(full.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(out);
  r.err = read_text(err);
  return r;
}

std::string vdb_shell_bin() { return VDB_SHELL_BIN; }
std::string vdb_shell_shapes_bin() { return VDB_SHELL_SHAPES_BIN; }

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << text;
}

namespace {

double signed_volume6(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  const Vec3d u = b - a, v = c - a, w = d - a;
  return u.x * (v.y * w.z - v.z * w.y) - u.y * (v.x * w.z - v.z * w.x) +
         u.z * (v.x * w.y - v.y * w.x);
}

/// Generalised winding number of a closed surface around p (van Oosterom-Strackee solid angles).
double winding_number(const SurfaceMesh& s, const Vec3d& p) {
  double sum = 0;
  for (const Triangle& t : s.triangles) {
    const Vec3d a = s.points[t[0]] - p, b = s.points[t[1]] - p, c = s.points[t[2]] - p;
    const double la = std::sqrt(dot(a, a)), lb = std::sqrt(dot(b, b)), lc = std::sqrt(dot(c, c));
    const double num = dot(a, cross(b, c));
    const double den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * M_PI);
}

double nearest_vertex_distance(const SurfaceMesh& s, const Vec3d& p) {
  // An upper bound of the distance to the surface.
  double best = INFINITY;
  for (const Vec3d& q : s.points) best = std::min(best, std::sqrt(dot(q - p, q - p)));
  return best;
}

}  // namespace

std::string independent_shell_problems(const SurfaceMesh& surface, const TetMesh& shell) {
  std::ostringstream problem;
  const std::size_t n = surface.points.size();
  if (shell.points.size() < n) return "fewer points than the surface has";
  for (std::size_t v = 0; v < n; ++v)
    if (!(shell.points[v].x == surface.points[v].x && shell.points[v].y == surface.points[v].y &&
          shell.points[v].z == surface.points[v].z)) {
      problem << "surface point " << v << " moved";
      return problem.str();
    }
  if (shell.tets.size() > 3 * surface.triangles.size())
    return "T > 3F: " + std::to_string(shell.tets.size()) + " tets";
  // Faces of the tets, as sorted triples -> (count, an oriented copy).
  std::map<std::array<std::uint32_t, 3>, std::pair<int, std::array<std::uint32_t, 3>>> faces;
  for (std::size_t t = 0; t < shell.tets.size(); ++t) {
    const Tet& k = shell.tets[t];
    for (std::uint32_t i : k)
      if (i >= shell.points.size()) return "tet " + std::to_string(t) + ": index out of range";
    const double v6 = signed_volume6(shell.points[k[0]], shell.points[k[1]], shell.points[k[2]],
                                     shell.points[k[3]]);
    if (!(v6 > 0)) {
      problem << "tet " << t << " has signed volume " << v6 / 6;
      return problem.str();
    }
    // Outward faces of a positive tet (a, b, c, d): (b, c, d), (a, d, c), (a, b, d), (a, c, b).
    const std::array<std::array<std::uint32_t, 3>, 4> out = {{{k[1], k[2], k[3]},
                                                              {k[0], k[3], k[2]},
                                                              {k[0], k[1], k[3]},
                                                              {k[0], k[2], k[1]}}};
    for (const auto& f : out) {
      std::array<std::uint32_t, 3> key = f;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      ++entry.first;
      entry.second = f;
    }
  }
  auto same_cycle = [](const std::array<std::uint32_t, 3>& a, const Triangle& b) {
    for (int r = 0; r < 3; ++r)
      if (a[r] == b[0] && a[(r + 1) % 3] == b[1] && a[(r + 2) % 3] == b[2]) return true;
    return false;
  };
  for (std::size_t f = 0; f < surface.triangles.size(); ++f) {
    const Triangle& t = surface.triangles[f];
    std::array<std::uint32_t, 3> key = {t[0], t[1], t[2]};
    std::sort(key.begin(), key.end());
    const auto it = faces.find(key);
    if (it == faces.end() || it->second.first != 1 || !same_cycle(it->second.second, t)) {
      problem << "surface triangle " << f << " is not the outward face of exactly one tet";
      return problem.str();
    }
  }
  // Inner points: inside, or within a hair of the surface (a vertex kept on it).
  const double diag = bounding_box(surface).diagonal();
  for (std::size_t i = n; i < shell.points.size(); ++i) {
    const Vec3d& p = shell.points[i];
    if (winding_number(surface, p) > 0.5) continue;
    if (nearest_vertex_distance(surface, p) < 1e-9 * diag) continue;
    problem << "inner point " << i << " at (" << p.x << ", " << p.y << ", " << p.z
            << ") lies outside the surface";
    return problem.str();
  }
  return "";
}

}  // namespace vdb_shell::test

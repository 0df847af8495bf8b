// test_support.cpp — see test_support.h.
#include "tests/test_support.h"

#include "cli/cli.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"

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

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
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

CliRun cli(std::vector<std::string> args) {
  args.insert(args.begin(), "vdb_shell");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  CliRun r;
  r.code = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  r.out = out.str();
  r.err = err.str();
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
  return sum / (4.0 * kPi);
}

/// Signed volume enclosed by the triangles of `s`, times 6.
double enclosed_volume6(const SurfaceMesh& s) {
  double sum = 0;
  for (const Triangle& t : s.triangles) {
    const Vec3d& a = s.points[t[0]];
    const Vec3d& b = s.points[t[1]];
    const Vec3d& c = s.points[t[2]];
    sum += a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) +
           a.z * (b.x * c.y - b.y * c.x);
  }
  return sum;
}

/// The first pair (t, u) of positive tets where a sample point of t (its centroid, and the
/// midpoints between the centroid and each corner) lies strictly inside u, or {-1, -1}. Tets are
/// found through a uniform grid of their bounding boxes over the shell's box.
std::pair<long, long> first_overlap(const TetMesh& shell) {
  const std::size_t count = shell.tets.size();
  if (count < 2) return {-1, -1};
  BBox box;
  for (const Tet& k : shell.tets)
    for (std::uint32_t i : k) box.expand(shell.points[i]);
  const Vec3d lo = box.lo, extent = box.extent();
  const int n = std::clamp(static_cast<int>(std::cbrt(static_cast<double>(count))), 1, 64);
  auto cell_of = [&](double x, double l, double e) {
    return e > 0 ? std::clamp(static_cast<int>((x - l) / e * n), 0, n - 1) : 0;
  };
  auto cell = [&](const Vec3d& p) {
    return std::array<int, 3>{cell_of(p.x, lo.x, extent.x), cell_of(p.y, lo.y, extent.y),
                              cell_of(p.z, lo.z, extent.z)};
  };
  std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(n) * n * n);
  auto slot = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * n + y) * n + x; };
  for (std::size_t t = 0; t < count; ++t) {
    const Tet& k = shell.tets[t];
    std::array<int, 3> a = cell(shell.points[k[0]]), b = a;
    for (int c = 1; c < 4; ++c) {
      const std::array<int, 3> q = cell(shell.points[k[c]]);
      for (int d = 0; d < 3; ++d) a[d] = std::min(a[d], q[d]), b[d] = std::max(b[d], q[d]);
    }
    for (int z = a[2]; z <= b[2]; ++z)
      for (int y = a[1]; y <= b[1]; ++y)
        for (int x = a[0]; x <= b[0]; ++x)
          grid[slot(x, y, z)].push_back(static_cast<std::uint32_t>(t));
  }
  // Strictly inside: every barycentric coordinate above a margin far beyond rounding.
  auto strictly_inside = [&](const Vec3d& p, const Tet& k) {
    const Vec3d& a = shell.points[k[0]];
    const Vec3d& b = shell.points[k[1]];
    const Vec3d& c = shell.points[k[2]];
    const Vec3d& d = shell.points[k[3]];
    const double v = signed_volume6(a, b, c, d), margin = 1e-6 * v;
    return signed_volume6(p, b, c, d) > margin && signed_volume6(a, p, c, d) > margin &&
           signed_volume6(a, b, p, d) > margin && signed_volume6(a, b, c, p) > margin;
  };
  for (std::size_t t = 0; t < count; ++t) {
    const Tet& k = shell.tets[t];
    const Vec3d centroid =
        (shell.points[k[0]] + shell.points[k[1]] + shell.points[k[2]] + shell.points[k[3]]) * 0.25;
    for (int s = 0; s < 5; ++s) {
      const Vec3d p = s == 0 ? centroid : (centroid + shell.points[k[s - 1]]) * 0.5;
      const std::array<int, 3> c = cell(p);
      for (std::uint32_t u : grid[slot(c[0], c[1], c[2])])
        if (u != t && strictly_inside(p, shell.tets[u]))
          return {static_cast<long>(t), static_cast<long>(u)};
    }
  }
  return {-1, -1};
}

double nearest_vertex_distance(const SurfaceMesh& s, const Vec3d& p) {
  // An upper bound of the distance to the surface.
  double best = INFINITY;
  for (const Vec3d& q : s.points) best = std::min(best, std::sqrt(dot(q - p, q - p)));
  return best;
}

}  // namespace

std::string independent_shell_problems(const SurfaceMesh& surface, const TetMesh& shell,
                                       std::size_t extra_tets, std::size_t flat_tets) {
  auto same_cycle = [](const std::array<std::uint32_t, 3>& a, const Triangle& b) {
    for (int r = 0; r < 3; ++r)
      if (a[r] == b[0] && a[(r + 1) % 3] == b[1] && a[(r + 2) % 3] == b[2]) return true;
    return false;
  };
  std::ostringstream problem;
  const std::size_t n = surface.points.size();
  if (shell.points.size() < n) return "fewer points than the surface has";
  for (std::size_t v = 0; v < n; ++v)
    if (!(shell.points[v].x == surface.points[v].x && shell.points[v].y == surface.points[v].y &&
          shell.points[v].z == surface.points[v].z)) {
      problem << "surface point " << v << " moved";
      return problem.str();
    }
  if (shell.tets.size() > 3 * surface.triangles.size() + extra_tets)
    return "T > 3F + " + std::to_string(extra_tets) + ": " + std::to_string(shell.tets.size()) +
           " tets";
  // Faces of the tets, as sorted triples -> (count, an oriented copy).
  std::map<std::array<std::uint32_t, 3>, std::pair<int, std::array<std::uint32_t, 3>>> faces;
  for (std::size_t t = 0; t < shell.tets.size(); ++t) {
    const Tet& k = shell.tets[t];
    for (std::uint32_t i : k)
      if (i >= shell.points.size()) return "tet " + std::to_string(t) + ": index out of range";
    const double v6 = signed_volume6(shell.points[k[0]], shell.points[k[1]], shell.points[k[2]],
                                     shell.points[k[3]]);
    if (t + flat_tets >= shell.tets.size()) {  // a flat tet: four surface points, no volume
      const double diag = bounding_box(surface).diagonal();
      if (std::any_of(k.begin(), k.end(), [&](std::uint32_t i) { return i >= n; }) ||
          !(std::abs(v6) <= 6e-12 * diag * diag * diag)) {
        problem << "flat tet " << t << " has an inner corner or signed volume " << v6 / 6;
        return problem.str();
      }
    } else if (!(v6 > 0)) {
      problem << "tet " << t << " has signed volume " << v6 / 6;
      return problem.str();
    }
    // Outward faces of a positive tet (a, b, c, d): (b, c, d), (a, d, c), (a, b, d), (a, c, b).
    const std::array<std::array<std::uint32_t, 3>, 4> out = {
        {{k[1], k[2], k[3]}, {k[0], k[3], k[2]}, {k[0], k[1], k[3]}, {k[0], k[2], k[1]}}};
    for (const auto& f : out) {
      std::array<std::uint32_t, 3> key = f;
      std::sort(key.begin(), key.end());
      auto& entry = faces[key];
      if (++entry.first == 1) {
        entry.second = f;  // the first tet's copy
      } else if (entry.first > 2 || same_cycle(entry.second, {f[0], f[1], f[2]})) {
        problem << "face (" << key[0] << ", " << key[1] << ", " << key[2] << ") of tet " << t
                << (entry.first > 2 ? " is shared by more than two tets"
                                    : " has another tet on the same side");
        return problem.str();
      }
    }
  }
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
  TetMesh solid;  // the tets with a volume, when some are flat
  if (flat_tets > 0) {
    solid = shell;
    solid.tets.resize(shell.tets.size() - std::min(flat_tets, shell.tets.size()));
  }
  const auto [t, u] = first_overlap(flat_tets > 0 ? solid : shell);
  if (t >= 0) {
    problem << "tets " << t << " and " << u << " overlap";
    return problem.str();
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

double independent_quality(const TetMesh& mesh, const Tet& t) {
  const Vec3d p[4] = {mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]], mesh.points[t[3]]};
  const double volume = dot(p[1] - p[0], cross(p[2] - p[0], p[3] - p[0])) / 6.0;
  double sum2 = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) sum2 += norm2(p[i] - p[j]);
  return 6 * std::sqrt(2.0) * volume / std::pow(sum2 / 6, 1.5);
}

double independent_coverage(const SurfaceMesh& surface, const TetMesh& shell) {
  const double enclosed = enclosed_volume6(surface);
  if (enclosed == 0) return 0;
  double volume = 0;
  for (const Tet& k : shell.tets)
    volume += signed_volume6(shell.points[k[0]], shell.points[k[1]], shell.points[k[2]],
                             shell.points[k[3]]);
  return volume / enclosed;
}

namespace {

/// The rows of a TetGen table without comments ('#' to the end of the line) and blank lines.
std::vector<std::vector<std::string>> tetgen_rows(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line.substr(0, line.find('#')));
    std::vector<std::string> row;
    for (std::string w; words >> w;) row.push_back(w);
    if (!row.empty()) rows.push_back(row);
  }
  if (rows.empty() || static_cast<long long>(rows.size()) != std::stoll(rows[0][0]) + 1)
    throw std::runtime_error(path + ": the row count differs from the header's");
  return rows;
}

}  // namespace

TetMesh read_tetgen_shell(const std::string& ele_path) {
  const fs::path ele(ele_path);
  const fs::path node = fs::path(ele).replace_extension(".node");
  const auto nodes = tetgen_rows(node.string());
  const auto eles = tetgen_rows(ele.string());
  TetMesh mesh;
  const long long first = nodes.size() > 1 ? std::stoll(nodes[1].at(0)) : 0;
  for (std::size_t r = 1; r < nodes.size(); ++r)
    mesh.points.push_back(
        {std::stod(nodes[r].at(1)), std::stod(nodes[r].at(2)), std::stod(nodes[r].at(3))});
  for (std::size_t r = 1; r < eles.size(); ++r) {
    Tet k{};
    for (int c = 0; c < 4; ++c) {
      const long long i = std::stoll(eles[r].at(c + 1)) - first;
      if (i < 0 || i >= static_cast<long long>(mesh.points.size()))
        throw std::runtime_error(ele_path + ": node index out of range in row " +
                                 std::to_string(r));
      k[c] = static_cast<std::uint32_t>(i);
    }
    mesh.tets.push_back(k);
  }
  return mesh;
}

namespace {

struct Vec2 {
  double x, y;
};

double orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

/// Coplanar triangles (2D, after projection): some pair of edges crosses properly or a vertex
/// lies strictly inside the other triangle. Shared vertices and edges do not count.
bool coplanar_overlap(const std::array<Vec2, 3>& p, const std::array<Vec2, 3>& q, double tol) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec2 &a = p[i], &b = p[(i + 1) % 3], &c = q[j], &d = q[(j + 1) % 3];
      const double o1 = orient2d(a, b, c), o2 = orient2d(a, b, d);
      const double o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
      if (((o1 > tol && o2 < -tol) || (o1 < -tol && o2 > tol)) &&
          ((o3 > tol && o4 < -tol) || (o3 < -tol && o4 > tol))) {
        return true;
      }
    }
  }
  auto inside = [&](const Vec2& v, const std::array<Vec2, 3>& t) {
    const double s0 = orient2d(t[0], t[1], v), s1 = orient2d(t[1], t[2], v);
    const double s2 = orient2d(t[2], t[0], v);
    return (s0 > tol && s1 > tol && s2 > tol) || (s0 < -tol && s1 < -tol && s2 < -tol);
  };
  for (int i = 0; i < 3; ++i) {
    if (inside(p[i], q) || inside(q[i], p)) return true;
  }
  return false;
}

/// Some edge of `t` passes through the interior of `u` (touching counts; sharing does not).
bool edge_pierces(const std::array<Vec3d, 3>& t, const std::array<Vec3d, 3>& u, double tol3) {
  for (int i = 0; i < 3; ++i) {
    const Vec3d &p = t[i], &q = t[(i + 1) % 3];
    const double d1 = signed_volume6(u[0], u[1], u[2], p), d2 = signed_volume6(u[0], u[1], u[2], q);
    if ((d1 > tol3 && d2 > tol3) || (d1 < -tol3 && d2 < -tol3)) continue;
    if (std::fabs(d1) <= tol3 && std::fabs(d2) <= tol3) continue;  // in the plane: 2D test
    const double s1 = signed_volume6(p, q, u[0], u[1]), s2 = signed_volume6(p, q, u[1], u[2]);
    const double s3 = signed_volume6(p, q, u[2], u[0]);
    if ((s1 > tol3 && s2 > tol3 && s3 > tol3) || (s1 < -tol3 && s2 < -tol3 && s3 < -tol3)) {
      return true;
    }
  }
  return false;
}

}  // namespace

bool triangles_intersect(const std::array<Vec3d, 3>& t, const std::array<Vec3d, 3>& u) {
  double longest = 0.0;
  for (int i = 0; i < 3; ++i) {
    longest = std::max({longest, norm(t[i] - t[(i + 1) % 3]), norm(u[i] - u[(i + 1) % 3])});
  }
  const double tol3 = 1e-10 * longest * longest * longest;
  const double tol2 = 1e-10 * longest * longest;
  bool coplanar = true;
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(signed_volume6(u[0], u[1], u[2], t[i])) > tol3) coplanar = false;
  }
  if (coplanar) {
    const Vec3d n = cross(u[1] - u[0], u[2] - u[0]);
    const Vec3d an{std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)};
    const int drop = an.x >= an.y && an.x >= an.z ? 0 : (an.y >= an.z ? 1 : 2);
    auto project = [&](const std::array<Vec3d, 3>& tri) {
      std::array<Vec2, 3> out;
      for (int i = 0; i < 3; ++i) {
        const Vec3d& v = tri[i];
        out[i] = drop == 0 ? Vec2{v.y, v.z} : (drop == 1 ? Vec2{v.z, v.x} : Vec2{v.x, v.y});
      }
      return out;
    };
    return coplanar_overlap(project(t), project(u), tol2);
  }
  return edge_pierces(t, u, tol3) || edge_pierces(u, t, tol3);
}

std::vector<std::pair<std::size_t, std::size_t>> self_intersections(const SurfaceMesh& mesh) {
  const std::size_t nf = mesh.num_faces();
  std::vector<BBox> boxes(nf);
  std::vector<std::array<Vec3d, 3>> tris(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      tris[f][k] = mesh.points[mesh.triangles[f][k]];
      boxes[f].expand(tris[f][k]);
    }
  }
  std::vector<std::size_t> order(nf);
  for (std::size_t f = 0; f < nf; ++f) order[f] = f;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return boxes[a].lo.x < boxes[b].lo.x; });
  const double pad = 1e-12;
  std::vector<std::pair<std::size_t, std::size_t>> hits;
  for (std::size_t i = 0; i < nf; ++i) {
    const std::size_t f = order[i];
    for (std::size_t k = i + 1; k < nf; ++k) {
      const std::size_t g = order[k];
      if (boxes[g].lo.x > boxes[f].hi.x + pad) break;
      if (boxes[g].lo.y > boxes[f].hi.y + pad || boxes[f].lo.y > boxes[g].hi.y + pad ||
          boxes[g].lo.z > boxes[f].hi.z + pad || boxes[f].lo.z > boxes[g].hi.z + pad) {
        continue;
      }
      int shared = 0;
      for (std::uint32_t a : mesh.triangles[f]) {
        for (std::uint32_t b : mesh.triangles[g]) shared += a == b ? 1 : 0;
      }
      if (shared >= 2) {
        const Vec3d nf_ = face_normal_area(mesh, f), ng = face_normal_area(mesh, g);
        if (dot(nf_, ng) < -0.999 * norm(nf_) * norm(ng)) hits.emplace_back(f, g);
        continue;
      }
      if (triangles_intersect(tris[f], tris[g])) hits.emplace_back(f, g);
    }
  }
  return hits;
}

SurfaceMesh with_vertices_near_edge_ends(const SurfaceMesh& mesh, std::size_t every, double t,
                                         std::vector<InsertedVertex>& inserted) {
  SurfaceMesh out = mesh;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> faces_of;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;  // in order of first appearance
  for (std::uint32_t f = 0; f < mesh.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[f][k], b = mesh.triangles[f][(k + 1) % 3];
      auto& faces = faces_of[{std::min(a, b), std::max(a, b)}];
      if (faces.empty()) edges.emplace_back(std::min(a, b), std::max(a, b));
      faces.push_back(f);
    }
  std::vector<char> split(mesh.triangles.size(), 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> chain;
  std::size_t turn = 0;
  for (std::size_t e = 0; e < edges.size(); e += every) {
    const auto [a, b] = edges[e];
    const auto& faces = faces_of[edges[e]];
    if (std::any_of(faces.begin(), faces.end(), [&](std::uint32_t f) { return split[f]; }))
      continue;
    for (const std::uint32_t f : faces) split[f] = 1;
    std::vector<std::uint32_t>& ids = chain[edges[e]];
    ids.push_back(a);
    const auto insert = [&](std::uint32_t near, std::uint32_t far, double at) {
      const Vec3d& p = mesh.points[near];
      const Vec3d& q = mesh.points[far];
      ids.push_back(static_cast<std::uint32_t>(out.points.size()));
      inserted.push_back({ids.back(), near, far, at});
      out.points.push_back(p + (q - p) * at);
    };
    switch (turn++ % 3) {
      case 0:
        insert(a, b, t);
        break;
      case 1:
        insert(a, b, t);
        insert(a, b, 2 * t);
        break;
      default:
        insert(a, b, t);
        insert(b, a, t);
    }
    ids.push_back(b);
  }
  out.triangles.clear();
  for (const Triangle& tri : mesh.triangles) {
    int k = 0;
    while (k < 3 &&
           !chain.count({std::min(tri[k], tri[(k + 1) % 3]), std::max(tri[k], tri[(k + 1) % 3])}))
      ++k;
    if (k == 3) {
      out.triangles.push_back(tri);
      continue;
    }
    const std::uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
    std::vector<std::uint32_t> ids = chain[{std::min(a, b), std::max(a, b)}];
    if (ids.front() != a) std::reverse(ids.begin(), ids.end());
    for (std::size_t i = 0; i + 1 < ids.size(); ++i)
      out.triangles.push_back({ids[i], ids[i + 1], c});
  }
  return out;
}

SurfaceMesh with_caps(const SurfaceMesh& mesh, std::size_t every, double height,
                      std::size_t vertices, std::vector<InsertedVertex>& inserted) {
  SurfaceMesh out = mesh;
  out.triangles.clear();
  std::size_t turn = 0;
  std::set<std::pair<std::uint32_t, std::uint32_t>> bases;  // one strip per edge
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& tri = mesh.triangles[f];
    const int k = static_cast<int>(turn % 3);
    if (f % every != 0 ||
        !bases.insert({std::min(tri[k], tri[(k + 1) % 3]), std::max(tri[k], tri[(k + 1) % 3])})
             .second) {
      out.triangles.push_back(tri);
      continue;
    }
    const double shift = 0.1 * (static_cast<double>(turn++ % 3) - 1.0) / double(vertices + 1);
    const std::uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
    const Vec3d &pa = mesh.points[a], &pb = mesh.points[b], &pc = mesh.points[c];
    const Vec3d along = pb - pa;
    const Vec3d towards = normalized((pc - pa) - along * (dot(pc - pa, along) / norm2(along)));
    std::vector<std::uint32_t> m;
    for (std::size_t i = 0; i < vertices; ++i) {
      const double t = 0.2 + 0.6 * double(i + 1) / double(vertices + 1) + shift;
      m.push_back(static_cast<std::uint32_t>(out.points.size()));
      out.points.push_back(pa + along * t + towards * (4 * height * t * (1 - t) * norm(along)));
      inserted.push_back({m.back(), a, b, t});
    }
    out.triangles.push_back({a, b, m.back()});
    for (std::size_t i = vertices - 1; i > 0; --i) out.triangles.push_back({a, m[i], m[i - 1]});
    out.triangles.push_back({a, m.front(), c});
    for (std::size_t i = 0; i + 1 < vertices; ++i) out.triangles.push_back({m[i], m[i + 1], c});
    out.triangles.push_back({m.back(), b, c});
  }
  return out;
}

SurfaceMesh with_vertices_near_corners(const SurfaceMesh& mesh, std::size_t every, double distance,
                                       std::vector<InsertedVertex>& inserted) {
  SurfaceMesh out = mesh;
  out.triangles.clear();
  std::vector<char> split(mesh.points.size(), 0);
  std::size_t turn = 0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& tri = mesh.triangles[f];
    if (f % every != 0 || split[tri[0]] || split[tri[1]] || split[tri[2]]) {
      out.triangles.push_back(tri);
      continue;
    }
    const int k = static_cast<int>(turn % 3);
    const double mix = 0.3 + 0.2 * static_cast<double>(turn++ % 3);
    const std::uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
    const Vec3d &pa = mesh.points[a], &pb = mesh.points[b], &pc = mesh.points[c];
    const Vec3d into = normalized(normalized(pb - pa) * mix + normalized(pc - pa) * (1 - mix));
    const auto m = static_cast<std::uint32_t>(out.points.size());
    out.points.push_back(pa + into * (distance * std::min(norm(pb - pa), norm(pc - pa))));
    inserted.push_back({m, a, a, distance});
    for (const std::uint32_t v : tri) split[v] = 1;
    out.triangles.push_back({a, b, m});
    out.triangles.push_back({b, c, m});
    out.triangles.push_back({c, a, m});
  }
  return out;
}

SurfaceMesh folded_sliver_box(double across, double turn, Tet& flat) {
  SurfaceMesh box = make_shape("box", 1);
  const auto on_top = [&](std::uint32_t v) { return box.points[v].z == 0.5; };
  const auto fold = [&]() -> bool {
    for (std::uint32_t f = 0; f < box.triangles.size(); ++f) {
      const Triangle t = box.triangles[f];
      if (!std::all_of(t.begin(), t.end(), on_top)) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
        for (const Triangle& g : box.triangles) {
          const auto at = static_cast<std::size_t>(std::find(g.begin(), g.end(), b) - g.begin());
          if (at == 3 || g[(at + 1) % 3] != a || !on_top(g[(at + 2) % 3])) continue;
          const std::uint32_t y = g[(at + 2) % 3];
          const Vec3d &pa = box.points[a], &pb = box.points[b], mid = 0.5 * (pa + pb);
          const Vec3d along = normalized(pb - pa), to_y = box.points[y] - mid;
          const auto m = static_cast<std::uint32_t>(box.points.size());
          box.points.push_back(mid + across * norm(pb - pa) *
                                         normalized(to_y - dot(to_y, along) * along));
          box.triangles[f] = {a, b, m};
          box.triangles.push_back({b, c, m});
          box.triangles.push_back({c, a, m});
          flat = {a, b, y, m};
          return true;
        }
      }
    }
    return false;
  };
  if (!fold())
    throw std::logic_error("folded_sliver_box: no face of the top has a neighbour in it");
  turn_points(box.points, Vec3d{turn, 2 * turn, 0});
  return box;
}

void turn_points(std::vector<Vec3d>& points, const Vec3d& turn) {
  const double cz = std::cos(turn[0]), sz = std::sin(turn[0]), cx = std::cos(turn[1]),
               sx = std::sin(turn[1]), cy = std::cos(turn[2]), sy = std::sin(turn[2]);
  for (Vec3d& p : points) {
    p = Vec3d{cz * p[0] - sz * p[1], sz * p[0] + cz * p[1], p[2]};
    p = Vec3d{p[0], cx * p[1] - sx * p[2], sx * p[1] + cx * p[2]};
    p = Vec3d{cy * p[0] + sy * p[2], p[1], -sy * p[0] + cy * p[2]};
  }
}

}  // namespace vdb_shell::test

// vdb_io.cpp — .vdb files: write_grids() (content-derived header UUID), reading grid
// descriptions, reading a float grid, and volume_to_soup() (OpenVDB volumeToMesh).
#include "vdb_ops/fields/fields_internal.h"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <vector>

#include "core/base/errors.h"
#include "core/read/load_surface.h"
#include "core/validity/shell_checks.h"
#include "core/write/atomic_file.h"
#include "vdb_ops/trace_points_grid.h"

namespace vdb_shell {

using namespace fields_detail;

namespace {

std::uint64_t fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

template <typename GridT>
std::uint64_t checksum_of(const GridT& grid) {
  std::uint64_t h = 14695981039346656037ull;
  // Value iteration order is the tree's (deterministic for equal topology).
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    const auto value = *it;
    h = fnv1a(h, &box, sizeof(box));
    h = fnv1a(h, &value, sizeof(value));
  }
  return h;
}

VdbGridInfo info_of(const openvdb::GridBase& grid) {
  VdbGridInfo info;
  info.name = grid.getName();
  info.value_type = grid.valueType();
  info.grid_class = openvdb::GridBase::gridClassToString(grid.getGridClass());
  info.active_voxels = grid.activeVoxelCount();
  info.voxel_size = grid.voxelSize()[0];
  for (auto it = grid.beginMeta(); it != grid.endMeta(); ++it) {
    info.metadata[it->first] = it->second ? it->second->str() : std::string();
  }
  if (const auto* f = dynamic_cast<const FloatGrid*>(&grid)) {
    info.checksum = checksum_of(*f);
  } else if (const auto* v = dynamic_cast<const Vec3SGrid*>(&grid)) {
    info.checksum = checksum_of(*v);
  }
  return info;
}

openvdb::GridPtrVec output_grids(const Fields& fields,
                                 const std::map<std::string, std::string>& metadata) {
  const Fields::Impl& f = FieldsAccess::impl(fields);
  openvdb::GridPtrVec grids;
  std::vector<openvdb::GridBase::Ptr> all = {f.sdf->copyGrid(), f.flux->copyGrid()};
  if (f.gradient) all.push_back(f.gradient->copyGrid());
  for (openvdb::GridBase::Ptr& g : all) {
    for (const auto& [k, v] : fields.parameters()) g->insertMeta(k, openvdb::StringMetadata(v));
    for (const auto& [k, v] : metadata) g->insertMeta(k, openvdb::StringMetadata(v));
    grids.push_back(g);
  }
  return grids;
}

/// OpenVDB writes a random UUID into every file header, as 36 characters at byte kUuidOffset
/// (after the magic number, three version numbers and a flag), so two writes of the same grids
/// would differ. write_grids() replaces it by one derived from the rest of the file: the same
/// grids give the same bytes (for any thread count, on every run), and different content still
/// gets a different UUID, which is what OpenVDB compares it for.
constexpr std::streamoff kUuidOffset = 21;
constexpr std::size_t kUuidChars = 36;

/// Forwards every byte to `target`, hashing all but the header's UUID and keeping a copy of it.
class HashingBuf final : public std::streambuf {
 public:
  explicit HashingBuf(std::streambuf* target) : target_(target) {}

  /// "xxxxxxxx-xxxx-8xxx-axxx-xxxxxxxxxxxx" from the hash (RFC 9562 version 8, custom), or ""
  /// when the header did not hold a UUID where expected (then the file is left as written).
  std::string content_uuid() const {
    if (!is_uuid(uuid_)) return "";
    std::uint64_t hi = hash_, lo = hash_ ^ (bytes_ * 0x9e3779b97f4a7c15ull);
    lo ^= lo >> 30, lo *= 0xbf58476d1ce4e5b9ull, lo ^= lo >> 27, lo *= 0x94d049bb133111ebull;
    lo ^= lo >> 31;                                // splitmix64 finaliser
    hi = (hi & ~0xf000ull) | 0x8000ull;            // version 8
    lo = (lo & ~(0x3ull << 62)) | (0x2ull << 62);  // variant 10
    char buf[40];
    std::snprintf(buf, sizeof buf, "%08llx-%04llx-%04llx-%04llx-%012llx",
                  static_cast<unsigned long long>(hi >> 32),
                  static_cast<unsigned long long>((hi >> 16) & 0xffff),
                  static_cast<unsigned long long>(hi & 0xffff),
                  static_cast<unsigned long long>(lo >> 48),
                  static_cast<unsigned long long>(lo & 0xffffffffffffull));
    return buf;
  }

 protected:
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::uint64_t begin = bytes_, end = bytes_ + static_cast<std::uint64_t>(n);
    const std::uint64_t u0 = kUuidOffset, u1 = u0 + kUuidChars;
    auto hash = [&](std::uint64_t a, std::uint64_t b) {  // absolute offsets [a, b)
      if (a < b) hash_ = fnv1a(hash_, s + (a - begin), b - a);
    };
    hash(begin, std::min(end, u0));
    const std::uint64_t c0 = std::max(begin, u0), c1 = std::min(end, u1);
    if (c0 < c1) uuid_.append(s + (c0 - begin), c1 - c0);
    hash(std::max(begin, u1), end);
    bytes_ = end;
    return target_->sputn(s, n);
  }
  int_type overflow(int_type c) override {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char ch = traits_type::to_char_type(c);
    return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
  }
  int sync() override { return target_->pubsync(); }

 private:
  static bool is_uuid(const std::string& u) {
    if (u.size() != kUuidChars) return false;
    for (std::size_t i = 0; i < u.size(); ++i) {
      const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
      if (dash ? u[i] != '-' : !std::isxdigit(static_cast<unsigned char>(u[i]))) return false;
    }
    return true;
  }

  std::streambuf* target_;
  std::uint64_t hash_ = 14695981039346656037ull;
  std::uint64_t bytes_ = 0;
  std::string uuid_;
};

}  // namespace

void write_grids(const std::string& path, const Fields& fields,
                 const std::map<std::string, std::string>& metadata, const TraceResult* traces) {
  init_openvdb();
  auto tag = [&](openvdb::MetaMap& m) {
    for (const auto& [k, v] : fields.parameters()) m.insertMeta(k, openvdb::StringMetadata(v));
    for (const auto& [k, v] : metadata) m.insertMeta(k, openvdb::StringMetadata(v));
  };
  openvdb::GridPtrVec grids = output_grids(fields, metadata);
  if (traces) {
    grids.push_back(make_trace_points_grid(*traces, FieldsAccess::impl(fields).sdf->transform()));
    tag(*grids.back());
  }
  openvdb::MetaMap file_meta;
  tag(file_meta);
  write_file_atomically(path, [&](std::ostream& os) {
    HashingBuf hashing(os.rdbuf());
    std::ostream hashed(&hashing);
    try {
      openvdb::io::Stream(hashed).write(grids, file_meta);
    } catch (const openvdb::Exception& e) {
      throw ResourceError("cannot write '" + path + "': " + e.what());
    }
    const std::string uuid = hashing.content_uuid();
    if (hashed && !uuid.empty()) {
      os.seekp(kUuidOffset);
      os.write(uuid.data(), static_cast<std::streamsize>(uuid.size()));
      os.seekp(0, std::ios::end);
    }
    if (!hashed || !os)
      throw ResourceError("cannot write '" + path + "': write failed (disk full?)");
  });
}

std::size_t estimate_write_grids_bytes(const Fields& fields, const TraceResult* traces) {
  return static_cast<std::size_t>(kGridWriteFactor * double(fields.stats().grid_bytes)) +
         (traces ? estimate_trace_points_bytes(*traces) : 0);
}

std::vector<VdbGridInfo> read_vdb_grid_infos(const std::string& path) {
  init_openvdb();
  require_readable(path);
  std::vector<VdbGridInfo> out;
  const openvdb::GridPtrVecPtr grids = read_vdb_isolated(path, {});
  for (const openvdb::GridBase::Ptr& g : *grids) out.push_back(info_of(*g));
  return out;
}

std::vector<VdbGridInfo> grid_infos(const Fields& fields) {
  std::vector<VdbGridInfo> out;
  for (const openvdb::GridBase::Ptr& g : output_grids(fields, {})) out.push_back(info_of(*g));
  return out;
}

namespace fields_detail {

namespace {

/// Writes all of `bytes` to `fd`; false when the reader has gone.
bool write_all(int fd, const std::string& bytes) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

/// The helper's memory beyond what it maps at start: sizes a corrupt file claims (a string of
/// 1.6 GB in a 75 kB file, found by the fuzz target) fail fast instead of being zeroed page by
/// page. A sound .vdb holds its grids in a small multiple of its size: a fog volume of constant
/// leaves, the most compressible, takes 10 times its file's size. What a claim below the
/// allowance costs is zeroing and copying it: OpenVDB's reader of unknown metadata fills a
/// buffer of the claimed size, then copies it: a 38 kB file claiming several hundred MB took
/// 2.7 s with a floor of 1 GiB (the .vdb fuzz target's four reads of it 34 s under
/// AddressSanitizer), and takes 0.06 s with 128 MiB (1.3 s).
std::uintmax_t limit_reader_memory(const std::string& path) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  const std::uintmax_t allowance = std::max<std::uintmax_t>(std::uintmax_t{128} << 20, 64 * size);
  std::ifstream statm("/proc/self/statm");
  std::uintmax_t pages = 0;
  if (statm >> pages) {  // the mapped size so far (a sanitizer's shadow included)
    const std::uintmax_t mapped = pages * static_cast<std::uintmax_t>(::sysconf(_SC_PAGESIZE));
    const rlimit limit{mapped + allowance, mapped + allowance};
    ::setrlimit(RLIMIT_AS, &limit);
  }
  return allowance;
}

/// How vdb_shell_vdb_reader is asked for grids (its first argument): every grid of the file, or
/// the grids' metadata first and then the one grid whose name it is sent.
constexpr const char* kAllGrids = "--all";
constexpr const char* kSelect = "--select";
constexpr const char* kReaderName = "vdb_shell_vdb_reader";
/// A reply of the reader: a status byte, then the size of what follows (8 bytes, native order).
constexpr char kGrids = 0;  // OpenVDB's writer's stream of the grids
constexpr char kError = 2;  // the error message, the read's end

/// Where vdb_shell_vdb_reader is: $VDB_SHELL_VDB_READER, else beside the code of this library (the
/// build tree), else in its installed place relative to the library
/// (VDB_SHELL_READER_FROM_LIBDIR: <libexecdir>/vdb_shell seen from <libdir>).
/// \throw ResourceError naming the places looked at.
std::string reader_path(const std::string& path) {
  if (const char* env = std::getenv("VDB_SHELL_VDB_READER"); env && *env) return env;
  std::string tried;
  Dl_info info{};
  if (::dladdr(reinterpret_cast<void*>(&reader_path), &info) != 0 && info.dli_fname) {
    const std::filesystem::path dir = std::filesystem::path(info.dli_fname).parent_path();
    for (const std::filesystem::path& p :
         {dir / kReaderName, dir / VDB_SHELL_READER_FROM_LIBDIR / kReaderName}) {
      if (::access(p.c_str(), X_OK) == 0) return p.string();
      tried += (tried.empty() ? "'" : "', '") + p.lexically_normal().string();
    }
  }
  throw ResourceError("cannot read '" + path + "': OpenVDB's reader runs in the program " +
                      kReaderName + ", which is not at " +
                      (tried.empty() ? std::string("any known place") : tried + "'") +
                      " — fix: install vdb_shell again, or set VDB_SHELL_VDB_READER to its path");
}

/// Reads exactly `size` bytes from `fd` into `out`; false at an early end.
bool read_exactly(int fd, char* out, std::size_t size) {
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::read(fd, out + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

/// One run of vdb_shell_vdb_reader on a file, talked to over a socket that is its stdin and
/// stdout (a socket, so that a write to a reader that has ended fails instead of raising
/// SIGPIPE here). The reader is waited for when the object goes.
class ReaderProcess {
 public:
  ReaderProcess(const std::string& path, const char* mode) : path_(path) {
    const std::string helper = reader_path(path);
    std::vector<std::string> words{helper, mode, path};
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
      throw ResourceError("cannot read '" + path + "': no socket (" + std::strerror(errno) + ")");
    // What a failing reader prints (glibc's heap checks, a sanitizer) is not the user's: this
    // process reports how the reader ended in one line.
    posix_spawn_file_actions_t actions;
    ::posix_spawn_file_actions_init(&actions);
    ::posix_spawn_file_actions_adddup2(&actions, fds[1], STDIN_FILENO);
    ::posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
    ::posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    const int spawned =
        ::posix_spawn(&pid_, helper.c_str(), &actions, nullptr, argv.data(), environ);
    ::posix_spawn_file_actions_destroy(&actions);
    ::close(fds[1]);
    if (spawned != 0) {
      ::close(fds[0]);
      throw ResourceError(
          "cannot read '" + path + "': cannot start its reader '" + helper + "' (" +
          std::strerror(spawned) +
          ") — fix: point VDB_SHELL_VDB_READER at vdb_shell_vdb_reader, or unset it");
    }
    fd_ = fds[0];
  }
  ReaderProcess(const ReaderProcess&) = delete;
  ReaderProcess& operator=(const ReaderProcess&) = delete;
  ~ReaderProcess() { finish(); }

  /// The reader's next reply: the grids it wrote.
  /// \throw InputError with the reader's message, or naming how it ended.
  std::string next() {
    char status = 0;
    std::uint64_t size = 0;
    std::string payload;
    const bool whole = read_exactly(fd_, &status, 1) &&
                       read_exactly(fd_, reinterpret_cast<char*>(&size), sizeof size) &&
                       (status == kGrids || status == kError) && size <= (std::uint64_t{1} << 40);
    if (whole) {
      payload.resize(size);
      if (read_exactly(fd_, payload.data(), payload.size())) {
        if (status == kGrids) return payload;
        finish();
        throw InputError(payload);
      }
    }
    finish();
    const std::string how = WIFSIGNALED(status_)
                                ? "signal " + std::to_string(WTERMSIG(status_)) + " (" +
                                      std::string(strsignal(WTERMSIG(status_))) + ")"
                                : "exit code " + std::to_string(WEXITSTATUS(status_));
    throw InputError("cannot read '" + path_ + "' as a .vdb file: OpenVDB's reader failed on it (" +
                     how + "); the file is corrupt — fix: write it again");
  }

  /// Sends `name` to the reader: its size (8 bytes, native order), then its bytes.
  void send(const std::string& name) {
    const std::uint64_t size = name.size();
    const std::string bytes = std::string(reinterpret_cast<const char*>(&size), sizeof size) + name;
    for (std::size_t done = 0; done < bytes.size();) {
      const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return;  // the reader has ended: next() says how
      done += static_cast<std::size_t>(n);
    }
  }

 private:
  /// Closes the socket (a reader waiting for a name ends) and waits for the reader.
  void finish() {
    if (fd_ < 0) return;
    ::close(fd_);
    fd_ = -1;
    while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
    }
  }

  std::string path_;
  pid_t pid_ = 0;
  int fd_ = -1;
  int status_ = 0;
};

/// The grids in `payload`, which OpenVDB's writer made in vdb_shell_vdb_reader.
openvdb::GridPtrVecPtr grids_written_by_reader(const std::string& path,
                                               const std::string& payload) {
  try {
    std::istringstream in(payload, std::ios::binary);
    return openvdb::io::Stream(in).getGrids();
  } catch (const openvdb::Exception& e) {
    throw InternalError("reading '" + path + "': OpenVDB cannot read back its own copy (" +
                        e.what() + "); please report");
  }
}

/// Writes one reply of the reader to stdout; false when the caller has gone.
bool reply(char status, const std::string& bytes) {
  const std::uint64_t size = bytes.size();
  return write_all(STDOUT_FILENO,
                   std::string(1, status) +
                       std::string(reinterpret_cast<const char*>(&size), sizeof size)) &&
         write_all(STDOUT_FILENO, bytes);
}

}  // namespace

int vdb_reader_main(int argc, char** argv) {
  const std::string mode = argc == 3 ? argv[1] : "";
  if (mode != kAllGrids && mode != kSelect) {
    std::fprintf(stderr,
                 "usage: %s --all FILE | --select FILE\n"
                 "Reads the .vdb FILE for vdb_shell, which starts it: replies on stdout with the "
                 "grids as OpenVDB's writer writes them (--all: every grid; --select: their "
                 "metadata, then the grid whose name it reads from stdin), or the error.\n",
                 kReaderName);
    return 1;
  }
  const std::string path = argv[2];
  // One thread: OpenVDB's writer runs parallel loops, and each TBB worker would map a stack and
  // a malloc arena (64 MiB) inside the allowance below, as many as the machine has cores.
  const tbb::global_control serial(tbb::global_control::max_allowed_parallelism, 1);
  const std::uintmax_t allowance = limit_reader_memory(path);
  const auto grids_bytes = [](const openvdb::GridPtrVec& grids) {
    std::ostringstream out(std::ios::binary);
    openvdb::io::Stream(out).write(grids);
    return out.str();
  };
  try {
    init_openvdb();
    // Nothing read is destroyed (the file and the grids are left to _exit): freeing a large
    // tree takes time the reader's caller waits for.
    auto* file = new openvdb::io::File(path);
    file->open(false);
    auto* grids = new openvdb::GridPtrVecPtr(mode == kAllGrids ? file->getGrids()
                                                               : file->readAllGridMetadata());
    reply(kGrids, grids_bytes(**grids));
    if (mode == kSelect) {
      std::uint64_t size = 0;
      if (!read_exactly(STDIN_FILENO, reinterpret_cast<char*>(&size), sizeof size) ||
          size > (std::uint64_t{1} << 20))
        ::_exit(0);  // the caller chose none
      std::string name(size, '\0');
      if (!read_exactly(STDIN_FILENO, name.data(), name.size())) ::_exit(0);
      auto* grid = new openvdb::GridPtrVec{file->readGrid(name)};
      reply(kGrids, grids_bytes(*grid));
    }
  } catch (const openvdb::Exception& e) {
    reply(kError, "cannot read '" + path + "' as a .vdb file: " + e.what());
  } catch (const std::bad_alloc&) {
    reply(kError,
          "cannot read '" + path + "' as a .vdb file: its reader asked for more than " +
              std::to_string(allowance >> 20) +
              " MiB (64 times the file's size, at least 128 MiB): the file is corrupt — fix: write "
              "it again");
  } catch (const std::exception& e) {
    reply(kError, "cannot read '" + path + "' as a .vdb file: " + e.what());
  }
  ::_exit(0);  // (no exit handlers: a leak check would report the grids left alive)
}

openvdb::GridPtrVecPtr read_vdb_isolated(const std::string& path, const GridSelector& select) {
  ReaderProcess reader(path, select ? kSelect : kAllGrids);
  if (!select) return grids_written_by_reader(path, reader.next());
  const std::string name = select(*grids_written_by_reader(path, reader.next()));
  reader.send(name);
  return grids_written_by_reader(path, reader.next());
}

void require_readable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError("cannot read level set file '" + path + "': no such file");
  }
}

VolumeMesh mesh_volume(const FloatGrid& grid, double isovalue, double adaptivity) {
  VolumeMesh out;
  const auto mesh = [&](const openvdb::BoolTree::Ptr& mask) {
    openvdb::tools::VolumeToMesh mesher(isovalue, adaptivity);
    if (mask) mesher.setAdaptivityMask(mask);
    mesher(grid);
    out.triangles.clear();
    out.quads.clear();
    for (std::size_t n = 0; n < mesher.polygonPoolListSize(); ++n) {
      const openvdb::tools::PolygonPool& pool = mesher.polygonPoolList()[n];
      for (std::size_t i = 0; i < pool.numQuads(); ++i) out.quads.push_back(pool.quad(i));
      for (std::size_t i = 0; i < pool.numTriangles(); ++i)
        out.triangles.push_back(pool.triangle(i));
    }
    PolygonSoup& soup = out.soup;
    soup = PolygonSoup{};
    soup.points.reserve(mesher.pointListSize());
    for (std::size_t i = 0; i < mesher.pointListSize(); ++i) {
      const openvdb::Vec3s& p = mesher.pointList()[i];
      soup.points.push_back({p[0], p[1], p[2]});
    }
    soup.polygons.reserve(out.triangles.size() + out.quads.size());
    for (const openvdb::Vec3I& t : out.triangles) soup.polygons.push_back({t[2], t[1], t[0]});
    for (const openvdb::Vec4I& q : out.quads) soup.polygons.push_back({q[3], q[2], q[1], q[0]});
  };
  // The corners of the zero-area triangles and crossing pairs, by find_surface_problems()'s
  // rules, and of the pairs of faces folded onto each other across an edge (their normals
  // within 2.6 degrees of opposite: a sliver folded back), in index space (voxels are units).
  // None for a mesh with a point that is not finite (a grid holding NaNs) or no extent at all:
  // make_surface() says what is wrong with those.
  const auto defects = [&] {
    SurfaceMesh m, sound;  // sound: the triangles with an area, for the crossing test
    std::vector<Vec3d> at;
    for (const Vec3d& p : out.soup.points) {
      const openvdb::Vec3d c = grid.worldToIndex(openvdb::Vec3d(p.x, p.y, p.z));
      m.points.push_back({c[0], c[1], c[2]});
      if (!is_finite(m.points.back())) return at;
    }
    for (const auto& f : out.soup.polygons)
      for (std::size_t k = 1; k + 1 < f.size(); ++k)
        m.triangles.push_back({std::uint32_t(f[0]), std::uint32_t(f[k]), std::uint32_t(f[k + 1])});
    const double diag = bounding_box(m).diagonal();
    if (!(diag > 0)) return at;
    const double min_twice_area = 2.0 * ValidationOptions{}.degenerate_area_fraction * diag * diag;
    const auto add = [&](const Triangle& t) {
      for (const std::uint32_t v : t) at.push_back(m.points[v]);
    };
    sound.points = m.points;
    for (const Triangle& t : m.triangles) {
      if (norm(cross(m.points[t[1]] - m.points[t[0]], m.points[t[2]] - m.points[t[0]])) >
          min_twice_area)
        sound.triangles.push_back(t);
      else
        add(t);
    }
    for (const auto& [f, g] : surface_self_intersections(sound, SIZE_MAX))
      add(sound.triangles[f]), add(sound.triangles[g]);
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> first_face;
    for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
        const auto [it, fresh] = first_face.try_emplace({std::min(a, b), std::max(a, b)}, t);
        if (fresh) continue;
        const Vec3d n = face_normal_area(m, t), o = face_normal_area(m, it->second);
        if (dot(n, o) < -0.999 * norm(n) * norm(o))
          add(m.triangles[t]), add(m.triangles[it->second]);
      }
    return at;
  };
  openvdb::BoolTree::Ptr mask;
  mesh(mask);
  for (int round = 1; round <= 3 && adaptivity > 0; ++round) {
    const std::vector<Vec3d> at = defects();
    if (at.empty()) break;
    if (!mask) mask = std::make_shared<openvdb::BoolTree>(false);
    openvdb::tree::ValueAccessor<openvdb::BoolTree> on(*mask);
    const int reach = 1 << round;
    for (const Vec3d& p : at) {
      const openvdb::Coord c = openvdb::Coord::round(openvdb::Vec3d(p.x, p.y, p.z));
      for (int k = -reach; k <= reach; ++k)
        for (int j = -reach; j <= reach; ++j)
          for (int i = -reach; i <= reach; ++i) on.setValueOn(c.offsetBy(i, j, k));
    }
    mesh(mask);
  }
  return out;
}

FloatGrid::Ptr read_float_grid(const std::string& vdb_path, const std::string& grid_name,
                               GridKinds kinds, std::string& where, const std::string& hint) {
  const auto choose = [&](const openvdb::GridPtrVec& metas) {
    std::string names;
    for (const auto& m : metas) names += (names.empty() ? "'" : ", '") + m->getName() + "'";
    const auto named = [&](const std::string& name) {
      return std::any_of(metas.begin(), metas.end(),
                         [&](const auto& m) { return m->getName() == name; });
    };
    if (!grid_name.empty()) {
      if (!named(grid_name)) {
        throw InputError("'" + vdb_path + "' has no grid named '" + grid_name +
                         "'; its grids are " + (names.empty() ? "none" : names));
      }
      return grid_name;
    }
    // 'surface' if it is a float level set, else the first float level set, else (any
    // volume) the first float fog volume, else the first float grid.
    const auto first = [&](auto&& accept) {
      for (const auto& m : metas)
        if (m->template isType<FloatGrid>() && accept(*m)) return m->getName();
      return std::string();
    };
    const auto level_set = [](const openvdb::GridBase& g) {
      return g.getGridClass() == openvdb::GRID_LEVEL_SET;
    };
    std::string name =
        first([&](const openvdb::GridBase& g) { return g.getName() == "surface" && level_set(g); });
    if (name.empty()) name = first(level_set);
    if (name.empty() && kinds == GridKinds::kAnyFloat) {
      name = first(
          [](const openvdb::GridBase& g) { return g.getGridClass() == openvdb::GRID_FOG_VOLUME; });
      if (name.empty()) name = first([](const openvdb::GridBase&) { return true; });
    }
    if (name.empty()) {
      throw InputError("'" + vdb_path + "' holds no float " +
                       (kinds == GridKinds::kAnyFloat ? "grid" : "level set grid") +
                       " (its grids: " + (names.empty() ? "none" : names) +
                       "); pass --grid NAME, and if that grid is a signed distance field, "
                       "set its grid class to level set" +
                       hint);
    }
    return name;
  };
  const openvdb::GridPtrVecPtr grids = read_vdb_isolated(vdb_path, choose);
  const openvdb::GridBase::Ptr base = grids->at(0);
  const std::string chosen = base->getName();
  FloatGrid::Ptr grid = openvdb::gridPtrCast<FloatGrid>(base);
  where = "grid '" + chosen + "' of '" + vdb_path + "'";
  if (!grid) {
    throw InputError(where + " holds " + base->valueType() + " values; a " +
                     (kinds == GridKinds::kAnyFloat ? "volume" : "level set") +
                     " must be a float grid");
  }
  if (kinds == GridKinds::kLevelSet && grid->getGridClass() != openvdb::GRID_LEVEL_SET) {
    throw InputError(where + " is not a level set (its class is '" +
                     openvdb::GridBase::gridClassToString(grid->getGridClass()) +
                     "'); if it holds signed distances (negative inside), try setting the grid "
                     "class to level set" +
                     hint);
  }
  return grid;
}

}  // namespace fields_detail

VolumeSurface volume_to_soup(const std::string& vdb_path, const std::string& grid_name,
                             double adaptivity, bool any_volume) {
  init_openvdb();
  require_readable(vdb_path);
  if (!(adaptivity >= 0.0 && adaptivity <= 1.0))
    throw InputError("--adaptivity must lie in [0, 1]; got " + format_double(adaptivity));
  const std::string repair_hint = " — or rerun with --repair to mesh it as it is";
  VolumeSurface out;
  const FloatGrid::Ptr grid =
      read_float_grid(vdb_path, grid_name, any_volume ? GridKinds::kAnyFloat : GridKinds::kLevelSet,
                      out.where, repair_hint);
  const openvdb::GridClass grid_class = grid->getGridClass();
  out.grid_class = openvdb::GridBase::gridClassToString(grid_class);
  // A fog volume's surface is at density 0.5; so is that of a grid of no class whose values are
  // densities (background 0, all in [0, 1]). Anything else is a distance: its zero crossing.
  bool densities = grid_class == openvdb::GRID_FOG_VOLUME;
  if (grid_class != openvdb::GRID_LEVEL_SET && !densities) {
    densities = grid->background() == 0.0f;
    for (auto it = grid->cbeginValueOn(); it && densities; ++it)
      densities = *it >= 0.0f && *it <= 1.0f;
  }
  out.isovalue = densities ? 0.5 : 0.0;
  out.soup = mesh_volume(*grid, out.isovalue, adaptivity).soup;
  PolygonSoup& soup = out.soup;
  if (soup.polygons.empty()) {
    throw InputError(out.where + " has no crossing of " + format_double(out.isovalue) +
                     ": it holds no surface to mesh");
  }
  // The enclosed volume (fans of the polygons) says which side the solid is on.
  double volume6 = 0.0;
  for (const std::vector<std::int64_t>& poly : soup.polygons) {
    const Vec3d& o = soup.points[static_cast<std::size_t>(poly[0])];
    for (std::size_t i = 1; i + 1 < poly.size(); ++i)
      volume6 += dot(o, cross(soup.points[static_cast<std::size_t>(poly[i])],
                              soup.points[static_cast<std::size_t>(poly[i + 1])]));
  }
  out.positive_inside = (grid_class == openvdb::GRID_LEVEL_SET) == (volume6 < 0.0);
  if (volume6 < 0.0) {
    if (!any_volume) {
      throw InputError(out.where +
                       " is positive inside: the region its zero crossing encloses holds phi > "
                       "0; vdb_shell needs OpenVDB's convention, negative inside: negate the "
                       "grid" +
                       repair_hint);
    }
    for (std::vector<std::int64_t>& poly : soup.polygons) std::reverse(poly.begin(), poly.end());
  }
  return out;
}

}  // namespace vdb_shell

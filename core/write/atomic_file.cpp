// atomic_file.cpp — see atomic_file.h.
#include "core/write/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <utility>

#include "core/base/errors.h"

namespace vdb_shell {
namespace {

namespace fs = std::filesystem;

// The registry of temporary files in flight, readable from a signal handler: fixed storage, one
// atomic state per slot. A slot is claimed (kFree -> kBusy), filled, then armed (kArmed); the
// handler only touches armed slots. Released after the file was renamed or removed, so that a
// signal arriving in between unlinks a path that no longer exists, which is harmless.
constexpr int kSlotFree = 0;
constexpr int kSlotBusy = 1;
constexpr int kSlotArmed = 2;
constexpr std::size_t kMaxTempPath = 4096;

struct PendingSlot {
  std::atomic<int> state{kSlotFree};
  char path[kMaxTempPath] = {};
};

PendingSlot g_pending[kMaxPendingTempFiles];

static_assert(std::atomic<int>::is_always_lock_free,
              "the signal-time registry needs lock-free ints");

int register_temp_file(const std::string& temp_path) noexcept {
  if (temp_path.size() + 1 > kMaxTempPath) return -1;
  for (int i = 0; i < kMaxPendingTempFiles; ++i) {
    int expected = kSlotFree;
    if (g_pending[i].state.compare_exchange_strong(expected, kSlotBusy)) {
      std::memcpy(g_pending[i].path, temp_path.c_str(), temp_path.size() + 1);
      g_pending[i].state.store(kSlotArmed);
      return i;
    }
  }
  return -1;  // registry full: the destructor still removes the file
}

void release_temp_file(int slot) noexcept {
  if (slot < 0) return;
  g_pending[slot].state.store(kSlotBusy);
  g_pending[slot].path[0] = '\0';
  g_pending[slot].state.store(kSlotFree);
}

std::string next_temp_path(const std::string& path) {
  static std::atomic<unsigned long> counter{0};
  return path + ".tmp." + std::to_string(static_cast<long>(::getpid())) + "." +
         std::to_string(counter.fetch_add(1));
}

[[noreturn]] void throw_cannot_write(
    const std::string& path, const std::string& reason,
    const char* remedy = "check that the folder exists and is writable") {
  throw ResourceError("cannot write " + path + ": " + reason + "; " + remedy);
}

std::string errno_reason(int err, const char* fallback) {
  return err != 0 ? std::string(std::strerror(err)) : std::string(fallback);
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  if (path_.empty()) throw_cannot_write("\"\"", "empty file name", "give a file name");
  std::error_code ec;
  if (fs::is_directory(path_, ec)) {
    throw_cannot_write(path_, "a folder of that name exists", "choose another file name");
  }
  temp_path_ = next_temp_path(path_);
  registry_slot_ = register_temp_file(temp_path_);
  errno = 0;
  stream_.open(temp_path_, std::ios::out | std::ios::binary | std::ios::trunc);
  if (!stream_.is_open()) {
    const int err = errno;
    release_temp_file(registry_slot_);
    registry_slot_ = -1;
    throw_cannot_write(path_, errno_reason(err, "cannot create a file there"));
  }
}

AtomicFile::~AtomicFile() {
  if (!committed_) discard();
}

void AtomicFile::discard() noexcept {
  if (stream_.is_open()) stream_.close();
  std::error_code ec;
  fs::remove(temp_path_, ec);
  release_temp_file(registry_slot_);
  registry_slot_ = -1;
}

void AtomicFile::finish() {
  if (finished_) return;
  errno = 0;
  stream_.flush();
  bool ok = !stream_.fail();
  int err = errno;
  stream_.close();
  if (ok && stream_.fail()) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    discard();
    throw_cannot_write(path_, errno_reason(err, "write failed (disk full?)"));
  }
  finished_ = true;
}

namespace {
thread_local CommitGroup* t_group = nullptr;  ///< the innermost group of this thread
}  // namespace

CommitGroup::CommitGroup() : previous_(t_group) { t_group = this; }

CommitGroup::~CommitGroup() {
  t_group = previous_;
  for (const Pending& p : pending_) {
    std::error_code ec;
    fs::remove(p.temp_path, ec);
    release_temp_file(p.registry_slot);
  }
}

void CommitGroup::commit() {
  while (!pending_.empty()) {
    const Pending p = pending_.front();
    std::error_code ec;
    fs::rename(p.temp_path, p.path, ec);
    if (ec) throw_cannot_write(p.path, ec.message());  // the destructor removes the rest
    release_temp_file(p.registry_slot);
    pending_.erase(pending_.begin());
  }
}

void AtomicFile::commit() {
  if (committed_) return;
  finish();
  if (t_group != nullptr) {  // complete: the group renames it with the others
    t_group->pending_.push_back({temp_path_, path_, registry_slot_});
    registry_slot_ = -1;
    committed_ = true;
    return;
  }
  std::error_code ec;
  fs::rename(temp_path_, path_, ec);
  if (ec) {
    discard();
    throw_cannot_write(path_, ec.message());
  }
  committed_ = true;
  release_temp_file(registry_slot_);
  registry_slot_ = -1;
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& body) {
  AtomicFile file(path);
  body(file.stream());
  file.commit();
}

void remove_pending_temp_files() noexcept {
  for (PendingSlot& slot : g_pending) {
    if (slot.state.load() == kSlotArmed) ::unlink(slot.path);
  }
}

}  // namespace vdb_shell

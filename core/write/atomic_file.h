// atomic_file.h — writing a file so that readers never see it half written.
//
// Every output file is written to a temporary file beside its target, `<path>.tmp.<pid>.<n>`, and
// renamed onto the target only once it was written completely: a crash, a full disk or an
// interruption leaves either the old file or the new one, never a truncated one, and no temporary
// file (the destructor removes it; a signal handler can call remove_pending_temp_files()).
//
// Errors: every failure (folder missing or not writable, disk full, rename refused) throws
// ResourceError naming the target path and the reason.
#pragma once

#include <fstream>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace vdb_shell {

/// One file being written atomically. Not copyable or movable (its temporary path is registered
/// for signal-time cleanup).
///
///   AtomicFile file(path);          // creates <path>.tmp.<pid>.<n>
///   file.stream() << ...;           // binary std::ofstream
///   file.commit();                  // flush, check, rename onto `path`
///
/// Without commit() (an exception, an early return) the temporary file is removed and `path` is
/// left as it was.
class AtomicFile {
 public:
  /// Opens the temporary file beside `path`.
  /// \throw ResourceError if it cannot be created (missing folder, no permission, a folder named
  ///        `path` in the way, ...).
  explicit AtomicFile(std::string path);
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// The stream to write the content to (binary mode: no newline translation).
  std::ostream& stream() { return stream_; }

  /// Flushes and closes the temporary file and checks that every write succeeded, without
  /// renaming it yet: lets a caller make sure several files are complete before committing any
  /// of them. Called by commit() if not called before. Idempotent.
  /// \throw ResourceError if a write failed (disk full, I/O error).
  void finish();

  /// finish(), then renames the temporary file onto the target (replacing an existing file).
  /// \throw ResourceError if finishing or the rename fails; the temporary file is then removed.
  void commit();

  /// The target path, as given.
  const std::string& path() const { return path_; }
  /// The temporary path, `<path>.tmp.<pid>.<n>`.
  const std::string& temp_path() const { return temp_path_; }
  /// True once commit() succeeded (or handed the file to a CommitGroup).
  bool committed() const { return committed_; }

 private:
  void discard() noexcept;

  std::string path_;
  std::string temp_path_;
  std::ofstream stream_;
  int registry_slot_ = -1;  ///< slot in the pending-temp-file registry, -1 if none
  bool finished_ = false;
  bool committed_ = false;
};

/// All-or-nothing outputs: while a CommitGroup lives on a thread, AtomicFile::commit() there only
/// finishes its file (complete and checked, still under its temporary name) and hands it to
/// the group; commit() renames them all onto their targets, in order; a group destroyed without
/// commit() (an exception on the way) removes them all, so none of the outputs appears.
///
///   CommitGroup outputs;
///   write_shell(...); write_report(...);   // each complete, none visible yet
///   outputs.commit();                      // all appear
class CommitGroup {
 public:
  CommitGroup();
  /// Removes every file not yet committed.
  ~CommitGroup();
  CommitGroup(const CommitGroup&) = delete;
  CommitGroup& operator=(const CommitGroup&) = delete;
  /// Renames every finished file onto its target. A rename that fails removes the files not yet
  /// renamed and throws ResourceError naming the target (those renamed before stay: renames are
  /// where nothing can be undone).
  void commit();

 private:
  friend class AtomicFile;
  struct Pending {
    std::string temp_path, path;
    int registry_slot;
  };
  std::vector<Pending> pending_;
  CommitGroup* previous_;
};

/// Writes `path` atomically: opens an AtomicFile, calls `body` with its stream, commits.
/// If `body` throws, the exception propagates and `path` is left untouched.
/// \throw ResourceError naming `path` if the file cannot be written.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& body);

/// Unlinks every temporary file currently being written by an AtomicFile in this process.
/// Meant for a signal handler (SIGINT, SIGTERM) before it exits: it only calls unlink() over a
/// fixed array of paths guarded by atomic flags — no allocation, no locks. At most
/// kMaxPendingTempFiles files are tracked at once (further ones still work and are still removed
/// by their destructor, but not by this function).
void remove_pending_temp_files() noexcept;

/// How many temporary files the registry above tracks at once.
inline constexpr int kMaxPendingTempFiles = 32;

}  // namespace vdb_shell

// errors.h — the exception hierarchy of vdb_shell.
//
// Library code reports every failure by throwing one of these; messages name the file, the
// elements at fault and the remedy. The CLI maps each class to one exit code:
//   InputError     -> 2  (bad input file, bad option; nothing was written)
//   ResourceError  -> 3  (out of memory budget, cannot write a file, interrupted)
//   InternalError  -> 3  (an invariant of the output was violated: a bug)
//   CancelledError -> 3  (the caller cancelled the run through RunControl; nothing was written)
#pragma once

#include <stdexcept>
#include <string>

namespace vdb_shell {

/// Base of every error vdb_shell throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The input (file, mesh or option) cannot be used as given. Exit code 2.
class InputError : public Error {
 public:
  using Error::Error;
};

/// A resource ran out or failed: memory budget, disk, interruption. Exit code 3.
class ResourceError : public Error {
 public:
  using Error::Error;
};

/// The program broke one of its own invariants. Exit code 3.
class InternalError : public Error {
 public:
  using Error::Error;
};

/// The caller asked the run to stop (RunControl::cancel, run_control.h). Exit code 3.
class CancelledError : public Error {
 public:
  using Error::Error;
};

}  // namespace vdb_shell

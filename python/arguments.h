// arguments.h — the Python module's arguments as the library's types: numpy arrays as vertices
// and polygons, path-likes as paths, and build_shell()'s keyword options (the CLI's long
// options in snake_case) as ShellOptions. Internal to python/.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <vector>

#include "vdb_shell/vdb_shell.h"

namespace vdb_shell::python {

namespace py = pybind11;

/// The vertex positions of `vertices`, an (n, 3) array (any float or integer dtype; C-contiguous
/// float64 is read in place, anything else converted to it first).
/// \throw InputError naming `vertices`, the shape or the dtype.
std::vector<Vec3d> read_vertices(py::handle vertices);

/// The triangles of `faces`, an (m, 3) integer array, as 0-based int64 indices; out-of-range
/// values are kept as they are (make_surface() names them).
std::vector<std::vector<std::int64_t>> read_faces(py::handle faces);

/// The Python type name of `value` (for messages).
std::string type_name(py::handle value);

/// A str or os.PathLike as a path string. \throw InputError naming `name`.
std::string to_path(py::handle value, const char* name);

/// One keyword option of build_shell(): the CLI's long option in snake_case.
struct OptionSpec {
  const char* name;
  const char* cli;  ///< the CLI's long option, as the library's messages name it
  const char* doc;
  void (*apply)(ShellOptions& options, py::handle value, const char* name);
  std::string (*shown_default)(const ShellOptions& defaults);
};

/// Every option, in the CLI's order (cli/cli.cpp); defaults are ShellOptions{}'s.
const std::vector<OptionSpec>& option_specs();

/// `message` with the CLI's option names (--max-thickness) replaced by the keywords
/// (max_thickness).
std::string with_keyword_names(std::string message);

/// ShellOptions{} with the keyword arguments applied (None leaves an option at its default).
/// \throw InputError for an unknown keyword (listing the known ones) or an unusable value.
ShellOptions parse_options(const py::kwargs& kwargs);

}  // namespace vdb_shell::python

// arguments.cpp — see arguments.h.
#include "python/arguments.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <string>
#include <type_traits>
#include <vector>

namespace vdb_shell::python {

static_assert(std::is_standard_layout_v<Vec3d> && sizeof(Vec3d) == 3 * sizeof(double),
              "Vec3d arrays are read as (n, 3) float64 arrays");

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtype_text(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

/// `value` as a numpy array (numpy.asarray) of `shape` (n, 3) whose dtype kind is in `kinds`.
/// \throw InputError naming `name`, the shape or the dtype otherwise.
py::array as_rows_of_three(py::handle value, const char* name, const char* shape, const char* kinds,
                           const char* what) {
  py::array a;
  try {
    a = py::module_::import("numpy").attr("asarray")(value);
  } catch (py::error_already_set& e) {
    throw InputError(std::string(name) + " cannot be read as an array: " + e.what());
  }
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw InputError(std::string(name) + " must be an " + shape + " array of " + what +
                     "; got shape " + shape_text(a));
  if (std::string(kinds).find(a.dtype().kind()) == std::string::npos)
    throw InputError(std::string(name) + " must hold " + what + "; got dtype " + dtype_text(a));
  return a;
}

}  // namespace

/// The vertex positions of `vertices` (any float or integer dtype; C-contiguous float64 is read
/// in place, anything else converted to it first).
std::vector<Vec3d> read_vertices(py::handle vertices) {
  py::array a = as_rows_of_three(vertices, "vertices", "(n, 3)", "fiu", "floats (coordinates)");
  using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
  if (!(py::isinstance<py::array_t<double>>(a) && (a.flags() & py::array::c_style)))
    a = Doubles::ensure(a);
  if (!a) throw InputError("vertices cannot be converted to float64");
  const auto* data = static_cast<const Vec3d*>(a.data());
  return std::vector<Vec3d>(data, data + a.shape(0));
}

/// The triangles of `faces` as 0-based int64 indices, out-of-range values kept as they are
/// (make_surface() names them); uint64 values beyond the int64 range saturate.
std::vector<std::vector<std::int64_t>> read_faces(py::handle faces) {
  const py::array a = as_rows_of_three(faces, "faces", "(m, 3)", "iu", "integers (vertex indices)");
  std::vector<std::vector<std::int64_t>> polygons(static_cast<std::size_t>(a.shape(0)));
  if (a.dtype().kind() == 'u' && a.itemsize() == 8) {
    using Unsigned = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>;
    const Unsigned u = Unsigned::ensure(a);
    if (!u) throw InputError("faces cannot be converted to uint64");
    const std::uint64_t* d = u.data();
    for (std::size_t f = 0; f < polygons.size(); ++f)
      for (int c = 0; c < 3; ++c)
        polygons[f].push_back(static_cast<std::int64_t>(
            std::min<std::uint64_t>(d[3 * f + c], static_cast<std::uint64_t>(INT64_MAX))));
    return polygons;
  }
  using Signed = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
  const Signed s = Signed::ensure(a);
  if (!s) throw InputError("faces cannot be converted to int64");
  const std::int64_t* d = s.data();
  for (std::size_t f = 0; f < polygons.size(); ++f) polygons[f].assign(d + 3 * f, d + 3 * f + 3);
  return polygons;
}

std::string type_name(py::handle value) {
  return py::str(py::type::of(value).attr("__name__")).cast<std::string>();
}

/// A str or os.PathLike as a path string.
std::string to_path(py::handle value, const char* name) {
  try {
    return py::module_::import("os").attr("fspath")(value).cast<std::string>();
  } catch (py::error_already_set&) {
    throw InputError(std::string(name) + " must be a path (str or os.PathLike); got " +
                     type_name(value));
  }
}

namespace {

/// An integer option (int or numpy integer, not bool); range checks are the library's.
int to_int(py::handle value, const char* name) {
  if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
    throw InputError(std::string("option ") + name + " must be an integer; got " +
                     type_name(value));
  const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (!i) throw py::error_already_set();
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
  if (overflow != 0 || v < INT_MIN || v > INT_MAX)
    throw InputError(std::string(name) + " " + py::repr(i).cast<std::string>() + ": out of range");
  return static_cast<int>(v);
}

/// A real option (int, float or numpy scalar, not bool or str); range checks are the library's.
double to_float(py::handle value, const char* name) {
  if (PyBool_Check(value.ptr()) || PyUnicode_Check(value.ptr()) || PyBytes_Check(value.ptr()))
    throw InputError(std::string("option ") + name + " must be a number; got " + type_name(value));
  const double v = PyFloat_AsDouble(value.ptr());
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw InputError(std::string("option ") + name + " must be a number; got " + type_name(value));
  }
  return v;
}

bool to_bool(py::handle value, const char* name) {
  if (!PyBool_Check(value.ptr()))
    throw InputError(std::string("option ") + name + " must be True or False; got " +
                     type_name(value));
  return value.ptr() == Py_True;
}

std::string to_text(py::handle value, const char* name) {
  if (!PyUnicode_Check(value.ptr()))
    throw InputError(std::string("option ") + name + " must be a str; got " + type_name(value));
  return value.cast<std::string>();
}

std::string number_text(double v) { return py::str(py::float_(v)).cast<std::string>(); }

}  // namespace

/// Every option, in the CLI's order (cli/cli.cpp); defaults are ShellOptions{}'s.
const std::vector<OptionSpec>& option_specs() {
  static const std::vector<OptionSpec> specs = {
      {"resolution", "--resolution", "voxels along the longest bounding-box side",
       [](ShellOptions& o, py::handle v, const char* n) { o.fields.resolution = to_int(v, n); },
       [](const ShellOptions& o) { return std::to_string(o.fields.resolution); }},
      {"voxel_size", "--voxel-size",
       "voxel edge, input units; overrides resolution (0: use resolution)",
       [](ShellOptions& o, py::handle v, const char* n) { o.fields.voxel_size = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.fields.voxel_size); }},
      {"max_memory", "--max-memory",
       "memory budget, GiB: every stage estimates its peak first and refuses to start above it",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.fields.max_memory_gb = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.fields.max_memory_gb); }},
      {"planar_angle", "--planar-angle",
       "degrees: a vertex is planar when its face normals lie within it",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.planar_angle = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.planar_angle); }},
      {"step", "--step", "trace step, input units (0: half a voxel)",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.step = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.step); }},
      {"critical", "--critical", "c of eq. 4: stop where |grad phi|^2 < c |grad phi(p)|^2",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.critical = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.critical); }},
      {"point_size", "--point-size", "merge distance, input units (0: one voxel diagonal)",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.point_size = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.point_size); }},
      {"flux_threshold", "--flux-threshold",
       "rho of eq. 8: planar traces stop where the flux exceeds it",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.trace.flux_threshold = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.trace.flux_threshold); }},
      {"merge_angle", "--merge-angle",
       "degrees: traces meeting at a smaller angle run side by side",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.merge_angle = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.merge_angle); }},
      {"integrator", "--integrator", "'euler' (the paper's), 'rk2' or 'rk4'",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.trace.integrator = parse_integrator(to_text(v, n));
       },
       [](const ShellOptions& o) {
         return "'" + std::string(to_string(o.trace.integrator)) + "'";
       }},
      {"min_step", "--min-step",
       "shortest step where |grad phi| < 1 shortens it, a fraction of step (paper: 0)",
       [](ShellOptions& o, py::handle v, const char* n) { o.trace.min_step = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.trace.min_step); }},
      {"max_thickness", "--max-thickness",
       "largest thickness along the trace, input units (0: no limit)",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.thickness.max_thickness = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.thickness.max_thickness); }},
      {"thickness_edge_factor", "--thickness-edge-factor",
       "K: limit each vertex to K x its mean edge length (0: none)",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.thickness.edge_factor = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.thickness.edge_factor); }},
      {"min_quality", "--min-quality",
       "step inner vertices back from tets of a lower quality, in [0, 0.5]",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.validity.min_quality = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.validity.min_quality); }},
      {"layers", "--layers", "stack this many prisms along each prism's side edges (3K tets)",
       [](ShellOptions& o, py::handle v, const char* n) { o.validity.layers = to_int(v, n); },
       [](const ShellOptions& o) { return std::to_string(o.validity.layers); }},
      {"layer_ratio", "--layer-ratio",
       "each layer this many times as thick as the one outside it, in [0.1, 10]",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.validity.layer_ratio = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.validity.layer_ratio); }},
      {"threads", "--threads", "worker threads of this call (0: all cores)",
       [](ShellOptions& o, py::handle v, const char* n) { o.threads = to_int(v, n); },
       [](const ShellOptions& o) { return std::to_string(o.threads); }},
      {"level_set", "--level-set",
       "a .vdb file whose level set is the distance field, instead of building one",
       [](ShellOptions& o, py::handle v, const char* n) { o.level_set = to_path(v, n); },
       [](const ShellOptions&) { return std::string("None"); }},
      {"grid", "--grid", "grid of level_set to use (default: 'surface', else the first level set)",
       [](ShellOptions& o, py::handle v, const char* n) { o.grid_name = to_text(v, n); },
       [](const ShellOptions&) { return std::string("None"); }},
      {"adaptivity", "--adaptivity",
       "build_shell_from_level_set(): 0 keeps voxel-sized quads, up to 1 merges flat regions",
       [](ShellOptions& o, py::handle v, const char* n) { o.adaptivity = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.adaptivity); }},
      {"optimize", "--optimize",
       "after the validity search, move inner vertices and recut prism sides to raise the worst "
       "tets' quality (default True)",
       [](ShellOptions& o, py::handle v, const char* n) { o.optimize.enabled = to_bool(v, n); },
       [](const ShellOptions& o) { return std::string(o.optimize.enabled ? "True" : "False"); }},
      {"max_coverage_loss", "--max-coverage-loss",
       "optimize: coverage its moves may cost in all (fraction of the enclosed volume)",
       [](ShellOptions& o, py::handle v, const char* n) {
         o.optimize.max_coverage_loss = to_float(v, n);
       },
       [](const ShellOptions& o) { return number_text(o.optimize.max_coverage_loss); }},
      {"repair", "--repair",
       "rebuild the surface watertight through a volume first (report['repair'] says how)",
       [](ShellOptions& o, py::handle v, const char* n) { o.repair = to_bool(v, n); },
       [](const ShellOptions& o) { return std::string(o.repair ? "True" : "False"); }},
      {"repair_closing", "--repair-closing", "repair: close holes up to about twice this (voxels)",
       [](ShellOptions& o, py::handle v, const char* n) { o.repair_closing = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.repair_closing); }},
      {"repair_voxel_size", "--repair-voxel-size",
       "repair: the repair volume's voxel size (0: the fields')",
       [](ShellOptions& o, py::handle v, const char* n) { o.repair_voxel_size = to_float(v, n); },
       [](const ShellOptions& o) { return number_text(o.repair_voxel_size); }},
  };
  return specs;
}

namespace {

std::string option_names() {
  std::vector<std::string> names;
  for (const OptionSpec& s : option_specs()) names.emplace_back(s.name);
  std::sort(names.begin(), names.end());
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

}  // namespace

/// `message` with the CLI's option names (--max-thickness) replaced by the keywords
/// (max_thickness).
std::string with_keyword_names(std::string message) {
  for (const OptionSpec& s : option_specs()) {
    const std::string cli = s.cli;
    for (std::size_t at = message.find(cli); at != std::string::npos;
         at = message.find(cli, at + 1)) {
      const std::size_t end = at + cli.size();
      if (end < message.size() &&
          (std::isalnum(static_cast<unsigned char>(message[end])) || message[end] == '-'))
        continue;
      message.replace(at, cli.size(), s.name);
    }
  }
  return message;
}

/// ShellOptions{} with the keyword arguments applied (None leaves an option at its default).
/// \throw InputError for an unknown keyword (listing the known ones) or an unusable value.
ShellOptions parse_options(const py::kwargs& kwargs) {
  ShellOptions options;
  for (const auto& item : kwargs) {
    const std::string key = py::str(item.first).cast<std::string>();
    const auto& specs = option_specs();
    const auto spec = std::find_if(specs.begin(), specs.end(),
                                   [&](const OptionSpec& s) { return key == s.name; });
    if (spec == specs.end()) {
      py::list names;
      for (const OptionSpec& s : specs) names.append(s.name);
      const py::list close =
          py::module_::import("difflib").attr("get_close_matches")(key, names, 1);
      const std::string hint =
          close.empty() ? "" : " (did you mean " + close[0].cast<std::string>() + "?)";
      throw InputError("build_shell() got an unknown option '" + key + "'" + hint +
                       "; the options are: " + option_names());
    }
    if (!item.second.is_none()) spec->apply(options, item.second, spec->name);
  }
  try {
    check_options(options);
  } catch (const InputError& e) {
    throw InputError(with_keyword_names(e.what()));
  }
  return options;
}

}  // namespace vdb_shell::python

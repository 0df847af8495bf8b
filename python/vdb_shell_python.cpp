// vdb_shell_python.cpp — the Python module `vdb_shell`: build_shell() on numpy arrays, with the
// CLI's options as keyword arguments, progress reports and Ctrl-C; load_surface() and the
// writers. A thin layer: every rule (validation, option ranges, formats) is the library's.
//
//   import vdb_shell
//   v, f = vdb_shell.load_surface("bunny.obj")
//   r = vdb_shell.build_shell(v, f, resolution=64, progress=lambda stage, x: print(stage, x))
//   vdb_shell.write("bunny.vtu", r)
//
// Threads: build_shell() runs the library on a worker thread while the calling thread waits with
// the GIL released; every kPollInterval it takes the GIL back, runs the Python signal handlers
// (a KeyboardInterrupt cancels the run through RunControl::cancel and is re-raised) and hands
// the progress reports the worker queued to the Python callback. The worker never touches a
// Python object.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <climits>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include "vdb_shell/vdb_shell.h"

namespace py = pybind11;

namespace vdb_shell {
namespace {

/// How often the waiting thread checks for signals and delivers progress reports.
constexpr std::chrono::milliseconds kPollInterval{50};

static_assert(std::is_standard_layout_v<Vec3d> && sizeof(Vec3d) == 3 * sizeof(double),
              "Vec3d arrays are read as (n, 3) float64 arrays");

// ---------------------------------------------------------------------------------------------
// Exceptions: vdb_shell.Error and its subclasses, one per class of core/base/errors.h.

struct ExceptionTypes {
  PyObject* error = nullptr;
  PyObject* input = nullptr;
  PyObject* resource = nullptr;
  PyObject* internal = nullptr;
  PyObject* cancelled = nullptr;
};

/// The module's exception types, created once by register_exceptions() and never freed (the
/// module is never unloaded).
ExceptionTypes& exception_types() {
  static ExceptionTypes types;
  return types;
}

/// A new exception type `vdb_shell.<name>` deriving from vdb_shell.Error and `builtin`.
PyObject* new_exception(py::module_& m, const char* name, PyObject* builtin, const char* doc) {
  const std::string qualified = std::string("vdb_shell.") + name;
  py::tuple bases = py::make_tuple(py::handle(exception_types().error), py::handle(builtin));
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.attr(name) = py::handle(type);
  return type;
}

void register_exceptions(py::module_& m) {
  ExceptionTypes& types = exception_types();
  types.error = PyErr_NewExceptionWithDoc(
      "vdb_shell.Error", "Base of every error vdb_shell raises.", PyExc_Exception, nullptr);
  if (types.error == nullptr) throw py::error_already_set();
  m.attr("Error") = py::handle(types.error);
  types.input = new_exception(
      m, "InputError", PyExc_ValueError,
      "The surface, an array or an option cannot be used as given (the message names the "
      "argument or option and the first offending element). Also a ValueError.");
  types.resource = new_exception(
      m, "ResourceError", PyExc_RuntimeError,
      "A resource ran out or failed: the memory budget (max_memory), a file that cannot be "
      "written. Also a RuntimeError.");
  types.internal = new_exception(
      m, "InternalError", PyExc_RuntimeError,
      "The library broke one of its own invariants (a bug: please report the input). Also a "
      "RuntimeError.");
  types.cancelled = new_exception(
      m, "CancelledError", PyExc_RuntimeError,
      "The run was cancelled: the progress callback returned False. Also a RuntimeError.");
  py::register_exception_translator([](std::exception_ptr p) {
    const ExceptionTypes& t = exception_types();
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(t.input, e.what());
    } catch (const ResourceError& e) {
      PyErr_SetString(t.resource, e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(t.internal, e.what());
    } catch (const CancelledError& e) {
      PyErr_SetString(t.cancelled, e.what());
    } catch (const Error& e) {
      PyErr_SetString(t.error, e.what());
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Arguments: arrays, paths and option values.

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

std::string to_text(py::handle value, const char* name) {
  if (!PyUnicode_Check(value.ptr()))
    throw InputError(std::string("option ") + name + " must be a str; got " + type_name(value));
  return value.cast<std::string>();
}

std::string number_text(double v) { return py::str(py::float_(v)).cast<std::string>(); }

/// One keyword option of build_shell(): the CLI's long option in snake_case.
struct OptionSpec {
  const char* name;
  const char* cli;  ///< the CLI's long option, as the library's messages name it
  const char* doc;
  void (*apply)(ShellOptions& options, py::handle value, const char* name);
  std::string (*shown_default)(const ShellOptions& defaults);
};

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
      {"max_memory", "--max-memory", "refuse field builds estimated above this many GiB",
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
  };
  return specs;
}

std::string option_names() {
  std::vector<std::string> names;
  for (const OptionSpec& s : option_specs()) names.emplace_back(s.name);
  std::sort(names.begin(), names.end());
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

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

// ---------------------------------------------------------------------------------------------
// Running a call on a worker thread.

/// One progress report, queued by the worker for the calling thread.
struct Report {
  std::string stage;
  double fraction = 0;
};

/// Runs `work(control)` on a worker thread; the calling thread, which holds the GIL, waits with
/// it released and every kPollInterval (or at each new report) takes it back to run the signal
/// handlers and to call `progress(stage, fraction)` with the queued reports. A Python exception
/// there (KeyboardInterrupt, or one the callback raised) cancels the run, waits for the worker to
/// stop and propagates; `progress` returning False cancels it too (CancelledError). Otherwise the
/// worker's result is returned or its exception rethrown.
template <class Result, class Work>
Result run_on_worker(const Work& work, const py::object& progress) {
  std::mutex mutex;
  std::condition_variable wake;
  std::vector<Report> pending;
  bool done = false;
  std::atomic<bool> cancel{false};
  Result result{};
  std::exception_ptr error;

  RunControl control;
  control.cancel = &cancel;
  if (!progress.is_none()) {
    control.progress = [&](const std::string& stage, double fraction) {
      {
        const std::lock_guard<std::mutex> lock(mutex);
        // Keep a stage's first report and its latest: the caller may be slower than the worker.
        if (!pending.empty() && pending.back().stage == stage && pending.back().fraction > 0)
          pending.back().fraction = fraction;
        else
          pending.push_back({stage, fraction});
      }
      wake.notify_one();
    };
  }

  std::thread worker;
  {
    py::gil_scoped_release released;
    worker = std::thread([&] {
      try {
        result = work(control);
      } catch (...) {
        error = std::current_exception();
      }
      {
        const std::lock_guard<std::mutex> lock(mutex);
        done = true;
      }
      wake.notify_one();
    });
  }
  const auto join = [&] {
    py::gil_scoped_release released;
    worker.join();
  };

  bool cancelled_by_callback = false;
  try {
    for (bool finished = false; !finished;) {
      std::vector<Report> reports;
      {
        py::gil_scoped_release released;
        std::unique_lock<std::mutex> lock(mutex);
        wake.wait_for(lock, kPollInterval, [&] { return done || !pending.empty(); });
        reports.swap(pending);
        finished = done;
      }
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      for (const Report& r : reports) {
        if (cancelled_by_callback) break;
        const py::object answer = progress(r.stage, r.fraction);
        if (answer.ptr() == Py_False) {
          cancelled_by_callback = true;
          cancel = true;
        }
      }
    }
  } catch (...) {
    cancel = true;
    join();
    throw;
  }
  join();
  if (cancelled_by_callback && !error)
    throw CancelledError("the progress callback returned False: the run was cancelled");
  if (error) std::rethrow_exception(error);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Results.

void make_read_only(py::array& a) { a.attr("setflags")(py::arg("write") = false); }

/// A read-only array over `count` rows of `columns` values of type T at `data`, owned by
/// `owner` (the array keeps it alive).
template <class T>
py::array view(const std::shared_ptr<const ShellResult>& owner, const T* data, std::size_t count,
               std::size_t columns) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(count)};
  if (columns > 0) shape.push_back(static_cast<py::ssize_t>(columns));
  auto* keep = new std::shared_ptr<const ShellResult>(owner);
  const py::capsule base(
      keep, [](void* p) { delete static_cast<std::shared_ptr<const ShellResult>*>(p); });
  py::array a(py::dtype::of<T>(), shape, {}, count > 0 ? data : nullptr, base);
  make_read_only(a);
  return a;
}

/// Rows of N unsigned indices as an (n, N) int64 array.
template <std::size_t N>
py::array_t<std::int64_t> int64_rows(const std::vector<std::array<std::uint32_t, N>>& rows) {
  py::array_t<std::int64_t> a({static_cast<py::ssize_t>(rows.size()), static_cast<py::ssize_t>(N)});
  std::int64_t* out = a.mutable_data();
  for (const auto& row : rows)
    for (const std::uint32_t i : row) *out++ = i;
  return a;
}

py::array_t<std::int64_t> int64_values(const std::vector<std::uint32_t>& values) {
  py::array_t<std::int64_t> a(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), a.mutable_data());
  return a;
}

/// The Python view of a ShellResult: arrays made once, the C++ result kept for the writers.
struct PyShellResult {
  std::shared_ptr<const ShellResult> result;
  py::array points, tets, source_triangle, quality, inner, thickness;
  py::array inner_vertices, inner_faces;
  py::object report;
  py::list notices;

  explicit PyShellResult(std::shared_ptr<const ShellResult> r) : result(std::move(r)) {
    const TetMesh& mesh = result->mesh;
    points =
        view(result, reinterpret_cast<const double*>(mesh.points.data()), mesh.points.size(), 3);
    tets = int64_rows(mesh.tets);
    source_triangle = int64_values(mesh.source_triangle);
    quality = view(result, mesh.quality.data(), mesh.quality.size(), 0);
    thickness = view(result, mesh.thickness.data(), mesh.thickness.size(), 0);
    py::array_t<bool> in(static_cast<py::ssize_t>(mesh.inner.size()));
    std::transform(mesh.inner.begin(), mesh.inner.end(), in.mutable_data(),
                   [](std::uint8_t v) { return v != 0; });
    inner = in;
    const SurfaceMesh& s = result->inner_surface;
    inner_vertices =
        view(result, reinterpret_cast<const double*>(s.points.data()), s.points.size(), 3);
    inner_faces = int64_rows(s.triangles);
    for (py::array* a : {&tets, &source_triangle, &inner, &inner_faces}) make_read_only(*a);
    report = py::module_::import("json").attr("loads")(report_json(*result));
    for (const std::string& n : result->notices) notices.append(n);
  }
};

// ---------------------------------------------------------------------------------------------
// The module's functions.

PyShellResult build_shell_py(py::handle vertices, py::handle faces, const py::object& progress,
                             const std::string& source, const py::kwargs& kwargs) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("progress must be callable as progress(stage, fraction) or None; got " +
                         type_name(progress));
  const ShellOptions options = parse_options(kwargs);
  PolygonSoup soup;
  soup.points = read_vertices(vertices);
  soup.polygons = read_faces(faces);
  std::shared_ptr<const ShellResult> result;
  try {
    result = run_on_worker<std::shared_ptr<const ShellResult>>(
        [&](const RunControl& control) {
          const LoadedSurface surface = make_surface(soup, source);
          return std::make_shared<const ShellResult>(build_shell(surface, options, control));
        },
        progress);
  } catch (const InputError& e) {
    throw InputError(with_keyword_names(e.what()));
  } catch (const ResourceError& e) {
    throw ResourceError(with_keyword_names(e.what()));
  }
  return PyShellResult(std::move(result));
}

py::tuple load_surface_py(py::handle path_like) {
  const std::string path = to_path(path_like, "path");
  LoadedSurface surface;
  {
    py::gil_scoped_release released;
    surface = load_surface(path);
  }
  const SurfaceMesh& mesh = surface.mesh;
  py::array_t<double> vertices({static_cast<py::ssize_t>(mesh.points.size()), py::ssize_t{3}});
  double* out = vertices.mutable_data();
  for (const Vec3d& p : mesh.points) {
    *out++ = p.x;
    *out++ = p.y;
    *out++ = p.z;
  }
  return py::make_tuple(vertices, int64_rows(mesh.triangles));
}

template <class Write>
void write_released(const Write& write) {
  py::gil_scoped_release released;
  write();
}

std::string build_shell_doc() {
  const ShellOptions defaults;
  std::string doc =
      "build_shell(vertices, faces, *, progress=None, source='arrays', **options) -> "
      "ShellResult\n\n"
      "Builds the tetrahedral shell of a closed triangle surface.\n\n"
      "vertices: (n, 3) array of coordinates (float64 C-contiguous is read in place; other "
      "float or integer dtypes are converted).\n"
      "faces: (m, 3) integer array of 0-based vertex indices, triangles counter-clockwise seen "
      "from outside (an inward surface is flipped, a notice says so).\n"
      "progress: None or progress(stage, fraction), called on this thread with the stages "
      "'fields', 'trace', 'inner', 'validity' and their fraction done in [0, 1]; returning "
      "False cancels the run (CancelledError); an exception it raises cancels the run and "
      "propagates.\n"
      "source: the name messages and the report use for the input.\n\n"
      "The GIL is released while the shell is built; Ctrl-C (KeyboardInterrupt) cancels the "
      "run. Vertices no face uses are dropped, so the shell's first points are the used input "
      "vertices in their order.\n\n"
      "Options (keyword arguments, the CLI's long options in snake_case; None: the default):\n";
  for (const OptionSpec& s : option_specs())
    doc += "  " + std::string(s.name) + " (default " + s.shown_default(defaults) + "): " + s.doc +
           "\n";
  doc +=
      "\nRaises InputError (a ValueError) for arrays of the wrong shape or dtype, a surface that "
      "is not closed and 2-manifold or has NaN/Inf coordinates or out-of-range indices (the "
      "message names the first offending element), unknown options or values out of range; "
      "ResourceError for the memory budget; InternalError for a bug.";
  return doc;
}

}  // namespace
}  // namespace vdb_shell

PYBIND11_MODULE(vdb_shell, m) {
  using namespace vdb_shell;
  m.doc() =
      "Volumetric shells of tetrahedra from closed triangle surfaces.\n\n"
      "Every surface vertex is traced inward through an OpenVDB signed distance field "
      "(\"Volumetric Shells using Path Tracing\"); build_shell() makes the thickest valid shell "
      "along the traces.\n\n"
      "    v, f = vdb_shell.load_surface('bunny.obj')\n"
      "    r = vdb_shell.build_shell(v, f, resolution=64)\n"
      "    vdb_shell.write('bunny.vtu', r)\n\n"
      "Units and frame are the input's; tets are positively oriented; the shell's first points "
      "are the surface's vertices.";
  m.attr("__version__") = VDB_SHELL_VERSION;
  // Every docstring starts with its signature, in Python's terms.
  py::options options;
  options.disable_function_signatures();
  register_exceptions(m);

  py::class_<PyShellResult>(m, "ShellResult",
                            "The shell build_shell() made. Arrays are read-only (copy them to "
                            "change them); write() and write_inner() write the shell they show.")
      .def_readonly("points", &PyShellResult::points,
                    "(p, 3) float64: the surface's vertices first, then the inner vertices")
      .def_readonly("tets", &PyShellResult::tets,
                    "(t, 4) int64 indices into points, positively oriented (t <= 3 * faces)")
      .def_readonly("source_triangle", &PyShellResult::source_triangle,
                    "(t,) int64: per tet, the input triangle (row of faces) it was built on")
      .def_readonly("quality", &PyShellResult::quality,
                    "(t,) float64: per tet, the volume-length ratio (regular tet: 1)")
      .def_readonly("inner", &PyShellResult::inner, "(p,) bool: per point, True for inner vertices")
      .def_readonly("thickness", &PyShellResult::thickness,
                    "(p,) float64: per inner point, its distance to the farthest surface "
                    "vertex whose inner vertex it is (input units); 0 on the surface")
      .def_readonly("inner_vertices", &PyShellResult::inner_vertices,
                    "(q, 3) float64: vertices of the inner surface")
      .def_readonly("inner_faces", &PyShellResult::inner_faces,
                    "(m, 3) int64: the inner surface, one triangle per input triangle, facing "
                    "the interior")
      .def_readonly("report", &PyShellResult::report,
                    "dict: the JSON report (keys input, fields, trace, stop_reasons, shell, "
                    "validity, quality, timings_s; docs/usage.md)")
      .def_readonly("notices", &PyShellResult::notices,
                    "list of str: every notice of the run (flipped input, dropped vertices, ...)")
      .def("__repr__", [](const PyShellResult& r) {
        return "<vdb_shell.ShellResult: " + std::to_string(r.result->mesh.points.size()) +
               " points, " + std::to_string(r.result->mesh.tets.size()) + " tets>";
      });

  static const std::string build_doc = build_shell_doc();
  m.def("build_shell", &build_shell_py, build_doc.c_str(), py::arg("vertices"), py::arg("faces"),
        py::kw_only(), py::arg("progress") = py::none(), py::arg("source") = "arrays");
  m.def("load_surface", &load_surface_py,
        "load_surface(path) -> (vertices, faces)\n\n"
        "Reads and validates a surface file (.obj .off .ply .stl): vertices (n, 3) float64 and "
        "faces (m, 3) int64, as build_shell() uses them (polygons split into triangles, unused "
        "vertices dropped, an inward surface flipped). Raises InputError for a missing or "
        "unreadable file and for a surface that is not closed and 2-manifold.",
        py::arg("path"));
  m.def(
      "write",
      [](py::handle path, const PyShellResult& result, int msh_version) {
        const std::string p = to_path(path, "path");
        write_released([&] { write_shell(p, *result.result, msh_version); });
      },
      "write(path, result, msh_version=41)\n\n"
      "Writes the shell to path, format from its extension (.vtu .vtk .msh .mesh .ele; .msh as "
      "Gmsh 4.1 or, with msh_version=22, 2.2), atomically: a failed write leaves no file. "
      "Raises InputError for an unknown extension, ResourceError if the file cannot be written.",
      py::arg("path"), py::arg("result"), py::arg("msh_version") = 41);
  m.def(
      "write_inner",
      [](py::handle path, const PyShellResult& result) {
        const std::string p = to_path(path, "path");
        write_released([&] { write_inner_surface(p, *result.result); });
      },
      "write_inner(path, result)\n\n"
      "Writes the inner surface (.obj .ply .off) atomically. Raises InputError for an unknown "
      "extension, ResourceError if the file cannot be written.",
      py::arg("path"), py::arg("result"));
  m.def(
      "write_traces",
      [](py::handle path, const PyShellResult& result) {
        const std::string p = to_path(path, "path");
        write_released([&] { vdb_shell::write_traces(p, *result.result); });
      },
      "write_traces(path, result)\n\n"
      "Writes every vertex's trace as VTK polylines (.vtk) atomically. Raises ResourceError if "
      "the file cannot be written.",
      py::arg("path"), py::arg("result"));
}

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

#include "python/arguments.h"
#include "vdb_shell/vdb_shell.h"

namespace py = pybind11;

namespace vdb_shell {
namespace {

using python::option_specs;
using python::OptionSpec;
using python::parse_options;
using python::read_faces;
using python::read_vertices;
using python::to_path;
using python::type_name;
using python::with_keyword_names;

/// How often the waiting thread checks for signals and delivers progress reports.
constexpr std::chrono::milliseconds kPollInterval{50};

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

template <class T>
py::array_t<std::int64_t> int64_values(const std::vector<T>& values) {
  py::array_t<std::int64_t> a(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), a.mutable_data());
  return a;
}

/// The Python view of a ShellResult: arrays made once, the C++ result kept for the writers.
struct PyShellResult {
  std::shared_ptr<const ShellResult> result;
  py::array points, tets, source_triangle, layer, quality, inner, thickness, surface_vertex;
  py::array inner_vertices, inner_faces;
  py::object report;
  py::list notices;

  explicit PyShellResult(std::shared_ptr<const ShellResult> r) : result(std::move(r)) {
    const TetMesh& mesh = result->mesh;
    points =
        view(result, reinterpret_cast<const double*>(mesh.points.data()), mesh.points.size(), 3);
    tets = int64_rows(mesh.tets);
    source_triangle = int64_values(mesh.source_triangle);
    layer = int64_values(mesh.layer);
    surface_vertex = int64_values(mesh.surface_vertex);
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
    for (py::array* a : {&tets, &source_triangle, &layer, &surface_vertex, &inner, &inner_faces})
      make_read_only(*a);
    report = py::module_::import("json").attr("loads")(report_json(*result));
    for (const std::string& n : result->notices) notices.append(n);
  }
};

// ---------------------------------------------------------------------------------------------
// The module's functions.

/// Runs `build` (ShellResult(const RunControl&)) on a worker thread with `progress`, the
/// messages naming the Python keywords.
template <class Build>
PyShellResult run_build(const py::object& progress, const Build& build) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("progress must be callable as progress(stage, fraction) or None; got " +
                         type_name(progress));
  std::shared_ptr<const ShellResult> result;
  try {
    result = run_on_worker<std::shared_ptr<const ShellResult>>(
        [&](const RunControl& control) {
          return std::make_shared<const ShellResult>(build(control));
        },
        progress);
  } catch (const InputError& e) {
    throw InputError(with_keyword_names(e.what()));
  } catch (const ResourceError& e) {
    throw ResourceError(with_keyword_names(e.what()));
  }
  return PyShellResult(std::move(result));
}

PyShellResult build_shell_py(py::handle vertices, py::handle faces, const py::object& progress,
                             const std::string& source, const py::kwargs& kwargs) {
  const ShellOptions options = parse_options(kwargs);
  PolygonSoup soup;
  soup.points = read_vertices(vertices);
  soup.polygons = read_faces(faces);
  return run_build(progress, [&](const RunControl& control) {
    if (!options.repair) return build_shell(make_surface(soup, source), options, control);
    RepairReport repair;
    ShellResult result =
        build_shell(load_repaired_surface(soup, source, options, repair), options, control);
    result.repair = repair;
    return result;
  });
}

PyShellResult build_shell_from_level_set_py(py::handle path_like, const py::object& progress,
                                            const py::kwargs& kwargs) {
  const std::string path = to_path(path_like, "path");
  const ShellOptions options = parse_options(kwargs);
  return run_build(progress, [&](const RunControl& control) {
    return build_shell_from_level_set(path, options, control);
  });
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
      "is not closed and 2-manifold, crosses itself or has NaN/Inf coordinates or out-of-range "
      "indices (the "
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
                    "(p, 3) float64: the surface's vertices first, then the inner vertices (and "
                    "with layers > 1 the layer points between them)")
      .def_readonly("tets", &PyShellResult::tets,
                    "(t, 4) int64 indices into points, positively oriented (t <= 3 * layers * "
                    "faces + 2 * sectors of folded vertices)")
      .def_readonly("source_triangle", &PyShellResult::source_triangle,
                    "(t,) int64: per tet, the input triangle (row of faces) it was built on")
      .def_readonly("layer", &PyShellResult::layer,
                    "(t,) int64: per tet, its layer through the thickness, 1 at the outer "
                    "surface to `layers` at the inner one")
      .def_readonly("quality", &PyShellResult::quality,
                    "(t,) float64: per tet, the volume-length ratio (regular tet: 1)")
      .def_readonly("inner", &PyShellResult::inner,
                    "(p,) bool: per point, True for inner vertices and layer points")
      .def_readonly("thickness", &PyShellResult::thickness,
                    "(p,) float64: per inner point, its distance to the farthest surface "
                    "vertex whose inner vertex it is (input units); 0 on the surface")
      .def_readonly("surface_vertex", &PyShellResult::surface_vertex,
                    "(p,) int64: per point, its surface vertex (itself on the surface; for an "
                    "inner point the smallest surface vertex whose inner vertex it is)")
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
  m.def("build_shell_from_level_set", &build_shell_from_level_set_py,
        "build_shell_from_level_set(path, *, progress=None, **options) -> ShellResult\n\n"
        "Meshes the level set of a .vdb file at its zero crossing (options grid and adaptivity) "
        "and shells that surface in the same field, as `vdb_shell FILE.vdb -o ...` does. The "
        "options and the result are build_shell()'s (level_set must not be given: the file is "
        "its own). Raises InputError for a missing or corrupt file, a grid that is not a float "
        "level set, negative outside, or holds no closed surface.",
        py::arg("path"), py::kw_only(), py::arg("progress") = py::none());
  m.def("load_surface", &load_surface_py,
        "load_surface(path) -> (vertices, faces)\n\n"
        "Reads and validates a surface file (.obj .off .ply .stl): vertices (n, 3) float64 and "
        "faces (m, 3) int64, as build_shell() uses them (polygons split into triangles, unused "
        "vertices dropped, an inward surface flipped). Raises InputError for a missing or "
        "unreadable file and for a surface that is not closed and 2-manifold.",
        py::arg("path"));
  m.def(
      "write",
      [](py::handle path, const PyShellResult& result, const py::object& msh_version) {
        const std::string p = to_path(path, "path");
        // 4.1 / 2.2 as users write them: numbers or strings, or 41 / 22.
        const std::string v = py::str(msh_version).cast<std::string>();
        const int version = v == "4.1" || v == "41" ? 41 : v == "2.2" || v == "22" ? 22 : 0;
        if (version == 0)
          throw InputError("msh_version " + v + ": must be 4.1 or 2.2 (the Gmsh format version)");
        write_released([&] { write_shell(p, *result.result, version); });
      },
      "write(path, result, msh_version='4.1')\n\n"
      "Writes the shell to path, format from its extension (.vtu .vtk .msh .mesh .ele; .msh as "
      "Gmsh 4.1 or, with msh_version='2.2' (or 2.2, 22), 2.2), atomically: a failed write leaves "
      "no file. Raises InputError for an unknown extension or version, ResourceError if the file "
      "cannot be written.",
      py::arg("path"), py::arg("result"), py::arg("msh_version") = "4.1");
  m.def(
      "write_inner",
      [](py::handle path, const PyShellResult& result) {
        const std::string p = to_path(path, "path");
        write_released([&] { write_inner_surface(p, *result.result); });
      },
      "write_inner(path, result)\n\n"
      "Writes the inner surface (.obj .ply .off .stl) atomically. Raises InputError for an unknown "
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
  m.def(
      "write_html",
      [](py::handle path, const PyShellResult& result) {
        const std::string p = to_path(path, "path");
        write_released([&] { vdb_shell::write_html(p, *result.result); });
      },
      "write_html(path, result)\n\n"
      "Writes the HTML report of the run (what vdb_shell --html writes: cut-away pictures, "
      "cross-sections, thickness, traces, quality histograms and the run's figures, in one "
      "self-contained page) atomically. Raises ResourceError if the file cannot be written.",
      py::arg("path"), py::arg("result"));
}

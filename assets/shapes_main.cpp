// shapes_main.cpp — vdb_shell_shapes: writes one of the procedural test shapes as an OBJ file.
//
//   vdb_shell_shapes NAME -o FILE.obj [--detail N]
//   vdb_shell_shapes --list
//
// Coordinates are written with 17 significant digits (doubles round-trip exactly), through a
// temporary file renamed onto the target (core/write/shell_writers.h), so a failure never leaves a
// partial file. Exit codes: 0 success, 2 bad input (unknown shape, bad detail, bad command line,
// missing output folder; nothing is written), 3 write failure or internal error.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/base/file_name.h"
#include "core/write/shell_writers.h"

namespace {

namespace fs = std::filesystem;
using vdb_shell::InputError;

void print_catalog() {
  std::cout << "shape        faces  description (detail N has about N^2 times the faces)\n";
  for (const vdb_shell::ShapeInfo& s : vdb_shell::shape_catalog()) {
    std::cout << std::left << std::setw(10) << s.name << std::right << std::setw(8)
              << s.default_faces << "  " << s.description << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Writes a procedural test shape of the paper (closed, outward triangle surface "
      "fitting the unit cube centred at the origin) as an OBJ file."};
  app.get_formatter()->column_width(28);
  std::string name;
  std::string output;
  int detail = 1;
  bool list = false;
  app.add_option("name", name, "shape name (see --list)");
  app.add_option("-o,--output", output, "output OBJ file (written atomically)");
  app.add_option("-d,--detail", detail,
                 "resolution factor in [1, " + std::to_string(vdb_shell::kMaxShapeDetail) +
                     "]; faces grow as detail^2")
      ->capture_default_str();
  app.add_flag("-l,--list", list, "list the shapes with their face counts at detail 1");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "vdb_shell_shapes: error: " << e.what() << " (see --help)\n";
    return 2;
  }

  try {
    if (list) {
      print_catalog();
      return 0;
    }
    if (name.empty()) throw InputError("no shape name given (see --list)");
    if (output.empty()) throw InputError("no output file given: add -o FILE.obj");
    if (vdb_shell::lower_extension(output) != ".obj") {
      throw InputError("output '" + output + "' must end in .obj (only OBJ is written)");
    }
    const vdb_shell::SurfaceMesh mesh = vdb_shell::make_shape(name, detail);
    const fs::path folder = fs::path(output).parent_path();
    if (!folder.empty() && !fs::is_directory(folder))
      throw InputError("cannot write '" + output + "': the folder " + folder.string() +
                       " does not exist; create it first");
    vdb_shell::write_surface(output, mesh);  // full precision, temp file + rename
    std::cout << name << " (detail " << detail << "): " << mesh.num_vertices() << " vertices, "
              << mesh.num_faces() << " faces -> " << output << '\n';
    return 0;
  } catch (const InputError& e) {
    std::cerr << "vdb_shell_shapes: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "vdb_shell_shapes: internal error: " << e.what() << '\n';
    return 3;
  }
}

// trace_points_test.cpp — the traces as OpenVDB points in the --grids file
// (vdb_ops/trace_points.h, write_grids in vdb_ops/fields.h).
//
// The horn (non-planar tip and sides, planar base) at 48^3 is traced once; its traces are written
// with the fields and read back through the OpenVDB points API, then compared with the
// TraceResult sample by sample.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <functional>
#include <memory>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "assets/shapes.h"
#include "core/base/errors.h"
#include "core/trace/trace.h"
#include "tests/test_support.h"
#include "vdb_ops/fields.h"
#include "vdb_ops/trace_points.h"

namespace vdb_shell {
namespace {

struct Traced {
  SurfaceMesh mesh;
  std::unique_ptr<Fields> fields;
  TraceResult traces;
};

const Traced& horn() {
  static const Traced t = [] {
    Traced r;
    r.mesh = make_shape("horn");
    FieldOptions options;
    options.resolution = 48;
    r.fields = build_fields(r.mesh, options);
    r.traces = trace_paths(r.mesh, *r.fields, TraceOptions{});
    return r;
  }();
  return t;
}

/// Stored point indices ordered by (vertex, sample).
std::vector<std::size_t> by_vertex_and_sample(const TracePoints& p) {
  std::vector<std::size_t> order(p.vertex.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::make_pair(p.vertex[a], p.sample[a]) < std::make_pair(p.vertex[b], p.sample[b]);
  });
  return order;
}

TEST(TracePoints, EverySampleUpToTheEndRoundTrips) {
  const Traced& h = horn();
  const TraceResult& tr = h.traces;
  test::TempDir dir;
  const std::string path = dir.file("horn.vdb");
  write_grids(path, *h.fields, {{"vdb_shell_input", "horn.obj"}}, &tr);
  const TracePoints p = read_trace_points(path);

  std::size_t expected = 0;
  for (std::size_t v = 0; v < tr.num_traces(); ++v) expected += tr.end[v] + 1;
  ASSERT_GT(expected, tr.num_traces());  // the traces do go inward
  EXPECT_EQ(trace_point_count(tr), expected);
  ASSERT_EQ(p.positions.size(), expected);
  for (const auto* column : {&p.stop_reason, &p.planar, &p.vertex, &p.sample})
    ASSERT_EQ(column->size(), expected);
  ASSERT_EQ(p.arc_length.size(), expected);
  EXPECT_EQ(p.attributes, (std::vector<std::string>{"P", "arc_length", "stop_reason", "planar",
                                                    "vertex", "sample"}));
  const double h_vox = h.fields->voxel_size();
  EXPECT_DOUBLE_EQ(p.voxel_size, h_vox);

  // Every (vertex, sample) with sample <= end once, in order; values equal the TraceResult's.
  const std::vector<std::size_t> order = by_vertex_and_sample(p);
  std::size_t k = 0;
  for (std::size_t v = 0; v < tr.num_traces(); ++v) {
    for (std::size_t i = 0; i <= tr.end[v]; ++i, ++k) {
      const std::size_t n = order[k];
      ASSERT_EQ(p.vertex[n], static_cast<int>(v));
      ASSERT_EQ(p.sample[n], static_cast<int>(i));
      // Stored as float offsets within a voxel: exact to a tiny fraction of a voxel.
      EXPECT_LE(distance(p.positions[n], tr.sample(v, i)), 1e-6 * h_vox) << v << " " << i;
      const double arc = tr.arc_length[tr.offsets[v] + i];
      EXPECT_FLOAT_EQ(p.arc_length[n], static_cast<float>(arc)) << v << " " << i;
      if (i == 0) {
        EXPECT_EQ(p.arc_length[n], 0.0f);
      } else {
        EXPECT_GT(p.arc_length[n], p.arc_length[order[k - 1]]) << v << " " << i;
      }
      EXPECT_EQ(p.stop_reason[n], static_cast<int>(tr.stop[v]));
      EXPECT_EQ(p.planar[n], tr.planar[v] ? 1 : 0);
    }
  }
  // The horn has both vertex classes and more than one stop reason.
  EXPECT_NE(std::count(p.planar.begin(), p.planar.end(), 1), 0);
  EXPECT_NE(std::count(p.planar.begin(), p.planar.end(), 0), 0);
  EXPECT_GT(std::set<int>(p.stop_reason.begin(), p.stop_reason.end()).size(), 1u);

  // Metadata: the codes, the trace parameters and the caller's items.
  EXPECT_EQ(p.metadata.at("vdb_shell_attribute_stop_reason"),
            "int32, per trace: 0 critical, 1 merge, 2 flux, 3 cap");
  EXPECT_EQ(p.metadata.at("vdb_shell_attribute_planar"),
            "int32, per trace: 1 planar vertex, 0 non-planar");
  EXPECT_NEAR(std::stod(p.metadata.at("vdb_shell_trace_step")), tr.parameters.step, 1e-15);
  EXPECT_EQ(p.metadata.at("vdb_shell_trace_points"), std::to_string(expected));
  EXPECT_EQ(p.metadata.at("vdb_shell_input"), "horn.obj");
  EXPECT_EQ(p.metadata.count("vdb_shell_voxel_size"), 1u);
}

TEST(TracePoints, FieldsAreUnchangedAndTracesComeLast) {
  const Traced& h = horn();
  test::TempDir dir;
  write_grids(dir.file("with.vdb"), *h.fields, {}, &h.traces);
  write_grids(dir.file("without.vdb"), *h.fields, {});
  const std::vector<VdbGridInfo> with = read_vdb_grid_infos(dir.file("with.vdb"));
  const std::vector<VdbGridInfo> without = read_vdb_grid_infos(dir.file("without.vdb"));
  ASSERT_EQ(without.size(), 2u);
  ASSERT_EQ(with.size(), 3u);
  for (std::size_t g = 0; g < 2; ++g) {
    EXPECT_EQ(with[g].name, without[g].name);
    EXPECT_EQ(with[g].checksum, without[g].checksum) << with[g].name;
  }
  EXPECT_EQ(with[2].name, "traces");
  EXPECT_EQ(with[2].value_type, "ptdataidx32");
  EXPECT_DOUBLE_EQ(with[2].voxel_size, with[0].voxel_size);  // the surface grid's transform
}

TEST(TracePoints, SameFileForAnyThreadCount) {
  // The point partitioner bins by task (2 x the arena's concurrency); the stored order and the
  // bytes must not depend on it.
  const Traced& h = horn();
  test::TempDir dir;
  std::vector<std::string> bytes;
  for (const int threads : {1, 2}) {
    const std::string path = dir.file("t" + std::to_string(threads) + ".vdb");
    tbb::task_arena arena(threads);
    arena.execute([&] { write_grids(path, *h.fields, {}, &h.traces); });
    bytes.push_back(test::read_text(path));
  }
  ASSERT_FALSE(bytes[0].empty());
  EXPECT_EQ(bytes[0], bytes[1]);
  // And the same file when written again (no random content, e.g. the header's UUID).
  write_grids(dir.file("again.vdb"), *h.fields, {}, &h.traces);
  EXPECT_EQ(test::read_text(dir.file("again.vdb")), bytes[0]);
}

TEST(TracePoints, VdbPrintListsTheTracesGrid) {
  if (test::run_command("command -v vdb_print").exit_code != 0)
    GTEST_SKIP() << "vdb_print (libopenvdb-tools) not installed";
  const Traced& h = horn();
  test::TempDir dir;
  const std::string path = dir.file("horn.vdb");
  write_grids(path, *h.fields, {}, &h.traces);
  // One line per grid: "traces      ptdataidx32 (6,6,7)->(38,37,17) ...".
  const test::CommandResult r = test::run_command("vdb_print '" + path + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("surface ", 0), 0u) << r.out;
  const std::size_t line = r.out.find("\ntraces ");
  ASSERT_NE(line, std::string::npos) << r.out;
  const std::string traces_line = r.out.substr(line + 1, r.out.find('\n', line + 1) - line - 1);
  EXPECT_NE(traces_line.find("ptdataidx32"), std::string::npos) << traces_line;
  // vdb_print -m lists the attributes' documentation (grid metadata).
  const test::CommandResult m = test::run_command("vdb_print -m '" + path + "'");
  EXPECT_NE(m.out.find("0 critical, 1 merge, 2 flux, 3 cap"), std::string::npos) << m.out;
}

TEST(TracePoints, ReaderRejectsWhatIsNotATracesGrid) {
  const Traced& h = horn();
  test::TempDir dir;
  const std::string path = dir.file("f.vdb");
  write_grids(path, *h.fields, {});
  auto message = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no InputError");
  };
  EXPECT_NE(message([&] { read_trace_points(path); }).find("--grids"), std::string::npos);
  EXPECT_NE(message([&] { read_trace_points(path, "surface"); }).find("not OpenVDB points"),
            std::string::npos);
  EXPECT_NE(message([&] { read_trace_points(dir.file("missing.vdb")); }).find("no such file"),
            std::string::npos);
  test::write_text(dir.file("junk.vdb"), "not a vdb file");
  EXPECT_NE(message([&] { read_trace_points(dir.file("junk.vdb")); }).find("junk.vdb"),
            std::string::npos);
}

}  // namespace
}  // namespace vdb_shell

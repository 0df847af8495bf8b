// trace_points.cpp — the traces as an OpenVDB PointDataGrid; see trace_points.h. The only
// translation unit that includes OpenVDB's points headers.
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/tools/PointIndexGrid.h>

#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "core/base/errors.h"
#include "vdb_ops/trace_points_grid.h"

namespace vdb_shell {

namespace {

using openvdb::points::PointDataGrid;
using openvdb::points::PointDataTree;

constexpr const char* kArcLength = "arc_length";
constexpr const char* kStopReason = "stop_reason";
constexpr const char* kPlanar = "planar";
constexpr const char* kVertex = "vertex";
constexpr const char* kSample = "sample";

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

/// Per-point arrays in (vertex, sample) order, the order handed to the point partitioner.
struct PointArrays {
  std::vector<openvdb::Vec3d> positions;
  std::vector<float> arc_length;
  std::vector<std::int32_t> stop_reason, planar, vertex, sample;
};

PointArrays gather(const TraceResult& traces) {
  constexpr std::size_t kMaxInt = std::numeric_limits<std::int32_t>::max();
  const std::size_t n = trace_point_count(traces);
  if (traces.num_traces() > kMaxInt)
    throw InputError("traces grid: " + std::to_string(traces.num_traces()) +
                     " traces exceed the int32 'vertex' attribute; use a mesh with fewer "
                     "vertices or leave out --grids");
  PointArrays a;
  a.positions.reserve(n);
  a.arc_length.reserve(n);
  a.stop_reason.reserve(n);
  a.planar.reserve(n);
  a.vertex.reserve(n);
  a.sample.reserve(n);
  for (std::size_t v = 0; v < traces.num_traces(); ++v) {
    for (std::size_t i = 0; i <= traces.end[v]; ++i) {
      const Vec3d& p = traces.sample(v, i);
      if (!is_finite(p))
        throw InternalError("traces grid: sample " + std::to_string(i) + " of the trace of " +
                            "vertex " + std::to_string(v) + " is not finite");
      a.positions.emplace_back(p.x, p.y, p.z);
      a.arc_length.push_back(static_cast<float>(traces.arc_length[traces.offsets[v] + i]));
      a.stop_reason.push_back(static_cast<std::int32_t>(traces.stop[v]));
      a.planar.push_back(traces.planar[v] ? 1 : 0);
      a.vertex.push_back(static_cast<std::int32_t>(v));
      a.sample.push_back(static_cast<std::int32_t>(i));
    }
  }
  return a;
}

template <typename T>
void add_attribute(PointDataTree& tree, const openvdb::tools::PointIndexTree& index,
                   const char* name, const std::vector<T>& values) {
  openvdb::points::appendAttribute<T>(tree, name);
  openvdb::points::populateAttribute(tree, index, name,
                                     openvdb::points::PointAttributeVector<T>(values));
}

std::string format_double(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

/// The attribute `name` of `leaf` as a handle of T.
/// \throw InputError naming `where` if it is missing or of another type.
template <typename T>
typename openvdb::points::AttributeHandle<T>::Ptr handle_of(
    const openvdb::points::PointDataTree::LeafNodeType& leaf, const char* name,
    const std::string& where) {
  const std::size_t pos = leaf.attributeSet().find(name);
  if (pos == openvdb::points::AttributeSet::INVALID_POS)
    throw InputError(where + ": no point attribute '" + name + "'");
  const openvdb::points::AttributeArray& array = leaf.constAttributeArray(pos);
  if (!array.hasValueType<T>())
    throw InputError(where + ": point attribute '" + name + "' has type " + array.type().first +
                     ", expected " + openvdb::typeNameAsString<T>());
  return openvdb::points::AttributeHandle<T>::create(array);
}

}  // namespace

const std::vector<std::pair<std::string, std::string>>& trace_points_metadata() {
  static const std::vector<std::pair<std::string, std::string>> meta = {
      {"vdb_shell_traces",
       "one point per trace sample, from the surface vertex (sample 0) to the trace's end "
       "sample"},
      {"vdb_shell_attribute_arc_length",
       "float: length along the trace from the surface vertex, world units"},
      {"vdb_shell_attribute_stop_reason", "int32, per trace: 0 critical, 1 merge, 2 flux, 3 cap"},
      {"vdb_shell_attribute_planar", "int32, per trace: 1 planar vertex, 0 non-planar"},
      {"vdb_shell_attribute_vertex", "int32: index of the surface vertex the trace starts from"},
      {"vdb_shell_attribute_sample", "int32: index of the sample along its trace, 0 = surface"},
  };
  return meta;
}

std::size_t trace_point_count(const TraceResult& traces) {
  std::size_t n = 0;
  for (const std::uint32_t e : traces.end) n += std::size_t{e} + 1;
  return n;
}

openvdb::GridBase::Ptr make_trace_points_grid(const TraceResult& traces,
                                              const openvdb::math::Transform& xform) {
  init_openvdb();
  const PointArrays a = gather(traces);
  const openvdb::points::PointAttributeVector<openvdb::Vec3d> positions(a.positions);
  // The partitioner keeps the input order within a voxel (a stable sort), so the stored order is
  // (leaf, voxel, vertex, sample) for any thread count.
  const openvdb::tools::PointIndexGrid::Ptr index =
      openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(positions, xform);
  PointDataGrid::Ptr grid =
      openvdb::points::createPointDataGrid<openvdb::points::NullCodec, PointDataGrid>(
          *index, positions, xform);
  PointDataTree& tree = grid->tree();
  if (tree.leafCount() > 0) {  // attributes live in the leaves: an empty grid has none
    add_attribute(tree, index->tree(), kArcLength, a.arc_length);
    add_attribute(tree, index->tree(), kStopReason, a.stop_reason);
    add_attribute(tree, index->tree(), kPlanar, a.planar);
    add_attribute(tree, index->tree(), kVertex, a.vertex);
    add_attribute(tree, index->tree(), kSample, a.sample);
  }
  grid->setName(kTracePointsGridName);
  for (const auto& [k, v] : trace_points_metadata())
    grid->insertMeta(k, openvdb::StringMetadata(v));
  grid->insertMeta("vdb_shell_trace_points",
                   openvdb::Int64Metadata(static_cast<std::int64_t>(a.positions.size())));
  grid->insertMeta("vdb_shell_trace_step",
                   openvdb::StringMetadata(format_double(traces.parameters.step)));
  grid->insertMeta("vdb_shell_trace_point_size",
                   openvdb::StringMetadata(format_double(traces.parameters.point_size)));
  return grid;
}

TracePoints read_trace_points(const std::string& vdb_path, const std::string& grid_name) {
  init_openvdb();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(vdb_path, ec))
    throw InputError("cannot read points from '" + vdb_path + "': no such file");
  const std::string where = "'" + vdb_path + "', grid '" + grid_name + "'";
  openvdb::GridBase::Ptr base;
  try {
    openvdb::io::File file(vdb_path);
    file.open(false);
    if (!file.hasGrid(grid_name))
      throw InputError("'" + vdb_path + "' has no grid named '" + grid_name +
                       "'; write it with vdb_shell --grids (which adds the traces grid)");
    base = file.readGrid(grid_name);
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError("cannot read '" + vdb_path + "' as a .vdb file: " + e.what());
  }
  const PointDataGrid::Ptr grid = openvdb::gridPtrCast<PointDataGrid>(base);
  if (!grid) throw InputError(where + " is a " + base->valueType() + " grid, not OpenVDB points");

  TracePoints out;
  out.voxel_size = grid->voxelSize()[0];
  for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it)
    out.metadata[it->first] = it->second ? it->second->str() : std::string();
  const openvdb::math::Transform& xform = grid->transform();
  for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
    if (out.attributes.empty()) {
      const auto& names = leaf->attributeSet().descriptor().map();  // name -> position
      out.attributes.resize(names.size());
      for (const auto& [name, pos] : names) out.attributes.at(pos) = name;
    }
    const auto p = handle_of<openvdb::Vec3f>(*leaf, "P", where);
    const auto arc = handle_of<float>(*leaf, kArcLength, where);
    const auto stop = handle_of<std::int32_t>(*leaf, kStopReason, where);
    const auto planar = handle_of<std::int32_t>(*leaf, kPlanar, where);
    const auto vertex = handle_of<std::int32_t>(*leaf, kVertex, where);
    const auto sample = handle_of<std::int32_t>(*leaf, kSample, where);
    for (auto idx = leaf->beginIndexOn(); idx; ++idx) {
      const openvdb::Vec3d w =
          xform.indexToWorld(idx.getCoord().asVec3d() + openvdb::Vec3d(p->get(*idx)));
      out.positions.push_back({w[0], w[1], w[2]});
      out.arc_length.push_back(arc->get(*idx));
      out.stop_reason.push_back(stop->get(*idx));
      out.planar.push_back(planar->get(*idx));
      out.vertex.push_back(vertex->get(*idx));
      out.sample.push_back(sample->get(*idx));
    }
  }
  return out;
}

}  // namespace vdb_shell

#include <cmath>
#include <cstdint>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <lightvol/airlight/detail/vdb_codec.h>
#include <lightvol/core/text.h>

namespace lightvol::detail {
namespace {

std::string in_quotes(const std::string& name) { return "'" + utf8_prefix(name, 80) + "'"; }

std::string shortest(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// Sends the refusal; the request was answered.
bool refuse(ChildOutput& channel, const Error& error) {
  channel.refuse(error);
  return true;
}

// The grids of an open file, for the message that names a missing one.
std::string grid_names(openvdb::io::File& file) {
  std::string names;
  int count = 0;
  for (auto name = file.beginName(); name != file.endName(); ++name, ++count) {
    if (count == 8) return names + ", ...";
    names += (names.empty() ? "" : ", ") + in_quotes(name.gridName());
  }
  return names.empty() ? "none: a truncated or corrupt file?" : names;
}

// The dense voxels of `grid` over `box`, x fastest, checked (finite, ≥ 0) and sent after the
// verdict; or the refusal naming the first bad voxel.
template <class GridT>
void send_voxels(ChildOutput& channel, const GridT& grid, const openvdb::CoordBBox& box,
                 const std::string& where) {
  using Value = typename GridT::ValueType;
  std::vector<Value> values(box.volume());
  openvdb::tools::Dense<Value, openvdb::tools::LayoutXYZ> dense(box, values.data());
  openvdb::tools::copyToDense(grid, dense);
  const openvdb::Coord dim = box.dim();
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = static_cast<double>(values[i]);
    if (std::isfinite(v) && v >= 0 && std::isfinite(static_cast<float>(v))) continue;
    const auto x = static_cast<std::int64_t>(i % static_cast<std::size_t>(dim.x()));
    const auto y = static_cast<std::int64_t>(i / static_cast<std::size_t>(dim.x()) %
                                             static_cast<std::size_t>(dim.y()));
    const auto z = static_cast<std::int64_t>(
        i / (static_cast<std::size_t>(dim.x()) * static_cast<std::size_t>(dim.y())));
    const openvdb::Coord at =
        box.min() + openvdb::Coord(static_cast<openvdb::Int32>(x), static_cast<openvdb::Int32>(y),
                                   static_cast<openvdb::Int32>(z));
    std::string what = std::isnan(v)       ? "is NaN"
                       : !std::isfinite(v) ? "is infinite"
                       : v < 0             ? "is negative (" + shortest(v) + ")"
                                           : "is beyond float's range";
    channel.refuse(Error{where + ": the voxel at index (" + std::to_string(at.x()) + ", " +
                         std::to_string(at.y()) + ", " + std::to_string(at.z()) + ") " + what +
                         "; densities are finite and >= 0"});
    return;
  }
  channel.accept();
  if constexpr (std::is_same_v<Value, float>) {
    channel.write(values.data(), values.size() * sizeof(float));
  } else {
    std::vector<float> row(static_cast<std::size_t>(dim.x()));
    for (std::size_t at = 0; at < values.size(); at += row.size()) {
      for (std::size_t i = 0; i < row.size(); ++i) row[i] = static_cast<float>(values[at + i]);
      channel.write(row.data(), row.size() * sizeof(float));
    }
  }
}

// The conversation after the grid is read: its box, transform and background, the parent's go,
// the voxels.
template <class GridT>
bool serve_grid(ChildOutput& channel, const GridT& grid, const std::string& where) {
  const double background = static_cast<double>(grid.background());
  if (!(std::isfinite(background) && background >= 0))
    return refuse(channel, Error{where + ": its background value (" + shortest(background) +
                                 ") is not a density (finite, >= 0)"});
  const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
  if (box.empty()) return refuse(channel, Error{where + ": has no active voxels (an empty grid)"});
  const openvdb::math::Transform& transform = grid.transform();
  if (!transform.isLinear())
    return refuse(channel, Error{where + ": has a non-linear transform (" + transform.mapType() +
                                 "); lightvol reads grids with a linear (affine) one"});
  // OpenVDB's matrices act on row vectors (world = [i j k 1]·M); lightvol's on columns.
  const openvdb::math::Mat4d m = transform.baseMap()->getAffineMap()->getMat4();
  double to_world[16];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) to_world[4 * r + c] = m(c, r);
  for (const double v : to_world)
    if (!std::isfinite(v)) return refuse(channel, Error{where + ": its transform is not finite"});
  channel.accept();
  const std::int32_t origin[3] = {box.min().x(), box.min().y(), box.min().z()};
  std::int64_t dims[3];
  for (int a = 0; a < 3; ++a) dims[a] = std::int64_t{box.max()[a]} - std::int64_t{box.min()[a]} + 1;
  channel.write(origin, sizeof(origin));
  channel.write(dims, sizeof(dims));
  channel.write(to_world, sizeof(to_world));
  channel.write_value(background);
  std::int32_t go = 0;
  if (!channel.read_value(&go) || go != 1) return true;  // the parent refused (its budget)
  send_voxels(channel, grid, box, where);
  return true;
}

}  // namespace

bool serve_vdb_request(ChildOutput& channel) {
  static const bool initialized = (openvdb::initialize(), true);
  (void)initialized;
  std::string path, name;
  if (!channel.read_string(&path) || !channel.read_string(&name)) return false;
  const std::string where = path + ": grid " + in_quotes(name);
  openvdb::GridBase::Ptr grid;
  try {
    openvdb::io::File file(path);
    file.open(false);  // no delayed loading (no memory-mapped file behind the grid)
    if (!file.hasGrid(name))
      return refuse(channel, Error{path + ": has no grid named " + in_quotes(name) +
                                   " (its grids: " + grid_names(file) + ")"});
    const openvdb::GridBase::Ptr meta = file.readGridMetadata(name);
    const std::string type = meta->valueType();
    if (type != "float" && type != "double")
      return refuse(channel, Error{where + ": holds " + utf8_prefix(type, 40) +
                                   " values; a density grid holds scalars (float or double)"});
    grid = file.readGrid(name);
    file.close();
  } catch (const std::bad_alloc&) {
    throw;  // the program ends: the parent reports the memory limit
  } catch (const std::exception& e) {
    std::string why = e.what();
    if (why.empty()) why = "unknown error";
    return refuse(channel,
                  Error{path + ": OpenVDB cannot read it (a truncated or corrupt file?): " +
                        utf8_prefix(why, 300)});
  }
  if (const auto floats = openvdb::GridBase::grid<openvdb::FloatGrid>(grid))
    return serve_grid(channel, *floats, where);
  if (const auto doubles = openvdb::GridBase::grid<openvdb::DoubleGrid>(grid))
    return serve_grid(channel, *doubles, where);
  return refuse(channel, Error{where + ": holds " + utf8_prefix(grid->valueType(), 40) +
                               " values; a density grid holds scalars (float or double)"});
}

}  // namespace lightvol::detail

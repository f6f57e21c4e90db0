#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <lightvol/airlight/detail/vdb_file.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/text.h>

namespace lightvol::detail {

namespace {

// OpenVDB's files start with the int64 0x56444220 (" BDV" and four zeros, little-endian), then
// the file version (4 bytes), the library's version (8), whether grids have offsets (1) and the
// file's UUID (36 characters): 57 bytes before the first metadata. OpenVDB reads this header
// without checking each read, so a shorter file would leave it judging bytes it never read (a
// verdict that changed from run to run); such a file is refused here.
constexpr char kVdbMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};
constexpr std::uintmax_t kVdbHeaderBytes = 57;

Status check_vdb_file(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) return Error{path + ": no such file"};
  if (std::filesystem::is_directory(status))
    return Error{path + ": is a directory, not an OpenVDB file"};
  if (!std::filesystem::is_regular_file(status))
    return Error{path + ": is not a regular file (a device or a pipe); grids are read from files"};
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  const std::streamsize got = in.gcount();
  if (!std::equal(magic, magic + got, kVdbMagic) || got < 4)
    return Error{path + ": not an OpenVDB file (it does not start with OpenVDB's magic number)"};
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec || size < kVdbHeaderBytes)
    return Error{path + ": a truncated OpenVDB file (" + std::to_string(ec ? 0 : size) +
                 " bytes, shorter than OpenVDB's " + std::to_string(kVdbHeaderBytes) +
                 "-byte header)"};
  return {};
}

}  // namespace

Result<std::shared_ptr<const VoxelGrid>> read_vdb_grid(const std::string& path,
                                                       const std::string& grid) {
  if (Status s = check_vdb_file(path); !s) return s.error();
  const std::string source = path + ": grid '" + utf8_prefix(grid, 80) + "'";
  Result<std::shared_ptr<const VoxelGrid>> result = Error{""};
  const Error broken{path + ": the OpenVDB reader broke off its answer"};
  // The conversation of vdb_codec.h serve_vdb_request.
  const auto parent = [&](ChildInput& in) -> Status {
    if (!in.write_value(ImageRequest::vdb) || !in.write_string(path) || !in.write_string(grid))
      return broken;
    Status answer;
    if (!in.read_go_on(&result, broken, &answer)) return answer;
    auto out = std::make_shared<VoxelGrid>();
    out->source = source;
    std::int64_t dims[3] = {};
    Mat4d to_world;
    if (!in.read(out->origin.data(), sizeof(out->origin)) || !in.read(dims, sizeof(dims)) ||
        !in.read(to_world.m.data(), sizeof(to_world.m)) || !in.read_value(&out->background))
      return broken;
    const auto stop = [&](const Error& error) -> Status {
      in.write_value(std::int32_t{-1});
      result = error;
      return {};
    };
    double count = 1;
    for (const std::int64_t d : dims) {
      if (d < 1 || d > (std::int64_t{1} << 32)) return broken;
      count *= static_cast<double>(d);
    }
    if (!(std::isfinite(out->background) && out->background >= 0)) return broken;
    const std::string size =
        std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]);
    // The voxels here and their copy on the GPU (docs/robustness.md).
    const double bytes = 2 * count * sizeof(float);
    if (Status s =
            check_memory(bytes > 1.8e19 ? std::uint64_t{18000000000000000000u}
                                        : static_cast<std::uint64_t>(bytes),
                         source, "its " + size + " voxels (dense floats, here and on the GPU)");
        !s)
      return stop(s.error());
    for (int axis = 0; axis < 3; ++axis)
      if (dims[axis] > kMaxGridSide)
        return stop(Error{source + ": its active voxels span " + size +
                          "; lightvol renders grids "
                          "of at most " +
                          std::to_string(kMaxGridSide) + " voxels along each axis"});
    for (int axis = 0; axis < 3; ++axis) out->dims[axis] = static_cast<int>(dims[axis]);
    const bool affine =
        to_world.m[12] == 0 && to_world.m[13] == 0 && to_world.m[14] == 0 && to_world.m[15] == 1;
    if (!affine || !out->set_transform(to_world)) return broken;
    const auto voxels = static_cast<std::size_t>(count);
    in.allow_more(2 + 50e-9 * count);
    if (!in.write_value(std::int32_t{1})) return broken;
    if (!in.read_go_on(&result, broken, &answer)) return answer;
    out->values.resize(voxels);
    if (!in.read(out->values.data(), voxels * sizeof(float))) return broken;
    // Nothing the reader sends is trusted: the same checks it made.
    for (const float v : out->values)
      if (!(std::isfinite(v) && v >= 0)) return broken;
    result = std::shared_ptr<const VoxelGrid>(std::move(out));
    return {};
  };
  IsolationLimits limits;
  // The budget, and room for OpenVDB's tree and the libraries' own state.
  limits.memory = (std::uint64_t{512} << 20) + memory_budget();
  std::error_code ec;
  const double file_bytes = static_cast<double>(std::filesystem::file_size(path, ec));
  limits.cpu_seconds = 10 + (ec ? 0 : 100e-9 * file_bytes);
  limits.wall_seconds = 20 + 4 * limits.cpu_seconds;
  if (Status run = run_image_helper(path + ": OpenVDB's reader", limits, parent); !run)
    return run.error();
  return result;
}

}  // namespace lightvol::detail

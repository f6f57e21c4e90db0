#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/detail/block_scan.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/path.h>
#include <lightvol/depth/depth_image.h>
#include <lightvol/depth/detail/image_file.h>
#include <lightvol/depth/image_channel.h>

namespace lightvol {
namespace {

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

Result<int> choose_channel(const detail::ImageHeader& spec, const DepthReadOptions& options,
                           const std::string& path) {
  const auto& names = spec.names;
  if (!options.channel.empty()) {
    for (int c = 0; c < spec.nchannels(); ++c)
      if (names[c] == options.channel) return c;
    return Error{path + ": no channel named '" + options.channel +
                 "' (channels: " + join_names(names) + ")"};
  }
  const auto is_alpha = [&](int c) { return c == spec.alpha_channel || names[c] == "A"; };
  if (spec.nchannels() == 1 && !is_alpha(0)) return 0;
  if (spec.nchannels() == 1)
    return Error{path + ": its only channel, '" + names[0] +
                 "', is alpha (coverage), not depth; to read it as depth anyway, name it with "
                 "DepthReadOptions::channel " +
                 names[0]};
  for (const char* preferred : {"Z", "depth", "Y"})
    for (int c = 0; c < spec.nchannels(); ++c)
      if (names[c] == preferred) return c;
  int candidate = -1, non_alpha = 0;
  for (int c = 0; c < spec.nchannels(); ++c) {
    if (is_alpha(c)) continue;
    ++non_alpha;
    candidate = c;
  }
  if (non_alpha == 1) return candidate;
  return Error{path + ": has " + std::to_string(spec.nchannels()) + " channels (" +
               join_names(names) + "): choose the depth channel with DepthReadOptions::channel"};
}

}  // namespace

Status validate_depths(const DepthImage& image, const std::string& source) {
  const std::size_t n = image.values.size();
  // The first block of texels holding a depth that is not finite and ≥ 0, then that block one
  // texel at a time.
  const float* values = image.values.data();
  const std::size_t from = detail::first_failing_block(n, [values](std::size_t i) {
    return (values[i] >= 0.0f) & (values[i] <= std::numeric_limits<float>::max());
  });
  for (std::size_t i = from; i < n; ++i) {
    const float v = image.values[i];
    if (std::isfinite(v) && v >= 0) continue;
    const std::size_t col = i % static_cast<std::size_t>(image.width);
    const std::size_t row = i / static_cast<std::size_t>(image.width);
    const char* what = std::isnan(v) ? "NaN" : (std::isinf(v) ? "infinite" : "negative");
    return Error{source + ": pixel (" + std::to_string(col) + ", " + std::to_string(row) +
                 "): depth is " + what + " (" + std::to_string(v) +
                 "); depths must be finite and >= 0"};
  }
  return {};
}

std::optional<std::array<int, 2>> peek_image_size(const std::string& path) {
  return detail::exr_data_window_size(path);
}

Result<DepthImage> read_depth_image(const std::string& path, const DepthReadOptions& options) {
  const auto within_budget = [&](const detail::ImageHeader& spec) {
    return check_memory(
        build_memory_bytes(options.memory, spec.width, spec.height, options.images), path,
        "a volume from " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
            " texels" + (options.images > 1 ? " x " + std::to_string(options.images) : ""));
  };
  const auto select = [&](const detail::ImageHeader& spec) -> Result<int> {
    const Result<int> channel = choose_channel(spec, options, path);
    if (!channel) return channel.error();
    if (spec.channel_eight_bit[static_cast<std::size_t>(*channel)] != 0)
      return Error{path + ": channel '" + spec.names[static_cast<std::size_t>(*channel)] +
                   "' holds 8-bit values, too coarse for depth; use a float or 16-bit image"};
    return channel;
  };
  Result<ImageChannel> read =
      detail::read_image_channel(path, within_budget, select, "cannot read pixels");
  if (!read) return read.error();
  DepthImage image;
  image.width = read->width;
  image.height = read->height;
  image.values = std::move(read->values);
  if (Status s = validate_depths(image, path); !s) return s.error();
  return image;
}

Result<ImageChannel> read_first_channel(const std::string& path,
                                        const ChannelReadOptions& options) {
  const auto within_budget = [&](const detail::ImageHeader& spec) {
    const auto texels =
        static_cast<std::uint64_t>(spec.width) * static_cast<std::uint64_t>(spec.height);
    return check_memory(
        texels * options.bytes_per_texel, path,
        "a " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " image");
  };
  const auto select = [&](const detail::ImageHeader& spec) -> Result<int> {
    if (!options.refuse_8_bit.empty() && spec.eight_bit)
      return Error{path + ": " + options.refuse_8_bit};
    return 0;
  };
  return detail::read_image_channel(path, within_budget, select, "cannot read image");
}

namespace {
// OpenImageIO reads PFM but has no PFM writer: the format is a text header and little-endian
// floats, rows stored bottom to top.
static_assert(std::endian::native == std::endian::little, "PFM output assumes little-endian");
Status write_pfm(const std::string& path, const DepthImage& image) {
  std::string bytes =
      "Pf\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n";
  const std::size_t row_bytes = sizeof(float) * static_cast<std::size_t>(image.width);
  for (int r = image.height - 1; r >= 0; --r)
    bytes.append(
        reinterpret_cast<const char*>(&image.values[static_cast<std::size_t>(r) * image.width]),
        row_bytes);
  return write_bytes_atomically(path, bytes);
}
}  // namespace

Status write_depth_image(const std::string& path, const DepthImage& image) {
  const std::string ext = lower_extension(path);
  if (ext == ".pfm") return write_pfm(path, image);
  return write_file_atomically(path, [&](const std::string& temp_path) -> Status {
    detail::ImageWrite pixels;
    pixels.width = image.width;
    pixels.height = image.height;
    pixels.stored =
        ext == ".png" ? detail::ImageWrite::Stored::u16 : detail::ImageWrite::Stored::f32;
    pixels.names = {ext == ".exr" ? "Z" : "Y"};
    pixels.floats = image.values.data();
    const detail::ImageWriteResult written = detail::write_image_file(path, temp_path, pixels);
    using Outcome = detail::ImageWriteResult::Outcome;
    if (written.outcome == Outcome::no_writer)
      return Error{path +
                   ": cannot write images of this type: " + detail::oiio_message(written.message)};
    if (written.outcome == Outcome::failed)
      return Error{path + ": cannot write image: " + detail::oiio_message(written.message)};
    return {};
  });
}

}  // namespace lightvol

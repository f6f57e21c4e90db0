#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/depth/detail/image_codec.h>
#include <lightvol/depth/detail/image_file.h>

namespace lightvol::detail {
namespace {

struct OpenImage {
  std::unique_ptr<OIIO::ImageInput> input;
  OIIO::ImageSpec spec;
};

bool is_eight_bit(OIIO::TypeDesc type) {
  return type.basetype == OIIO::TypeDesc::UINT8 || type.basetype == OIIO::TypeDesc::INT8;
}

// OpenImageIO's open with the plugin check_image_file chose, and the checks that need nothing
// but the header: at least 2x2 texels, not a volume.
Result<OpenImage> open_image(const std::string& path, const std::string& plugin, int threads) {
  const std::string* const format = &plugin;
  OpenImage image;
  image.input = OIIO::ImageInput::create(*format);
  if (!image.input)
    return Error{path + ": cannot read image: no " + *format +
                 " reader: " + oiio_message(OIIO::geterror())};
  // In lightvol-image, every core (0); in a forked child, the one thread it has.
  image.input->threads(threads);
  if (!image.input->open(path, image.spec))
    return Error{path + ": cannot read image: " + oiio_message(image.input->geterror())};
  const OIIO::ImageSpec& spec = image.spec;
  if (spec.width < 2 || spec.height < 2)
    return Error{path + ": is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                 "; an image needs at least 2x2 texels"};
  if (spec.depth > 1) return Error{path + ": is a volume image, not a 2D one"};
  return image;
}

// The header against the file it came with, after the parent's memory check: more than 2^30
// texels; PFM exactly, EXR by its chunk table, every format by the most any compression packs
// into a byte; the data window against the display window. Long (over 80 lines) on purpose: each
// check with its own message, in order.
Status check_header(const std::string& path, const std::string& magic, const std::string& plugin,
                    const OIIO::ImageSpec& spec) {
  const std::string* const format = &plugin;
  std::error_code ec;
  const std::int64_t texels = static_cast<std::int64_t>(spec.width) * spec.height;
  if (texels > (std::int64_t{1} << 30))
    return Error{path + ": is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                 ", more than 2^30 texels; lightvol's 32-bit indices cannot hold its volume"};
  // The header against the file it came with: PFM exactly, EXR by its chunk table, every format
  // by the most any compression packs into a byte.
  const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
  const bool sized = !ec;
  // PFM is uncompressed: a header that promises more floats than the file holds is truncated (or
  // forged); refuse it before allocating what it promises.
  if (magic.rfind("Pf", 0) == 0 || magic.rfind("PF", 0) == 0) {
    const std::uintmax_t needed = static_cast<std::uintmax_t>(texels) *
                                  static_cast<std::uintmax_t>(spec.nchannels) * sizeof(float);
    if (sized && file_size < needed)
      return Error{path + ": PFM header says " + std::to_string(spec.width) + "x" +
                   std::to_string(spec.height) + " (" + std::to_string(needed) +
                   " bytes of floats), but the file has " + std::to_string(file_size) +
                   " bytes (truncated file?)"};
  }
  // EXR stores an offset table of 8 bytes per chunk (scanline blocks or tiles) and each chunk
  // starts with at least 8 bytes: a file smaller than that for its size is truncated or forged.
  // Refuse it before OpenEXR walks (and allocates for) every missing chunk (fuzz finding).
  if (*format == "openexr") {
    const std::string compression = spec.get_string_attribute("compression", "none");
    std::int64_t lines = 1;  // scanlines per chunk, by compression
    if (compression == "zip" || compression == "pxr24") lines = 16;
    if (compression == "piz" || compression == "b44" || compression == "b44a" ||
        compression == "dwaa")
      lines = 32;
    if (compression == "dwab") lines = 256;
    const std::int64_t chunks =
        spec.tile_width > 0 && spec.tile_height > 0
            ? ((spec.width + spec.tile_width - 1) / spec.tile_width) *
                  std::int64_t{(spec.height + spec.tile_height - 1) / spec.tile_height}
            : (spec.height + lines - 1) / lines;
    if (sized && static_cast<std::uintmax_t>(chunks) * 16 > file_size)
      return Error{path + ": EXR of " + std::to_string(spec.width) + "x" +
                   std::to_string(spec.height) + " has " + std::to_string(chunks) +
                   " chunks, needing at least " + std::to_string(chunks * 16) +
                   " bytes, but the file has " + std::to_string(file_size) + " (truncated file?)"};
  }
  // No image format packs more than about 1,100 decoded bytes into a compressed byte (deflate,
  // LZW, PIZ and DWA on constant data, measured); a header promising much more than that from a
  // small file is forged (fuzz finding: 446 bytes of EXR claiming 6894084x17, and a 7 GB
  // allocation in OpenImageIO).
  {
    constexpr std::uintmax_t kMaxRatio = 4096;
    const std::uintmax_t decoded = static_cast<std::uintmax_t>(spec.image_bytes(true));
    if (sized && decoded / kMaxRatio > file_size)
      return Error{path + ": is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                   " with " + std::to_string(spec.nchannels) + " channels, " +
                   std::to_string(decoded) + " bytes, in a file of " + std::to_string(file_size) +
                   ": more than any compression holds (truncated or forged)"};
  }
  // The pixels stored (the data window) must be the view (the display window): a crop read as
  // the whole view would stretch it over the frustum, silently wrong geometry.
  if (spec.x != spec.full_x || spec.y != spec.full_y || spec.width != spec.full_width ||
      spec.height != spec.full_height) {
    const auto window = [](int x, int y, int w, int h) {
      return std::to_string(w) + "x" + std::to_string(h) + " at (" + std::to_string(x) + ", " +
             std::to_string(y) + ")";
    };
    return Error{path + ": its data window (" + window(spec.x, spec.y, spec.width, spec.height) +
                 ") is not its display window (" +
                 window(spec.full_x, spec.full_y, spec.full_width, spec.full_height) +
                 "): it covers another part than the whole view; store the whole view, or make "
                 "the data window the view (oiiotool in.exr --fullpixels -o out.exr)"};
  }
  return {};
}

void serve_read(ChildOutput& channel, int threads) {
  std::string path, plugin, magic, read_failure;
  if (!channel.read_string(&path) || !channel.read_string(&plugin) ||
      !channel.read_string(&magic) || !channel.read_string(&read_failure))
    return;
  Result<OpenImage> opened = open_image(path, plugin, threads);
  if (!opened) return channel.refuse(opened.error());
  const OIIO::ImageSpec& spec = opened->spec;
  if (spec.nchannels < 1 || spec.nchannels > kMaxImageChannels)
    return channel.refuse(Error{path + ": has " + std::to_string(spec.nchannels) +
                                " channels; lightvol reads images of 1 to " +
                                std::to_string(kMaxImageChannels)});
  channel.accept();
  channel.write_value(static_cast<std::int32_t>(spec.width));
  channel.write_value(static_cast<std::int32_t>(spec.height));
  channel.write_value(static_cast<std::int32_t>(
      spec.alpha_channel >= 0 && spec.alpha_channel < spec.nchannels ? spec.alpha_channel : -1));
  channel.write_value(std::uint8_t{is_eight_bit(spec.format)});
  channel.write_value(static_cast<std::int32_t>(spec.nchannels));
  for (int c = 0; c < spec.nchannels; ++c) {
    channel.write_string(c < static_cast<int>(spec.channelnames.size()) ? spec.channelnames[c]
                                                                        : std::string());
    channel.write_value(std::uint8_t{is_eight_bit(spec.channelformat(c))});
  }
  std::int32_t go = 0;
  if (!channel.read_value(&go) || go != 1) return;
  if (Status s = check_header(path, magic, plugin, spec); !s) return channel.refuse(s.error());
  channel.accept();
  std::int32_t chosen = -1;
  if (!channel.read_value(&chosen) || chosen < 0 || chosen >= spec.nchannels) return;
  // The parent's shared memory for the floats (a memfd of exactly their size), or none.
  std::uint8_t offered = 0;
  int shared_fd = -1;
  if (!channel.read_with_fd(&offered, &shared_fd)) return;
  DecodedFloats floats(
      shared_fd, static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height));
  float* const values = floats.data();
  OIIO::ImageInput* const in = opened->input.get();
  // A truncated file can come back "read" with the damage reported only in the error queue.
  const bool read =
      in->read_image(0, 0, chosen, chosen + 1, OIIO::TypeDesc::FLOAT, values) && !in->has_error();
  floats.unmap();
  if (!read)
    return channel.refuse(Error{path + ": " + read_failure + ": " + oiio_message(in->geterror())});
  in->close();
  channel.accept();
  floats.send(channel);
}

void serve_write(ChildOutput& channel, int threads) {
  std::string create_name, temp;
  std::int32_t width = 0, height = 0, channels = 0;
  std::uint8_t stored = 0, bytes = 0;
  std::uint32_t names = 0;
  if (!channel.read_string(&create_name) || !channel.read_string(&temp) ||
      !channel.read_value(&width) || !channel.read_value(&height) ||
      !channel.read_value(&channels) || !channel.read_value(&stored) ||
      !channel.read_value(&bytes) || !channel.read_value(&names) || width < 1 || height < 1 ||
      channels < 1 || channels > kMaxImageChannels || stored > 2 ||
      names > static_cast<std::uint32_t>(channels))
    return;
  OIIO::ImageSpec spec(width, height, channels,
                       stored == 1   ? OIIO::TypeDesc::UINT8
                       : stored == 2 ? OIIO::TypeDesc::UINT16
                                     : OIIO::TypeDesc::FLOAT);
  if (names > 0) spec.channelnames.resize(names);
  for (std::uint32_t c = 0; c < names; ++c)
    if (!channel.read_string(&spec.channelnames[c])) return;
  const std::size_t values = static_cast<std::size_t>(width) * static_cast<std::size_t>(height) *
                             static_cast<std::size_t>(channels);
  std::vector<float> floats(bytes ? 0 : values);
  std::vector<std::uint8_t> eight(bytes ? values : 0);
  if (bytes ? !channel.read(eight.data(), values)
            : !channel.read(floats.data(), values * sizeof(float)))
    return;
  const auto answer = [&](std::uint8_t outcome, const std::string& message) {
    channel.write_value(outcome);
    channel.write_string(message);
  };
  auto out = OIIO::ImageOutput::create(create_name);
  if (!out) return answer(1, OIIO::geterror());
  out->threads(threads);
  const bool ok =
      out->open(temp, spec) && (bytes ? out->write_image(OIIO::TypeDesc::UINT8, eight.data())
                                      : out->write_image(OIIO::TypeDesc::FLOAT, floats.data()));
  const bool closed = out->close();
  if (!ok || !closed) return answer(2, out->geterror());
  answer(0, "");
}

}  // namespace

bool serve_image_request(ChildOutput& channel, int threads) {
  ImageRequest request{};
  if (!channel.read_value(&request)) return false;
  return serve_image_request(channel, threads, request);
}

bool serve_image_request(ChildOutput& channel, int threads, ImageRequest request) {
  // EXR through OpenEXR's C core (OpenEXRCore) rather than its C++ library, whose header reader
  // allocates unknown attributes at whatever size the file claims and reads known ones (channel
  // lists) past their stated size. The core checks most sizes; check_exr_header refuses what
  // made either of them lose its place in fuzzing. Set here, where every image request of every
  // server (lightvol-image's loop, the in-process and fake servers) passes.
  static const bool exr_core = OIIO::attribute("openexr:core", 1);
  (void)exr_core;
  if (request == ImageRequest::read) serve_read(channel, threads);
  if (request == ImageRequest::write) serve_write(channel, threads);
  return request == ImageRequest::read || request == ImageRequest::write;
}

}  // namespace lightvol::detail

#include <algorithm>
#include <array>
#include <cmath>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/check.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/path.h>
#include <lightvol/depth/image_channel.h>
#include <lightvol/render/image_io.h>

namespace lightvol {

namespace {

double srgb(double x) {
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

// Writes the three channels `rgb` (one image each, of one size): 8-bit formats tone-mapped with
// `scale` as write_image describes, float formats linear.
Status write_channels(const std::string& path, const std::array<const Image*, 3>& rgb, double scale,
                      bool eight_bit) {
  const Image& first = *rgb[0];
  const std::size_t n = first.values.size();
  for (const Image* c : rgb) LV_CHECK(c->width == first.width && c->height == first.height);
  return write_file_atomically(path, [&](const std::string& temp) -> Status {
    detail::ImageWrite write;
    write.width = first.width;
    write.height = first.height;
    write.channels = 3;
    write.stored = eight_bit ? detail::ImageWrite::Stored::u8 : detail::ImageWrite::Stored::f32;
    std::vector<unsigned char> bytes;
    std::vector<float> floats;
    if (eight_bit) {
      bytes.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < 3; ++k) {
          const double x = std::max(0.0, rgb[k]->values[i] * scale);
          const double v = std::clamp(srgb(x / (1 + x)), 0.0, 1.0);
          bytes[3 * i + k] = static_cast<unsigned char>(std::lround(255 * v));
        }
      write.bytes = bytes.data();
    } else {
      floats.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < 3; ++k)
          floats[3 * i + k] = static_cast<float>(rgb[k]->values[i]);
      write.floats = floats.data();
    }
    const detail::ImageWriteResult written = detail::write_image_file(temp, temp, write);
    using Outcome = detail::ImageWriteResult::Outcome;
    if (written.outcome == Outcome::no_writer)
      return Error{path + ": cannot write images of this type (" + written.message + ")"};
    if (written.outcome == Outcome::failed)
      return Error{path + ": cannot write image: " + written.message};
    return {};
  });
}

bool is_eight_bit(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tga";
}

}  // namespace

Status write_image(const std::string& path, const Image& image, double exposure) {
  const bool eight_bit = is_eight_bit(path);
  double scale = exposure;
  if (eight_bit && !(scale > 0)) {
    std::vector<double> sorted;
    for (double v : image.values)
      if (v > 0) sorted.push_back(v);
    double p = 0;
    if (!sorted.empty()) {
      const std::size_t k = std::min(sorted.size() - 1, sorted.size() * 995 / 1000);
      std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k),
                       sorted.end());
      p = sorted[k];
    }
    scale = p > 0 ? 4.0 / p : 1.0;
  }
  return write_channels(path, {&image, &image, &image}, scale, eight_bit);
}

Status write_rgb_image(const std::string& path, const Image& red, const Image& green,
                       const Image& blue, double exposure) {
  return write_channels(path, {&red, &green, &blue}, exposure, is_eight_bit(path));
}

Result<Image> read_image(const std::string& path) {
  ChannelReadOptions options;
  options.bytes_per_texel = sizeof(float) + sizeof(double);  // a float while reading, then ours
  options.refuse_8_bit = "an 8-bit image holds no linear airlight; compare against an .exr";
  const Result<ImageChannel> read = read_first_channel(path, options);
  if (!read) return read.error();
  Image image;
  image.width = read->width;
  image.height = read->height;
  image.values.assign(read->values.begin(), read->values.end());
  return image;
}

}  // namespace lightvol

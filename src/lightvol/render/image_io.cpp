#include <algorithm>
#include <cmath>

#include <lightvol/core/atomic_file.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/path.h>
#include <lightvol/depth/image_channel.h>
#include <lightvol/render/image_io.h>

namespace lightvol {

namespace {

double srgb(double x) {
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

}  // namespace

Status write_image(const std::string& path, const Image& image, double exposure) {
  const std::string ext = lower_extension(path);
  const bool eight_bit =
      ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tga";
  const std::size_t n = image.values.size();
  return write_file_atomically(path, [&](const std::string& temp) -> Status {
    detail::ImageWrite write;
    write.width = image.width;
    write.height = image.height;
    write.channels = 3;
    write.stored = eight_bit ? detail::ImageWrite::Stored::u8 : detail::ImageWrite::Stored::f32;
    std::vector<unsigned char> bytes;
    std::vector<float> floats;
    if (eight_bit) {
      double scale = exposure;
      if (!(scale > 0)) {
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
      std::vector<unsigned char>& pixels = bytes;
      pixels.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i) {
        const double x = std::max(0.0, image.values[i] * scale);
        const double v = std::clamp(srgb(x / (1 + x)), 0.0, 1.0);
        pixels[3 * i] = pixels[3 * i + 1] = pixels[3 * i + 2] =
            static_cast<unsigned char>(std::lround(255 * v));
      }
      write.bytes = pixels.data();
    } else {
      std::vector<float>& pixels = floats;
      pixels.resize(3 * n);
      for (std::size_t i = 0; i < n; ++i)
        pixels[3 * i] = pixels[3 * i + 1] = pixels[3 * i + 2] = static_cast<float>(image.values[i]);
      write.floats = pixels.data();
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

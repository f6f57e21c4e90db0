#include <algorithm>
#include <cstddef>
#include <memory>

#include <lightvol/render/fog_picture.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/surfaces.h>

namespace lightvol {

namespace {

// One half of the picture: the airlight and lit surfaces (in the light's colour) and the ambient
// surfaces (in the sky's), as red, green and blue.
std::array<Image, 3> colour_half(const RenderScene& scene, const Image& airlight,
                                 const std::vector<float>& shadow_window, int map_width,
                                 int map_height, const FogPictureOptions& o, Image* total) {
  SurfaceShading direct;
  direct.ambient = 0;
  SurfaceShading ambient;
  ambient.albedo = 0;
  ambient.ambient = o.ambient;
  Image dark = airlight;
  std::fill(dark.values.begin(), dark.values.end(), 0.0);
  const Image lit = lit_surfaces(scene, shadow_window, map_width, map_height, airlight, direct);
  const Image sky = lit_surfaces(scene, shadow_window, map_width, map_height, dark, ambient);
  std::array<Image, 3> rgb{lit, lit, lit};
  *total = lit;
  for (std::size_t i = 0; i < lit.values.size(); ++i) {
    total->values[i] += sky.values[i];
    for (std::size_t k = 0; k < 3; ++k)
      rgb[k].values[i] = o.light_colour[k] * lit.values[i] + o.ambient_colour[k] * sky.values[i];
  }
  return rgb;
}

// `left` and `right` (one size) side by side.
Image beside(const Image& left, const Image& right) {
  Image out;
  out.width = left.width + right.width;
  out.height = left.height;
  out.values.reserve(static_cast<std::size_t>(out.width) * out.height);
  for (int row = 0; row < left.height; ++row)
    for (const Image* half : {&left, &right})
      for (int col = 0; col < half->width; ++col) out.values.push_back(half->at(col, row));
  return out;
}

double sum(const Image& image) {
  double s = 0;
  for (const double v : image.values) s += v;
  return s;
}

}  // namespace

Result<FogPicture> write_fog_picture(const RenderScene& scene, const Mesh& volume,
                                     const Medium& fog, const std::vector<float>& shadow_window,
                                     int map_width, int map_height, const std::string& path,
                                     const FogPictureOptions& options, const Image* homogeneous) {
  RenderScene clear = scene;
  clear.medium.density = {};
  RenderScene foggy = scene;
  foggy.medium = fog;
  FogPicture result;
  std::array<Image, 2> airlight;
  GlVolumeOptions volume_options = options.volume;
  volume_options.density.tile = options.grid_tile;
  for (int k = 0; k < 2; ++k) {
    if (k == 0 && homogeneous) {
      airlight[0] = *homogeneous;
      continue;
    }
    Result<std::unique_ptr<GlVolumeRenderer>> renderer =
        GlVolumeRenderer::create(k == 0 ? clear : foggy, volume_options);
    if (!renderer) return renderer.error();
    (*renderer)->set_volume(volume);
    airlight[k] = (*renderer)->render(k == 1 ? &result.fog_seconds : nullptr);
  }
  const double clear_sum = sum(airlight[0]);
  result.fog_airlight_ratio = clear_sum > 0 ? sum(airlight[1]) / clear_sum : 0;
  Image total_clear, total_fog;
  const std::array<Image, 3> left =
      colour_half(clear, airlight[0], shadow_window, map_width, map_height, options, &total_clear);
  const std::array<Image, 3> right =
      colour_half(foggy, airlight[1], shadow_window, map_width, map_height, options, &total_fog);
  if (Status s = write_rgb_image(path, beside(left[0], right[0]), beside(left[1], right[1]),
                                 beside(left[2], right[2]),
                                 percentile_exposure(total_clear, options.exposure));
      !s)
    return s.error();
  return result;
}

}  // namespace lightvol

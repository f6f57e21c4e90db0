#include <algorithm>
#include <array>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/pipeline/detail/demo_rows.h>
#include <lightvol/pipeline/gl_demo.h>
#include <lightvol/render/fog_picture.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/image_io.h>
#include <lightvol/render/surfaces.h>
#include <lightvol/scene/shadowmap.h>

namespace lightvol {
namespace {
using detail::end_row;
using detail::size_text;

// demo.png's colours: a warm spot light (about 3,000 K) and a cool ambient light (the sky); its
// ambient radiance; and the exposure, the tone-mapped value (x/(1+x) of it) of the picture's
// 99.5th percentile.
constexpr std::array<double, 3> kLightColour = {1.0, 0.72, 0.42};
constexpr std::array<double, 3> kAmbientColour = {0.5, 0.62, 0.9};
constexpr double kDemoAmbient = 0.0002;
constexpr double kDemoExposure = 1.2;

// The airlight of each volume and of ray marching, and the pictures: lit surfaces plus the static
// volume's airlight, and the fog beside it.
Status render_pictures(const DemoPictureInputs& in, StageLog& log, std::vector<DemoRow>* rows) {
  const RenderScene& scene = in.scene;
  const auto out = [&](const std::string& name) { return in.out_dir + "/" + name; };
  const std::string size = size_text(scene.camera.width, scene.camera.height);
  Result<std::unique_ptr<GlVolumeRenderer>> volume_renderer = GlVolumeRenderer::create(scene);
  if (!volume_renderer) return volume_renderer.error();
  std::vector<Image> images;
  double exposure = 1;
  char text[96];
  for (const DemoVolume& v : in.volumes) {
    log.begin("render " + v.name + " volume");
    (*volume_renderer)->set_volume(v.mesh);
    double seconds = 0;
    images.push_back((*volume_renderer)->render(&seconds));
    if (images.size() == 1) exposure = percentile_exposure(images[0], 1.5);
    const std::string name = "airlight_" + v.name;
    if (Status s = write_image(out(name + ".exr"), images.back()); !s) return s;
    if (Status s = write_image(out(name + ".png"), images.back(), exposure); !s) return s;
    std::snprintf(text, sizeof text, "GPU %.1f ms", seconds * 1e3);
    std::string result = text;
    if (images.size() > 1) {
      std::snprintf(text, sizeof text, "; vs static: rel. L2 %.2e",
                    compare_images(images.back(), images[0]).relative_l2);
      result += text;
    }
    end_row(log, rows, {"render " + v.name + " (volume)", name + ".png", size, result});
  }
  MarchOptions march;
  march.samples = 128;
  march.interleave = 2;
  Result<std::unique_ptr<GlMarcher>> marcher =
      GlMarcher::create(scene, in.shadow.images(), in.shadow.sources(), march);
  if (!marcher) return marcher.error();
  log.begin("render raymarch");
  double seconds = 0;
  const Image marched = (*marcher)->render(&seconds);
  if (Status s = write_image(out("airlight_raymarch.exr"), marched); !s) return s;
  if (Status s = write_image(out("airlight_raymarch.png"), marched, exposure); !s) return s;
  std::snprintf(text, sizeof text, "GPU %.1f ms; vs static: rel. L2 %.2e", seconds * 1e3,
                compare_images(marched, images[0]).relative_l2);
  end_row(log, rows, {"render raymarch 128x2x2", "airlight_raymarch.png", size, text});

  log.begin("composite");
  // The picture: the surfaces the spot lights and the static volume's airlight in the light's
  // warm colour, the ambient light in a cool one, exposed so that the shafts keep their gradient.
  const MapSize map{in.shadow.width(), in.shadow.height()};
  SurfaceShading direct;
  direct.ambient = 0;
  SurfaceShading ambient;
  ambient.albedo = 0;
  ambient.ambient = kDemoAmbient;
  Image dark = images[0];
  std::fill(dark.values.begin(), dark.values.end(), 0.0);
  const Image lit = lit_surfaces(scene, in.shadow_window, map.width, map.height, images[0], direct);
  const Image sky = lit_surfaces(scene, in.shadow_window, map.width, map.height, dark, ambient);
  Image picture = lit;
  for (std::size_t i = 0; i < picture.values.size(); ++i) picture.values[i] += sky.values[i];
  std::array<Image, 3> rgb{lit, lit, lit};
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < lit.values.size(); ++i)
      rgb[k].values[i] = kLightColour[k] * lit.values[i] + kAmbientColour[k] * sky.values[i];
  if (Status s = write_rgb_image(out("demo.png"), rgb[0], rgb[1], rgb[2],
                                 percentile_exposure(picture, kDemoExposure));
      !s)
    return s;
  end_row(log, rows, {"picture", "demo.png", size, "lit surfaces + static volume's airlight"});
  log.begin("fog picture");
  const Result<FogPicture> fog_picture =
      write_fog_picture(scene, in.volumes[0].mesh, in.fog, in.shadow_window, map.width, map.height,
                        out("demo_fog.png"), {}, &images[0]);
  if (!fog_picture) return fog_picture.error();
  std::snprintf(text, sizeof text, "GPU %.1f ms; noise fog (right) beside demo.png's medium",
                fog_picture->fog_seconds * 1e3);
  end_row(log, rows,
          {"fog picture", "demo_fog.png", size_text(2 * scene.camera.width, scene.camera.height),
           text});
  return {};
}

}  // namespace

DemoGpu gl_demo_steps() {
  DemoGpu gpu;
  gpu.depth_passes = gl_depth_passes;
  gpu.pictures = render_pictures;
  return gpu;
}

}  // namespace lightvol

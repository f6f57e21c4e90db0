#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/depth/shadow_maps.h>
#include <lightvol/gl/context.h>
#include <lightvol/render/gl_airlight_render.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/gl_volume.h>
#include <lightvol/render/live_volume.h>

namespace lightvol {
namespace {

// Renders once, then `frames` more times, timing those.
template <class Renderer>
Image render_frames(Renderer& renderer, int frames, std::vector<double>* frame_seconds) {
  Image image = renderer.render();
  for (int i = 0; i < frames; ++i) {
    double s = 0;
    renderer.render(&s);
    frame_seconds->push_back(s);
  }
  return image;
}

// The volume method: `volume` drawn with signed additive blending.
Result<Image> render_volume(const RenderRequest& r, const RenderScene& scene, const Mesh& volume,
                            std::vector<double>* frame_seconds) {
  GlVolumeOptions vo;
  vo.density.tile = r.grid_tile;
  vo.density.slices = r.grid_slices;
  vo.density.opacity.size = r.opacity_size;
  vo.density.opacity.layers = r.opacity_layers;
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene, vo);
  if (!renderer) return renderer.error();
  (*renderer)->set_volume(volume);
  return render_frames(**renderer, r.frames, frame_seconds);
}

// The live method: the shadow maps go to the GPU as textures; each frame makes the volume from
// them there. `generation_seconds` receives request.frames timings of the generation alone.
Result<Image> render_live(const RenderRequest& r, const RenderScene& scene,
                          std::vector<double>* frame_seconds,
                          std::vector<double>* generation_seconds) {
  Result<ShadowMaps> maps = read_shadow_maps(scene.light, r.shadow_map_paths, {r.channel});
  if (!maps) return maps.error();
  std::vector<gl::TextureHandle> textures;
  std::vector<GlShadowMap> on_gpu;
  for (const DepthImage& map : maps->images()) {
    textures.push_back(upload_shadow_map(scene.light, map));
    on_gpu.push_back({textures.back().id(), map.width, map.height});
  }
  LiveOptions live_options;
  if (r.max_error >= 0) live_options.max_error = r.max_error;
  Result<std::unique_ptr<LiveVolume>> live = LiveVolume::create(scene.light, on_gpu, live_options);
  if (!live) return live.error();
  Result<std::unique_ptr<GlVolumeRenderer>> renderer = GlVolumeRenderer::create(scene);
  if (!renderer) return renderer.error();
  if (Status s = (*renderer)->set_volume(**live); !s) return s.error();
  Image image = render_frames(**renderer, r.frames, frame_seconds);
  for (int i = 0; i < r.frames; ++i) {
    const auto start = std::chrono::steady_clock::now();
    (*live)->generate();
    gl::glFinish();
    generation_seconds->push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return image;
}

// Ray marching or the radial blur (which needs no shadow map).
Result<Image> render_marcher(const RenderRequest& r, const RenderScene& scene,
                             std::vector<double>* frame_seconds) {
  ShadowMaps maps;
  if (!r.shadow_map_paths.empty()) {
    Result<ShadowMaps> read = read_shadow_maps(scene.light, r.shadow_map_paths, {r.channel});
    if (!read) return read.error();
    maps = std::move(*read);
  }
  MarchOptions mo;
  mo.samples = r.samples;
  mo.interleave = r.interleave;
  mo.method = r.method == RenderMethod::radial ? MarchMethod::radial : MarchMethod::raymarch;
  mo.opacity.size = r.opacity_size;
  mo.opacity.layers = r.opacity_layers;
  Result<std::unique_ptr<GlMarcher>> marcher =
      r.shadow_map_paths.empty() ? GlMarcher::create(scene, {}, {}, mo)
                                 : GlMarcher::create(scene, maps.images(), maps.sources(), mo);
  if (!marcher) return marcher.error();
  return render_frames(**marcher, r.frames, frame_seconds);
}

}  // namespace

Result<AirlightRender> render_airlight(const RenderRequest& r, const RenderScene& scene,
                                       const Mesh& volume, StageLog& log) {
  if (r.method == RenderMethod::reference) return render_airlight_reference(scene, volume, log);
  Result<std::unique_ptr<gl::Context>> context = gl::Context::create();
  if (!context) return context.error();
  AirlightRender render;
  render.renderer = (*context)->renderer();
  log.begin(std::string("rendering ") + to_string(r.method) + " on " + render.renderer);
  Result<Image> image =
      r.method == RenderMethod::volume ? render_volume(r, scene, volume, &render.frame_seconds)
      : r.method == RenderMethod::live
          ? render_live(r, scene, &render.frame_seconds, &render.generation_seconds)
          : render_marcher(r, scene, &render.frame_seconds);
  if (!image) return image.error();
  render.image = std::move(*image);
  log.end();
  return render;
}

}  // namespace lightvol

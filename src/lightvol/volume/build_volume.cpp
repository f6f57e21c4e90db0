#include <utility>

#include <lightvol/core/check.h>
#include <lightvol/volume/build_volume.h>
#include <lightvol/volume/omni_adaptive.h>
#include <lightvol/volume/omni_volume.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

Result<Mesh> build_volume(const Light& light, const ShadowMaps& maps,
                          const BuildVolumeOptions& options, AdaptiveReport* report, Mesh storage) {
  LV_CHECK(maps.omni == (light.type == LightType::omni));
  VolumeOptions volume;
  volume.space = options.space;
  volume.light_source = options.light_source;
  return options.grid == VolumeGrid::adaptive
             ? (maps.omni
                    ? build_adaptive_omni_volume(light, maps.cube, volume, options.adaptive, report)
                    : build_adaptive_volume(light, maps.image, volume, options.adaptive,
                                            maps.source, report))
             : (maps.omni ? build_omni_volume(light, maps.cube, volume)
                          : build_static_volume(light, maps.image, volume, maps.source,
                                                std::move(storage)));
}

}  // namespace lightvol

// One entry point for every light volume: static or adaptive tessellation, of one depth image
// (spot, directional) or of six cube faces (omni). The builders it dispatches to are
// static_volume.h, omni_volume.h, adaptive_volume.h and omni_adaptive.h.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/light/light.h>
#include <lightvol/volume/adaptive_volume.h>

namespace lightvol {

enum class VolumeGrid {
  static_grid,  // one vertex per texel (build_static_volume, build_omni_volume)
  adaptive,     // a tessellation under a bound (build_adaptive_volume, build_adaptive_omni_volume;
                // AdaptiveOptions::tessellation chooses collapse or quadtree)
};

struct BuildVolumeOptions {
  Space space = Space::world;  // frame of the output: world, or the light's eye space
  VolumeGrid grid = VolumeGrid::static_grid;
  AdaptiveOptions adaptive;  // with VolumeGrid::adaptive: criterion, bound, tessellation
  std::string light_source = "the light";  // names the light's file in float32 refusals
};

// The closed light volume of `light` over `maps` (read_shadow_maps): closed, edge-manifold,
// oriented outward, star-shaped from the light. `maps` must match the light (six faces for an omni
// light, one image otherwise). `report` (optional) receives an adaptive build's counts, reached
// error and stage times; a static build leaves it untouched. Errors name the map's source and the
// pixel (a radial depth no ray reaches), or the face (unequal omni faces); a valid light whose
// volume float32 cannot hold is refused with check_representable's Error, naming
// `options.light_source` and its keys.
// `storage` (optional): a static spot or directional build's buffers, made in advance
// (reserve_static_volume, volume/static_volume.h); other builds drop it.
Result<Mesh> build_volume(const Light& light, const ShadowMaps& maps,
                          const BuildVolumeOptions& options, AdaptiveReport* report = nullptr,
                          Mesh storage = {});

}  // namespace lightvol

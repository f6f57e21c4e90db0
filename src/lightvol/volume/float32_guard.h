// The float32 guard: whether a light volume, stored as float32 coordinates, still is the volume
// its checks and renderers need. Every builder of volume/ runs it on what it returns.
#pragma once

#include <string>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/light/light.h>

namespace lightvol {

// Whether `mesh`, a volume of `light` built in `space`, holds in float32 as it is: every
// coordinate finite and below 1e18 in magnitude (so that the products the checks and renderers
// form stay finite), the volume at least 1e-12 across (so that they do not underflow), no face
// collapsed to zero area by float32 rounding or turned towards the light (judged as the proof from
// the light of check_volume_linear judges it, in the volume's frame and with its tolerance: eight
// float ulps of the largest coordinate), and float steps at most a sixteenth of a texel's spacing
// across the light's rays (point lights: the angle a step subtends at the vertex nearest the light
// against a texel's angle; directional: against a texel's width in the ortho extents). That
// refuses a spot far from the origin or a needle of a frustum, but not a thin, wide box. Lights
// whose volumes cannot be represented are valid lights: the Error says which keys of
// `light_source` are to blame and what to do (far from the origin: VolumeOptions::space =
// Space::light; a frustum too thin, too large, or with far/near beyond what the precision holds:
// the keys to change). Every public builder runs it on the volume it returns (build_static_volume,
// build_omni_volume, build_adaptive_volume, build_adaptive_omni_volume, and so build_volume),
// StaticVolumeStream on the volume it streams (the same verdict and message); it never writes NaN.
// Two parallel passes: the vertices, then the faces.
Status check_representable(const Mesh& mesh, const Light& light, Space space,
                           const std::string& light_source);

}  // namespace lightvol

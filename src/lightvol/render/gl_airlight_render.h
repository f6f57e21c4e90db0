// `lightvol render`'s methods on the GPU (render/airlight_render.h), in lightvol::gl.
#pragma once

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/core/stages.h>
#include <lightvol/render/airlight_render.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// The airlight of `scene` by request.method: reference on the CPU (render_airlight_reference);
// else in an OpenGL context of its own, volume (GlVolumeRenderer of `volume`, the density grid's
// settings of `request` for a medium of varying density), live (the shadow maps uploaded, a
// LiveVolume made from them each frame: the static one, or the adaptive one at
// request.max_error), raymarch and radial (GlMarcher, with the shadow maps when given). The first
// frame is the image; request.frames more are timed. The render is timed in `log`. Errors: the
// shadow maps' reads, the context's and the renderers' creation.
Result<AirlightRender> render_airlight(const RenderRequest& request, const RenderScene& scene,
                                       const Mesh& volume, StageLog& log);

}  // namespace lightvol

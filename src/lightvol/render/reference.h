// The CPU reference for `lightvol render`: the exact signed airlight sum of a light volume.
#pragma once

#include <lightvol/core/mesh.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// For every pixel, intersects its ray with every triangle of `volume` (world space, closed,
// oriented outward) through a BVH and sums Σ sₙ·La(0, tₙ) in double precision: sₙ = +1 where the
// ray leaves the volume, −1 where it enters, tₙ clamped to the pixel's surface distance. Hits with
// t ≤ 0 (behind the eye) are ignored, as they contribute La(0, 0) = 0. Rows run in parallel (TBB).
// A medium of varying density integrates the same lit intervals by quadrature instead
// (airlight/heterogeneous.h), with panels of a quarter of the density's finest wavelength.
// With `stride` > 1 only the pixel at the centre of each stride × stride block is computed (the
// others stay 0): a sampled reference for slow media at large sizes.
Image render_reference(const Mesh& volume, const RenderScene& scene, int stride = 1);

}  // namespace lightvol

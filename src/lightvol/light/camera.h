// Cameras: a light description plus an image size (docs/design.md §2), the rays through their
// pixels, and the distances a camera depth image gives along them. What `lightvol render` and
// `lightvol shadowmap --camera` read.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <lightvol/core/float_buffer.h>
#include <lightvol/core/math.h>
#include <lightvol/core/result.h>
#include <lightvol/light/light.h>

namespace lightvol {

// A camera is a light description (docs/design.md §2, "type" defaults to "spot"; a directional type
// gives an orthographic camera) plus the image size. Its "depth" key is the encoding of the camera
// depth image that `lightvol render --depth` reads.
struct Camera {
  Light view;  // position, direction, projection, near/far, depth encoding, flip_y
  int width = 0;
  int height = 0;
};

// Errors name `source` and the key: missing or non-integer "width"/"height" (1..16384), omni
// cameras, and everything parse_light rejects.
Result<Camera> parse_camera(std::string_view json_text, const std::string& source);
Result<Camera> load_camera(const std::string& path);

// A world-space ray through the centre of pixel (col, row) (first row = top unless flip_y).
struct Ray {
  Vec3d origin;     // perspective: the eye; orthographic: the pixel's point on the near plane
  Vec3d direction;  // unit
};
Ray pixel_ray(const Camera& camera, int col, int row);

// Distance along each pixel's ray to the visible surface, from the camera's depth image (its size
// must be the camera's). Depths at or beyond the far plane ("nothing hit") give +infinity. The
// result is row-major, first row first. Errors name `source` and the size mismatch.
Result<std::vector<double>> surface_distances(const Camera& camera, const FloatBuffer& depth,
                                              int width, int height, const std::string& source);

}  // namespace lightvol

// What every airlight renderer of `lightvol render` takes: a camera, the visible surface's
// distance per pixel, a light and a medium. Images are row-major, first row = top.
#pragma once

#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>

namespace lightvol {

struct RenderScene {
  Camera camera;
  std::vector<double> surface;  // per pixel: distance along the pixel ray to the visible surface
                                // (+infinity where nothing was hit); see surface_distances()
  Light light;
  Medium medium;
};

// A float image with one channel, in linear radiometric units (the airlight).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<double> values;

  double at(int col, int row) const {
    return values[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + col];
  }
};

// Comparison of an image against a reference of the same size.
struct ImageDifference {
  double relative_l2 = 0;  // ‖a − ref‖₂ / ‖ref‖₂ (the absolute L2 when the reference is zero)
  double max_abs = 0;  // max |a − ref|
  double psnr_db = 0;  // 20 log10(max |ref| / RMSE); +infinity for identical images
};
ImageDifference compare_images(const Image& image, const Image& reference);

}  // namespace lightvol

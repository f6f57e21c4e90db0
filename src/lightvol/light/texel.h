// Texels: where a texel (or a camera's pixel) is sampled, and the error for a depth its ray never
// reaches. Texel (col, row) is sampled at its centre (see light.h's frames).
#pragma once

#include <string>

#include <lightvol/core/result.h>

namespace lightvol {

// NDC x of the centre of column `col` of an image `width` texels (or pixels) wide: 2(col + ½)/W
// − 1.
inline double texel_ndc_x(int col, int width) { return 2.0 * (col + 0.5) / width - 1.0; }
// NDC y of the centre of row `row` of an image `height` rows high: the first row is at the top
// (y = +1 side) unless `flip_y`: −(2(row + ½)/H − 1), or +(2(row + ½)/H − 1) with flip_y.
inline double texel_ndc_y(int row, int height, bool flip_y) {
  const double y_down = 2.0 * (row + 0.5) / height - 1.0;
  return flip_y ? y_down : -y_down;
}

// The Error for a radial depth that its texel's parallel ray never reaches (Unprojector::point
// returned false), naming `source` and the pixel (column, row as stored).
Error unreachable_radial_depth(const std::string& source, int col, int row, double depth);

}  // namespace lightvol

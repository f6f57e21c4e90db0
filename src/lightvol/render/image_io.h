// Airlight images on disk: .exr (and any float format OpenImageIO writes) keeps linear floats;
// .png is tone-mapped for people to look at.
#pragma once

#include <string>

#include <lightvol/core/result.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// Writes `image` atomically. Float formats (.exr, .tif, .pfm, .hdr) store the linear values in R, G
// and B. .png (and other 8-bit formats) stores sRGB after a Reinhard tone map x/(1+x) of the values
// scaled so that the 99.5th percentile maps to 4 (`exposure` > 0 replaces that scale); negative
// values show as black. Errors name the file.
Status write_image(const std::string& path, const Image& image, double exposure = 0);

// Reads the first channel of an image as linear floats (8-bit images are not airlight: rejected).
Result<Image> read_image(const std::string& path);

}  // namespace lightvol

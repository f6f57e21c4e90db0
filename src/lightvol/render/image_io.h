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

// Writes a colour picture from three images of one size (red, green, blue) as write_image writes
// one: float formats keep the linear values; 8-bit formats scale each by `exposure`, tone-map it
// x/(1+x) and store it as sRGB (so a bright colour goes toward white, as on film).
Status write_rgb_image(const std::string& path, const Image& red, const Image& green,
                       const Image& blue, double exposure);

// Reads the first channel of an image as linear floats (8-bit images are not airlight: rejected).
Result<Image> read_image(const std::string& path);

}  // namespace lightvol

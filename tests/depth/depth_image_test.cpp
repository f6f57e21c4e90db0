#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <lightvol/depth/depth_image.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

DepthImage ramp(int w, int h) {
  return test::make_depth(w, h,
                          [](int c, int r) { return 0.01f * static_cast<float>(c + 10 * r); });
}

// Writes an image with the given channels through OpenImageIO directly.
void write_raw(const std::string& path, int w, int h, const std::vector<std::string>& names,
               OIIO::TypeDesc format, const std::vector<float>& pixels) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out);
  OIIO::ImageSpec spec(w, h, static_cast<int>(names.size()), format);
  spec.channelnames = names;
  ASSERT_TRUE(out->open(path, spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
  ASSERT_TRUE(out->close());
}

void expect_error(const Result<DepthImage>& r, const std::string& needle) {
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
}

TEST(DepthImage, FloatFormatsRoundTripExactly) {
  test::TempDir dir;
  const DepthImage in = ramp(7, 5);
  for (const char* name : {"d.exr", "d.tif", "d.pfm"}) {
    ASSERT_TRUE(write_depth_image(dir.file(name), in).ok()) << name;
    Result<DepthImage> out = read_depth_image(dir.file(name));
    ASSERT_TRUE(out.ok()) << out.error().message;
    EXPECT_EQ(out->width, 7);
    EXPECT_EQ(out->height, 5);
    EXPECT_EQ(out->values, in.values) << name;
  }
}

TEST(DepthImage, PeekedSizeIsTheReadImagesForEveryExrAndNothingElse) {
  // lightvol's own look at an EXR header (the static build's buffers are made from it while the
  // map is read): the size the read finds, whatever the data window's origin, compression or
  // tiling; nothing for other formats, truncated headers and junk.
  test::TempDir dir;
  ASSERT_TRUE(write_depth_image(dir.file("d.exr"), ramp(7, 5)).ok());
  const std::optional<std::array<int, 2>> peeked = peek_image_size(dir.file("d.exr"));
  ASSERT_TRUE(peeked.has_value());
  EXPECT_EQ((*peeked)[0], 7);
  EXPECT_EQ((*peeked)[1], 5);
  {
    auto out = OIIO::ImageOutput::create(dir.file("w.exr"));
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(33, 17, 1, OIIO::TypeDesc::FLOAT);
    spec.x = spec.full_x = -4, spec.y = spec.full_y = 9;  // windows away from the origin
    spec.tile_width = spec.tile_height = 16;
    spec.attribute("compression", "piz");
    ASSERT_TRUE(out->open(dir.file("w.exr"), spec));
    const std::vector<float> pixels(33 * 17, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()));
    ASSERT_TRUE(out->close());
  }
  const Result<DepthImage> read = read_depth_image(dir.file("w.exr"));
  ASSERT_TRUE(read.ok()) << read.error().message;
  const std::optional<std::array<int, 2>> window = peek_image_size(dir.file("w.exr"));
  ASSERT_TRUE(window.has_value());
  EXPECT_EQ((*window)[0], read->width);
  EXPECT_EQ((*window)[1], read->height);
  ASSERT_TRUE(write_depth_image(dir.file("d.tif"), ramp(7, 5)).ok());
  EXPECT_FALSE(peek_image_size(dir.file("d.tif")).has_value());
  EXPECT_FALSE(peek_image_size(dir.file("missing.exr")).has_value());
  // The header cut before its data window: nothing.
  std::ifstream in(dir.file("d.exr"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t window_at = bytes.find("dataWindow");
  ASSERT_NE(window_at, std::string::npos);
  std::ofstream(dir.file("cut.exr"), std::ios::binary) << bytes.substr(0, window_at + 12);
  EXPECT_FALSE(peek_image_size(dir.file("cut.exr")).has_value());
}

TEST(DepthImage, Png16IsNormalizedWindowDepth) {
  test::TempDir dir;
  const DepthImage in = test::make_depth(
      4, 3, [](int c, int r) { return static_cast<float>(c * 3 + r) / 65535.0f * 1000; });
  ASSERT_TRUE(write_depth_image(dir.file("d.png"), in).ok());
  Result<DepthImage> out = read_depth_image(dir.file("d.png"));
  ASSERT_TRUE(out.ok()) << out.error().message;
  for (std::size_t i = 0; i < in.values.size(); ++i)
    EXPECT_NEAR(out->values[i], in.values[i], 0.5 / 65535);
}

TEST(DepthImage, ChannelSelection) {
  test::TempDir dir;
  std::vector<float> px(3 * 2 * 2);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<float>(i);
  const std::string path = dir.file("rgb.exr");
  write_raw(path, 2, 2, {"R", "G", "B"}, OIIO::TypeDesc::FLOAT, px);
  expect_error(read_depth_image(path), "choose the depth channel with DepthReadOptions::channel");
  Result<DepthImage> g = read_depth_image(path, {"G"});
  ASSERT_TRUE(g.ok()) << g.error().message;
  EXPECT_EQ(g->values, (std::vector<float>{1, 4, 7, 10}));
  expect_error(read_depth_image(path, {"Q"}), "no channel named 'Q'");

  const std::string zpath = dir.file("rgbz.exr");
  std::vector<float> pz(4 * 2 * 2, 0.5f);
  write_raw(zpath, 2, 2, {"R", "G", "B", "Z"}, OIIO::TypeDesc::FLOAT, pz);
  EXPECT_TRUE(read_depth_image(zpath).ok()) << "a channel named Z is the depth";
}

TEST(DepthImage, BadPixelsNameTheFirstOne) {
  test::TempDir dir;
  for (float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.5f}) {
    DepthImage in = ramp(6, 4);
    in.values[2 * 6 + 3] = bad;
    in.values[3 * 6 + 5] = bad;
    ASSERT_TRUE(write_depth_image(dir.file("bad.exr"), in).ok());
    const Result<DepthImage> r = read_depth_image(dir.file("bad.exr"));
    expect_error(r, "pixel (3, 2)");
    expect_error(r, dir.file("bad.exr"));
  }
}

// validate_depths tests blocks of 65,536 texels in parallel: the texel it names is still the first
// in row order, whichever blocks hold bad ones, and -0 passes as 0 does.
TEST(DepthImage, ValidationNamesTheFirstBadTexelOfALargeImage) {
  const int w = 1000, h = 700;  // 11 blocks, the last one partial
  const float nan = std::numeric_limits<float>::quiet_NaN(),
              inf = std::numeric_limits<float>::infinity(),
              tiny = -std::numeric_limits<float>::denorm_min();
  DepthImage image = ramp(w, h);
  image.values[123] = -0.0f;
  EXPECT_TRUE(validate_depths(image, "m.exr").ok());
  struct Case {
    std::vector<std::pair<std::size_t, float>> bad;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{{699999, tiny}}, "m.exr: pixel (999, 699): depth is negative"},
      {{{65536 * 7 + 5, -inf}, {65536 * 3 + 1, nan}},
       "m.exr: pixel (609, 196): depth is NaN"},  // 196,609 = 65,536·3 + 1
      {{{65535, inf}, {65536, -1.0f}, {0 + 999, inf}}, "m.exr: pixel (999, 0): depth is infinite"},
      {{{65536 * 10 + 17, nan}}, "m.exr: pixel (377, 655): depth is NaN"},  // 655,377
  };
  for (const Case& c : cases) {
    DepthImage bad = image;
    for (const auto& [at, value] : c.bad) bad.values[at] = value;
    const Status s = validate_depths(bad, "m.exr");
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.error().message.rfind(c.message, 0), 0u) << s.error().message;
  }
}

TEST(DepthImage, RejectsMissingTruncatedJunkTinyAnd8Bit) {
  test::TempDir dir;
  expect_error(read_depth_image(dir.file("none.exr")), "no such file");
  expect_error(read_depth_image(dir.write("junk.exr", "this is not an image")), "junk.exr");
  expect_error(read_depth_image(dir.path()), "is a directory");

  const DepthImage big = test::make_depth(
      256, 256, [](int c, int r) { return 0.001f * static_cast<float>(c * r % 997); });
  ASSERT_TRUE(write_depth_image(dir.file("full.exr"), big).ok());
  std::string bytes;
  {
    std::ifstream in(dir.file("full.exr"), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::ofstream(dir.file("cut.exr"), std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
  expect_error(read_depth_image(dir.file("cut.exr")), "cut.exr");

  ASSERT_TRUE(write_depth_image(dir.file("tiny.exr"), test::constant_depth(1, 5, 0.5f)).ok());
  expect_error(read_depth_image(dir.file("tiny.exr")), "at least 2x2");

  write_raw(dir.file("eight.png"), 3, 3, {"Y"}, OIIO::TypeDesc::UINT8, std::vector<float>(9, 0.5f));
  expect_error(read_depth_image(dir.file("eight.png")), "8-bit");
}

// The plugin is chosen by the file's first bytes among the formats depth images come in, else by
// its extension among those: never OpenImageIO's try-every-plugin fallback, which hands an unknown
// file to its video, camera-raw and DICOM decoders, nor its DPX reader (1.9 GB for a 2 KB header).
TEST(DepthImage, FormatByContentThenByExtensionAmongTheVettedOnes) {
  test::TempDir dir;
  const DepthImage in = ramp(7, 5);
  ASSERT_TRUE(write_depth_image(dir.file("d.exr"), in).ok());
  std::filesystem::copy_file(dir.file("d.exr"), dir.file("misnamed.tif"));
  std::filesystem::copy_file(dir.file("d.exr"), dir.file("depth.bin"));
  for (const char* name : {"misnamed.tif", "depth.bin"}) {
    const Result<DepthImage> back = read_depth_image(dir.file(name));
    ASSERT_TRUE(back.ok()) << back.error().message;
    EXPECT_EQ(back->values, in.values) << name;
  }
  write_raw(dir.file("eight.bmp"), 3, 3, {"R", "G", "B"}, OIIO::TypeDesc::UINT8,
            std::vector<float>(27, 0.5f));
  const std::string refused =
      ": not an image lightvol reads depths from (EXR, TIFF, PNG, PFM, PGM, HDR or "
      "ZFile, by its first bytes or its extension)";
  for (const std::string name :
       {"eight.bmp", "clip.mp4", "scan.dcm", "any.null", "noextension", "film.dpx"}) {
    if (!std::filesystem::exists(dir.file(name))) dir.write(name, std::string(64, '\x01'));
    const Result<DepthImage> r = read_depth_image(dir.file(name));
    ASSERT_FALSE(r.ok()) << name;
    EXPECT_EQ(r.error().message, dir.file(name) + refused);
  }
  // A known extension on junk: that plugin alone says what is wrong.
  dir.write("junk.hdr", std::string(64, '\x01'));
  expect_error(read_depth_image(dir.file("junk.hdr")), "junk.hdr: cannot read image: ");
}

// Before: an EXR whose data window was a 32x32 crop of a 64x64 display window was read as the
// whole view (oiiotool full.exr --crop 32x32+16+16 -o crop.exr), silently wrong geometry.
TEST(DepthImage, DataWindowOtherThanTheDisplayWindowIsRefused) {
  test::TempDir dir;
  const std::string path = dir.file("crop.exr");
  {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(32, 32, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"Z"};
    spec.x = spec.y = 16;
    spec.full_x = spec.full_y = 0;
    spec.full_width = spec.full_height = 64;
    ASSERT_TRUE(out->open(path, spec));
    const std::vector<float> px(32 * 32, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->close());
  }
  expect_error(read_depth_image(path),
               "crop.exr: its data window (32x32 at (16, 16)) is not its display window (64x64 "
               "at (0, 0))");
}

// Before: the scale's magnitude multiplied the depths undocumented, and scale 0 made every depth
// 0. Now: the sign is the byte order, the magnitude multiplies (documented), 0 is refused.
TEST(DepthImage, PfmScaleMultipliesAndZeroIsRefused) {
  test::TempDir dir;
  const auto pfm = [&](const std::string& name, const std::string& scale) {
    std::string bytes = "Pf\n2 2\n" + scale + "\n";
    const float v[4] = {0.25f, 0.5f, 0.75f, 1.0f};
    bytes.append(reinterpret_cast<const char*>(v), sizeof v);
    return dir.write(name, bytes);
  };
  const Result<DepthImage> one = read_depth_image(pfm("one.pfm", "-1.0"));
  ASSERT_TRUE(one.ok()) << one.error().message;
  EXPECT_EQ(one->values, (std::vector<float>{0.75f, 1.0f, 0.25f, 0.5f}));  // bottom row first
  const Result<DepthImage> half = read_depth_image(pfm("half.pfm", "-0.5"));
  ASSERT_TRUE(half.ok()) << half.error().message;
  EXPECT_EQ(half->values, (std::vector<float>{0.375f, 0.5f, 0.125f, 0.25f}));
  for (const char* bad : {"0", "-0.0", "nan", "-inf", "x"})
    expect_error(read_depth_image(pfm("bad.pfm", bad)), "is not a finite non-zero number");
}

// Before: an image whose only channel is alpha was read as depth.
TEST(DepthImage, AlphaOnlyImageIsRefusedUnlessNamed) {
  test::TempDir dir;
  const std::string path = dir.file("alpha.exr");
  {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(2, 2, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"A"};
    spec.alpha_channel = 0;
    ASSERT_TRUE(out->open(path, spec));
    const std::vector<float> px(4, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->close());
  }
  // The library names its own parameter (the CLI says --channel).
  expect_error(read_depth_image(path),
               "alpha.exr: its only channel, 'A', is alpha (coverage), not depth; to read it as "
               "depth anyway, name it with DepthReadOptions::channel A");
  DepthReadOptions named;
  named.channel = "A";
  const Result<DepthImage> read = read_depth_image(path, named);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(read->values, std::vector<float>(4, 0.5f));
}

}  // namespace
}  // namespace lightvol

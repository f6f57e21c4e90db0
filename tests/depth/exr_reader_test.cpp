// lightvol-exr (depth/detail/exr_codec.h) against lightvol-image's OpenImageIO reader: for every
// EXR the repository holds, and EXRs written here (half and float, scanlines and tiles, each
// lossless compression, odd sizes, special values; and files it must decline), the fast reader
// either declines or gives the same header and the same floats, bit for bit.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <lightvol/core/detail/image_helper.h>
#include <lightvol/depth/detail/exr_codec.h>
#include <lightvol/depth/detail/image_codec.h>
#include <lightvol/depth/detail/image_file.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr const char* kDeclined = "DECLINED-BY-TEST";

// Stands in for lightvol-image when only the fast reader is to answer: refuses every read.
bool decline_all(ChildOutput& channel, int /*threads*/) {
  detail::ImageRequest request{};
  std::string text;
  if (!channel.read_value(&request)) return false;
  for (int i = 0; i < 4; ++i)
    if (!channel.read_string(&text)) return false;
  channel.refuse(Error{kDeclined});
  return true;
}

// The fast reader on three threads (the programs use every core; the forked child one).
bool exr_three_threads(ChildOutput& channel, int /*threads*/) {
  return detail::serve_exr_request(channel, 3);
}

struct Read {
  bool ok = false;
  bool declined = false;
  std::string error;
  detail::ImageHeader header;
  std::vector<float> values;
};

Read read_with(const std::string& path, detail::ImageServer image, detail::ImageServer exr) {
  detail::set_in_process_image_server(image);
  detail::set_in_process_exr_server(exr);
  Read out;
  const auto seen = [&](const detail::ImageHeader& header) {
    out.header = header;
    return Status{};
  };
  const auto select = [&](const detail::ImageHeader& header) -> Result<int> {
    out.header = header;
    return 0;
  };
  const Result<ImageChannel> read =
      detail::read_image_channel(path, seen, select, "cannot read pixels");
  detail::set_in_process_image_server(nullptr);
  detail::set_in_process_exr_server(nullptr);
  out.ok = read.ok();
  if (!read) {
    out.error = read.error().message;
    out.declined = out.error.find(kDeclined) != std::string::npos;
  } else {
    out.values.assign(read->values.data(), read->values.data() + read->values.size());
  }
  return out;
}

// The fast reader's answer for `path` against OpenImageIO's; true when the fast reader took it.
bool same_as_openimageio(const std::string& path) {
  const Read fast = read_with(path, &decline_all, &exr_three_threads);
  const Read oiio = read_with(path, &detail::serve_image_request, nullptr);
  if (fast.declined) return false;
  if (!fast.ok) {  // lightvol's own checks, before either reader
    EXPECT_EQ(fast.error, oiio.error) << path;
    return false;
  }
  EXPECT_TRUE(oiio.ok) << path << ": the fast reader read what OpenImageIO refuses: " << oiio.error;
  if (!oiio.ok) return true;
  EXPECT_EQ(fast.header.width, oiio.header.width) << path;
  EXPECT_EQ(fast.header.height, oiio.header.height) << path;
  EXPECT_EQ(fast.header.alpha_channel, oiio.header.alpha_channel) << path;
  EXPECT_EQ(fast.header.eight_bit, oiio.header.eight_bit) << path;
  EXPECT_EQ(fast.header.names, oiio.header.names) << path;
  EXPECT_EQ(fast.header.channel_eight_bit, oiio.header.channel_eight_bit) << path;
  EXPECT_EQ(fast.values.size(), oiio.values.size()) << path;
  if (fast.values.size() == oiio.values.size()) {
    EXPECT_EQ(
        std::memcmp(fast.values.data(), oiio.values.data(), fast.values.size() * sizeof(float)), 0)
        << path << ": other floats";
  }
  return true;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

bool is_exr(const std::string& bytes) { return bytes.rfind("\x76\x2f\x31\x01", 0) == 0; }

// Depth-like values with the special ones a reader could convert differently.
std::vector<float> values_for(int w, int h, int channels) {
  std::vector<float> v(static_cast<std::size_t>(w) * h * channels);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = 0.5f + 0.37f * static_cast<float>(i % 997);
  const float special[] = {0.0f,
                           -0.0f,
                           -3.25f,
                           std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(),
                           std::numeric_limits<float>::quiet_NaN(),
                           6.0e-8f,   // a half denormal
                           1.0e-40f,  // a float denormal
                           70000.0f,  // beyond half's range
                           65504.0f};
  for (std::size_t i = 0; i < std::size(special) && i < v.size(); ++i)
    v[i * 3 % v.size()] = special[i];
  return v;
}

struct Written {
  std::string path;
  bool plain;  // the fast reader must take it
};

Written write_exr(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type,
                  const std::string& compression, int tile, bool plain,
                  const std::string& name = "Z", int x = 0, int y = 0, bool mip = false) {
  // No OpenEXR or OpenImageIO worker threads in this process, which forks the readers' children.
  static const bool single = OIIO::attribute("exr_threads", -1) && OIIO::attribute("threads", 1);
  (void)single;
  OIIO::ImageSpec spec(w, h, channels, type);
  spec.x = x;
  spec.y = y;
  if (channels == 1) spec.channelnames = {name};
  spec.attribute("compression", compression);
  if (mip) spec.attribute("openexr:levelmode", 1);
  if (tile > 0) {
    spec.tile_width = tile;
    spec.tile_height = tile + 3;
  }
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out) << path;
  if (!out) return {path, false};
  out->threads(1);
  const std::vector<float> v = values_for(w, h, channels);
  const bool ok = mip ? out->open(path, spec, OIIO::ImageOutput::Create) && out->supports("mipmap")
                      : out->open(path, spec);
  EXPECT_TRUE(ok) << path << out->geterror();
  if (mip) {
    // Level 0, then a half-size level.
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
    OIIO::ImageSpec level = spec;
    level.width = level.full_width = w / 2;
    level.height = level.full_height = h / 2;
    EXPECT_TRUE(out->open(path, level, OIIO::ImageOutput::AppendMIPLevel)) << out->geterror();
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
  } else {
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data())) << out->geterror();
  }
  EXPECT_TRUE(out->close());
  return {path, plain};
}

TEST(ExrReader, EveryEXRTheRepositoryHoldsReadsAsOpenImageIOReadsIt) {
  test::TempDir dir;
  int files = 0, taken = 0;
  const std::filesystem::path root(LIGHTVOL_SOURCE_DIR);
  for (const char* under : {"data", "tests"})
    for (const auto& entry : std::filesystem::recursive_directory_iterator(root / under)) {
      if (!entry.is_regular_file() || entry.file_size() > (64u << 20)) continue;
      const std::string bytes = bytes_of(entry.path().string());
      std::string path;
      if (is_exr(bytes)) {
        path = entry.path().string();
      } else if (bytes.size() > 1 && is_exr(bytes.substr(1)) &&
                 entry.path().string().find("fuzz") != std::string::npos) {
        // A fuzz input: its first byte picks the extension, the rest is the file.
        path = dir.file("corpus" + std::to_string(files) + ".exr");
        write_bytes(path, bytes.substr(1));
      } else {
        continue;
      }
      ++files;
      taken += same_as_openimageio(path) ? 1 : 0;
    }
  EXPECT_GE(files, 8);  // data/synthetic_256.exr and the fuzz corpus's EXRs
  EXPECT_GE(taken, 1);  // at least data/synthetic_256.exr is plain
}

TEST(ExrReader, WrittenEXRsAndTheirDamagedCopiesReadAsOpenImageIOReadsThem) {
  test::TempDir dir;
  std::vector<Written> files;
  int n = 0;
  const auto name = [&] { return dir.file("w" + std::to_string(n++) + ".exr"); };
  for (const OIIO::TypeDesc type : {OIIO::TypeDesc::HALF, OIIO::TypeDesc::FLOAT})
    for (const char* compression : {"none", "rle", "zips", "zip", "piz"})
      for (const int tile : {0, 16})
        for (const auto& size : {std::array<int, 2>{2, 2}, std::array<int, 2>{3, 5},
                                 std::array<int, 2>{37, 19}, std::array<int, 2>{130, 67}})
          files.push_back(write_exr(name(), size[0], size[1], 1, type, compression, tile, true));
  // Declined: lossy compressions, more channels, UINT, an alpha name, a data window elsewhere,
  // (MIP-mapped files are declined too; OpenImageIO here writes none.)
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::HALF, "pxr24", 0, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::HALF, "b44", 0, false));
  files.push_back(write_exr(name(), 33, 20, 3, OIIO::TypeDesc::FLOAT, "zip", 0, false));
  files.push_back(write_exr(name(), 33, 20, 2, OIIO::TypeDesc::HALF, "none", 16, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::UINT32, "zip", 0, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::FLOAT, "zip", 0, false, "A"));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::FLOAT, "zip", 0, false, "Z", 4, 2));
  for (const Written& file : files) {
    const bool taken = same_as_openimageio(file.path);
    EXPECT_EQ(taken, file.plain) << file.path;
    // Damaged copies (of every fourth file: each read forks two children): cut short, and a byte
    // changed in the pixels.
    if (n % 4 != 0) continue;
    const std::string bytes = bytes_of(file.path);
    for (const std::size_t keep : {bytes.size() / 2, bytes.size() - 1, bytes.size() - 9}) {
      const std::string cut = dir.file("cut" + std::to_string(n++) + ".exr");
      write_bytes(cut, bytes.substr(0, keep));
      same_as_openimageio(cut);
    }
    std::string changed = bytes;
    changed[changed.size() - 5] = static_cast<char>(changed[changed.size() - 5] ^ 0x5a);
    const std::string flipped = dir.file("flip" + std::to_string(n++) + ".exr");
    write_bytes(flipped, changed);
    same_as_openimageio(flipped);
  }
}

// The programs: a plain EXR is read by lightvol-exr (the fake lightvol-image, which crashes on a
// path naming "crash", is never asked), any other by lightvol-image; without lightvol-exr, every
// EXR by lightvol-image.
class Helpers {
 public:
  Helpers(const char* image, const char* exr) {
    detail::close_idle_image_servers();
    if (image != nullptr) ::setenv("LIGHTVOL_IMAGE_HELPER", image, 1);
    if (exr != nullptr) ::setenv("LIGHTVOL_EXR_HELPER", exr, 1);
  }
  ~Helpers() {
    ::unsetenv("LIGHTVOL_IMAGE_HELPER");
    ::unsetenv("LIGHTVOL_EXR_HELPER");
    detail::close_idle_image_servers();
  }
};

Result<ImageChannel> read_program(const std::string& path) {
  return detail::read_image_channel(
      path, [](const detail::ImageHeader&) { return Status{}; },
      [](const detail::ImageHeader&) -> Result<int> { return 0; }, "cannot read pixels");
}

TEST(ExrReader, ThePlainFileGoesToLightvolExrAndAnyOtherToLightvolImage) {
  test::TempDir dir;
  const std::string plain = dir.file("crash_plain.exr"), other = dir.file("crash_rgb.exr"),
                    fine = dir.file("fine.exr");
  write_exr(plain, 40, 30, 1, OIIO::TypeDesc::HALF, "zip", 0, true);
  write_exr(other, 40, 30, 3, OIIO::TypeDesc::HALF, "zip", 0, false);
  write_exr(fine, 40, 30, 1, OIIO::TypeDesc::FLOAT, "piz", 16, true);
  const Read expected = read_with(plain, &detail::serve_image_request, nullptr);
  ASSERT_TRUE(expected.ok) << expected.error;
  {
    const Helpers helpers(LIGHTVOL_FAKE_IMAGE_HELPER, LIGHTVOL_EXR_HELPER_PROGRAM);
    const Result<ImageChannel> read = read_program(plain);
    ASSERT_TRUE(read.ok()) << read.error().message;
    ASSERT_EQ(read->values.size(), expected.values.size());
    EXPECT_EQ(std::memcmp(read->values.data(), expected.values.data(),
                          expected.values.size() * sizeof(float)),
              0);
    // Declined, then the (fake) lightvol-image, which crashes on it.
    const Result<ImageChannel> declined = read_program(other);
    ASSERT_FALSE(declined.ok());
    EXPECT_NE(declined.error().message.find("OpenImageIO's reader"), std::string::npos)
        << declined.error().message;
  }
  {
    // lightvol-exr missing: lightvol-image reads the plain file too.
    const Helpers helpers(LIGHTVOL_FAKE_IMAGE_HELPER, "/nonexistent/lightvol-exr");
    EXPECT_FALSE(read_program(plain).ok());
  }
  {
    const Helpers helpers(nullptr, "/nonexistent/lightvol-exr");
    EXPECT_TRUE(read_program(fine).ok());
  }
}

}  // namespace
}  // namespace lightvol

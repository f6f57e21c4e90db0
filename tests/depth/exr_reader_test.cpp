// lightvol-exr (depth/detail/exr_codec.h) against lightvol-image's OpenImageIO reader: for every
// EXR the repository holds, and EXRs written here (half and float, scanlines and tiles, each
// lossless compression, odd sizes, special values; and files it must decline), the fast reader
// either declines or gives the same header and the same floats, bit for bit.
#include <unistd.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
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
  // ZIP (16 scanlines a chunk) and ZIPS (one) at sizes whose chunks are longer than libdeflate's
  // and the predictor's blocks, the last chunk of the ZIP files shorter than the rest (77 = 4 x 16
  // + 13, 1000 = 62 x 16 + 8); each with its compressed data damaged at a few places below.
  const std::size_t first_zip = files.size();
  for (const OIIO::TypeDesc type : {OIIO::TypeDesc::HALF, OIIO::TypeDesc::FLOAT})
    for (const char* compression : {"zips", "zip"})
      for (const int tile : {0, 64})
        for (const auto& size : {std::array<int, 2>{517, 77}, std::array<int, 2>{1000, 33},
                                 std::array<int, 2>{61, 1000}})
          files.push_back(write_exr(name(), size[0], size[1], 1, type, compression, tile, true));
  const std::size_t end_zip = files.size();
  // Declined: lossy compressions, more channels, UINT, an alpha name, a data window elsewhere,
  // (MIP-mapped files are declined too; OpenImageIO here writes none.)
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::HALF, "pxr24", 0, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::HALF, "b44", 0, false));
  files.push_back(write_exr(name(), 33, 20, 3, OIIO::TypeDesc::FLOAT, "zip", 0, false));
  files.push_back(write_exr(name(), 33, 20, 2, OIIO::TypeDesc::HALF, "none", 16, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::UINT32, "zip", 0, false));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::FLOAT, "zip", 0, false, "A"));
  files.push_back(write_exr(name(), 33, 20, 1, OIIO::TypeDesc::FLOAT, "zip", 0, false, "Z", 4, 2));
  for (std::size_t f = 0; f < files.size(); ++f) {
    const Written& file = files[f];
    const bool taken = same_as_openimageio(file.path);
    EXPECT_EQ(taken, file.plain) << file.path;
    if (f >= first_zip && f < end_zip) {
      // A byte of the chunks' data changed, at a third, a half and nine tenths of the file (its
      // header and chunk table are in the first few hundred bytes; every chunk is compressed).
      const std::string bytes = bytes_of(file.path);
      for (const std::size_t tenths : {3, 5, 9}) {
        std::string changed = bytes;
        const std::size_t at = changed.size() * tenths / 10;
        changed[at] = static_cast<char>(changed[at] ^ 0x21);
        const std::string damaged = dir.file("zipflip" + std::to_string(n++) + ".exr");
        write_bytes(damaged, changed);
        same_as_openimageio(damaged);
      }
    }
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

// OpenEXRCore 3.1's ZIP routine (internal_zip.c, its portable code), the reference for
// undo_exr_zip: zlib, then the predictor, then the interleave. False where it fails.
bool reference_undo_zip(const std::string& packed, std::size_t unpacked_size, std::string* out) {
  if (packed.size() == unpacked_size) {
    *out = packed;
    return true;
  }
  std::string scratch(unpacked_size, '\0');
  uLongf size = static_cast<uLongf>(unpacked_size);
  if (uncompress(reinterpret_cast<Bytef*>(scratch.data()), &size,
                 reinterpret_cast<const Bytef*>(packed.data()),
                 static_cast<uLong>(packed.size())) != Z_OK ||
      size != unpacked_size)
    return false;
  for (std::size_t i = 1; i < unpacked_size; ++i)
    scratch[i] = static_cast<char>(static_cast<unsigned char>(scratch[i - 1]) +
                                   static_cast<unsigned char>(scratch[i]) - 128);
  out->assign(unpacked_size, '\0');
  const std::size_t half = (unpacked_size + 1) / 2;
  for (std::size_t i = 0; i < unpacked_size; ++i)
    (*out)[i] = scratch[i % 2 == 0 ? i / 2 : half + i / 2];
  return true;
}

// OpenEXR's ZIP compression of `raw` (internal_zip.c's apply_zip_impl): the halves split, the
// predictor applied, zlib at `level`; or `raw` itself.
std::string zip_compress(const std::string& raw, int level) {
  std::string split(raw.size(), '\0');
  const std::size_t half = (raw.size() + 1) / 2;
  for (std::size_t i = 0; i < raw.size(); ++i) split[i % 2 == 0 ? i / 2 : half + i / 2] = raw[i];
  for (std::size_t i = split.size(); i-- > 1;)
    split[i] = static_cast<char>(static_cast<unsigned char>(split[i]) -
                                 static_cast<unsigned char>(split[i - 1]) + 128);
  uLongf size = compressBound(static_cast<uLong>(split.size()));
  std::string packed(size, '\0');
  EXPECT_EQ(compress2(reinterpret_cast<Bytef*>(packed.data()), &size,
                      reinterpret_cast<const Bytef*>(split.data()),
                      static_cast<uLong>(split.size()), level),
            Z_OK);
  packed.resize(size);
  // Stored when it does not shrink (OpenEXR stores it only when it grows: a stream as long as the
  // chunk would then read as stored, and wrongly).
  return packed.size() >= raw.size() ? raw : packed;
}

// Whether undo_exr_zip gives what OpenEXRCore's routine gives for `packed`: the same verdict, and
// the same bytes when it succeeds.
void expect_undo_zip_as_openexr(const std::string& packed, std::size_t unpacked_size,
                                const std::string& what) {
  std::string expected;
  const bool reference = reference_undo_zip(packed, unpacked_size, &expected);
  std::string got(unpacked_size + 1, '\x5c');  // one byte more: it must stay untouched
  const bool undone = detail::undo_exr_zip(packed.data(), packed.size(), got.data(), unpacked_size);
  EXPECT_EQ(undone, reference) << what;
  EXPECT_EQ(got.back(), '\x5c') << what << ": a byte written beyond the chunk";
  got.pop_back();
  if (undone && reference) {
    EXPECT_EQ(got, expected) << what;
  }
}

TEST(ExrReader, ZipChunksUndoAsOpenEXRsOwnRoutineUndoesThem) {
#ifdef LIGHTVOL_EXPECT_LIBDEFLATE
  ASSERT_TRUE(detail::exr_zip_by_libdeflate()) << "built with libdeflate, but lightvol-exr is not";
#else
  if (!detail::exr_zip_by_libdeflate()) GTEST_SKIP() << "built without libdeflate";
#endif
  std::mt19937 random(29);
  // Sizes around the 16-byte blocks of the predictor (each half) and odd ones (the halves differ).
  for (const std::size_t size :
       {std::size_t{1}, std::size_t{2}, std::size_t{3}, std::size_t{31}, std::size_t{32},
        std::size_t{33}, std::size_t{63}, std::size_t{64}, std::size_t{65}, std::size_t{97},
        std::size_t{1000}, std::size_t{4097}, std::size_t{65536 + 3}, std::size_t{1} << 20}) {
    for (const bool smooth : {true, false}) {
      // Depth-like floats (slowly varying bytes) or random bytes below 32 (which compress less).
      std::string raw(size, '\0');
      for (std::size_t i = 0; i < size; ++i)
        raw[i] = static_cast<char>(smooth ? (i % 4 == 3 ? 0x3f : (i / 4) % 7 + (i % 4) * 11)
                                          : static_cast<int>(random() & 31u));
      const std::string what = std::to_string(size) + (smooth ? " smooth" : " random") + " bytes";
      for (const int level : {1, 6, 9}) {
        const std::string packed = zip_compress(raw, level);
        std::string got(size, '\0');
        ASSERT_TRUE(detail::undo_exr_zip(packed.data(), packed.size(), got.data(), size)) << what;
        EXPECT_EQ(got, raw) << what;
        expect_undo_zip_as_openexr(packed, size, what);
      }
      const std::string packed = zip_compress(raw, 6);
      // Another size than the stream's: an error in both.
      expect_undo_zip_as_openexr(packed, size + 1, what + ", one more expected");
      if (size > 1) expect_undo_zip_as_openexr(packed, size - 1, what + ", one fewer expected");
      // Stored: the packed size is the unpacked size.
      expect_undo_zip_as_openexr(raw, size, what + ", stored");
      // Damaged: cut short, and bytes changed across the stream (header, blocks, checksum).
      expect_undo_zip_as_openexr(packed.substr(0, packed.size() / 2), size, what + ", cut");
      expect_undo_zip_as_openexr(packed.substr(0, packed.size() - 1), size, what + ", cut");
      for (std::size_t k = 0; k < 24; ++k) {
        std::string changed = packed;
        const std::size_t at = k < 4 ? k : random() % changed.size();
        changed[at] = static_cast<char>(changed[at] ^ (1 << (random() % 8)));
        if (changed.size() == size) continue;  // would read as stored
        expect_undo_zip_as_openexr(changed, size,
                                   what + ", byte " + std::to_string(at) + " changed");
      }
    }
  }
  // Nothing at all: an error (OpenEXRCore would leave the chunk's bytes unwritten).
  std::string out(8, '\0');
  EXPECT_FALSE(detail::undo_exr_zip("", 0, out.data(), out.size()));
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

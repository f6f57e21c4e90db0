#include <openexr.h>
#include <unistd.h>

#ifndef LIGHTVOL_HAVE_LIBDEFLATE
#define LIGHTVOL_HAVE_LIBDEFLATE 0
#endif
#if LIGHTVOL_HAVE_LIBDEFLATE
#include <libdeflate.h>
#endif
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include <lightvol/core/buffer.h>
#include <lightvol/depth/detail/exr_codec.h>
#include <lightvol/depth/detail/image_file.h>

namespace lightvol::detail {
namespace {

const Error kNotMine{"not a plain EXR depth map: read it through lightvol-image"};

// Whether OpenEXRCore reported an error during this request. It reports some (a required
// attribute of the wrong type, a damaged chunk table it works around) while the call still
// succeeds; OpenImageIO queues them and fails the read, so any report at all is a refusal here.
std::atomic<bool> reported{false};

// OpenEXRCore prints its errors to stderr by default; here every error is a refusal, and the
// parent's second reader says what is wrong.
void silent(exr_const_context_t /*context*/, exr_result_t /*code*/, const char* /*message*/) {
  reported = true;
}

struct Context {
  exr_context_t handle = nullptr;
  Context() = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context() {
    if (handle != nullptr) exr_finish(&handle);
  }
};

// What the file is, when it is plain (see exr_codec.h).
struct Plain {
  int width = 0;
  int height = 0;
  bool tiled = false;
  bool half = false;
  bool zip = false;  // ZIP or ZIPS
  std::string name;
};

float half_to_float(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  std::uint32_t bits = 0;
  if (exponent == 0) {
    const float magnitude = std::ldexp(static_cast<float>(mantissa), -24);  // zero or subnormal
    std::memcpy(&bits, &magnitude, sizeof bits);
    bits |= sign;
  } else if (exponent == 31) {
    bits = sign | 0x7f800000u | (mantissa << 13);  // infinity, NaN
  } else {
    bits = sign | ((exponent + 112) << 23) | (mantissa << 13);
  }
  float value = 0;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

#if LIGHTVOL_HAVE_LIBDEFLATE
// Each decoding thread's inflater, and the buffer it inflates a chunk into (grown as needed).
struct Inflater {
  libdeflate_decompressor* inflate = libdeflate_alloc_decompressor();
  std::unique_ptr<std::uint8_t[]> scratch;
  std::size_t capacity = 0;
  Inflater() = default;
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;
  ~Inflater() {
    if (inflate != nullptr) libdeflate_free_decompressor(inflate);
  }
  bool reserve(std::size_t bytes) {
    if (bytes <= capacity) return true;
    scratch.reset(new (std::nothrow) std::uint8_t[bytes]);
    capacity = scratch ? bytes : 0;
    return scratch != nullptr;
  }
};

Inflater& thread_inflater() {
  thread_local Inflater inflater;
  return inflater;
}

#if defined(__SSE2__)
// Running sums of the 16 bytes of `x` (each byte less 128) after `carry` (its 16 bytes the value
// before them), modulo 256; `carry` becomes the last sum's, in all 16 bytes.
inline __m128i running_sums(__m128i x, __m128i& carry) {
  x = _mm_add_epi8(x, _mm_set1_epi8(static_cast<char>(-128)));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
  x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
  x = _mm_add_epi8(x, carry);
  __m128i last = _mm_srli_si128(x, 15);
  last = _mm_unpacklo_epi8(last, last);
  carry = _mm_shuffle_epi32(_mm_shufflelo_epi16(last, 0), 0);
  return x;
}
#endif

// OpenEXRCore's ZIP predictor and interleave (internal_zip.c's reconstruct, then interleave) in
// one pass: `s` holds n bytes, each (but the first) the difference from the byte before it plus
// 128 (mod 256); once that is undone, the first (n + 1) / 2 bytes go to the even offsets of `out`,
// the rest to the odd ones. The two halves are undone side by side, the second starting from the
// first's last value (the sum of all its differences, found first).
void predict_and_interleave(std::uint8_t* s, std::size_t n, std::uint8_t* out) {
  if (n == 0) return;
  const std::size_t first = (n + 1) / 2, second = n / 2;
  const std::uint8_t* a = s;
  const std::uint8_t* b = s + first;
  s[0] = static_cast<std::uint8_t>(s[0] + 128);  // now a difference like every other byte
  std::uint64_t sum = 0;
  std::size_t i = 0;
#if defined(__SSE2__)
  __m128i sums = _mm_setzero_si128();
  for (; i + 16 <= first; i += 16)
    sums =
        _mm_add_epi64(sums, _mm_sad_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i)),
                                         _mm_setzero_si128()));
  sum = static_cast<std::uint64_t>(_mm_cvtsi128_si64(sums)) +
        static_cast<std::uint64_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(sums, sums)));
#endif
  for (; i < first; ++i) sum += a[i];
  unsigned value_a = 0;
  auto value_b = static_cast<unsigned>((sum - 128 * std::uint64_t{first}) & 255u);
  i = 0;
#if defined(__SSE2__)
  __m128i carry_a = _mm_setzero_si128();
  __m128i carry_b = _mm_set1_epi8(static_cast<char>(value_b));
  for (; i + 16 <= second; i += 16) {
    const __m128i x =
        running_sums(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a + i)), carry_a);
    const __m128i y =
        running_sums(_mm_loadu_si128(reinterpret_cast<const __m128i*>(b + i)), carry_b);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * i), _mm_unpacklo_epi8(x, y));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * i + 16), _mm_unpackhi_epi8(x, y));
  }
  value_a = static_cast<unsigned>(_mm_cvtsi128_si32(carry_a)) & 255u;
  value_b = static_cast<unsigned>(_mm_cvtsi128_si32(carry_b)) & 255u;
#endif
  for (; i < second; ++i) {
    value_a = (value_a + a[i] + 128) & 255u;  // + 128 is - 128, modulo 256
    value_b = (value_b + b[i] + 128) & 255u;
    out[2 * i] = static_cast<std::uint8_t>(value_a);
    out[2 * i + 1] = static_cast<std::uint8_t>(value_b);
  }
  if (first > second) out[n - 1] = static_cast<std::uint8_t>((value_a + a[second] + 128) & 255u);
}

// The file's bytes are little-endian, as OpenEXRCore's unpacking (a copy) leaves them here.
static_assert(std::endian::native == std::endian::little, "lightvol-exr assumes little-endian");

// Where a chunk's decoded bytes go when they are the image's own (a scanline chunk, as wide as
// the image, in the file's type): straight there, without OpenEXRCore's copy from its buffer.
struct ZipTarget {
  std::uint8_t* direct = nullptr;
  std::size_t bytes = 0;
};

// The pipeline's decompress_fn for ZIP and ZIPS chunks, in place of OpenEXRCore's
// (default_decompress_chunk, which calls internal_exr_undo_zip): the same bytes, or an error.
exr_result_t zip_decompress(exr_decode_pipeline_t* decode) {
  const auto* target = static_cast<const ZipTarget*>(decode->decoding_user_data);
  const std::uint64_t packed = decode->chunk.packed_size, unpacked = decode->chunk.unpacked_size;
  if (decode->packed_buffer == nullptr || target == nullptr) return EXR_ERR_INVALID_ARGUMENT;
  void* out = decode->unpacked_buffer;
  if (target->direct != nullptr) {
    if (unpacked != target->bytes) return EXR_ERR_CORRUPT_CHUNK;
    out = target->direct;
  }
  if (out == nullptr) return EXR_ERR_INVALID_ARGUMENT;
  // Stored as is: OpenEXRCore's buffers are then one.
  if (packed == unpacked && out == decode->packed_buffer) return EXR_ERR_SUCCESS;
  return undo_exr_zip(decode->packed_buffer, static_cast<std::size_t>(packed), out,
                      static_cast<std::size_t>(unpacked))
             ? EXR_ERR_SUCCESS
             : EXR_ERR_CORRUPT_CHUNK;
}
#endif

// HALF to float for `n` values, exactly as half_to_float: blocks of 64 halves all normal (exponent
// 1 to 30: no zero, subnormal, infinity or NaN) by the arithmetic, which vectorizes; other blocks
// value by value.
void halves_to_floats(const std::uint16_t* in, float* out, std::size_t n) {
  constexpr std::size_t kBlock = 64;
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    std::uint32_t bits[kBlock];
    unsigned special = 0;
    for (std::size_t k = 0; k < kBlock; ++k) {
      const std::uint32_t h = in[i + k], exponent = h & 0x7c00u;
      special |= static_cast<unsigned>(exponent == 0) | static_cast<unsigned>(exponent == 0x7c00u);
      bits[k] = ((h & 0x8000u) << 16) | (((h & 0x7fffu) << 13) + (112u << 23));
    }
    if (special == 0) {
      std::memcpy(out + i, bits, sizeof bits);
    } else {
      for (std::size_t k = 0; k < kBlock; ++k) out[i + k] = half_to_float(in[i + k]);
    }
  }
  for (; i < n; ++i) out[i] = half_to_float(in[i]);
}

bool lower_equal(const std::string& a, const char* b) {
  std::string lower = a;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower == b;
}

bool ends_lower(const std::string& a, const std::string& suffix) {
  return a.size() >= suffix.size() &&
         lower_equal(a.substr(a.size() - suffix.size()), suffix.c_str());
}

// The file's header when it is plain and passes image_codec.cpp's checks (open_image,
// check_header) as OpenImageIO would compute them; false otherwise.
bool plain_header(const std::string& path, exr_const_context_t ctx, Plain* plain) {
  int parts = 0;
  if (exr_get_count(ctx, &parts) != EXR_ERR_SUCCESS || parts != 1) return false;
  exr_storage_t storage{};
  if (exr_get_storage(ctx, 0, &storage) != EXR_ERR_SUCCESS) return false;
  if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) return false;
  plain->tiled = storage == EXR_STORAGE_TILED;
  exr_attr_box2i_t data{}, display{};
  if (exr_get_data_window(ctx, 0, &data) != EXR_ERR_SUCCESS ||
      exr_get_display_window(ctx, 0, &display) != EXR_ERR_SUCCESS)
    return false;
  if (data.min.x != 0 || data.min.y != 0 || display.min.x != 0 || display.min.y != 0 ||
      data.max.x != display.max.x || data.max.y != display.max.y)
    return false;
  const std::int64_t width = std::int64_t{data.max.x} + 1, height = std::int64_t{data.max.y} + 1;
  // open_image's 2x2, check_header's 2^30 texels.
  if (width < 2 || height < 2 || width * height > (std::int64_t{1} << 30)) return false;
  plain->width = static_cast<int>(width);
  plain->height = static_cast<int>(height);
  const exr_attr_chlist_t* channels = nullptr;
  if (exr_get_channels(ctx, 0, &channels) != EXR_ERR_SUCCESS || channels == nullptr ||
      channels->num_channels != 1)
    return false;
  const exr_attr_chlist_entry_t& channel = channels->entries[0];
  if (channel.pixel_type != EXR_PIXEL_HALF && channel.pixel_type != EXR_PIXEL_FLOAT) return false;
  if (channel.x_sampling != 1 || channel.y_sampling != 1) return false;
  plain->half = channel.pixel_type == EXR_PIXEL_HALF;
  if (channel.name.str == nullptr || channel.name.length <= 0) return false;
  plain->name.assign(channel.name.str, static_cast<std::size_t>(channel.name.length));
  // A name OpenImageIO may take for alpha (its header would then name an alpha channel).
  if (lower_equal(plain->name, "a") || lower_equal(plain->name, "alpha") ||
      ends_lower(plain->name, ".a") || ends_lower(plain->name, ".alpha") ||
      plain->name.size() > ChildOutput::kMaxString)
    return false;
  exr_compression_t compression{};
  if (exr_get_compression(ctx, 0, &compression) != EXR_ERR_SUCCESS) return false;
  plain->zip = compression == EXR_COMPRESSION_ZIP || compression == EXR_COMPRESSION_ZIPS;
  std::int64_t chunks = 0;
  if (plain->tiled) {
    std::uint32_t tile_x = 0, tile_y = 0;
    exr_tile_level_mode_t levels{};
    exr_tile_round_mode_t round{};
    if (exr_get_tile_descriptor(ctx, 0, &tile_x, &tile_y, &levels, &round) != EXR_ERR_SUCCESS ||
        levels != EXR_TILE_ONE_LEVEL || tile_x < 1 || tile_y < 1 || tile_x > (1u << 30) ||
        tile_y > (1u << 30))
      return false;
    chunks = ((width + tile_x - 1) / tile_x) * ((height + tile_y - 1) / tile_y);
  } else {
    // check_header's scanlines per chunk, by compression.
    std::int64_t lines = 1;
    switch (compression) {
      case EXR_COMPRESSION_NONE:
      case EXR_COMPRESSION_RLE:
      case EXR_COMPRESSION_ZIPS:
        lines = 1;
        break;
      case EXR_COMPRESSION_ZIP:
      case EXR_COMPRESSION_PXR24:
        lines = 16;
        break;
      case EXR_COMPRESSION_PIZ:
      case EXR_COMPRESSION_B44:
      case EXR_COMPRESSION_B44A:
      case EXR_COMPRESSION_DWAA:
        lines = 32;
        break;
      case EXR_COMPRESSION_DWAB:
        lines = 256;
        break;
      default:
        return false;
    }
    chunks = (height + lines - 1) / lines;
  }
  // Lossy compressions: whether OpenImageIO's floats would be the same is not checked here.
  if (compression != EXR_COMPRESSION_NONE && compression != EXR_COMPRESSION_RLE &&
      compression != EXR_COMPRESSION_ZIPS && compression != EXR_COMPRESSION_ZIP &&
      compression != EXR_COMPRESSION_PIZ)
    return false;
  std::error_code ec;
  const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return false;
  if (static_cast<std::uintmax_t>(chunks) * 16 > file_size) return false;
  const std::uintmax_t decoded = static_cast<std::uintmax_t>(width * height) *
                                 (channel.pixel_type == EXR_PIXEL_HALF ? 2u : 4u);
  if (decoded / 4096 > file_size) return false;
  return true;
}

// The file's chunk table (single part: right after the header) names, for each chunk, an offset
// in the file where that chunk starts, with its own coordinates. OpenEXRCore rebuilds a damaged
// table by scanning the file where OpenImageIO's reader fails: such a file is declined.
bool sane_chunk_table(const std::string& path, exr_const_context_t ctx, const Plain& plain) {
  std::int32_t count = 0, lines = 1;
  if (exr_get_chunk_count(ctx, 0, &count) != EXR_ERR_SUCCESS || count < 1) return false;
  if (!plain.tiled && (exr_get_scanlines_per_chunk(ctx, 0, &lines) != EXR_ERR_SUCCESS || lines < 1))
    return false;
  std::uint32_t tile_x = 1, tile_y = 1;
  if (plain.tiled) {
    exr_tile_level_mode_t levels{};
    exr_tile_round_mode_t round{};
    if (exr_get_tile_descriptor(ctx, 0, &tile_x, &tile_y, &levels, &round) != EXR_ERR_SUCCESS ||
        tile_x < 1 || tile_y < 1)
      return false;
  }
  const std::int64_t across = (std::int64_t{plain.width} + tile_x - 1) / tile_x;
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return false;
  std::ifstream in(path, std::ios::binary);
  const auto read_at = [&](std::uint64_t offset, std::size_t n, void* out) {
    if (offset > file_size || file_size - offset < n) return false;
    in.seekg(static_cast<std::streamoff>(offset));
    return static_cast<bool>(in.read(static_cast<char*>(out), static_cast<std::streamsize>(n)));
  };
  // The header, within its first MiB (else declined).
  std::string bytes(static_cast<std::size_t>(std::min<std::uint64_t>(file_size, 1 << 20)), '\0');
  if (!read_at(0, bytes.size(), bytes.data())) return false;
  std::size_t at = 8;  // the attributes: name, type, size, value; an empty name ends them
  while (at < bytes.size() && bytes[at] != '\0') {
    const std::size_t name_end = bytes.find('\0', at);
    if (name_end == std::string::npos) return false;
    const std::size_t type_end = bytes.find('\0', name_end + 1);
    if (type_end == std::string::npos || type_end + 5 > bytes.size()) return false;
    std::int32_t size = 0;
    std::memcpy(&size, bytes.data() + type_end + 1, sizeof size);
    if (size < 0) return false;
    at = type_end + 5 + static_cast<std::size_t>(size);
  }
  if (at >= bytes.size()) return false;
  const std::uint64_t table = at + 1, table_end = table + 8 * static_cast<std::uint64_t>(count);
  std::vector<std::uint64_t> offsets(static_cast<std::size_t>(count));
  if (!read_at(table, offsets.size() * 8, offsets.data())) return false;
  for (std::int32_t k = 0; k < count; ++k) {
    const std::uint64_t offset = offsets[static_cast<std::size_t>(k)];
    const std::size_t head = plain.tiled ? 20 : 8;  // coordinates and the packed size
    std::int32_t field[5] = {};
    if (offset < table_end || !read_at(offset, head, field)) return false;
    const std::int32_t packed = plain.tiled ? field[4] : field[1];
    if (packed < 0 || file_size - offset - head < static_cast<std::uint64_t>(packed)) return false;
    if (plain.tiled
            ? (field[0] != k % across || field[1] != k / across || field[2] != 0 || field[3] != 0)
            : field[0] != k * lines)
      return false;
  }
  return true;
}

// Decodes every chunk of the one channel, as floats, into `values` (width × height, rows top to
// bottom), chunks shared among `threads` threads; false on any error. A HALF file's chunks are
// decoded into `halves` first, each converted to floats by the thread that decoded it.
bool decode(exr_const_context_t ctx, const Plain& plain, float* values, std::uint16_t* halves,
            int threads) {
  std::vector<std::array<int, 2>> chunks;  // scanline: (y, 0); tiled: (tile x, tile y)
  std::int64_t tile_w = 0, tile_h = 0;
  if (plain.tiled) {
    std::uint32_t tile_x = 0, tile_y = 0;
    exr_tile_level_mode_t levels{};
    exr_tile_round_mode_t round{};
    if (exr_get_tile_descriptor(ctx, 0, &tile_x, &tile_y, &levels, &round) != EXR_ERR_SUCCESS ||
        tile_x < 1 || tile_y < 1)
      return false;
    tile_w = static_cast<std::int64_t>(tile_x);
    tile_h = static_cast<std::int64_t>(tile_y);
    const int across = static_cast<int>((std::int64_t{plain.width} + tile_x - 1) / tile_x);
    const int down = static_cast<int>((std::int64_t{plain.height} + tile_y - 1) / tile_y);
    for (int ty = 0; ty < down; ++ty)
      for (int tx = 0; tx < across; ++tx) chunks.push_back({tx, ty});
  } else {
    int32_t lines = 0;
    if (exr_get_scanlines_per_chunk(ctx, 0, &lines) != EXR_ERR_SUCCESS || lines < 1) return false;
    for (std::int64_t y = 0; y < plain.height; y += lines)
      chunks.push_back({static_cast<int>(y), 0});
  }
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  const auto work = [&] {
    exr_decode_pipeline_t decoder = EXR_DECODE_PIPELINE_INITIALIZER;
    bool started = false;
    for (std::size_t i = next++; i < chunks.size() && !failed.load(); i = next++) {
      exr_chunk_info_t chunk{};
      const exr_result_t info =
          plain.tiled ? exr_read_tile_chunk_info(ctx, 0, chunks[i][0], chunks[i][1], 0, 0, &chunk)
                      : exr_read_scanline_chunk_info(ctx, 0, chunks[i][0], &chunk);
      if (info != EXR_ERR_SUCCESS) {
        failed = true;
        break;
      }
      // Where the chunk goes: a tile's chunk information gives its tile indices, not its texels
      // (OpenEXR 3.1). Its rectangle must lie in the image.
      const std::int64_t x0 = plain.tiled ? chunks[i][0] * tile_w : 0;
      const std::int64_t y0 = plain.tiled ? chunks[i][1] * tile_h : chunk.start_y;
      if (y0 < 0 || chunk.width < 0 || chunk.height < 0 || x0 + chunk.width > plain.width ||
          y0 + chunk.height > plain.height) {
        failed = true;
        break;
      }
      // A fresh decoder for each chunk, as OpenImageIO's reader has (exr_decoding_update keeps
      // state that let a damaged chunk decode there while it failed in OpenImageIO).
      if (started) exr_decoding_destroy(ctx, &decoder);
      decoder = EXR_DECODE_PIPELINE_INITIALIZER;
      const exr_result_t set = exr_decoding_initialize(ctx, 0, &chunk, &decoder);
      started = true;
      if (set != EXR_ERR_SUCCESS || decoder.channel_count != 1) {
        failed = true;
        break;
      }
      // In the file's own type, as OpenImageIO's reader decodes (HALF into `halves`, converted
      // after).
      exr_coding_channel_info_t& out = decoder.channels[0];
      const std::size_t at = static_cast<std::size_t>(y0) * static_cast<std::size_t>(plain.width) +
                             static_cast<std::size_t>(x0);
      const std::size_t size = halves != nullptr ? sizeof(std::uint16_t) : sizeof(float);
      out.decode_to_ptr = halves != nullptr ? reinterpret_cast<std::uint8_t*>(halves + at)
                                            : reinterpret_cast<std::uint8_t*>(values + at);
      out.user_pixel_stride = static_cast<int32_t>(size);
      out.user_line_stride = static_cast<int32_t>(size * static_cast<std::size_t>(plain.width));
      if (exr_decoding_choose_default_routines(ctx, 0, &decoder) != EXR_ERR_SUCCESS) {
        failed = true;
        break;
      }
#if LIGHTVOL_HAVE_LIBDEFLATE
      // ZIP and ZIPS: libdeflate inflates in place of zlib. A scanline chunk's rows are contiguous
      // in the destination, in the file's type (little-endian, as this machine): its bytes go
      // there, and OpenEXRCore's unpacking (a copy of each row) is skipped.
      ZipTarget target;
      if (plain.zip && decoder.decompress_fn != nullptr) {
        decoder.decompress_fn = &zip_decompress;
        decoder.decoding_user_data = &target;
        if (!plain.tiled && chunk.width == plain.width &&
            decoder.unpack_and_convert_fn != nullptr) {
          target.direct = out.decode_to_ptr;
          target.bytes =
              size * static_cast<std::size_t>(chunk.width) * static_cast<std::size_t>(chunk.height);
          decoder.unpack_and_convert_fn = nullptr;
        }
      }
#endif
      if (exr_decoding_run(ctx, 0, &decoder) != EXR_ERR_SUCCESS) {
        failed = true;
        break;
      }
      // HALF to float, exactly (every half is a float; NaN keeps its payload, as in Imath's).
      if (halves != nullptr)
        for (std::int64_t y = 0; y < chunk.height; ++y) {
          const std::size_t row =
              at + static_cast<std::size_t>(y) * static_cast<std::size_t>(plain.width);
          halves_to_floats(halves + row, values + row, static_cast<std::size_t>(chunk.width));
        }
    }
    if (started) exr_decoding_destroy(ctx, &decoder);
  };
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t count = std::min<std::size_t>(
      chunks.size(), threads > 0 ? static_cast<std::size_t>(threads) : std::size_t{cores});
  std::vector<std::thread> pool;
  for (std::size_t t = 1; t < count; ++t) pool.emplace_back(work);
  work();
  for (std::thread& thread : pool) thread.join();
  return !failed.load();
}

void serve_read(ChildOutput& channel, int threads) {
  std::string path, plugin, magic, read_failure;
  if (!channel.read_string(&path) || !channel.read_string(&plugin) ||
      !channel.read_string(&magic) || !channel.read_string(&read_failure))
    return;
  if (plugin != "openexr") return channel.refuse(kNotMine);
  reported = false;
  Context context;
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.error_handler_fn = &silent;
  Plain plain;
  if (exr_start_read(&context.handle, path.c_str(), &init) != EXR_ERR_SUCCESS ||
      !plain_header(path, context.handle, &plain) ||
      !sane_chunk_table(path, context.handle, plain) || reported.load())
    return channel.refuse(kNotMine);
  channel.accept();
  channel.write_value(static_cast<std::int32_t>(plain.width));
  channel.write_value(static_cast<std::int32_t>(plain.height));
  channel.write_value(std::int32_t{-1});  // no alpha channel
  channel.write_value(std::uint8_t{0});   // not eight bits
  channel.write_value(std::int32_t{1});
  channel.write_string(plain.name);
  channel.write_value(std::uint8_t{0});
  std::int32_t go = 0;
  if (!channel.read_value(&go) || go != 1) return;
  channel.accept();  // check_header's checks passed in plain_header
  std::int32_t chosen = -1;
  if (!channel.read_value(&chosen) || chosen != 0) return;
  std::uint8_t offered = 0;
  int shared_fd = -1;
  if (!channel.read_with_fd(&offered, &shared_fd)) return;
  const std::size_t texels =
      static_cast<std::size_t>(plain.width) * static_cast<std::size_t>(plain.height);
  DecodedFloats floats(shared_fd, texels);
  float* const values = floats.data();
  std::unique_ptr<std::uint16_t[]> halves;
  if (plain.half) halves = std::make_unique_for_overwrite<std::uint16_t[]>(texels);
  const bool read =
      decode(context.handle, plain, values, halves.get(), threads) && !reported.load();
  floats.unmap();
  if (!read) return channel.refuse(kNotMine);
  channel.accept();
  floats.send(channel);
}

}  // namespace

bool exr_zip_by_libdeflate() { return LIGHTVOL_HAVE_LIBDEFLATE != 0; }

bool undo_exr_zip(const void* packed, std::size_t packed_size, void* out,
                  std::size_t unpacked_size) {
#if LIGHTVOL_HAVE_LIBDEFLATE
  if (packed_size == 0 || unpacked_size == 0 || packed == nullptr || out == nullptr) return false;
  if (packed_size == unpacked_size) {
    if (out != packed) std::memcpy(out, packed, unpacked_size);
    return true;
  }
  Inflater& inflater = thread_inflater();
  if (inflater.inflate == nullptr || !inflater.reserve(unpacked_size)) return false;
  std::size_t inflated = 0;
  if (libdeflate_zlib_decompress(inflater.inflate, packed, packed_size, inflater.scratch.get(),
                                 unpacked_size, &inflated) != LIBDEFLATE_SUCCESS ||
      inflated != unpacked_size)
    return false;
  predict_and_interleave(inflater.scratch.get(), unpacked_size, static_cast<std::uint8_t*>(out));
  return true;
#else
  (void)packed, (void)packed_size, (void)out, (void)unpacked_size;
  return false;
#endif
}

bool serve_exr_request(ChildOutput& channel, int threads) {
  ImageRequest request{};
  if (!channel.read_value(&request)) return false;
  return serve_exr_request(channel, threads, request);
}

bool serve_exr_request(ChildOutput& channel, int threads, ImageRequest request) {
  if (request != ImageRequest::read) return false;
  serve_read(channel, threads);
  return true;
}

}  // namespace lightvol::detail

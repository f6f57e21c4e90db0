#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string_view>
#include <vector>

#include <lightvol/core/buffer.h>
#include <lightvol/core/detail/image_helper.h>
#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/path.h>
#include <lightvol/core/text.h>
#include <lightvol/depth/detail/image_file.h>

namespace lightvol::detail {

// OpenImageIO keeps errors in per-thread (global) or per-object queues; fetch and tidy them.
// OpenImageIO's error queue as one line: OpenEXR's core can queue a dozen lines per file, each
// prefixed with "EXR Error (path): "; keep the first and the last (the cause and the conclusion).
std::string oiio_message(const std::string& message) {
  std::vector<std::string> lines;
  std::istringstream in(message);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("EXR Error (", 0) == 0) {
      if (const std::size_t end = line.find("): "); end != std::string::npos)
        line.erase(0, end + 3);
    }
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.pop_back();
    if (!line.empty()) lines.push_back(line);
  }
  if (lines.empty()) return "unknown OpenImageIO error";
  std::string one = lines.front();
  if (lines.size() > 2) one += "; ...";
  if (lines.size() > 1) one += "; " + lines.back();
  constexpr std::size_t kMaxLength = 400;
  if (one.size() > kMaxLength) one = one.substr(0, kMaxLength) + "...";
  return one;
}

namespace {

// Up to `n` bytes from the stream's position.
std::string file_prefix(std::ifstream& in, std::size_t n) {
  std::string bytes(n, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(n));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return bytes;
}

// OpenEXR's readers allocate header attributes at the size the file claims (up to 2 GB), and lose
// their place on malformed headers, reading text as sizes. Walk the header(s) as the format
// defines them first: names within their length limit and unique per header, every attribute
// inside the file. Only the structure is checked; OpenEXR judges the rest.
// The value of one EXR header attribute against its type: fixed-size types must have their size,
// and the variable ones (channel lists, string vectors, previews) must fill exactly their stated
// size. OpenEXR's readers trust these and lose their place when they disagree (fuzz findings: a
// channel list running past its size made the core read text as a 1.9 GB size). Returns why not.
Status check_exr_attribute(std::string_view value, const std::string& type) {
  static const std::map<std::string, std::size_t> kFixed = {{"box2i", 16},
                                                            {"box2f", 16},
                                                            {"v2i", 8},
                                                            {"v2f", 8},
                                                            {"v2d", 16},
                                                            {"v3i", 12},
                                                            {"v3f", 12},
                                                            {"v3d", 24},
                                                            {"int", 4},
                                                            {"float", 4},
                                                            {"double", 8},
                                                            {"compression", 1},
                                                            {"lineOrder", 1},
                                                            {"envmap", 1},
                                                            {"deepImageState", 1},
                                                            {"tiledesc", 9},
                                                            {"rational", 8},
                                                            {"timecode", 8},
                                                            {"keycode", 28},
                                                            {"chromaticities", 32},
                                                            {"m33f", 36},
                                                            {"m33d", 72},
                                                            {"m44f", 64},
                                                            {"m44d", 128}};
  const auto i32 = [&](std::size_t at) {
    std::int32_t v = 0;
    std::memcpy(&v, value.data() + at, 4);
    return v;
  };
  if (const auto fixed = kFixed.find(type); fixed != kFixed.end()) {
    if (value.size() != fixed->second)
      return Error{std::to_string(value.size()) + " bytes, where the type has " +
                   std::to_string(fixed->second)};
    return {};
  }
  if (type == "chlist") {  // (name \0, type, pLinear, 3 reserved, xSampling, ySampling)*, \0
    std::size_t at = 0;
    for (;;) {
      const std::size_t end = value.find('\0', at);
      if (end == std::string_view::npos) return Error{"the channel list has no end"};
      if (end == at) break;
      at = end + 1;
      if (at + 16 > value.size()) return Error{"a channel runs past the attribute"};
      if (i32(at) < 0 || i32(at) > 2 || i32(at + 8) < 1 || i32(at + 12) < 1)
        return Error{"a channel has an unknown pixel type or a sampling below 1"};
      at += 16;
    }
    if (at + 1 != value.size()) return Error{"the channel list does not fill the attribute"};
    return {};
  }
  if (type == "stringvector") {  // (length, bytes)*
    std::size_t at = 0;
    while (at < value.size()) {
      if (at + 4 > value.size() || i32(at) < 0 ||
          static_cast<std::size_t>(i32(at)) > value.size() - at - 4)
        return Error{"a string runs past the attribute"};
      at += 4 + static_cast<std::size_t>(i32(at));
    }
    return {};
  }
  if (type == "preview") {  // width, height, then width × height RGBA bytes
    if (value.size() < 8) return Error{"no preview size"};
    const std::uint64_t w = static_cast<std::uint32_t>(i32(0)),
                        h = static_cast<std::uint32_t>(i32(4));
    if (8 + 4 * w * h != value.size()) return Error{"the preview's size does not match its pixels"};
    return {};
  }
  return {};
}

Status check_exr_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string head = file_prefix(in, 1 << 20);
  if (head.size() < 8 || head.compare(0, 4, "\x76\x2f\x31\x01") != 0) return {};  // not EXR
  std::uintmax_t file_size = 0;
  std::error_code ec;
  if (file_size = std::filesystem::file_size(path, ec); ec) return {};
  const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;
  const std::size_t max_name = (static_cast<unsigned char>(head[5]) & 0x04) != 0 ? 255 : 31;
  const std::string where = path + ": EXR header: ";
  std::size_t at = 8;
  auto read_name = [&](std::string* name) {
    const std::size_t end = head.find('\0', at);
    if (end == std::string::npos) return false;
    *name = head.substr(at, end - at);
    at = end + 1;
    return true;
  };
  std::set<std::string> names;  // of the current header
  for (;;) {                    // headers; a single-part file has one
    std::string name, type;
    if (!read_name(&name)) return {};  // header longer than the prefix: leave it to OpenEXR
    if (name.empty()) {
      if (!multipart) return {};
      if (at < head.size() && head[at] == '\0') return {};  // empty header: end of the list
      names.clear();
      continue;
    }
    // OpenEXR's readers lose their place on these and then read text as sizes (fuzz findings:
    // 1.7 GB requested by a 515-byte file with a repeated attribute).
    if (name.size() > max_name)
      return Error{where + "attribute name '" + utf8_prefix(name, 40) + "' is longer than " +
                   std::to_string(max_name) + " characters (corrupt)"};
    if (!names.insert(name).second)
      return Error{where + "attribute '" + name + "' appears twice (corrupt)"};
    if (!read_name(&type) || at + 4 > head.size()) return {};
    if (type.empty() || type.size() > max_name)
      return Error{where + "attribute '" + name + "' has no valid type name (corrupt)"};
    std::int32_t size = 0;
    std::memcpy(&size, head.data() + at, sizeof size);
    at += 4;
    if (size < 0 ||
        static_cast<std::uintmax_t>(size) > file_size - std::min<std::uintmax_t>(at, file_size))
      return Error{where + "attribute '" + name + "' claims " + std::to_string(size) +
                   " bytes, but the file has " + std::to_string(file_size) +
                   " (truncated or corrupt)"};
    if (at + static_cast<std::size_t>(size) > head.size()) return {};
    if (Status s = check_exr_attribute(head.substr(at, static_cast<std::size_t>(size)), type); !s)
      return Error{where + "attribute '" + name + "' (" + type + "): " + s.error().message +
                   " (corrupt)"};
    at += static_cast<std::size_t>(size);
  }
}

// libpng allocates a chunk at the length the file claims (found by fuzz_depth_image: 1.9 GB);
// every chunk must fit in the file.
Status check_png_chunks(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string head = file_prefix(in, 8);
  if (head != "\x89PNG\r\n\x1a\n") return {};
  std::uintmax_t file_size = 0;
  std::error_code ec;
  if (file_size = std::filesystem::file_size(path, ec); ec) return {};
  std::uintmax_t at = 8;
  for (int chunk = 0; at + 8 <= file_size && chunk < 100000; ++chunk) {
    in.seekg(static_cast<std::streamoff>(at));
    const std::string header = file_prefix(in, 8);
    if (header.size() < 8) return {};
    const auto* b = reinterpret_cast<const unsigned char*>(header.data());
    const std::uintmax_t length = (std::uintmax_t{b[0]} << 24) | (std::uintmax_t{b[1]} << 16) |
                                  (std::uintmax_t{b[2]} << 8) | b[3];
    if (at + 12 + length > file_size)
      return Error{path + ": PNG chunk '" + header.substr(4, 4) + "' claims " +
                   std::to_string(length) + " bytes, but the file has " +
                   std::to_string(file_size) + " (truncated or corrupt)"};
    if (header.compare(4, 4, "IEND") == 0) return {};
    at += 12 + length;
  }
  return {};
}

// The OpenImageIO plugin to read `path` with: the one its first bytes name among the formats
// depth images come in (EXR, TIFF, PNG, PFM and 16-bit PGM, Radiance HDR, Pixar's ZFile), else
// the one among those its extension names (the plugin then says what is wrong with the file).
// Never any other: OpenImageIO's DPX reader allocated 1.9 GB for a 2 KB header (fuzz finding),
// and its try-every-plugin fallback reaches video, camera-raw and DICOM decoders.
Result<std::string> image_format(const std::string& path, const std::string& magic) {
  const auto starts = [&](std::string_view prefix) {
    return std::string_view(magic).substr(0, prefix.size()) == prefix;
  };
  using namespace std::string_view_literals;
  if (starts("\x76\x2f\x31\x01"sv)) return std::string("openexr");
  if (starts("II*\0"sv) || starts("MM\0*"sv) || starts("II+\0"sv) || starts("MM\0+"sv))
    return std::string("tiff");
  if (starts("\x89PNG"sv)) return std::string("png");
  if (magic.size() >= 2 && magic[0] == 'P' &&
      std::string_view("123456fF").find(magic[1]) != std::string_view::npos)
    return std::string("pnm");
  if (starts("#?RADIANCE"sv) || starts("#?RGBE"sv)) return std::string("hdr");
  if (starts("\x2f\x08\x67\xab"sv) || starts("\xab\x67\x08\x2f"sv)) return std::string("zfile");
  const std::string extension = lower_extension(path);
  static const std::map<std::string, std::string> kByExtension = {
      {".exr", "openexr"}, {".tif", "tiff"},   {".tiff", "tiff"}, {".png", "png"},
      {".pfm", "pnm"},     {".pgm", "pnm"},    {".ppm", "pnm"},   {".pnm", "pnm"},
      {".hdr", "hdr"},     {".zfile", "zfile"}};
  if (const auto f = kByExtension.find(extension); f != kByExtension.end()) return f->second;
  return Error{path +
               ": not an image lightvol reads depths from (EXR, TIFF, PNG, PFM, PGM, HDR or "
               "ZFile, by its first bytes or its extension)"};
}

// PFM's third header line: its sign is the byte order (negative: little-endian), its magnitude
// the scale factor that multiplies every stored value (as Netpbm describes it, and as
// OpenImageIO reads it). A scale of 0 (every depth 0), or one that is not a finite number, is
// refused.
Status check_pfm_scale(const std::string& path, const std::string& magic) {
  if (magic.rfind("Pf", 0) != 0 && magic.rfind("PF", 0) != 0) return {};
  std::ifstream in(path, std::ios::binary);
  const std::string head = file_prefix(in, 256);
  std::istringstream words(head);
  std::string id, width, height, scale;
  words >> id >> width >> height >> scale;
  char* end = nullptr;
  const double value = std::strtod(scale.c_str(), &end);
  if (scale.empty() || end != scale.c_str() + scale.size() || !std::isfinite(value) || value == 0)
    return Error{path + ": PFM scale '" + utf8_prefix(scale, 40) +
                 "' is not a finite non-zero number (its sign is the byte order, -1 for "
                 "little-endian; its magnitude multiplies the values)"};
  return {};
}

// A memfd the child decodes an image's floats into: created sized and sealed against resizing,
// so that the child can neither shrink it under our mapping nor grow it; after the child's answer
// sealed against writes too (which fails while the child still has it mapped writable), then
// mapped private (copy on write) as the image's storage. Not available (fd() -1) where the kernel
// has no memfd_create or refuses its size: the floats then come through the channel.
std::atomic<bool> shared_memory_offered{true};

class SharedFloats {
 public:
  explicit SharedFloats(std::size_t bytes) : bytes_(bytes) {
    if (!shared_memory_offered.load()) return;
    fd_ = ::memfd_create("lightvol-image", MFD_CLOEXEC | MFD_ALLOW_SEALING);
    if (fd_ < 0) return;
    if (::ftruncate(fd_, static_cast<off_t>(bytes)) != 0 ||
        ::fcntl(fd_, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~SharedFloats() {
    if (fd_ >= 0) ::close(fd_);
  }
  SharedFloats(const SharedFloats&) = delete;
  SharedFloats& operator=(const SharedFloats&) = delete;
  int fd() const { return fd_; }
  // The `texels` floats the child wrote, as this process's own pages (or, where they cannot be
  // mapped, a copy read from the memfd); an Error if the child kept them writable.
  Result<FloatBuffer> take(std::size_t texels) {
    if (::fcntl(fd_, F_ADD_SEALS, F_SEAL_WRITE) != 0)
      return Error{"the image reader kept its shared memory writable (" +
                   std::string(std::strerror(errno)) + ")"};
    // Private: a write (none of the library's) copies the page it writes. Populated for reading
    // (the page tables of the child's pages filled in one call, not one fault per 4 KiB page):
    // MAP_POPULATE on a writable private mapping would instead copy every page.
    void* mapped = ::mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE, fd_, 0);
    if (mapped != MAP_FAILED) {
#ifdef MADV_POPULATE_READ
      ::madvise(mapped, bytes_, MADV_POPULATE_READ);  // advice: where it fails, faults fill them
#endif
      return FloatBuffer::adopt_mapping(static_cast<float*>(mapped), texels, bytes_);
    }
    std::vector<float> values(texels);
    std::size_t done = 0;
    auto* out = reinterpret_cast<char*>(values.data());
    while (done < bytes_) {
      const ssize_t n = ::pread(fd_, out + done, bytes_ - done, static_cast<off_t>(done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0)
        return Error{"cannot read the image reader's shared memory (" +
                     std::string(n < 0 ? std::strerror(errno) : "it ended early") + ")"};
      done += static_cast<std::size_t>(n);
    }
    return FloatBuffer(std::move(values));
  }

 private:
  int fd_ = -1;
  std::size_t bytes_;
};

}  // namespace

void offer_shared_memory(bool offer) { shared_memory_offered.store(offer); }

std::optional<std::array<int, 2>> exr_data_window_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string head = file_prefix(in, 1 << 16);
  if (head.size() < 8 || head.compare(0, 4, "\x76\x2f\x31\x01") != 0) return {};  // not EXR
  if ((static_cast<unsigned char>(head[5]) & 0x18) != 0) return {};  // multi-part or deep
  std::size_t at = 8;
  for (;;) {
    const std::size_t name_end = head.find('\0', at);
    if (name_end == std::string::npos || name_end == at) return {};  // past the prefix, or the end
    const std::size_t type_end = head.find('\0', name_end + 1);
    if (type_end == std::string::npos || type_end + 5 > head.size()) return {};
    std::int32_t size = 0;
    std::memcpy(&size, head.data() + type_end + 1, sizeof size);
    const std::size_t value = type_end + 5;
    if (size < 0 || value + static_cast<std::size_t>(size) > head.size()) return {};
    if (head.compare(at, name_end - at, "dataWindow") == 0 &&
        head.compare(name_end + 1, type_end - name_end - 1, "box2i") == 0 && size == 16) {
      std::int32_t box[4];
      std::memcpy(box, head.data() + value, sizeof box);
      const std::int64_t w = std::int64_t{box[2]} - box[0] + 1,
                         h = std::int64_t{box[3]} - box[1] + 1;
      if (w < 1 || h < 1 || w > (1 << 20) || h > (1 << 20)) return {};
      return std::array<int, 2>{static_cast<int>(w), static_cast<int>(h)};
    }
    at = value + static_cast<std::size_t>(size);
  }
}

Result<ImageFile> check_image_file(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) return Error{path + ": no such file"};
  if (std::filesystem::is_directory(status)) return Error{path + ": is a directory, not an image"};
  if (!std::filesystem::is_regular_file(status))
    return Error{path + ": is not a regular file (a device or a pipe); images are read from files"};
  std::ifstream head(path, std::ios::binary);
  const std::string magic = file_prefix(head, 10);  // read once: the format, then PFM's sizes
  const Result<std::string> format = image_format(path, magic);
  if (!format) return format.error();
  if (Status s = check_exr_header(path); !s) return s.error();
  if (Status s = check_png_chunks(path); !s) return s.error();
  if (Status s = check_pfm_scale(path, magic); !s) return s.error();
  return ImageFile{*format, magic};
}

Result<ImageChannel> read_image_channel(
    const std::string& path, const std::function<Status(const ImageHeader&)>& within_budget,
    const std::function<Result<int>(const ImageHeader&)>& select, const std::string& read_failure) {
  // lightvol's own checks of the file run here, where fuzzing sees them; OpenImageIO in
  // lightvol-image.
  const Result<ImageFile> file = check_image_file(path);
  if (!file) return file.error();

  Result<ImageChannel> result = Error{""};
  const Error broken{path + ": the image reader broke off its answer"};
  // The conversation of image_codec.h serve_image_request.
  const auto parent = [&](ChildInput& in) -> Status {
    if (!in.write_value(ImageRequest::read) || !in.write_string(path) ||
        !in.write_string(file->format) || !in.write_string(file->magic) ||
        !in.write_string(read_failure))
      return broken;
    Status answer;
    if (!in.read_go_on(&result, broken, &answer)) return answer;
    ImageHeader header;
    std::int32_t channels = 0;
    std::uint8_t eight_bit = 0;
    if (!in.read_value(&header.width) || !in.read_value(&header.height) ||
        !in.read_value(&header.alpha_channel) || !in.read_value(&eight_bit) ||
        !in.read_value(&channels) || header.width < 2 || header.height < 2 || channels < 1 ||
        channels > kMaxImageChannels || header.alpha_channel < -1 ||
        header.alpha_channel >= channels)
      return broken;
    header.eight_bit = eight_bit != 0;
    header.names.resize(static_cast<std::size_t>(channels));
    header.channel_eight_bit.resize(static_cast<std::size_t>(channels));
    for (int c = 0; c < channels; ++c)
      if (!in.read_string(&header.names[c]) || !in.read_value(&header.channel_eight_bit[c]))
        return broken;
    // Each refusal tells the reader to stop before the error ends the conversation.
    const auto stop = [&](const Error& error) -> Status {
      in.write_value(std::int32_t{-1});
      result = error;
      return {};
    };
    if (Status s = within_budget(header); !s) return stop(s.error());
    if (!in.write_value(std::int32_t{1})) return broken;
    if (!in.read_go_on(&result, broken, &answer)) return answer;
    const Result<int> channel = select(header);
    if (!channel) return stop(channel.error());
    if (*channel < 0 || *channel >= channels) return stop(Error{path + ": no such channel"});
    const auto texels =
        static_cast<std::size_t>(header.width) * static_cast<std::size_t>(header.height);
    if (Status s = check_memory(texels * sizeof(float), path, "its pixels"); !s)
      return stop(s.error());
    in.allow_more(2 + 200e-9 * static_cast<double>(texels));
    if (!in.write_value(std::int32_t{*channel})) return broken;
    // Shared memory for the floats, offered with the next byte; without it (no memfd here), the
    // floats come through the channel.
    const std::size_t bytes = texels * sizeof(float);
    SharedFloats shared(bytes);
    if (!in.write_with_fd(std::uint8_t{shared.fd() >= 0}, shared.fd())) return broken;
    if (!in.read_go_on(&result, broken, &answer)) return answer;
    std::uint8_t where = 0;
    if (!in.read_value(&where) || where > 1 || (where == 1 && shared.fd() < 0)) return broken;
    ImageChannel image;
    image.width = header.width;
    image.height = header.height;
    if (where == 1) {
      Result<FloatBuffer> floats = shared.take(texels);
      if (!floats) return Error{path + ": " + floats.error().message};
      image.values = std::move(*floats);
    } else {
      std::vector<float> values;
      values.reserve(texels);
      values.resize(texels);
      if (!in.read(values.data(), bytes)) return broken;
      image.values = std::move(values);
    }
    result = std::move(image);
    return {};
  };
  IsolationLimits limits;
  limits.memory = (std::uint64_t{256} << 20) +
                  memory_budget();  // the budget, and room for the libraries' own state
  limits.cpu_seconds = 5;
  limits.wall_seconds = 10 + 4 * limits.cpu_seconds;
  // An EXR goes to lightvol-exr first (it starts in a fraction of lightvol-image's time; the
  // same conversation). It reads only plain files, the same floats OpenImageIO reads, and
  // declines every other one; on any failure or refusal of it (including the budget's, so that
  // every message is the one below) the file is read again, through OpenImageIO.
  if (file->format == "openexr" && exr_helper_available()) {
    const Status run =
        run_image_helper(path + ": OpenEXR's reader", limits, parent, ImageProgram::exr);
    if (run && result) return result;
    result = Error{""};
  }
  if (Status run = run_image_helper(path + ": OpenImageIO's reader", limits, parent); !run)
    return run.error();
  return result;
}

}  // namespace lightvol::detail

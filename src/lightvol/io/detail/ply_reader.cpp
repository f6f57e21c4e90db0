#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/text.h>
#include <lightvol/io/detail/ply_reader.h>
#include <lightvol/io/detail/text_numbers.h>

namespace lightvol::detail {
namespace {

enum class Type : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<Type> parse_type(std::string_view name) {
  static constexpr std::pair<std::string_view, Type> kNames[] = {
      {"char", Type::i8},   {"int8", Type::i8},     {"uchar", Type::u8},   {"uint8", Type::u8},
      {"short", Type::i16}, {"int16", Type::i16},   {"ushort", Type::u16}, {"uint16", Type::u16},
      {"int", Type::i32},   {"int32", Type::i32},   {"uint", Type::u32},   {"uint32", Type::u32},
      {"float", Type::f32}, {"float32", Type::f32}, {"double", Type::f64}, {"float64", Type::f64}};
  for (const auto& [n, t] : kNames)
    if (n == name) return t;
  return std::nullopt;
}

constexpr std::size_t size_of(Type t) {
  constexpr std::size_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSizes[static_cast<int>(t)];
}

// What the reader keeps of a property.
enum class Role : std::uint8_t { skip, x, y, z, face };

struct Property {
  std::string name;
  bool list = false;
  Type count_type = Type::u8;  // lists only
  Type type = Type::f32;       // the value's, or each list item's
  Role role = Role::skip;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Encoding { ascii, little_endian, big_endian };

struct Header {
  Encoding encoding = Encoding::ascii;
  std::vector<Element> elements;
  std::size_t body = 0;        // offset of the first byte after "end_header\n"
  std::uint64_t vertices = 0;  // the vertex element's count
  std::uint64_t faces = 0;     // the face element's count (0 without one)
};

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t at = 0;
  while (true) {
    at = line.find_first_not_of(" \t\r", at);
    if (at == std::string_view::npos) return words;
    const std::size_t end = std::min(line.find_first_of(" \t\r", at), line.size());
    words.push_back(line.substr(at, end - at));
    at = end;
  }
}

std::string quoted(std::string_view word) { return "'" + utf8_prefix(word, 40) + "'"; }

// The header: every line is one the format allows, every count fits in the bytes after it.
// Long (over 80 lines) on purpose: one pass over the header's lines, a case per keyword, each with
// its own message; the cases share the line counter and the element being declared.
Result<Header> read_header(const std::string& path, std::uintmax_t size) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  std::string head(std::size_t{1} << 16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  if (head.rfind("ply\n", 0) != 0 && head.rfind("ply\r\n", 0) != 0)
    return Error{path + ": not a PLY file (it does not start with 'ply')"};

  Header header;
  bool has_format = false, ended = false;
  std::size_t at = 0;
  for (int number = 1; at < head.size() && !ended; ++number) {
    const std::size_t newline = head.find('\n', at);
    if (newline == std::string::npos) break;
    const std::vector<std::string_view> words =
        split(std::string_view(head).substr(at, newline - at));
    at = newline + 1;
    const auto fail = [&](const std::string& what) -> Result<Header> {
      return Error{path + ": PLY header line " + std::to_string(number) + ": " + what};
    };
    const std::string_view keyword = words.empty() ? std::string_view() : words[0];
    if (number == 1 || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      if (words.size() != 1) return fail("expected 'end_header' alone");
      ended = true;
    } else if (keyword == "format") {
      if (has_format) return fail("a second 'format' line");
      if (words.size() != 3 || words[2] != "1.0" ||
          (words[1] != "ascii" && words[1] != "binary_little_endian" &&
           words[1] != "binary_big_endian"))
        return fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      has_format = true;
      header.encoding = words[1] == "ascii"                  ? Encoding::ascii
                        : words[1] == "binary_little_endian" ? Encoding::little_endian
                                                             : Encoding::big_endian;
    } else if (keyword == "element") {
      std::uint64_t count = 0;
      const auto [end, ec] =
          words.size() == 3
              ? std::from_chars(words[2].data(), words[2].data() + words[2].size(), count)
              : std::from_chars_result{nullptr, std::errc::invalid_argument};
      if (words.size() != 3 || (ec != std::errc() && ec != std::errc::result_out_of_range) ||
          end != words[2].data() + words[2].size())
        return fail("expected 'element NAME COUNT' with a whole-number COUNT");
      if (ec == std::errc::result_out_of_range) count = std::numeric_limits<std::uint64_t>::max();
      for (const Element& e : header.elements)
        if (e.name == words[1]) return fail("a second element " + quoted(words[1]));
      header.elements.push_back({std::string(words[1]), count, {}});
    } else if (keyword == "property") {
      Property p;
      const bool list = words.size() > 1 && words[1] == "list";
      std::optional<Type> count_type, type;
      if (list && words.size() == 5) {
        count_type = parse_type(words[2]);
        type = parse_type(words[3]);
      } else if (!list && words.size() == 3) {
        count_type = Type::u8;
        type = parse_type(words[1]);
      }
      if (!count_type || !type)
        return fail(
            "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME' with TYPE one "
            "of char, uchar, short, ushort, int, uint, float, double");
      if (header.elements.empty()) return fail("a property before any element");
      if (list && (*count_type == Type::f32 || *count_type == Type::f64))
        return fail("a list's count must be of an integer type, not " + quoted(words[2]));
      p.name = std::string(words.back());
      p.list = list;
      p.count_type = *count_type;
      p.type = *type;
      header.elements.back().properties.push_back(std::move(p));
    } else if (header.elements.empty() &&
               std::all_of(words.begin(), words.end(), [](std::string_view w) {
                 return std::all_of(w.begin(), w.end(), [](char ch) {
                   const auto u = static_cast<unsigned char>(ch);
                   return u >= 0x20 && u != 0x7f;
                 });
               })) {
      // Free text before the first element, without the 'comment' keyword: old Blender exporters
      // wrote "Created by Blender3D 247 - www.blender.org, ..." there. Read as a comment.
      continue;
    } else {
      return fail("unknown keyword " + quoted(keyword));
    }
  }
  if (!ended) return Error{path + ": PLY header has no 'end_header' line"};
  if (!has_format) return Error{path + ": PLY header has no 'format' line"};
  header.body = at;

  // What is kept, by name: the vertex element's x, y, z and the face element's index list.
  bool has_vertices = false;
  for (Element& e : header.elements) {
    if (e.name == "vertex") {
      has_vertices = true;
      header.vertices = e.count;
      for (const char* axis : {"x", "y", "z"}) {
        const auto p = std::find_if(e.properties.begin(), e.properties.end(),
                                    [&](const Property& q) { return q.name == axis && !q.list; });
        if (p == e.properties.end())
          return Error{path + ": PLY header: element 'vertex' has no property '" + axis + "'"};
        p->role = static_cast<Role>(static_cast<int>(Role::x) + (axis[0] - 'x'));
      }
    } else if (e.name == "face") {
      header.faces = e.count;
      const auto p = std::find_if(e.properties.begin(), e.properties.end(), [](const Property& q) {
        return q.list && (q.name == "vertex_indices" || q.name == "vertex_index");
      });
      if (p == e.properties.end())
        return Error{path + ": PLY header: element 'face' has no list property 'vertex_indices'"};
      p->role = Role::face;
    }
  }
  if (!has_vertices) return Error{path + ": PLY header declares no 'element vertex'"};

  // Counts against the bytes after the header, before anything is allocated: an element takes
  // at least its fixed-size values and list counts in binary, and two characters a value in ASCII
  // ("0 " or "0\n"); a face's list holds at least three items; an element without properties is
  // counted as one byte.
  // (An ASCII file may end without its last newline.)
  const std::uintmax_t body =
      (size > header.body ? size - header.body : 0) + (header.encoding == Encoding::ascii ? 1 : 0);
  std::uintmax_t needed = 0;
  for (const Element& e : header.elements) {
    std::uintmax_t record = 0;
    const bool ascii = header.encoding == Encoding::ascii;
    for (const Property& p : e.properties) {
      const std::size_t items = p.role == Role::face ? 3 : 0;
      record += ascii    ? 2 * (1 + items)
                : p.list ? size_of(p.count_type) + items * size_of(p.type)
                         : size_of(p.type);
    }
    record = std::max<std::uintmax_t>(record, 1);
    if (e.count > (body - std::min(body, needed)) / record)
      return Error{path + ": PLY header: " + std::to_string(e.count) + " " + e.name +
                   " elements cannot fit in " + std::to_string(size) + " bytes (truncated file?)"};
    needed += e.count * record;
  }
  return header;
}

// Reads bytes after the header in blocks.
class ByteReader {
 public:
  ByteReader(std::ifstream* in, std::uintmax_t left) : in_(in), left_(left), buffer_(1 << 20) {}

  // The next n (≤ 8) bytes, or nullptr when the file ends first.
  const unsigned char* take(std::size_t n) {
    if (end_ - at_ < n && !refill(n)) return nullptr;
    const unsigned char* p = buffer_.data() + at_;
    at_ += n;
    left_ -= std::min<std::uintmax_t>(left_, n);
    return p;
  }
  // Skips n bytes; false when the file ends first.
  bool skip(std::uintmax_t n) {
    while (n > 0) {
      if (at_ == end_ && !refill(1)) return false;
      const std::size_t step = static_cast<std::size_t>(std::min<std::uintmax_t>(n, end_ - at_));
      at_ += step;
      left_ -= std::min<std::uintmax_t>(left_, step);
      n -= step;
    }
    return true;
  }
  // Bytes the file has left, by its size when opened.
  std::uintmax_t left() const { return left_; }
  // Bulk access for whole records: makes at least `n` (≤ the buffer) bytes contiguous if the file
  // holds them, and returns how many are (possibly fewer than n at the end of the file); then
  // data() points at them and consume() moves past what was used.
  std::size_t fill(std::size_t n) {
    if (end_ - at_ < n) refill(n);
    return end_ - at_;
  }
  const unsigned char* data() const { return buffer_.data() + at_; }
  void consume(std::size_t n) {
    at_ += n;
    left_ -= std::min<std::uintmax_t>(left_, n);
  }
  std::size_t capacity() const { return buffer_.size(); }
  // Moves to `n` bytes before the end of the file (what another reader took is skipped).
  bool seek_to_left(std::uintmax_t n) {
    if (n > left_) return false;
    const std::uintmax_t forward = left_ - n;
    if (forward <= end_ - at_) return consume(static_cast<std::size_t>(forward)), true;
    in_->clear();
    in_->seekg(static_cast<std::streamoff>(forward - (end_ - at_)), std::ios::cur);
    at_ = end_ = 0;
    left_ = n;
    return static_cast<bool>(*in_);
  }

 private:
  bool refill(std::size_t n) {
    std::memmove(buffer_.data(), buffer_.data() + at_, end_ - at_);
    end_ -= at_;
    at_ = 0;
    in_->read(reinterpret_cast<char*>(buffer_.data() + end_),
              static_cast<std::streamsize>(buffer_.size() - end_));
    end_ += static_cast<std::size_t>(std::max<std::streamsize>(in_->gcount(), 0));
    return end_ >= n;
  }

  std::ifstream* in_;
  std::uintmax_t left_;
  std::vector<unsigned char> buffer_;
  std::size_t at_ = 0, end_ = 0;
};

template <class T>
double load(const unsigned char* p, bool swap) {
  unsigned char bytes[sizeof(T)];
  if (swap)
    std::reverse_copy(p, p + sizeof(T), bytes);
  else
    std::memcpy(bytes, p, sizeof(T));
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return static_cast<double>(v);
}

double decode(const unsigned char* p, Type t, bool swap) {
  switch (t) {
    case Type::i8:
      return load<std::int8_t>(p, false);
    case Type::u8:
      return load<std::uint8_t>(p, false);
    case Type::i16:
      return load<std::int16_t>(p, swap);
    case Type::u16:
      return load<std::uint16_t>(p, swap);
    case Type::i32:
      return load<std::int32_t>(p, swap);
    case Type::u32:
      return load<std::uint32_t>(p, swap);
    case Type::f32:
      return load<float>(p, swap);
    case Type::f64:
      return load<double>(p, swap);
  }
  return 0;
}

// The mesh as it fills: positions by vertex number, faces fan-triangulated as they come.
class Builder {
 public:
  // With `triangles`, the face element is expected to hold triangles: room for them is made
  // (and zeroed) now, while the positions are, for triangles() to fill.
  Builder(const Header& header, bool triangles) : vertices_(header.vertices) {
    const auto faces = static_cast<std::size_t>(header.faces);
    // The kernel zeroes fresh pages as they are mapped: mapped in parallel blocks first, so that
    // both threads share that, then zeroed again by the vectors (in cache-sized strides, fast).
    const std::size_t positions = 3 * static_cast<std::size_t>(header.vertices);
    mesh_.positions.reserve(positions);
    mesh_.indices.reserve(3 * faces);
    populate_in_parallel(
        {{mesh_.positions.data(), positions * sizeof(float)},
         {mesh_.indices.data(), (triangles ? 3 * faces : 0) * sizeof(std::uint32_t)}});
    tbb::parallel_invoke([&] { mesh_.positions.resize(positions); },
                         [&] {
                           if (triangles) mesh_.indices.resize(3 * faces);
                         });
    if (triangles) triangles_ = faces;
  }
  float* positions() { return mesh_.positions.data(); }
  // Room for `n` triangles at the start of the indices, when made by the constructor (else
  // nullptr); keep_triangles(k) then keeps the first k of them, and faces added later follow.
  std::uint32_t* triangles(std::uint64_t n) {
    return n <= triangles_ && mesh_.indices.size() == 3 * triangles_ ? mesh_.indices.data()
                                                                     : nullptr;
  }
  void keep_triangles(std::uint64_t k) {
    mesh_.indices.resize(3 * static_cast<std::size_t>(k));
    triangles_ = 0;
  }
  void set(std::uint64_t vertex, Role axis, double value) {
    mesh_.positions[3 * vertex + static_cast<std::size_t>(axis) -
                    static_cast<std::size_t>(Role::x)] = static_cast<float>(value);
  }
  // Adds face number `f`, whose vertex numbers are `face`; an empty string, or what is wrong.
  std::string add_face(std::uint64_t f, const std::vector<double>& face) {
    if (face.size() < 3)
      return "face " + std::to_string(f) + " has " + std::to_string(face.size()) + " vertices";
    for (const double v : face) {
      if (!(v >= 0 && v < static_cast<double>(vertices_) && v == std::floor(v)))
        return "face " + std::to_string(f) + " names vertex " + number_text(v) +
               ", but there are " + std::to_string(vertices_);
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      mesh_.indices.insert(mesh_.indices.end(), {static_cast<std::uint32_t>(face[0]),
                                                 static_cast<std::uint32_t>(face[k]),
                                                 static_cast<std::uint32_t>(face[k + 1])});
    return {};
  }
  // A triangle whose vertex numbers were checked already.
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    mesh_.indices.push_back(a);
    mesh_.indices.push_back(b);
    mesh_.indices.push_back(c);
  }
  std::uint64_t vertices() const { return vertices_; }
  Mesh take() { return std::move(mesh_); }

 private:
  static std::string number_text(double v) {
    if (v == std::floor(v) && std::abs(v) < 1e18) return std::to_string(static_cast<long long>(v));
    char text[32];
    return std::string(text, std::to_chars(text, text + sizeof text, v).ptr);
  }
  std::uint64_t vertices_;
  std::size_t triangles_ = 0;  // made room for by the constructor and not yet kept
  Mesh mesh_;
};

// Reads element `i` of `e` property by property (any types, lists anywhere); an empty string, or
// what is wrong.
std::string read_element(ByteReader& bytes, const Element& e, std::uint64_t i, bool swap,
                         Builder& mesh, std::vector<double>& face) {
  const std::string ends = "PLY file ends inside " + e.name + " element " + std::to_string(i) +
                           " of " + std::to_string(e.count) + " (truncated?)";
  for (const Property& p : e.properties) {
    if (!p.list) {
      const unsigned char* value = bytes.take(size_of(p.type));
      if (!value) return ends;
      if (p.role != Role::skip) mesh.set(i, p.role, decode(value, p.type, swap));
      continue;
    }
    const unsigned char* count = bytes.take(size_of(p.count_type));
    if (!count) return ends;
    const double n = decode(count, p.count_type, swap);
    if (n < 0 || n * static_cast<double>(size_of(p.type)) > static_cast<double>(bytes.left()))
      return "PLY body: " + e.name + " element " + std::to_string(i) + ": a list of " +
             std::to_string(static_cast<long long>(n)) +
             " items, more than the rest of the file holds";
    const auto items = static_cast<std::size_t>(n);
    if (p.role != Role::face) {
      if (!bytes.skip(items * size_of(p.type))) return ends;
      continue;
    }
    face.resize(items);
    for (double& v : face) {
      const unsigned char* item = bytes.take(size_of(p.type));
      if (!item) return ends;
      v = decode(item, p.type, swap);
    }
    if (std::string bad = mesh.add_face(i, face); !bad.empty()) return "PLY body: " + bad;
  }
  return {};
}

// An integer of type `t` (a list count or a vertex number) at `p`, as unsigned 64 bits; negative
// values come out huge.
std::uint64_t load_index(const unsigned char* p, Type t, bool swap) {
  const double v = decode(p, t, swap);
  return v >= 0 ? static_cast<std::uint64_t>(v) : std::numeric_limits<std::uint64_t>::max();
}

// Fixed-size records (no list property): whole records at a time from the buffer. Returns the
// number of elements read.
std::uint64_t read_fixed_records(ByteReader& bytes, const Element& e, std::uint64_t i, bool swap,
                                 Builder& mesh) {
  std::size_t stride = 0;
  std::array<std::pair<std::size_t, Type>, 3> axes{};  // offset and type of x, y, z
  std::array<bool, 3> has{};
  for (const Property& p : e.properties) {
    if (p.role >= Role::x && p.role <= Role::z) {
      const auto k = static_cast<std::size_t>(p.role) - static_cast<std::size_t>(Role::x);
      axes[k] = {stride, p.type};
      has[k] = true;
    }
    stride += size_of(p.type);
  }
  if (stride == 0 || stride > bytes.capacity()) return i;
  while (i < e.count) {
    const std::size_t records =
        static_cast<std::size_t>(std::min<std::uint64_t>(bytes.fill(stride) / stride, e.count - i));
    if (records == 0) break;
    const unsigned char* at = bytes.data();
    for (std::size_t r = 0; r < records; ++r, ++i, at += stride) {
      for (std::size_t k = 0; k < 3; ++k) {
        if (!has[k]) continue;
        const auto [offset, type] = axes[k];
        double value;
        if (type == Type::f32 && !swap) {
          float f;
          std::memcpy(&f, at + offset, 4);
          value = f;
        } else {
          value = decode(at + offset, type, swap);
        }
        mesh.set(i, static_cast<Role>(static_cast<std::size_t>(Role::x) + k), value);
      }
    }
    bytes.consume(records * stride);
  }
  return i;
}

// Whether a face element holds only the index list, of whole numbers: the layout read_triangles
// and read_triangles_parallel take.
bool triangle_layout(const Element& e) {
  if (e.properties.size() != 1 || e.properties[0].role != Role::face) return false;
  return e.properties[0].type != Type::f32 && e.properties[0].type != Type::f64;
}

// Vertex numbers `v` of the triangle at `p` (a record of triangle_layout), when its count is 3 and
// they name existing vertices.
bool load_triangle(const unsigned char* p, Type count_type, Type type, bool swap, bool fast_u32,
                   std::uint64_t nv, std::uint64_t v[3]) {
  if (load_index(p, count_type, swap) != 3) return false;
  const std::size_t cs = size_of(count_type), is = size_of(type);
  if (fast_u32) {
    std::uint32_t w[3];
    std::memcpy(w, p + cs, 12);
    // i32: a negative number reads as ≥ 2^31 ≥ nv.
    for (int k = 0; k < 3; ++k) v[k] = w[k];
  } else {
    for (int k = 0; k < 3; ++k) v[k] = load_index(p + cs + k * is, type, swap);
  }
  return v[0] < nv && v[1] < nv && v[2] < nv;
}

// Faces from number `i` on, while they are triangles naming vertices that exist: straight from
// the buffer. Returns the number of faces read in all; the caller reads the rest (and reports what
// is wrong with the face where this stopped) element by element.
std::uint64_t read_triangles(ByteReader& bytes, const Element& e, std::uint64_t i, bool swap,
                             Builder& mesh) {
  if (!triangle_layout(e)) return i;
  const Type count_type = e.properties[0].count_type, type = e.properties[0].type;
  const std::size_t record = size_of(count_type) + 3 * size_of(type);
  const std::uint64_t nv = mesh.vertices();
  const bool fast_u32 = !swap && (type == Type::u32 || type == Type::i32) && nv <= (1ull << 31);
  while (i < e.count) {
    const std::size_t avail = bytes.fill(std::min<std::size_t>(bytes.capacity(), 1 << 16));
    if (avail < record) break;
    const unsigned char* at = bytes.data();
    std::size_t used = 0;
    for (; i < e.count && avail - used >= record; ++i, used += record) {
      std::uint64_t v[3];
      if (!load_triangle(at + used, count_type, type, swap, fast_u32, nv, v))
        return bytes.consume(used), i;
      mesh.add_triangle(static_cast<std::uint32_t>(v[0]), static_cast<std::uint32_t>(v[1]),
                        static_cast<std::uint32_t>(v[2]));
    }
    bytes.consume(used);
  }
  return i;
}

// The file opened for pread, closed on scope exit; fd < 0 when it cannot be opened.
struct File {
  explicit File(const std::string& path) : fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {}
  ~File() {
    if (fd >= 0) ::close(fd);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  // Reads n bytes at `offset` into `to`; false on an error or a short read.
  bool read(void* to, std::size_t n, std::uintmax_t offset) const {
    auto* at = static_cast<unsigned char*>(to);
    while (n > 0) {
      const ssize_t got = ::pread(fd, at, n, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      at += got;
      n -= static_cast<std::size_t>(got);
      offset += static_cast<std::uintmax_t>(got);
    }
    return true;
  }
  int fd;
};

// Big elements are read in blocks of about this many bytes, in parallel, straight from the file:
// a block's pread and conversion stay in a core's cache.
constexpr std::size_t kParallelBlock = std::size_t{1} << 18;
using BlockBuffers = tbb::enumerable_thread_specific<std::vector<unsigned char>>;

// The vertex element (fixed-size records holding x, y, z) at `offset`, in parallel blocks: returns
// its count, or 0 when the file does not hold all its records or cannot be read (the caller then
// reads, and reports, record by record).
std::uint64_t read_vertices_parallel(const File& file, std::uintmax_t offset, std::uintmax_t size,
                                     const Element& e, bool swap, Builder& mesh) {
  std::size_t stride = 0;
  std::array<std::pair<std::size_t, Type>, 3> axes{};  // offset and type of x, y, z
  int found = 0;
  for (const Property& p : e.properties) {
    if (p.list) return 0;
    if (p.role >= Role::x && p.role <= Role::z) {
      axes[static_cast<std::size_t>(p.role) - static_cast<std::size_t>(Role::x)] = {stride, p.type};
      ++found;
    }
    stride += size_of(p.type);
  }
  if (found != 3 || e.count == 0 || e.count > (size - offset) / stride) return 0;
  // float x, y, z and nothing else, in this machine's order: the bytes are the positions.
  const bool direct = !swap && stride == 12 && axes[0] == std::pair{std::size_t{0}, Type::f32} &&
                      axes[1] == std::pair{std::size_t{4}, Type::f32} &&
                      axes[2] == std::pair{std::size_t{8}, Type::f32};
  const std::size_t per_block = std::max<std::size_t>(1, kParallelBlock / stride);
  const std::uint64_t blocks = (e.count + per_block - 1) / per_block;
  float* positions = mesh.positions();
  std::atomic<bool> failed{false};
  BlockBuffers buffers;
  tbb::parallel_for(std::uint64_t{0}, blocks, [&](std::uint64_t b) {
    const std::uint64_t first = b * per_block;
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(per_block, e.count - first));
    const std::uintmax_t at = offset + first * stride;
    if (direct) {
      if (!file.read(positions + 3 * first, 12 * n, at)) failed = true;
      return;
    }
    std::vector<unsigned char>& buffer = buffers.local();
    buffer.resize(n * stride);
    if (!file.read(buffer.data(), buffer.size(), at)) {
      failed = true;
      return;
    }
    for (std::size_t r = 0; r < n; ++r)
      for (std::size_t k = 0; k < 3; ++k)
        positions[3 * (first + r) + k] = static_cast<float>(
            decode(buffer.data() + r * stride + axes[k].first, axes[k].second, swap));
  });
  return failed ? 0 : e.count;
}

// The face element at `offset`, in parallel blocks, while its faces are triangles naming vertices
// that exist (triangle_layout): returns the number of faces read, those before the first face
// that is not such a triangle or that the file does not hold; the caller reads the rest (and
// reports what is wrong with the face where this stopped) element by element.
std::uint64_t read_triangles_parallel(const File& file, std::uintmax_t offset, std::uintmax_t size,
                                      const Element& e, bool swap, Builder& mesh) {
  if (!triangle_layout(e)) return 0;
  const Type count_type = e.properties[0].count_type, type = e.properties[0].type;
  const std::size_t record = size_of(count_type) + 3 * size_of(type);
  const std::uint64_t whole = std::min<std::uint64_t>(e.count, (size - offset) / record);
  std::uint32_t* out = mesh.triangles(whole);
  if (whole == 0 || !out) return 0;
  const std::uint64_t nv = mesh.vertices();
  const bool fast_u32 = !swap && (type == Type::u32 || type == Type::i32) && nv <= (1ull << 31);
  const std::size_t per_block = kParallelBlock / record;
  const std::uint64_t blocks = (whole + per_block - 1) / per_block;
  // Per block: its first face that is not a readable triangle, or `whole`.
  std::vector<std::uint64_t> stop(blocks, whole);
  BlockBuffers buffers;
  tbb::parallel_for(std::uint64_t{0}, blocks, [&](std::uint64_t b) {
    const std::uint64_t first = b * per_block;
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(per_block, whole - first));
    std::vector<unsigned char>& buffer = buffers.local();
    buffer.resize(n * record);
    if (!file.read(buffer.data(), buffer.size(), offset + first * record)) {
      stop[b] = first;
      return;
    }
    const unsigned char* records = buffer.data();
    if (count_type == Type::u8 && fast_u32) {  // the layout lightvol writes, without conversions
      for (std::size_t f = 0; f < n; ++f) {
        const unsigned char* r = records + f * record;
        std::uint32_t w[3];
        std::memcpy(w, r + 1, 12);
        if (r[0] != 3 || w[0] >= nv || w[1] >= nv || w[2] >= nv) {
          stop[b] = first + f;
          return;
        }
        std::memcpy(out + 3 * (first + f), w, 12);
      }
      return;
    }
    for (std::size_t f = 0; f < n; ++f) {
      std::uint64_t v[3];
      if (!load_triangle(records + f * record, count_type, type, swap, fast_u32, nv, v)) {
        stop[b] = first + f;
        return;
      }
      for (int k = 0; k < 3; ++k) out[3 * (first + f) + k] = static_cast<std::uint32_t>(v[k]);
    }
  });
  return *std::min_element(stop.begin(), stop.end());
}

// Elements at least this big (in records) are read in parallel.
constexpr std::uint64_t kParallelRecords = std::uint64_t{1} << 16;

Result<Mesh> read_binary(const std::string& path, std::uintmax_t size, const Header& header) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(header.body));
  if (!in) return Error{path + ": cannot read: " + std::strerror(errno)};
  ByteReader bytes(&in, size - header.body);
  const bool swap = header.encoding == Encoding::big_endian;
  const File file(path);
  const auto faces = std::find_if(header.elements.begin(), header.elements.end(),
                                  [](const Element& e) { return e.name == "face"; });
  const bool parallel_triangles = file.fd >= 0 && faces != header.elements.end() &&
                                  faces->count >= kParallelRecords && triangle_layout(*faces);
  Builder mesh(header, parallel_triangles);
  std::vector<double> face;
  for (const Element& e : header.elements) {
    // Big vertex and triangle elements in parallel blocks; the common layouts a record at a time
    // from the buffer; whatever they leave (another layout, a polygon, a bad index, the end of the
    // file), element by element.
    const bool fixed = std::none_of(e.properties.begin(), e.properties.end(),
                                    [](const Property& p) { return p.list; });
    std::uint64_t i = 0;
    const std::uintmax_t offset = size - bytes.left();
    if (e.name == "vertex" && fixed && file.fd >= 0 && e.count >= kParallelRecords) {
      i = read_vertices_parallel(file, offset, size, e, swap, mesh);
      std::uintmax_t stride = 0;
      for (const Property& p : e.properties) stride += size_of(p.type);
      if (!bytes.seek_to_left(size - offset - i * stride))
        return Error{path + ": cannot read: " + std::strerror(errno)};
    } else if (parallel_triangles && &e == &*faces) {
      i = read_triangles_parallel(file, offset, size, e, swap, mesh);
      mesh.keep_triangles(i);  // later faces follow these
      const std::size_t record =
          size_of(e.properties[0].count_type) + 3 * size_of(e.properties[0].type);
      if (!bytes.seek_to_left(size - offset - i * record))
        return Error{path + ": cannot read: " + std::strerror(errno)};
    }
    i = fixed ? read_fixed_records(bytes, e, i, swap, mesh)
              : read_triangles(bytes, e, i, swap, mesh);
    for (; i < e.count; ++i) {
      if (std::string bad = read_element(bytes, e, i, swap, mesh, face); !bad.empty())
        return Error{path + ": " + bad};
    }
  }
  // The last element ends the file: bytes after it are not silently dropped (they are a sign of a
  // count that is too small, or of two files joined).
  if (const std::uintmax_t after = bytes.left(); after > 0)
    return Error{path + ": " + std::to_string(after) + (after == 1 ? " byte" : " bytes") +
                 " after the last element ('" + header.elements.back().name +
                 "'), from byte offset " + std::to_string(size - after) +
                 " on: a binary PLY file ends with its last element"};
  return mesh.take();
}

// ASCII: one element a line (blank lines are skipped), its values separated by blanks.
Result<Mesh> read_ascii(const std::string& path, const Header& header) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(header.body));
  if (!in) return Error{path + ": cannot read: " + std::strerror(errno)};
  Builder mesh(header, false);
  std::string line;
  std::vector<std::string_view> words;
  std::size_t number = 0;  // body line
  std::vector<double> face;
  for (const Element& e : header.elements) {
    if (e.properties.empty()) continue;
    for (std::uint64_t i = 0; i < e.count; ++i) {
      do {
        if (!std::getline(in, line))
          return Error{path + ": PLY file ends after " + std::to_string(i) + " of " +
                       std::to_string(e.count) + " " + e.name + " elements (truncated?)"};
        ++number;
        words = split(line);
      } while (words.empty());
      const auto fail = [&](const std::string& what) -> Result<Mesh> {
        return Error{path + ": PLY body line " + std::to_string(number) + ": " + what};
      };
      std::size_t at = 0;
      for (const Property& p : e.properties) {
        double value = 0;
        if (at >= words.size())
          return fail(std::to_string(words.size()) +
                      " values, too few for the properties of element '" + e.name + "'");
        if (p.role >= Role::x && p.role <= Role::z) {
          float coordinate = 0;
          if (!parse_coordinate(words[at], &coordinate)) return fail(not_a_coordinate(words[at]));
          value = coordinate;
        } else if (!parse_number(words[at], &value)) {
          return fail(quoted(words[at]) + " is not a number");
        }
        ++at;
        if (!p.list) {
          if (p.role != Role::skip) mesh.set(i, p.role, value);
          continue;
        }
        if (!(value >= 0) || value > static_cast<double>(words.size() - at) ||
            value != std::floor(value))
          return fail("a list of " + utf8_prefix(words[at - 1], 20) + " items on a line of " +
                      std::to_string(words.size()) + " values");
        const auto items = static_cast<std::size_t>(value);
        if (p.role == Role::face) {
          face.resize(items);
          for (std::size_t k = 0; k < items; ++k)
            if (!parse_number(words[at + k], &face[k]))
              return fail(quoted(words[at + k]) + " is not a number");
          if (std::string bad = mesh.add_face(i, face); !bad.empty()) return fail(bad);
        }
        at += items;
      }
      if (at != words.size())
        return fail(std::to_string(words.size()) +
                    " values, more than the properties of element '" + e.name + "' take (" +
                    std::to_string(at) + ")");
    }
  }
  // After the last element, only blank lines (whitespace).
  while (std::getline(in, line)) {
    ++number;
    const std::size_t text = line.find_first_not_of(" \t\r\f\v");
    if (text == std::string::npos) continue;
    const std::size_t end = std::min(line.find_first_of(" \t\r\f\v", text), line.size());
    return Error{path + ": PLY body line " + std::to_string(number) +
                 ": text after the last element ('" + header.elements.back().name +
                 "'): " + quoted(std::string_view(line).substr(text, end - text)) +
                 "; an ASCII PLY file ends with its last element (blank lines aside)"};
  }
  if (in.bad()) return Error{path + ": cannot read: " + std::strerror(errno)};
  return mesh.take();
}

}  // namespace

Result<Mesh> read_ply(const std::string& path, std::uintmax_t size,
                      const std::function<Status(std::uint64_t, std::uint64_t)>& budget) {
  Result<Header> header = read_header(path, size);
  if (!header) return header.error();
  if (Status s = budget(header->vertices, header->faces); !s) return s.error();
  return header->encoding == Encoding::ascii ? read_ascii(path, *header)
                                             : read_binary(path, size, *header);
}

}  // namespace lightvol::detail

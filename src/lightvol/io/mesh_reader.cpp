#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/detail/isolated.h>
#include <lightvol/core/limits.h>
#include <lightvol/core/text.h>
#include <lightvol/io/detail/draco_mesh.h>
#include <lightvol/io/detail/glb_reader.h>
#include <lightvol/io/detail/obj_reader.h>
#include <lightvol/io/detail/ply_reader.h>
#include <lightvol/io/detail/stl_reader.h>
#include <lightvol/io/detail/text_numbers.h>
#include <lightvol/io/mesh_decode.h>
#include <lightvol/io/mesh_format.h>
#include <lightvol/io/mesh_reader.h>

namespace lightvol {
namespace {

// Asked with a file's counts (vertices, triangles) before they are allocated: MeshWork's check.
using Budget = std::function<Status(std::uint64_t, std::uint64_t)>;

namespace fs = std::filesystem;

// An OpenMesh importer that appends to the flat Mesh: no half-edge structure is built, so a
// multi-million-triangle volume reads in the memory of its two arrays. Faces are fan-triangulated;
// a face naming a vertex that was never added is remembered as the first error.
class FlatImporter final : public OpenMesh::IO::BaseImporter {
 public:
  using VH = OpenMesh::VertexHandle;
  using FH = OpenMesh::FaceHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using EH = OpenMesh::EdgeHandle;
  using Vec3f = OpenMesh::Vec3f;
  using Vec3d = OpenMesh::Vec3d;
  using StatusInfo = OpenMesh::Attributes::StatusInfo;

  // `max_elements` bounds the vertices and faces a file of its size can hold (a truncated file
  // whose header promises billions must not make the readers allocate them).
  FlatImporter(Mesh* mesh, std::size_t max_elements) : mesh_(mesh), max_elements_(max_elements) {}

  std::string error;         // the first bad face, if any
  std::size_t polygons = 0;  // faces as read, before triangulation

  VH add_vertex(const Vec3f& p) override {
    if (mesh_->num_vertices() >= max_elements_) {
      if (error.empty()) error = "more vertices than a file of this size can hold (truncated?)";
      return VH();
    }
    mesh_->positions.insert(mesh_->positions.end(), {p[0], p[1], p[2]});
    return VH(static_cast<int>(mesh_->num_vertices() - 1));
  }
  VH add_vertex(const Vec3d& p) override {
    return add_vertex(
        Vec3f(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])));
  }
  VH add_vertex() override { return add_vertex(Vec3f(0, 0, 0)); }
  void set_point(VH v, const Vec3f& p) override {
    if (v.idx() < 0 || static_cast<std::size_t>(v.idx()) >= mesh_->num_vertices()) return;
    std::copy(p.data(), p.data() + 3, &mesh_->positions[3 * static_cast<std::size_t>(v.idx())]);
  }

  FH add_face(const VHandles& vs) override {
    const std::size_t face = polygons++;
    if (face >= max_elements_) {
      if (error.empty()) error = "more faces than a file of this size can hold (truncated?)";
      return FH();
    }
    if (vs.size() < 3) {
      if (error.empty())
        error = "face " + std::to_string(face) + " has " + std::to_string(vs.size()) + " vertices";
      return FH();
    }
    // A face's vertex list takes bytes in the file too (fuzz finding, when OpenMesh read PLY: a
    // count of 32,749,287 in a 1 KB file, which OpenMesh filled in and we would have fanned out).
    if (vs.size() > max_elements_) {
      if (error.empty())
        error = "face " + std::to_string(face) + " lists " + std::to_string(vs.size()) +
                " vertices, more than a file of this size can hold (truncated or corrupt)";
      return FH();
    }
    const std::size_t nv = mesh_->num_vertices();
    for (const VH v : vs) {
      if (v.idx() < 0 || static_cast<std::size_t>(v.idx()) >= nv) {
        if (error.empty())
          error = "face " + std::to_string(face) + " names vertex " + std::to_string(v.idx()) +
                  ", but there are " + std::to_string(nv);
        return FH();
      }
    }
    for (std::size_t k = 1; k + 1 < vs.size(); ++k) {
      mesh_->indices.insert(mesh_->indices.end(), {static_cast<std::uint32_t>(vs[0].idx()),
                                                   static_cast<std::uint32_t>(vs[k].idx()),
                                                   static_cast<std::uint32_t>(vs[k + 1].idx())});
    }
    return FH(static_cast<int>(mesh_->num_triangles() - 1));
  }
  FH add_face(HH) override { return FH(); }
  HH add_edge(VH, VH) override { return HH(); }

  // Everything else a reader may offer is dropped.
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FH, VH, const std::vector<Vec3f>&) override {}
  void set_face_texindex(FH, int) override {}
  void set_halfedge(VH, HH) override {}
  void set_normal(VH, const Vec3f&) override {}
  void set_normal(VH, const Vec3d&) override {}
  void set_color(VH, const OpenMesh::Vec3uc&) override {}
  void set_color(VH, const OpenMesh::Vec4uc&) override {}
  void set_color(VH, const Vec3f&) override {}
  void set_color(VH, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VH, const OpenMesh::Vec2f&) override {}
  void set_status(VH, const StatusInfo&) override {}
  void set_next(HH, HH) override {}
  void set_face(HH, FH) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HH, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VH, const Vec3f&) override {}
  void set_texcoord(HH, const Vec3f&) override {}
  void set_status(HH, const StatusInfo&) override {}
  void set_color(EH, const OpenMesh::Vec3uc&) override {}
  void set_color(EH, const OpenMesh::Vec4uc&) override {}
  void set_color(EH, const Vec3f&) override {}
  void set_color(EH, const OpenMesh::Vec4f&) override {}
  void set_status(EH, const StatusInfo&) override {}
  void set_normal(FH, const Vec3f&) override {}
  void set_normal(FH, const Vec3d&) override {}
  void set_color(FH, const OpenMesh::Vec3uc&) override {}
  void set_color(FH, const OpenMesh::Vec4uc&) override {}
  void set_color(FH, const Vec3f&) override {}
  void set_color(FH, const OpenMesh::Vec4f&) override {}
  void set_status(FH, const StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

  bool is_triangle_mesh() const override { return false; }
  void reserve(unsigned int nv, unsigned int, unsigned int nf) override {
    // Headers can lie: reserve only what a sane file of this size could hold.
    constexpr unsigned int kCap = 1u << 26;
    mesh_->positions.reserve(3 * static_cast<std::size_t>(std::min(nv, kCap)));
    mesh_->indices.reserve(3 * static_cast<std::size_t>(std::min(nf, kCap)));
  }
  size_t n_vertices() const override { return mesh_->num_vertices(); }
  size_t n_faces() const override { return polygons; }
  size_t n_edges() const override { return 0; }

 private:
  Mesh* mesh_;
  std::size_t max_elements_;
};

// Every vertex or face takes at least 4 bytes in any of these formats ("0 0 0\n" is 6): more than
// this many elements cannot be in a file of `size` bytes.
std::size_t max_elements(std::uintmax_t size) { return static_cast<std::size_t>(size / 4 + 16); }

// The first `n` bytes of a file (fewer if it is shorter).
std::string file_head(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return head;
}

// Whether an STL file whose first bytes are `head` is binary: its size is that of the triangle
// count after its 80-byte header (as OpenMesh decides), whatever its first word.
bool stl_is_binary(const std::string& head, std::uintmax_t size) {
  if (size < 84 || head.size() < 84) return false;
  std::uint32_t n = 0;
  std::memcpy(&n, head.data() + 80, sizeof(n));
  return size == 84 + 50 * static_cast<std::uintmax_t>(n);
}

// Cheap sanity checks before reading: OFF's magic word, and STL's size arithmetic before handing
// the file to OpenMesh, whose reader trusts its input.
Status check_header(const std::string& path, MeshFormat format, std::uintmax_t size) {
  const std::string head = file_head(path, 512);
  switch (format) {
    case MeshFormat::off: {
      // The first word after blank and comment lines: the keyword ([ST][C][N][4][n]OFF), or the
      // vertex count of a file without one (the keyword is optional).
      std::size_t at = 0;
      while (at < head.size()) {
        at = head.find_first_not_of(" \t\r\n", at);
        if (at == std::string::npos || head[at] != '#') break;
        at = head.find('\n', at);
      }
      if (at == std::string::npos || at >= head.size())
        return {};  // long comments: read_off decides
      const std::size_t end = std::min(head.find_first_of(" \t\r\n#", at), head.size());
      const std::string word = head.substr(at, end - at);
      const bool keyword = word.size() >= 3 && word.compare(word.size() - 3, 3, "OFF") == 0;
      const bool count = !word.empty() && word.find_first_not_of("0123456789") == std::string::npos;
      if (!keyword && !count)
        return Error{path + ": not an OFF file (no 'OFF' keyword at its start)"};
      return {};  // read_off reads and bounds the rest
    }
    case MeshFormat::stl: {
      if (stl_is_binary(head, size)) return {};
      std::size_t first = head.find_first_not_of(" \t\r\n");
      if (first != std::string::npos && head.compare(first, 5, "solid") == 0 &&
          head.find('\0') == std::string::npos)
        return {};  // ASCII
      return Error{path +
                   ": not an STL file (binary size does not match its triangle count, and "
                   "it does not start with 'solid')"};
    }
    default:
      return {};
  }
}

// Text OFF as Geomview defines it, read here rather than by OpenMesh, whose reader trusts each
// face's vertex count: a 40-byte file with "500000000 0 1 2" took 12 GB and a minute (fuzz
// finding). '#' starts a comment anywhere (also before the keyword, as CGAL writes). An optional
// keyword [ST][C][N][4][n]OFF (nOFF: the dimension follows; only 3 makes a triangle mesh; 4: a
// homogeneous coordinate follows each vertex, which is divided by it), then "V F [E]" on its line
// or the next ones, V vertex lines (the coordinates first; normals, colours and texture
// coordinates after them are ignored), F face lines "n i1 .. in" (colours after them ignored),
// fan-triangulated. Binary OFF is refused.
// Long (over 80 lines) on purpose: a straight parse of the format (header, counts, vertices,
// faces), each step with its own message.
Result<Mesh> read_off(const std::string& path, std::uintmax_t size, const Budget& budget) {
  if (Status s = check_header(path, MeshFormat::off, size); !s) return s.error();
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  std::string line;
  std::size_t number = 0;
  // The next line with content, comments stripped; false at the end of the file.
  const auto next_line = [&](std::istringstream* words) {
    while (std::getline(in, line)) {
      ++number;
      if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      words->clear();
      words->str(line);
      return true;
    }
    return false;
  };
  const auto at_line = [&] { return path + ": OFF line " + std::to_string(number) + ": "; };
  std::istringstream words;
  if (!next_line(&words)) return Error{path + ": OFF file has no header"};
  // The header's words: the keyword's prefixes, then the numbers (dimension, counts).
  std::vector<std::string> header;
  for (std::string w; words >> w;) header.push_back(w);
  bool homogeneous = false, any_dimension = false;
  if (const std::string& keyword = header.front();
      keyword.size() >= 3 && keyword.compare(keyword.size() - 3, 3, "OFF") == 0) {
    std::string_view prefix(keyword.data(), keyword.size() - 3);
    for (std::string_view p : {"ST", "C", "N", "4", "n"})
      if (prefix.substr(0, p.size()) == p) {
        homogeneous = homogeneous || p == "4";
        any_dimension = any_dimension || p == "n";
        prefix.remove_prefix(p.size());
      }
    if (!prefix.empty())
      return Error{at_line() + "'" + utf8_prefix(keyword, 40) +
                   "' is not an OFF keyword ([ST][C][N][4][n]OFF)"};
    header.erase(header.begin());
    if (!header.empty() && header.front() == "BINARY")
      return Error{at_line() + "binary OFF is not supported; convert it to PLY"};
  } else if (keyword.find_first_not_of("0123456789") != std::string::npos) {
    return Error{at_line() + "expected the OFF keyword, got '" + utf8_prefix(keyword, 40) + "'"};
  }
  const std::size_t needed = any_dimension ? 3 : 2;
  while (header.size() < needed) {
    if (!next_line(&words)) return Error{path + ": OFF file has no vertex and face counts"};
    for (std::string w; words >> w;) header.push_back(w);
  }
  const auto integer = [&](const std::string& w, long long* out) {
    std::size_t used = 0;
    try {
      *out = std::stoll(w, &used);
    } catch (const std::exception&) {
      return false;
    }
    return used == w.size();
  };
  long long dimension = 3, nv = -1, nf = -1;
  if (any_dimension && !integer(header[0], &dimension))
    return Error{at_line() + "expected the dimension of nOFF"};
  if (dimension != 3)
    return Error{at_line() + "vertices of dimension " + utf8_prefix(header[0], 20) +
                 ": only 3-dimensional OFF makes a triangle mesh"};
  if (!integer(header[needed - 2], &nv) || !integer(header[needed - 1], &nf))
    return Error{at_line() + "expected the vertex and face counts"};
  const auto most = static_cast<long long>(max_elements(size));
  if (nv < 0 || nf < 0 || nv > most || nf > most || nv + nf > most)
    return Error{path + ": OFF header: " + std::to_string(nv) + " vertices and " +
                 std::to_string(nf) + " faces cannot fit in " + std::to_string(size) +
                 " bytes (truncated file?)"};
  if (Status s = budget(static_cast<std::uint64_t>(nv), static_cast<std::uint64_t>(nf)); !s)
    return s.error();
  Mesh mesh;
  mesh.positions.reserve(3 * static_cast<std::size_t>(nv));
  for (long long v = 0; v < nv; ++v) {
    if (!next_line(&words))
      return Error{path + ": OFF file ends after " + std::to_string(v) + " of " +
                   std::to_string(nv) + " vertices"};
    // x y z (and w): each a finite number, the point (divided by w) within a float's range.
    std::array<double, 4> xyzw{0, 0, 0, 1};
    for (int k = 0; k < (homogeneous ? 4 : 3); ++k) {
      std::string word;
      if (!(words >> word))
        return Error{at_line() +
                     (homogeneous ? "expected a vertex: x y z w" : "expected a vertex: x y z")};
      float coordinate = 0;
      if (!(homogeneous ? detail::parse_number(word, &xyzw[k]) && std::isfinite(xyzw[k])
                        : detail::parse_coordinate(word, &coordinate)))
        return Error{at_line() + detail::not_a_coordinate(word)};
      if (!homogeneous) xyzw[k] = coordinate;
    }
    if (homogeneous) {
      const double w = xyzw[3];
      if (w == 0)
        return Error{at_line() + "vertex " + std::to_string(v) +
                     " has the homogeneous coordinate 0 (a point at infinity)"};
      for (int k = 0; k < 3; ++k) {
        xyzw[k] /= w;
        if (!(std::abs(xyzw[k]) <= std::numeric_limits<float>::max()))
          return Error{at_line() + "vertex " + std::to_string(v) +
                       " divided by its homogeneous coordinate is beyond a float's range"};
      }
    }
    mesh.positions.insert(
        mesh.positions.end(),
        {static_cast<float>(xyzw[0]), static_cast<float>(xyzw[1]), static_cast<float>(xyzw[2])});
  }
  std::vector<long long> face;
  for (long long f = 0; f < nf; ++f) {
    if (!next_line(&words))
      return Error{path + ": OFF file ends after " + std::to_string(f) + " of " +
                   std::to_string(nf) + " faces"};
    long long n = 0;
    if (!(words >> n) || n < 3 || n > static_cast<long long>(line.size()))
      return Error{at_line() +
                   "expected a face: a vertex count of at least 3, then that many vertices"};
    face.resize(static_cast<std::size_t>(n));
    for (long long& i : face) {
      if (!(words >> i))
        return Error{at_line() + "face " + std::to_string(f) + " lists fewer than " +
                     std::to_string(n) + " vertices"};
      if (i < 0 || i >= nv)
        return Error{at_line() + "face " + std::to_string(f) + " names vertex " +
                     std::to_string(i) + ", but there are " + std::to_string(nv)};
    }
    for (std::size_t k = 1; k + 1 < face.size(); ++k)
      mesh.indices.insert(mesh.indices.end(),
                          {static_cast<std::uint32_t>(face[0]), static_cast<std::uint32_t>(face[k]),
                           static_cast<std::uint32_t>(face[k + 1])});
  }
  // The last face ends the file: after it, only blank lines and comments.
  if (next_line(&words)) {
    std::string word;
    words >> word;
    return Error{at_line() + "text after the last face: '" + utf8_prefix(word, 40) +
                 "'; an OFF file ends with its faces (comments and blank lines aside)"};
  }
  if (in.bad()) return Error{path + ": cannot read: " + std::strerror(errno)};
  return mesh;
}

Result<Mesh> read_with_openmesh_here(const std::string& path, std::uintmax_t size) {
  // OpenMesh chats (and complains) on its log streams; the Error says what went wrong instead.
  omlog().disable();
  omout().disable();
  omerr().disable();
  Mesh mesh;
  FlatImporter importer(&mesh, max_elements(size));
  OpenMesh::IO::Options options;
  bool read = false;
  try {
    read = OpenMesh::IO::IOManager().read(path, importer, options);
  } catch (const std::exception& e) {
    return Error{path + ": cannot read: " + e.what()};
  }
  if (!importer.error.empty()) return Error{path + ": " + importer.error};
  if (!read) return Error{path + ": cannot read: malformed or truncated file"};
  return mesh;
}

// Binary STL through OpenMesh's reader, which trusts its input: in a child process
// (core/isolated.h), with 5 s of processor time and 10 s per MiB (it parses tens of MiB a second)
// and the budget.
Result<Mesh> read_with_openmesh(const std::string& path, std::uintmax_t size) {
  IsolationLimits limits;
  limits.cpu_seconds = 5 + 10.0 * static_cast<double>(size) / (1 << 20);
  limits.wall_seconds = 10 + 4 * limits.cpu_seconds;
  limits.memory = (std::uint64_t{256} << 20) + memory_budget();
  Result<Mesh> result = Error{""};
  const Status run = run_isolated(
      path + ": OpenMesh's reader", limits,
      [&](ChildOutput& out) {
        const Result<Mesh> mesh = read_with_openmesh_here(path, size);
        if (!mesh) return out.refuse(mesh.error());
        out.accept();
        out.write_mesh(*mesh);
      },
      [&](ChildInput& in) -> Status {
        const Error broken{path + ": OpenMesh's reader broke off its answer"};
        if (Status answer; !in.read_go_on(&result, broken, &answer)) return answer;
        Mesh mesh;
        Status refused;
        if (!in.read_mesh(&mesh, path, &refused)) return refused ? Status{broken} : refused;
        result = std::move(mesh);
        return {};
      });
  if (!run) return run.error();
  return result;
}

// STL: binary by OpenMesh, ASCII by lightvol's own reader (io/detail/stl_reader.h).
Result<Mesh> read_stl(const std::string& path, std::uintmax_t size, const Budget& budget) {
  if (Status s = check_header(path, MeshFormat::stl, size); !s) return s.error();
  if (!stl_is_binary(file_head(path, 84), size)) return detail::read_stl_ascii(path);
  // Binary: (size - 84) / 50 triangles, three corners each before welding.
  const std::uint64_t triangles = (size - 84) / 50;
  if (Status s = budget(3 * triangles, triangles); !s) return s.error();
  return read_with_openmesh(path, size);
}

// DRC and GLB: the whole file in memory, decoded by Draco or read by the GLB reader.
Result<Mesh> read_draco_or_glb(const std::string& path, MeshFormat format,
                               double* quantization_step) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return Error{path + ": cannot read: " + std::strerror(errno)};
  Result<DecodedMesh> decoded = decode_mesh_bytes(bytes, format, path);
  if (!decoded) return decoded.error();
  if (quantization_step) *quantization_step = decoded->quantization_step;
  return std::move(decoded->mesh);
}

}  // namespace

Result<DecodedMesh> decode_mesh_bytes(std::string_view bytes, MeshFormat format,
                                      const std::string& what) {
  if (format != MeshFormat::drc && format != MeshFormat::glb)
    return Error{what + ": only DRC and GLB bytes are decoded in memory"};
  if (format == MeshFormat::glb && (bytes.size() < 12 || bytes.compare(0, 4, "glTF") != 0))
    return Error{what + ": not a GLB file (no 'glTF' magic)"};
  Result<detail::DracoMesh> decoded =
      format == MeshFormat::drc ? detail::decode_draco(bytes) : detail::read_glb(bytes, what);
  if (!decoded)
    return Error{format == MeshFormat::drc ? what + ": " + decoded.error().message
                                           : decoded.error().message};
  return DecodedMesh{std::move(decoded->mesh), decoded->step};
}

std::uint64_t mesh_read_bytes(std::uint64_t vertices, std::uint64_t triangles) {
  return process_base_bytes() + 24 * vertices + 12 * triangles;
}

Result<Mesh> read_mesh(const std::string& path, double* quantization_step, const MeshWork& work) {
  if (quantization_step) *quantization_step = 0;
  const Result<MeshFormat> format = mesh_format_from_path(path);
  if (!format) return format.error();
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return Error{path + ": no such file"};
  if (!fs::is_regular_file(st)) return Error{path + ": not a regular file"};
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return Error{path + ": cannot read: " + ec.message()};
  if (size == 0) return Error{path + ": empty file"};
  if (std::ifstream probe(path, std::ios::binary); !probe)
    return Error{path + ": cannot open: " + std::strerror(errno)};

  const Budget budget = [&](std::uint64_t vertices, std::uint64_t triangles) {
    const std::uint64_t bytes =
        work.bytes ? work.bytes(vertices, triangles) : mesh_read_bytes(vertices, triangles);
    return check_memory(bytes, path, work.what + " " + std::to_string(triangles) + " triangles");
  };
  Result<Mesh> mesh = (*format == MeshFormat::drc || *format == MeshFormat::glb)
                          ? read_draco_or_glb(path, *format, quantization_step)
                      : *format == MeshFormat::off ? read_off(path, size, budget)
                      : *format == MeshFormat::ply ? detail::read_ply(path, size, budget)
                      : *format == MeshFormat::obj ? detail::read_obj(path)
                                                   : read_stl(path, size, budget);
  if (!mesh) return mesh;
  // The counts read (polygons split; OBJ, ASCII STL, GLB and DRC have none before), before the
  // weld and the caller's work allocate more.
  if (Status s = budget(mesh->num_vertices(), mesh->num_triangles()); !s) return s.error();
  if (mesh->num_triangles() == 0) return Error{path + ": has no triangles"};
  if (mesh->num_vertices() >= std::numeric_limits<std::uint32_t>::max())
    return Error{path + ": has too many vertices"};
  const std::vector<float>& p = mesh->positions;
  const bool finite = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, p.size(), std::size_t{1} << 18), true,
      [&](const tbb::blocked_range<std::size_t>& r, bool ok) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) ok &= std::isfinite(p[i]);
        return ok;
      },
      [](bool x, bool y) { return x && y; });
  if (!finite) return Error{path + ": has a vertex with a non-finite coordinate"};
  return weld_identical_positions(std::move(*mesh));
}

}  // namespace lightvol

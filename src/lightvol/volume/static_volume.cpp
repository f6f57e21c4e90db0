#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <lightvol/core/buffer.h>
#include <lightvol/core/check.h>
#include <lightvol/core/light_side.h>
#include <lightvol/light/texel.h>
#include <lightvol/volume/closing.h>
#include <lightvol/volume/static_volume.h>

namespace lightvol {

VolumeCounts static_volume_counts(LightType type, int width, int height) {
  const std::uint64_t w = static_cast<std::uint64_t>(width), h = static_cast<std::uint64_t>(height);
  const std::uint64_t grid = 2 * (w - 1) * (h - 1);
  const std::uint64_t border = 2 * (w - 1) + 2 * (h - 1);
  switch (type) {
    case LightType::spot:
      return {w * h + 1, grid + border};
    case LightType::directional:
      return {w * h + border + 1, grid + 3 * border};
    case LightType::omni:
      return {6 * w * h, 6 * grid + 12 * 2 * (w - 1) + 8};
  }
  return {};
}

std::vector<std::uint32_t> border_loop(int width, int height, bool standard) {
  LV_CHECK(width >= 2 && height >= 2);
  const auto id = [&](int col, int row) {
    return static_cast<std::uint32_t>(row) * static_cast<std::uint32_t>(width) +
           static_cast<std::uint32_t>(col);
  };
  std::vector<std::uint32_t> loop;
  loop.reserve(2 * (width - 1) + 2 * (height - 1));
  for (int c = 0; c < width - 1; ++c) loop.push_back(id(c, 0));
  for (int r = 0; r < height - 1; ++r) loop.push_back(id(width - 1, r));
  for (int c = width - 1; c > 0; --c) loop.push_back(id(c, height - 1));
  for (int r = height - 1; r > 0; --r) loop.push_back(id(0, r));
  if (!standard) std::reverse(loop.begin(), loop.end());
  return loop;
}

namespace {

// The two triangles of texel quad (col c, row r) of a W-wide grid, wound to face away from the
// light.
inline void quad_triangles(std::uint32_t r, std::uint32_t c, std::uint32_t uw, bool standard,
                           std::uint32_t* out) {
  const std::uint32_t a = r * uw + c, b = a + 1, cc = a + uw, d = cc + 1;
  if (standard) {
    out[0] = a, out[1] = b, out[2] = cc, out[3] = b, out[4] = d, out[5] = cc;
  } else {
    out[0] = a, out[1] = cc, out[2] = b, out[3] = b, out[4] = cc, out[5] = d;
  }
}

// Grid triangles of quad rows [q0, q1) (two per texel quad, wound to face away from the light)
// into `out`, 6·(W − 1) indices a row, in parallel.
void grid_quad_rows(int q0, int q1, std::uint32_t uw, bool standard, std::uint32_t* out) {
  const std::size_t per_row = 6 * (std::size_t{uw} - 1);
  tbb::parallel_for(tbb::blocked_range<int>(q0, q1), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      std::uint32_t* quad = out + static_cast<std::size_t>(r - q0) * per_row;
      for (std::uint32_t c = 0; c + 1 < uw; ++c, quad += 6)
        quad_triangles(static_cast<std::uint32_t>(r), c, uw, standard, quad);
    }
  });
}

// Grid vertices of rows [r0, r1) (one per texel, on its ray at its depth) into `out`, 3·W floats
// a row, in parallel; the Error of the first texel (in row order) whose radial depth no ray
// reaches.
Status grid_rows(const Unprojector& unproject, const DepthImage& depth, int r0, int r1, float* out,
                 const std::string& source) {
  const std::size_t uw = static_cast<std::size_t>(depth.width);
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::atomic<std::size_t> first_bad{kNone};
  tbb::parallel_for(tbb::blocked_range<int>(r0, r1), [&](const tbb::blocked_range<int>& rows) {
    for (int r = rows.begin(); r != rows.end(); ++r) {
      const std::size_t row_start = static_cast<std::size_t>(r) * uw;
      const int bad_col = unproject.row_points(r, &depth.values[row_start],
                                               out + 3 * static_cast<std::size_t>(r - r0) * uw);
      if (bad_col < 0) continue;
      const std::size_t v = row_start + static_cast<std::size_t>(bad_col);
      std::size_t seen = first_bad.load();
      while (v < seen && !first_bad.compare_exchange_weak(seen, v)) {
      }
    }
  });
  const std::size_t bad = first_bad.load();
  if (bad == kNone) return {};
  return unreachable_radial_depth(source, static_cast<int>(bad % uw), static_cast<int>(bad / uw),
                                  depth.values[bad]);
}

// The grid's border loop as the closing's ring.
std::vector<BorderVertex> closing_ring(int width, int height, bool standard) {
  const auto uw = static_cast<std::uint32_t>(width);
  std::vector<BorderVertex> ring;
  for (const std::uint32_t v : border_loop(width, height, standard))
    ring.push_back({v, static_cast<int>(v % uw), static_cast<int>(v / uw)});
  return ring;
}

// The float32 guard (check_representable) judges a volume as check_volume_linear's proof from the
// light would: in the volume's frame (world, or the light's eye space with the light at the origin,
// spot and directional looking down −Z), with its tolerance, each face's own corner motion (eight
// float ulps of its corners' largest coordinate, core/light_side.h). The vertex at the light is
// known only after every vertex, so the guard runs in two passes,
// each a tally gathered vertex by vertex or face by face and merged in any order (maxima, minima
// and counts: the same numbers however the work is split): first the vertices (VertexTally), then
// the faces judged with what the vertices said (FaceJudge, FaceTally). A held mesh is read twice;
// StaticVolumeStream makes its rows twice. Both give the same verdict and message.

// The light as the guard sees it, in the volume's frame.
struct GuardLight {
  LightType type = LightType::spot;
  Vec3d position;       // the light's position in the frame
  Vec3d f;              // directional: the unit direction
  Vec3d near_origin;    // directional: a point of the near plane
  double at_light = 0;  // point lights: a vertex this close (max-norm) is at the light (4 ulps)
};

GuardLight guard_light(const Light& light, Space space) {
  GuardLight g;
  g.type = light.type;
  const bool world = space == Space::world;
  g.position = world ? light.position : Vec3d{0, 0, 0};
  if (light.type == LightType::directional) {
    g.f = normalize(world ? light.direction : Vec3d{0, 0, -1});
    g.near_origin = g.position + light.near * g.f;
  }
  g.at_light = 4 * std::ldexp(std::max({std::abs(g.position.x), std::abs(g.position.y),
                                        std::abs(g.position.z),
                                        static_cast<double>(std::numeric_limits<float>::min())}),
                              -23);
  return g;
}

// The first pass: the vertices.
struct VertexTally {
  bool finite = true;
  double largest = 0;  // the largest |coordinate|
  Vec3d lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
           std::numeric_limits<double>::max()};
  Vec3d hi{-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
           -std::numeric_limits<double>::max()};
  std::uint64_t vertices = 0;
  // Point lights: the vertices at the light (a spot volume's apex) and one of them (the one, when
  // there is one), and the squared distance from the light of the nearest other vertex.
  std::uint64_t at_light = 0;
  Vec3d apex;
  double nearest2 = std::numeric_limits<double>::infinity();

  // Adds `n` vertices (x y z floats from `xyz`), in locals the compiler keeps in registers:
  // branch-free but for the vertices at the light (the rest is of no use once a coordinate is not
  // finite: the verdict then says only that).
  void add(const float* xyz, std::size_t n, const GuardLight& g) {
    constexpr double kMax = std::numeric_limits<double>::max();
    const bool point = g.type != LightType::directional;
    bool all_finite = true;
    double big = largest, near2 = nearest2;
    double lx = lo.x, ly = lo.y, lz = lo.z, hx = hi.x, hy = hi.y, hz = hi.z;
    for (std::size_t v = 0; v < n; ++v) {
      const float* q = xyz + 3 * v;
      const double x = q[0], y = q[1], z = q[2];
      const double ax = std::abs(x), ay = std::abs(y), az = std::abs(z);
      all_finite &= ax <= kMax && ay <= kMax && az <= kMax;  // false for NaN too
      big = std::max(big, std::max(ax, std::max(ay, az)));
      lx = std::min(lx, x), ly = std::min(ly, y), lz = std::min(lz, z);
      hx = std::max(hx, x), hy = std::max(hy, y), hz = std::max(hz, z);
      if (!point) continue;
      const double dx = x - g.position.x, dy = y - g.position.y, dz = z - g.position.z;
      if (std::max(std::abs(dx), std::max(std::abs(dy), std::abs(dz))) <= g.at_light) {
        ++at_light;
        apex = {x, y, z};
      } else {
        near2 = std::min(near2, dx * dx + dy * dy + dz * dz);
      }
    }
    vertices += n;
    finite = finite && all_finite;
    largest = big, nearest2 = near2;
    lo = {lx, ly, lz}, hi = {hx, hy, hz};
  }
  void merge(const VertexTally& o) {
    finite = finite && o.finite;
    largest = std::max(largest, o.largest);
    lo = {std::min(lo.x, o.lo.x), std::min(lo.y, o.lo.y), std::min(lo.z, o.lo.z)};
    hi = {std::max(hi.x, o.hi.x), std::max(hi.y, o.hi.y), std::max(hi.z, o.hi.z)};
    vertices += o.vertices;
    if (o.at_light > 0) apex = o.apex;
    at_light += o.at_light;
    nearest2 = std::min(nearest2, o.nearest2);
  }
};

// The tally of `n` vertices (x y z floats from `xyz`), in parallel.
VertexTally tally_vertices(const float* xyz, std::size_t n, const GuardLight& g) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, std::size_t{1} << 14), VertexTally{},
      [&](const tbb::blocked_range<std::size_t>& r, VertexTally acc) {
        acc.add(xyz + 3 * r.begin(), r.size(), g);
        return acc;
      },
      [](VertexTally a, const VertexTally& b) {
        a.merge(b);
        return a;
      });
}

// How the second pass judges a face: turned towards the light, as the light proof of
// check_volume_linear decides it (check/light_proof.cpp), beyond what moving each vertex by `tol`
// could do. Point lights: the determinant of the face seen from the eye; directional: the face's
// area projected along the light, exits facing along it, the near plane's faces against it.
struct FaceJudge {
  LightType type = LightType::spot;
  Vec3d eye;  // point lights: the vertex at the light if there is exactly one, else the light
  Vec3d f, near_origin;
  double extra = 0;  // the rounding of the frame's own arithmetic (frame_motion), as the proof's

  FaceJudge(const VertexTally& v, const GuardLight& g)
      : type(g.type),
        eye(v.at_light == 1 ? v.apex : g.position),
        f(g.f),
        near_origin(g.near_origin),
        extra(g.type == LightType::directional
                  ? std::max(frame_motion(g.near_origin), frame_motion(g.position))
                  : frame_motion(eye)) {}

  // Whether face (a, b, c), of normal n = (b − a) × (c − a) (not zero), surely faces the right
  // way, from a test cheap enough for every face: nearly all of them pass it. Point lights:
  // det(a − eye, b − eye, c − eye) is (a − eye)·n, and a face where that is not negative faces
  // away (rounding moves it by some 1e-16 of its terms, the tolerance is 1e-6 of them: they could
  // only disagree for faces a billionth of a radian across, which the texel test of the verdict
  // refuses anyway). Directional: a face with a vertex off the near plane (beyond the face's
  // motion `tol`) is an exit, which faces the right way when its projected area is not negative.
  bool away(const Vec3d& a, const Vec3d& n, double tol) const {
    if (type == LightType::directional)
      return std::abs(dot(a - near_origin, f)) > tol && dot(n, f) >= 0;
    return dot(a - eye, n) >= 0;
  }

  // Whether face (a, b, c), of normal n = (b − a) × (c − a) (not zero), faces the wrong way: the
  // proof's own test (core/light_side.h), with the face's motion `tol`. A face of the vertex at
  // the eye has det 0 exactly: the proof leaves the apex's faces out.
  [[gnu::noinline]] bool turned(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& n,
                                double tol) const {
    if (type == LightType::directional) {
      const auto on_near_plane = [&](const Vec3d& p) {
        return std::abs(dot(p - near_origin, f)) <= tol;
      };
      const bool source = on_near_plane(a) && on_near_plane(b) && on_near_plane(c);
      return side_along(a, b, c, f, 0.5 * dot(n, f), source, tol) == -1;
    }
    const Vec3d pa = a - eye, pb = b - eye, pc = c - eye;
    const Vec3d bc = cross(pb, pc);
    return side_from_point(pa, pb, pc, bc, dot(pa, bc), tol) == -1;
  }
};

// What the second pass finds of a face of float corners `qa`, `qb`, `qc`.
enum class FaceFinding { sound, collapsed, turned };
inline FaceFinding judge_face(const float* qa, const float* qb, const float* qc,
                              const FaceJudge& judge) {
  const Vec3d a{qa[0], qa[1], qa[2]}, b{qb[0], qb[1], qb[2]}, c{qc[0], qc[1], qc[2]};
  const Vec3d n = cross(b - a, c - a);
  if (n.x == 0 && n.y == 0 && n.z == 0) return FaceFinding::collapsed;
  const double tol = corner_motion(a, b, c) + judge.extra;
  if (judge.away(a, n, tol) || !judge.turned(a, b, c, n, tol)) return FaceFinding::sound;
  return FaceFinding::turned;
}

// The second pass: the faces.
struct FaceTally {
  std::uint64_t triangles = 0, collapsed = 0, turned = 0;

  // Adds faces [0, n); corners(t, k) points to the x y z floats of corner k of face t. Counts in
  // locals the compiler keeps in registers.
  template <class Corners>
  void add(std::size_t n, const Corners& corners, const FaceJudge& judge) {
    std::uint64_t c = 0, t = 0;
    for (std::size_t f = 0; f < n; ++f) {
      const FaceFinding found = judge_face(corners(f, 0), corners(f, 1), corners(f, 2), judge);
      c += found == FaceFinding::collapsed;
      t += found == FaceFinding::turned;
    }
    triangles += n, collapsed += c, turned += t;
  }
  void merge(const FaceTally& o) {
    triangles += o.triangles;
    collapsed += o.collapsed;
    turned += o.turned;
  }
};

// Refusals the vertices decide alone: not finite, too large, too small.
Status vertex_verdict(const VertexTally& vertices, const Light& light,
                      const std::string& light_source);
// The whole verdict (vertex_verdict's first).
Status representable_verdict(const VertexTally& vertices, const FaceTally& faces,
                             const Light& light, Space space, const std::string& light_source);

}  // namespace

Result<Mesh> build_static_volume(const Light& light, const DepthImage& depth,
                                 const VolumeOptions& options, const std::string& source) {
  LV_CHECK(light.type != LightType::omni);
  const int w = depth.width, h = depth.height;
  LV_CHECK(w >= 2 && h >= 2);
  const Unprojector unproject(light, w, h, 0, options.space);
  const VolumeCounts counts = static_volume_counts(light.type, w, h);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});

  Mesh mesh;
  const std::size_t grid_vertices = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  reserve_large(mesh.positions, 3 * counts.vertices);
  reserve_large(mesh.indices, 3 * counts.triangles);
  mesh.positions.resize(3 * grid_vertices);
  mesh.indices.resize(6 * static_cast<std::size_t>(w - 1) * static_cast<std::size_t>(h - 1));

  if (Status s = grid_rows(unproject, depth, 0, h, mesh.positions.data(), source); !s)
    return s.error();
  const bool standard = unproject.standard_winding();
  grid_quad_rows(0, h - 1, static_cast<std::uint32_t>(w), standard, mesh.indices.data());
  // Closing: fan to the apex (spot) or walls and a cap on the near plane (directional).
  append_closing(light.type, unproject, w, h, closing_ring(w, h, standard), &mesh);
  LV_CHECK_EQ(mesh.num_vertices(), counts.vertices);
  LV_CHECK_EQ(mesh.num_triangles(), counts.triangles);
  return mesh;
}

std::vector<std::uint32_t> static_volume_indices(const Light& light, int width, int height) {
  LV_CHECK(light.type != LightType::omni);
  LV_CHECK(width >= 2 && height >= 2);
  const Unprojector unproject(light, width, height, 0, Space::world);
  const VolumeCounts counts = static_volume_counts(light.type, width, height);
  LV_CHECK_LT(counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});
  const bool standard = unproject.standard_winding();
  std::vector<std::uint32_t> indices(6 * static_cast<std::size_t>(width - 1) *
                                     static_cast<std::size_t>(height - 1));
  grid_quad_rows(0, height - 1, static_cast<std::uint32_t>(width), standard, indices.data());
  const ClosingPart closing =
      make_closing(light.type, unproject, width, height, closing_ring(width, height, standard),
                   static_cast<std::uint32_t>(width) * static_cast<std::uint32_t>(height));
  indices.insert(indices.end(), closing.indices.begin(), closing.indices.end());
  LV_CHECK_EQ(indices.size(), 3 * counts.triangles);
  return indices;
}

Status check_representable(const Mesh& mesh, const Light& light, Space space,
                           const std::string& light_source) {
  const GuardLight guard = guard_light(light, space);
  const VertexTally vertices = tally_vertices(mesh.positions.data(), mesh.num_vertices(), guard);
  if (Status s = vertex_verdict(vertices, light, light_source); !s) return s;
  const FaceJudge judge(vertices, guard);
  const float* p = mesh.positions.data();
  const FaceTally faces = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.num_triangles(), std::size_t{1} << 14), FaceTally{},
      [&](const tbb::blocked_range<std::size_t>& r, FaceTally acc) {
        const std::uint32_t* first = mesh.indices.data() + 3 * r.begin();
        acc.add(
            r.size(), [&](std::size_t t, int k) { return p + 3 * std::size_t{first[3 * t + k]}; },
            judge);
        return acc;
      },
      [](FaceTally a, const FaceTally& b) {
        a.merge(b);
        return a;
      });
  return representable_verdict(vertices, faces, light, space, light_source);
}

namespace {

std::string shown(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

std::string frustum_keys(const Light& light) {
  return light.type == LightType::spot   ? "keys 'near', 'far' and 'fov_y_deg'"
         : light.type == LightType::omni ? "keys 'near' and 'far'"
                                         : "keys 'ortho', 'near' and 'far'";
}

Status vertex_verdict(const VertexTally& vertices, const Light& light,
                      const std::string& light_source) {
  constexpr double kLargest = 1e18;  // squares stay below float's 3.4e38
  if (!vertices.finite)
    return Error{light_source + ": " + frustum_keys(light) +
                 ": the volume's vertices are not finite numbers (near " + shown(light.near) +
                 ", far " + shown(light.far) +
                 ": more than double precision holds); bring far closer to near"};
  if (vertices.largest > kLargest)
    return Error{light_source + ": " + frustum_keys(light) + ": the volume reaches coordinate " +
                 shown(vertices.largest) + "; float32 meshes need coordinates below " +
                 shown(kLargest) + " (choose the scene's units so that the frustum is smaller)"};
  const Vec3d span = vertices.hi - vertices.lo;
  const double across = std::max({span.x, span.y, span.z});
  // The checks form areas and volumes in float: a volume smaller than this underflows them.
  constexpr double kSmallest = 1e-12;
  if (across < kSmallest)
    return Error{light_source + ": " + frustum_keys(light) + ": the volume is " + shown(across) +
                 " across; float32 meshes and their checks need at least " + shown(kSmallest) +
                 " (choose the scene's units, or near and far, so that it is larger)"};
  return {};
}

Status representable_verdict(const VertexTally& vertices, const FaceTally& faces,
                             const Light& light, Space space, const std::string& light_source) {
  if (Status s = vertex_verdict(vertices, light, light_source); !s) return s;
  const double largest = vertices.largest;
  // The float step judged against a texel is that of the largest coordinate, the light's
  // position's included: a directional light far behind its near plane is refused however small
  // the volume's own coordinates are (where its faces would be placed is as coarse as that).
  const GuardLight guard = guard_light(light, space);
  const double light_largest = std::max(
      {std::abs(guard.position.x), std::abs(guard.position.y), std::abs(guard.position.z)});
  const double max_abs = std::max(largest, light_largest);
  // Faces the proof accepts may still be too fine for float32 to place where they belong, which
  // the apex's cone and the proof's sums then notice: float steps at those coordinates against the
  // spacing of the faces across the light's rays, about a texel (the light's field over the square
  // root of the vertex count per map). Point lights: the angle a step subtends at the vertex
  // nearest the light against a texel's angle; directional: the step against a texel's width in
  // the ortho extents. Steps coarser than a sixteenth of that refuse the volume (a spot far from
  // the origin, a fov of 1e-6 degrees); a thin but wide box (8193 wide, 1 deep) is fine.
  const double step = max_abs * std::numeric_limits<float>::epsilon();
  const double maps = light.type == LightType::omni ? double(kOmniFaces) : 1.0;
  const double texels_across = std::sqrt(std::max(1.0, double(vertices.vertices) / maps));
  const double px = std::abs(light.projection(0, 0)), py = std::abs(light.projection(1, 1));
  double ratio = 0;  // a float step over a texel's spacing
  if (light.type == LightType::directional) {
    ratio = step / (std::min(2 / px, 2 / py) / texels_across);
  } else if (std::isfinite(vertices.nearest2)) {
    const double field = light.type == LightType::omni
                             ? std::numbers::pi / 2
                             : std::min(2 * std::atan(1 / px), 2 * std::atan(1 / py));
    ratio = (step / std::sqrt(vertices.nearest2)) / (field / texels_across);
  }
  const bool coarse = ratio > 1.0 / 16;
  if (faces.collapsed == 0 && faces.turned == 0 && !coarse) return {};
  const Vec3d extent = vertices.hi - vertices.lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  std::string what =
      light_source + ": float32 cannot hold this volume (coordinates up to " + shown(largest) +
      (light_largest > largest ? ", the light's position up to " + shown(light_largest)
                               : std::string()) +
      ", steps of " + shown(step) + ", " + shown(ratio) + " of a texel's spacing; " +
      std::to_string(faces.collapsed) + " of " + std::to_string(faces.triangles) +
      " faces collapse to zero area, " + std::to_string(faces.turned) + " face the light)";

  // A directional light's volume begins `near` from its position, in either frame: far for the
  // volume's size, only moving the position closer helps.
  if (light.type == LightType::directional && light.near > 100 * size)
    return Error{what + ": keys 'position' and 'near': the volume begins " + shown(light.near) +
                 " from the light's position, far for its size " + shown(size) +
                 "; move the position along the light's direction towards the volume and reduce "
                 "near and far by as much"};
  if (space == Space::world && largest > 100 * size)
    return Error{what + ": key 'position': the light is far from the origin for the volume's " +
                 "size " + shown(size) +
                 "; write it in the light's eye space with --space light and place it with the "
                 "light's view matrix"};
  return Error{what + ": " + frustum_keys(light) +
               ": the frustum is too thin, or far/near too large, for float32; widen it or bring "
               "near and far closer"};
}

}  // namespace

struct StaticVolumeStream::State {
  const Light& light;
  const DepthImage& depth;
  Unprojector unproject;
  std::string source, light_source;
  Space space;
  VolumeCounts counts;
  ClosingPart closing;  // made by positions()
};

StaticVolumeStream::StaticVolumeStream(const Light& light, const DepthImage& depth,
                                       const VolumeOptions& options, std::string source,
                                       std::string light_source) {
  LV_CHECK(light.type != LightType::omni);
  LV_CHECK(depth.width >= 2 && depth.height >= 2);
  state_.reset(new State{light,
                         depth,
                         Unprojector(light, depth.width, depth.height, 0, options.space),
                         std::move(source),
                         std::move(light_source),
                         options.space,
                         static_volume_counts(light.type, depth.width, depth.height),
                         {}});
  LV_CHECK_LT(state_->counts.vertices, std::uint64_t{std::numeric_limits<std::uint32_t>::max()});
}

StaticVolumeStream::~StaticVolumeStream() = default;

std::uint64_t StaticVolumeStream::num_vertices() const { return state_->counts.vertices; }
std::uint64_t StaticVolumeStream::num_triangles() const { return state_->counts.triangles; }

// Long (over 80 lines) on purpose: two passes over blocks of rows. The first makes each block's
// vertices and tallies them for the float32 guard (its faces' tolerance needs the largest
// coordinate, known only after every vertex); the second makes them again, hands them on, judges
// the grid triangles they complete (with the row before) and sums the volume; the border rows and
// columns are kept for the closing.
Status StaticVolumeStream::positions(const PositionSink& sink) {
  State& st = *state_;
  const int w = st.depth.width, h = st.depth.height;
  const std::size_t uw = static_cast<std::size_t>(w);
  const bool standard = st.unproject.standard_winding();
  const std::size_t grid_vertices = uw * static_cast<std::size_t>(h);
  const std::size_t quad_triangles_per_row = 2 * (uw - 1);
  const int block_rows = std::clamp(static_cast<int>((std::size_t{1} << 18) / uw), 1, h);
  std::vector<float> buffer(3 * uw * (static_cast<std::size_t>(block_rows) + 1));
  const GuardLight guard = guard_light(st.light, st.space);
  // The closing: its vertices after the grid's, its triangles after the grid's (it needs none of
  // the grid's positions).
  st.closing = make_closing(st.light.type, st.unproject, w, h, closing_ring(w, h, standard),
                            static_cast<std::uint32_t>(grid_vertices));
  const std::size_t closing_vertices = st.closing.positions.size() / 3;

  // First pass: the vertices' tally; each block's rows made and dropped.
  VertexTally vertices;
  for (int r0 = 0; r0 < h; r0 += block_rows) {
    const int r1 = std::min(h, r0 + block_rows);
    if (Status s = grid_rows(st.unproject, st.depth, r0, r1, buffer.data(), st.source); !s)
      return s;
    vertices.merge(tally_vertices(buffer.data(), static_cast<std::size_t>(r1 - r0) * uw, guard));
  }
  vertices.merge(tally_vertices(st.closing.positions.data(), closing_vertices, guard));
  LV_CHECK_EQ(vertices.vertices, st.counts.vertices);
  if (Status s = vertex_verdict(vertices, st.light, st.light_source); !s) return s;
  const FaceJudge judge(vertices, guard);

  // Second pass: the same rows, handed on, their faces judged and summed.
  // The border: rows 0 and H−1, columns 0 and W−1 (for the closing's triangles).
  std::vector<float> top(3 * uw), bottom(3 * uw), left(3 * static_cast<std::size_t>(h)),
      right(3 * static_cast<std::size_t>(h));
  FaceTally faces;
  SignedVolumeSum volume(st.counts.triangles);
  bool have_previous = false;
  for (int r0 = 0; r0 < h; r0 += block_rows) {
    const int r1 = std::min(h, r0 + block_rows);
    const int first_row = have_previous ? r0 - 1 : r0;  // the buffer's first row
    float* fresh = buffer.data() + (have_previous ? 3 * uw : 0);
    if (Status s = grid_rows(st.unproject, st.depth, r0, r1, fresh, st.source); !s) return s;
    // Then (every row of the block made) the tally of the quad rows ending in it: quad row r − 1
    // (rows r − 1 and r) for each row r of the block but row 0.
    const FaceTally block = tbb::parallel_reduce(
        tbb::blocked_range<int>(std::max(r0, 1), r1), FaceTally{},
        [&](const tbb::blocked_range<int>& rows, FaceTally acc) {
          for (int r = rows.begin(); r != rows.end(); ++r) {
            const float* out = fresh + 3 * static_cast<std::size_t>(r - r0) * uw;
            const float* above = out - 3 * uw;
            // The quads' corners in rows 0 (above) and 1 (out), the same for every quad but for
            // its column.
            std::uint32_t tri[6];
            quad_triangles(0, 0, static_cast<std::uint32_t>(uw), standard, tri);
            const float* corner[6];
            for (int k = 0; k < 6; ++k)
              corner[k] = tri[k] >= uw ? out + 3 * (tri[k] - uw) : above + 3 * std::size_t{tri[k]};
            std::uint64_t collapsed = 0, turned = 0;
            for (std::size_t c = 0; c + 1 < uw; ++c) {
              const std::size_t o = 3 * c;
              for (int i = 0; i < 2; ++i) {
                const FaceFinding found = judge_face(corner[3 * i] + o, corner[3 * i + 1] + o,
                                                     corner[3 * i + 2] + o, judge);
                collapsed += found == FaceFinding::collapsed;
                turned += found == FaceFinding::turned;
              }
            }
            acc.triangles += 2 * (uw - 1), acc.collapsed += collapsed, acc.turned += turned;
          }
          return acc;
        },
        [](FaceTally a, const FaceTally& b) {
          a.merge(b);
          return a;
        });
    faces.merge(block);
    if (!sink(fresh, static_cast<std::size_t>(r1 - r0) * uw)) return {};
    // The volume's sum takes the grid triangles in order: quad rows [first_row, r1 − 1).
    const auto row_of = [&](std::size_t v) {
      return buffer.data() + 3 * (v - static_cast<std::size_t>(first_row) * uw);
    };
    const std::size_t t_begin = static_cast<std::size_t>(first_row) * quad_triangles_per_row;
    const std::size_t t_end = static_cast<std::size_t>(r1 - 1) * quad_triangles_per_row;
    volume.add(t_begin, t_end - t_begin, [&](std::size_t t, int k) {
      const std::size_t q = t / quad_triangles_per_row, c = (t % quad_triangles_per_row) / 2;
      std::uint32_t tri[6];
      quad_triangles(static_cast<std::uint32_t>(q), static_cast<std::uint32_t>(c),
                     static_cast<std::uint32_t>(uw), standard, tri);
      return row_of(tri[3 * (t % 2) + static_cast<std::size_t>(k)]);
    });
    for (int r = r0; r < r1; ++r) {
      const float* row = fresh + 3 * static_cast<std::size_t>(r - r0) * uw;
      if (r == 0) std::copy(row, row + 3 * uw, top.begin());
      if (r == h - 1) std::copy(row, row + 3 * uw, bottom.begin());
      std::copy(row, row + 3, left.begin() + 3 * r);
      std::copy(row + 3 * (uw - 1), row + 3 * uw, right.begin() + 3 * r);
    }
    // Keep the last row for the next block's first quad row.
    std::copy(fresh + 3 * static_cast<std::size_t>(r1 - 1 - r0) * uw,
              fresh + 3 * static_cast<std::size_t>(r1 - r0) * uw, buffer.begin());
    have_previous = true;
  }

  if (!sink(st.closing.positions.data(), closing_vertices)) return {};
  const auto position = [&](std::uint32_t v) -> const float* {
    if (v >= grid_vertices) return &st.closing.positions[3 * (v - grid_vertices)];
    const std::size_t col = v % uw, row = v / uw;
    if (row == 0) return &top[3 * col];
    if (row + 1 == static_cast<std::size_t>(h)) return &bottom[3 * col];
    return col == 0 ? &left[3 * row] : &right[3 * row];
  };
  const std::vector<std::uint32_t>& ci = st.closing.indices;
  faces.add(
      ci.size() / 3, [&](std::size_t t, int k) { return position(ci[3 * t + k]); }, judge);
  const std::size_t grid_triangles = static_cast<std::size_t>(h - 1) * quad_triangles_per_row;
  volume.add(grid_triangles, ci.size() / 3,
             [&](std::size_t t, int k) { return position(ci[3 * (t - grid_triangles) + k]); });
  LV_CHECK_EQ(faces.triangles, st.counts.triangles);
  if (Status s = representable_verdict(vertices, faces, st.light, st.space, st.light_source); !s)
    return s;
  for (int k = 0; k < 3; ++k) {
    bounds_.min[k] = vertices.lo[k];
    bounds_.max[k] = vertices.hi[k];
  }
  volume_ = volume.volume();
  return {};
}

Status StaticVolumeStream::triangles(const TriangleSink& sink) {
  const State& st = *state_;
  const int w = st.depth.width, h = st.depth.height;
  const std::uint32_t uw = static_cast<std::uint32_t>(w);
  const bool standard = st.unproject.standard_winding();
  const std::size_t per_row = 6 * (static_cast<std::size_t>(w) - 1);
  const int block_rows = std::clamp(static_cast<int>((std::size_t{1} << 18) / uw), 1, h);
  std::vector<std::uint32_t> buffer(per_row * static_cast<std::size_t>(block_rows));
  for (int q0 = 0; q0 < h - 1; q0 += block_rows) {
    const int q1 = std::min(h - 1, q0 + block_rows);
    grid_quad_rows(q0, q1, uw, standard, buffer.data());
    if (!sink(buffer.data(), static_cast<std::size_t>(q1 - q0) * per_row / 3)) return {};
  }
  sink(st.closing.indices.data(), st.closing.indices.size() / 3);
  return {};
}

}  // namespace lightvol

// lightvol's self-intersection and bounds-a-volume tests (exact_checks.h). CGAL's kernel gives
// the predicates (filtered: floating point first, exact arithmetic when that cannot decide);
// everything else (the mesh's structure, the broad phase) is plain data in flat arrays, in
// parallel with TBB.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Intersections_3/Segment_3_Triangle_3.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <lightvol/check/detail/exact_checks.h>
#include <lightvol/core/check.h>

namespace lightvol::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Pair = std::pair<std::uint32_t, std::uint32_t>;
using Tri = std::array<std::uint32_t, 3>;

constexpr std::size_t kMaxPairs = 10000;
constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// ---- The mesh as flat arrays
// ---------------------------------------------------------------------

struct Box {
  float lo[3], hi[3];
  static Box empty() {
    constexpr float inf = std::numeric_limits<float>::infinity();
    return {{inf, inf, inf}, {-inf, -inf, -inf}};
  }
  void add(const Box& b) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b.lo[k]), hi[k] = std::max(hi[k], b.hi[k]);
  }
  // Closed boxes: touching counts.
  bool overlaps(const Box& b) const {
    return lo[0] <= b.hi[0] && b.lo[0] <= hi[0] && lo[1] <= b.hi[1] && b.lo[1] <= hi[1] &&
           lo[2] <= b.hi[2] && b.lo[2] <= hi[2];
  }
};

struct Geometry {
  const float* pos;
  const std::uint32_t* idx;
  Tri tri(std::size_t f) const { return {idx[3 * f], idx[3 * f + 1], idx[3 * f + 2]}; }
  Point point(std::uint32_t v) const { return Point(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]); }
  Box box(std::size_t f) const {
    Box b;
    const float* a = pos + 3 * std::size_t{idx[3 * f]};
    const float* c = pos + 3 * std::size_t{idx[3 * f + 1]};
    const float* d = pos + 3 * std::size_t{idx[3 * f + 2]};
    for (int k = 0; k < 3; ++k) {
      b.lo[k] = std::min({a[k], c[k], d[k]});
      b.hi[k] = std::max({a[k], c[k], d[k]});
    }
    return b;
  }
  std::array<std::array<double, 3>, 3> corners(std::size_t f) const {
    std::array<std::array<double, 3>, 3> t;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) t[i][k] = pos[3 * std::size_t{idx[3 * f + i]} + k];
    return t;
  }
};

// An allocator whose resize leaves new elements uninitialized (every one is written before it is
// read): large arrays are not zeroed first.
template <class T>
struct NoInit : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = NoInit<U>;
  };
  NoInit() = default;
  template <class U>
  NoInit(const NoInit<U>&) {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

// Faces around each vertex, in face order (compressed rows).
struct VertexFaces {
  std::vector<std::uint32_t> first;  // nv + 1
  std::vector<std::uint32_t, NoInit<std::uint32_t>> faces;
  std::size_t degree(std::uint32_t v) const { return first[v + 1] - first[v]; }
};

VertexFaces vertex_faces(const Geometry& g, std::size_t nv, std::size_t nt) {
  VertexFaces vf;
  std::vector<std::atomic<std::uint32_t>> count(nv + 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, 3 * nt, 1 << 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        count[g.idx[k]].fetch_add(1, std::memory_order_relaxed);
                    });
  vf.first.resize(nv + 1);
  std::uint32_t sum = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    vf.first[v] = sum;
    sum += count[v].load(std::memory_order_relaxed);
    count[v].store(vf.first[v], std::memory_order_relaxed);
  }
  vf.first[nv] = sum;
  vf.faces.resize(sum);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, 3 * nt, 1 << 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        vf.faces[count[g.idx[k]].fetch_add(1, std::memory_order_relaxed)] =
                            static_cast<std::uint32_t>(k / 3);
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 12),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v)
                        std::sort(vf.faces.begin() + vf.first[v],
                                  vf.faces.begin() + vf.first[v + 1]);
                    });
  return vf;
}

// Are the faces around v one fan (connected through the edges at v)? The mesh is edge-manifold
// and oriented, so each face (v, x, y) links x to y and every neighbour starts and ends at most
// one link: walk forward from the first face, then backward, and count.
// Up to this degree, the fans around a vertex are walked in arrays on the stack (linear searches).
constexpr std::size_t kSmallFan = 32;

// The faces around v (degree d ≤ kSmallFan) as links (x, y): face (v, x, y).
void fan_links(const Geometry& g, const std::uint32_t* faces, std::size_t d, std::uint32_t v,
               std::uint32_t (*links)[2]) {
  for (std::size_t i = 0; i < d; ++i) {
    const Tri t = g.tri(faces[i]);
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    links[i][0] = t[(k + 1) % 3];
    links[i][1] = t[(k + 2) % 3];
  }
}

// The first slot (in face order) whose link's end `side` (0: x, 1: y) is `key`, or kNone.
std::uint32_t find_link(const std::uint32_t (*links)[2], std::size_t d, int side,
                        std::uint32_t key) {
  for (std::size_t i = 0; i < d; ++i)
    if (links[i][side] == key) return static_cast<std::uint32_t>(i);
  return kNone;
}

bool one_fan(const Geometry& g, const VertexFaces& vf, std::uint32_t v) {
  const std::uint32_t* begin = vf.faces.data() + vf.first[v];
  const std::size_t d = vf.degree(v);
  if (d <= 1) return true;
  if (d <= kSmallFan) {  // the same walks as below, on the stack
    std::uint32_t links[kSmallFan][2];
    fan_links(g, begin, d, v, links);
    std::size_t seen = 1;
    std::uint32_t i = 0;
    for (;;) {
      const std::uint32_t next = find_link(links, d, 0, links[i][1]);
      if (next == kNone || next == 0 || seen > d) break;
      ++seen, i = next;
    }
    if (seen < d) {
      i = 0;
      for (;;) {
        const std::uint32_t prev = find_link(links, d, 1, links[i][0]);
        if (prev == kNone || prev == 0 || seen > d) break;
        ++seen, i = prev;
      }
    }
    return seen == d;
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> links(d);  // (x, y) of each face
  for (std::size_t i = 0; i < d; ++i) {
    const Tri t = g.tri(begin[i]);
    const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
    links[i] = {t[(k + 1) % 3], t[(k + 2) % 3]};
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> by_x(d);  // (x, face slot)
  for (std::size_t i = 0; i < d; ++i) by_x[i] = {links[i].first, static_cast<std::uint32_t>(i)};
  std::sort(by_x.begin(), by_x.end());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> by_y(d);
  for (std::size_t i = 0; i < d; ++i) by_y[i] = {links[i].second, static_cast<std::uint32_t>(i)};
  std::sort(by_y.begin(), by_y.end());
  const auto find = [](const std::vector<std::pair<std::uint32_t, std::uint32_t>>& list,
                       std::uint32_t key) {
    const auto it =
        std::lower_bound(list.begin(), list.end(), std::pair<std::uint32_t, std::uint32_t>{key, 0});
    return it != list.end() && it->first == key ? it->second : kNone;
  };
  std::size_t seen = 1;
  std::uint32_t i = 0;
  for (;;) {  // forward: the face whose x is this face's y
    const std::uint32_t next = find(by_x, links[i].second);
    if (next == kNone || next == 0 || seen > d) break;
    ++seen, i = next;
  }
  if (seen < d) {
    i = 0;
    for (;;) {  // backward: the face whose y is this face's x
      const std::uint32_t prev = find(by_y, links[i].first);
      if (prev == kNone || prev == 0 || seen > d) break;
      ++seen, i = prev;
    }
  }
  return seen == d;
}

// Is the star of v (its faces) embedded, so that any two of its faces meet only along the edge or
// at the vertex they share? Sufficient (exact) condition: the faces around v make one closed fan
// (v, a_0, a_1), (v, a_1, a_2), …, (v, a_{d-1}, a_0) whose projections along some direction n are
// triangles of one orientation winding once around v. The projection is then one-to-one on the
// star (the triangles lie in the wedges between the rays to a_i, which cover the plane once), so
// faces meet only where their projections do: along a shared edge or at v. Each projected
// orientation is the exact orientation of (v, a_i, a_{i+1}, v + n); n (the fan's area normal, in
// floating point) only chooses the direction. Winding once: no step from a_i to a_{i+1}
// (0 < i < d - 1) passes a_0's ray, and no a_i (i > 0) lies on it. False when undecided (large or
// open fans, a face repeating a vertex, neighbours collinear in projection other than opposite):
// the pairs around v are then tested one by one.
bool flat_star(const Geometry& g, const VertexFaces& vf, std::uint32_t v) {
  const std::size_t d = vf.degree(v);
  if (d < 3 || d > kSmallFan) return false;
  std::uint32_t links[kSmallFan][2];
  fan_links(g, vf.faces.data() + vf.first[v], d, v, links);
  std::uint32_t ring[kSmallFan];  // a_0, a_1, … in fan order
  std::uint32_t i = 0;
  for (std::size_t k = 0; k < d; ++k) {
    if (links[i][0] == v || links[i][1] == v || links[i][0] == links[i][1]) return false;
    ring[k] = links[i][0];
    const std::uint32_t next = find_link(links, d, 0, links[i][1]);
    if (next == kNone || (next == 0) != (k + 1 == d)) return false;
    i = next;
  }
  const float* pv = g.pos + 3 * std::size_t{v};
  double rel[kSmallFan][3];
  double scale = 0;
  for (std::size_t k = 0; k < d; ++k) {
    const float* pa = g.pos + 3 * std::size_t{ring[k]};
    for (int c = 0; c < 3; ++c) rel[k][c] = double{pa[c]} - pv[c];
    scale = std::max({scale, std::abs(rel[k][0]), std::abs(rel[k][1]), std::abs(rel[k][2])});
  }
  double n[3] = {0, 0, 0};
  for (std::size_t k = 0; k < d; ++k) {
    const double* a = rel[k];
    const double* b = rel[(k + 1) % d];
    n[0] += a[1] * b[2] - a[2] * b[1];
    n[1] += a[2] * b[0] - a[0] * b[2];
    n[2] += a[0] * b[1] - a[1] * b[0];
  }
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0) || !(scale > 0) || !std::isfinite(len)) return false;
  const Point pt = g.point(v);
  const Point up(pt.x() + n[0] / len * scale, pt.y() + n[1] / len * scale,
                 pt.z() + n[2] / len * scale);
  Point a[kSmallFan];
  for (std::size_t k = 0; k < d; ++k) a[k] = g.point(ring[k]);
  const CGAL::Orientation side = CGAL::orientation(pt, a[0], a[1], up);
  if (side == CGAL::COPLANAR) return false;
  for (std::size_t k = 1; k < d; ++k)
    if (CGAL::orientation(pt, a[k], a[(k + 1) % d], up) != side) return false;
  // Opposite in projection (a_k collinear with v and a_0 in projection, on the other side of v):
  // a clear negative dot product of the projected directions; anything else is refused.
  const double nx = n[0] / len, ny = n[1] / len, nz = n[2] / len;
  const auto opposite = [&](std::size_t k) {
    const double* p = rel[0];
    const double* q = rel[k];
    const double pn = p[0] * nx + p[1] * ny + p[2] * nz, qn = q[0] * nx + q[1] * ny + q[2] * nz;
    const double px = p[0] - pn * nx, py = p[1] - pn * ny, pz = p[2] - pn * nz;
    const double qx = q[0] - qn * nx, qy = q[1] - qn * ny, qz = q[2] - qn * nz;
    const double dot = px * qx + py * qy + pz * qz;
    const double pp = std::sqrt(px * px + py * py + pz * pz),
                 qq = std::sqrt(qx * qx + qy * qy + qz * qz);
    return dot < -0.5 * pp * qq;
  };
  // o[k]: orientation of (v, a_0, a_k, up), for 0 < k < d.
  CGAL::Orientation o[kSmallFan];
  for (std::size_t k = 1; k < d; ++k) {
    o[k] = CGAL::orientation(pt, a[0], a[k], up);
    if (o[k] == CGAL::COPLANAR && !opposite(k)) return false;
  }
  // The step a_k → a_{k+1} passes a_0's ray when a_0 lies strictly inside the wedge:
  // orientation(v, a_k, a_0) = side and orientation(v, a_0, a_{k+1}) = side.
  for (std::size_t k = 1; k + 1 < d; ++k)
    if (o[k] == -side && o[k + 1] == side) return false;
  return true;
}

// ---- The exact pair test (CGAL's do_faces_intersect, on vertex indices) -------------------------

bool segment_meets_triangle(const Point& a, const Point& b, const Point& c, const Point& p,
                            const Point& q) {
  // Both ends strictly on one side of the plane: apart. Otherwise CGAL's full test.
  const CGAL::Orientation op = CGAL::orientation(a, b, c, p);
  if (op != CGAL::COPLANAR && op == CGAL::orientation(a, b, c, q)) return false;
  return CGAL::do_intersect(Kernel::Triangle_3(a, b, c), Kernel::Segment_3(p, q));
}

bool all_on_one_side(const Point& a, const Point& b, const Point& c, const Point& p, const Point& q,
                     const Point& r) {
  const CGAL::Orientation o = CGAL::orientation(a, b, c, p);
  return o != CGAL::COPLANAR && o == CGAL::orientation(a, b, c, q) &&
         o == CGAL::orientation(a, b, c, r);
}

// A point off the faces' planes, for separating planes through an edge of one of them: `p` moved
// along the sum of the two faces' unit normals (computed in floating point: any point serves, the
// predicates below being exact; a well-placed one lets their fast filter decide). Near-coplanar
// neighbours (a flat region, the wall a depth step makes) are where the planes of the faces
// themselves are useless: the exact orientations of their vertices are zero or nearly so.
struct Lift {
  double x, y, z;
};

Lift lift(const Point* f, const Point* g) {
  const auto normal = [](const Point* t) {
    const double ux = t[1].x() - t[0].x(), uy = t[1].y() - t[0].y(), uz = t[1].z() - t[0].z();
    const double vx = t[2].x() - t[0].x(), vy = t[2].y() - t[0].y(), vz = t[2].z() - t[0].z();
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double n = std::sqrt(nx * nx + ny * ny + nz * nz);
    const double len = std::sqrt(ux * ux + uy * uy + uz * uz);
    return n > 0 ? Lift{nx / n * len, ny / n * len, nz / n * len} : Lift{0, 0, 0};
  };
  const Lift a = normal(f), b = normal(g);
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}

Point lifted(const Point& p, const Lift& n) { return Point(p.x() + n.x, p.y() + n.y, p.z() + n.z); }

// The plane through p, q and p + n has every point of `ours` strictly on one side and every point
// of `theirs` strictly on the other (exact orientations).
bool splits(const Point& p, const Point& q, const Point& up, std::initializer_list<Point> ours,
            std::initializer_list<Point> theirs) {
  CGAL::Orientation side = CGAL::COPLANAR;
  for (const Point& x : ours) {
    const CGAL::Orientation o = CGAL::orientation(p, q, up, x);
    if (o == CGAL::COPLANAR || (side != CGAL::COPLANAR && o != side)) return false;
    side = o;
  }
  for (const Point& x : theirs)
    if (CGAL::orientation(p, q, up, x) != -side) return false;
  return true;
}

// Faces f and g (neither degenerate) intersect other than along the edge or vertex they share
// (CGAL's do_faces_intersect). Separating planes through an edge decide most pairs cheaply and
// exactly; CGAL's own tests decide the rest.
bool faces_intersect(const Geometry& geo, std::uint32_t f, std::uint32_t g) {
  const Tri t = geo.tri(f), u = geo.tri(g);
  int shared = 0;
  int fi = -1, gj = -1;  // the first shared vertex, in CGAL's order
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (t[i] == u[j]) {
        ++shared;
        if (fi < 0) fi = i, gj = j;
      }
  const Point tp[3] = {geo.point(t[0]), geo.point(t[1]), geo.point(t[2])};
  const Point up[3] = {geo.point(u[0]), geo.point(u[1]), geo.point(u[2])};
  const Lift n = lift(tp, up);
  if (shared >= 2) {
    // A shared edge p→q of f that g holds as q→p: they intersect when g's third vertex s lies in
    // f's plane on the same side of the edge as f's third vertex r (the faces fold onto each
    // other). A plane through the edge with r and s strictly apart proves they do not.
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t p = t[i], q = t[(i + 1) % 3];
      for (int j = 0; j < 3; ++j) {
        if (u[j] != q || u[(j + 1) % 3] != p) continue;
        const Point &pp = tp[i], &pq = tp[(i + 1) % 3], &pr = tp[(i + 2) % 3],
                    &ps = up[(j + 2) % 3];
        if (splits(pp, pq, lifted(pp, n), {pr}, {ps})) return false;
        return CGAL::orientation(pp, pq, pr, ps) == CGAL::COPLANAR &&
               CGAL::coplanar_orientation(pp, pq, pr, ps) == CGAL::POSITIVE;
      }
    }
  }
  if (shared >= 1) {
    // A shared vertex v: each face's opposite edge against the other face. A plane through an
    // edge at v with the faces' other vertices strictly apart proves they meet only at v.
    const Point& v = tp[fi];
    const Point &a = tp[(fi + 1) % 3], &b = tp[(fi + 2) % 3];
    const Point &c = up[(gj + 1) % 3], &d = up[(gj + 2) % 3];
    const Point vn = lifted(v, n);
    if (splits(v, a, vn, {b}, {c, d}) || splits(v, b, vn, {a}, {c, d}) ||
        splits(v, c, vn, {d}, {a, b}) || splits(v, d, vn, {c}, {a, b}))
      return false;
    return segment_meets_triangle(v, a, b, c, d) || segment_meets_triangle(v, c, d, a, b);
  }
  const Point &a = tp[0], &b = tp[1], &c = tp[2];
  const Point &p = up[0], &q = up[1], &r = up[2];
  if (all_on_one_side(a, b, c, p, q, r) || all_on_one_side(p, q, r, a, b, c)) return false;
  for (int i = 0; i < 3; ++i) {
    const Point &e0 = tp[i], &e1 = tp[(i + 1) % 3];
    if (splits(e0, e1, lifted(e0, n), {tp[(i + 2) % 3]}, {p, q, r})) return false;
    const Point &g0 = up[i], &g1 = up[(i + 1) % 3];
    if (splits(g0, g1, lifted(g0, n), {up[(i + 2) % 3]}, {a, b, c})) return false;
  }
  return CGAL::do_intersect(Kernel::Triangle_3(a, b, c), Kernel::Triangle_3(p, q, r));
}

// Collinear vertices (CGAL::collinear), deciding most faces by one orientation against a point
// off the face's plane: any four points with three collinear ones are coplanar.
bool is_collinear(const Geometry& geo, std::uint32_t f) {
  const Tri t = geo.tri(f);
  const Point a = geo.point(t[0]), b = geo.point(t[1]), c = geo.point(t[2]);
  const double ux = b.x() - a.x(), uy = b.y() - a.y(), uz = b.z() - a.z();
  const double vx = c.x() - a.x(), vy = c.y() - a.y(), vz = c.z() - a.z();
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const Point off(a.x() + nx, a.y() + ny, a.z() + nz);
  if (CGAL::orientation(a, b, c, off) != CGAL::COPLANAR) return false;
  return CGAL::collinear(a, b, c);
}

// ---- Hubs: faces around a vertex of high degree, through their directions from it -------------
// (as in cgal_checks.cpp: two faces around h meet other than at h only if their arcs of
// directions from h meet; the arcs' boxes are conservative by far more than their rounding).

struct SphereBox {
  double lo[3], hi[3];
  std::uint32_t face;
};

struct Dir {
  double x, y, z;
};

Dir direction(const float* from, const float* to) {
  const double dx = double{to[0]} - from[0], dy = double{to[1]} - from[1],
               dz = double{to[2]} - from[2];
  const double n = std::sqrt(dx * dx + dy * dy + dz * dz);
  return n > 0 ? Dir{dx / n, dy / n, dz / n} : Dir{0, 0, 0};
}

// The box of the minor great-circle arc from u to w: the triangle of u, w and the point where the
// tangents at u and w meet; arcs close to a half circle (or a zero direction) get the whole
// sphere. Grown by the directions' rounding many times over.
SphereBox arc_box(const Dir& u, const Dir& w, std::uint32_t face) {
  SphereBox box{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}, face};
  const double uw = u.x * w.x + u.y * w.y + u.z * w.z;
  const bool zero = (u.x == 0 && u.y == 0 && u.z == 0) || (w.x == 0 && w.y == 0 && w.z == 0);
  if (zero || 1 + uw < 1e-3) {
    for (int k = 0; k < 3; ++k) box.lo[k] = -1.5, box.hi[k] = 1.5;
    return box;
  }
  const double s = 1 / (1 + uw);
  const double pts[3][3] = {
      {u.x, u.y, u.z}, {w.x, w.y, w.z}, {(u.x + w.x) * s, (u.y + w.y) * s, (u.z + w.z) * s}};
  constexpr double kSlack = 1e-7;
  for (const auto& p : pts)
    for (int k = 0; k < 3; ++k)
      box.lo[k] = std::min(box.lo[k], p[k] - kSlack),
      box.hi[k] = std::max(box.hi[k], p[k] + kSlack);
  return box;
}

double det3(const Dir& a, const Dir& b, const Dir& c) {
  return a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x) +
         a.z * (b.x * c.y - b.y * c.x);
}

// The box of the cone of directions from a point to a triangle (u: its vertices' directions):
// its three edge arcs, and each axis point ±e_k the cone contains (where a coordinate peaks
// inside; the tolerance counts a point on the cone's boundary as inside).
SphereBox cone_box(const Dir u[3], std::uint32_t face) {
  SphereBox box{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}, face};
  for (int i = 0; i < 3; ++i) {
    const SphereBox arc = arc_box(u[i], u[(i + 1) % 3], face);
    for (int k = 0; k < 3; ++k)
      box.lo[k] = std::min(box.lo[k], arc.lo[k]), box.hi[k] = std::max(box.hi[k], arc.hi[k]);
  }
  const double d = det3(u[0], u[1], u[2]);
  for (int k = 0; k < 3; ++k)
    for (const double sign : {-1.0, 1.0}) {
      Dir e{0, 0, 0};
      (k == 0 ? e.x : k == 1 ? e.y : e.z) = sign;
      const double a = det3(e, u[1], u[2]), b = det3(u[0], e, u[2]), c = det3(u[0], u[1], e);
      constexpr double tol = 1e-12;
      const bool inside = (a >= -tol && b >= -tol && c >= -tol && d >= -tol) ||
                          (a <= tol && b <= tol && c <= tol && d <= tol);
      if (inside) box.lo[k] = std::min(box.lo[k], sign), box.hi[k] = std::max(box.hi[k], sign);
    }
  return box;
}

// Pairs of faces around hub h whose arcs' boxes overlap (a sweep along x).
void hub_candidates(const Geometry& geo, const VertexFaces& vf, std::uint32_t h,
                    const std::vector<char>& degenerate, std::vector<Pair>* out) {
  std::vector<SphereBox> arcs;
  const float* ph = geo.pos + 3 * std::size_t{h};
  for (std::uint32_t k = vf.first[h]; k < vf.first[h + 1]; ++k) {
    const std::uint32_t f = vf.faces[k];
    if (degenerate[f]) continue;
    const Tri t = geo.tri(f);
    const int i = t[0] == h ? 0 : t[1] == h ? 1 : 2;
    arcs.push_back(arc_box(direction(ph, geo.pos + 3 * std::size_t{t[(i + 1) % 3]}),
                           direction(ph, geo.pos + 3 * std::size_t{t[(i + 2) % 3]}), f));
  }
  std::sort(arcs.begin(), arcs.end(),
            [](const SphereBox& a, const SphereBox& b) { return a.lo[0] < b.lo[0]; });
  for (std::size_t i = 0; i < arcs.size(); ++i)
    for (std::size_t j = i + 1; j < arcs.size() && arcs[j].lo[0] <= arcs[i].hi[0]; ++j) {
      const SphereBox &a = arcs[i], &b = arcs[j];
      if (a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] && a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2])
        out->emplace_back(std::min(a.face, b.face), std::max(a.face, b.face));
    }
}

// ---- Bounding-volume hierarchies over faces in Morton order
// --------------------------------------

// Does triangle `tri` meet the box? The separating-axis test in double precision on a slightly
// inflated box (as cgal_checks.cpp's): conservative, so it only prunes; the exact test follows.
bool triangle_may_meet_box(const std::array<std::array<double, 3>, 3>& tri, const Box& box) {
  std::array<double, 3> centre, half;
  for (int k = 0; k < 3; ++k) {
    centre[k] = 0.5 * (double{box.lo[k]} + box.hi[k]);
    half[k] = 0.5 * (double{box.hi[k]} - box.lo[k]);
    half[k] += 1e-9 * (std::abs(centre[k]) + half[k]) + 1e-300;
  }
  std::array<std::array<double, 3>, 3> v;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) v[i][k] = tri[i][k] - centre[k];
  const auto separated = [&](double ax, double ay, double az) {
    const double p0 = v[0][0] * ax + v[0][1] * ay + v[0][2] * az;
    const double p1 = v[1][0] * ax + v[1][1] * ay + v[1][2] * az;
    const double p2 = v[2][0] * ax + v[2][1] * ay + v[2][2] * az;
    const double r = half[0] * std::abs(ax) + half[1] * std::abs(ay) + half[2] * std::abs(az);
    const double slack = 1e-9 * (std::abs(p0) + std::abs(p1) + std::abs(p2) + r);
    return std::min({p0, p1, p2}) > r + slack || std::max({p0, p1, p2}) < -r - slack;
  };
  double e[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) e[i][k] = v[(i + 1) % 3][k] - v[i][k];
  if (separated(e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                e[0][0] * e[1][1] - e[0][1] * e[1][0]))
    return false;
  for (const auto& d : e) {
    if (separated(0, -d[2], d[1]) || separated(d[2], 0, -d[0]) || separated(-d[1], d[0], 0))
      return false;
  }
  return true;
}

std::uint64_t spread_bits(std::uint64_t x) {  // 21 bits to every third of 63
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// A complete binary tree over leaves of kLeaf consecutive items (sorted by group, then Morton code
// of the box centre); node k's children are 2k and 2k + 1, the leaves are nodes [P, 2P). An item
// is a face (its box computed from its vertices) or, with `boxes`, a piece of a face (`faces[i]`
// the face, `boxes[i]` the piece's box).
class FaceTree {
 public:
  static constexpr std::size_t kLeaf = 8;

  FaceTree(const Geometry& geo, const std::vector<std::uint32_t>& faces,
           const std::vector<Box>* boxes, const std::vector<std::uint32_t>* group, const Box& world)
      : geo_(geo) {
    const std::size_t n = faces.size();
    struct Key {
      std::uint64_t key;
      std::uint32_t group, item;
      bool operator<(const Key& o) const {
        return group != o.group ? group < o.group : key != o.key ? key < o.key : item < o.item;
      }
    };
    double scale[3];
    for (int k = 0; k < 3; ++k) {
      const double extent = double{world.hi[k]} - world.lo[k];
      scale[k] = extent > 0 ? 2097151.0 / extent : 0;
    }
    const auto morton = [&](std::size_t i) {
      const Box b = boxes ? (*boxes)[i] : geo.box(faces[i]);
      std::uint64_t code = 0;
      for (int k = 0; k < 3; ++k) {
        const double c = 0.5 * (double{b.lo[k]} + b.hi[k]) - world.lo[k];
        const double q = std::clamp(c * scale[k], 0.0, 2097151.0);
        code |= spread_bits(static_cast<std::uint64_t>(q)) << k;
      }
      return code;
    };
    if (group == nullptr && boxes == nullptr) {
      // One 64-bit key an item: the Morton code's leading bits, then the item (ties in input
      // order, as below).
      int item_bits = 1;
      while (item_bits < 63 && (std::uint64_t{1} << item_bits) < n) ++item_bits;
      std::vector<std::uint64_t, NoInit<std::uint64_t>> packed(n);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                            packed[i] = (morton(i) >> (item_bits - 1)) << item_bits | i;
                        });
      tbb::parallel_sort(packed.begin(), packed.end());
      faces_.resize(n);
      const std::uint64_t item_mask = (std::uint64_t{1} << item_bits) - 1;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                            faces_[i] = faces[packed[i] & item_mask];
                        });
    } else {
      std::vector<Key> keys(n);
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(0, n, 1 << 14),
          [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i)
              keys[i] = {morton(i), group ? (*group)[faces[i]] : 0, static_cast<std::uint32_t>(i)};
          });
      tbb::parallel_sort(keys.begin(), keys.end());
      faces_.resize(n);
      if (group) groups_.resize(n);
      if (boxes) boxes_.resize(n);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            faces_[i] = faces[keys[i].item];
                            if (group) groups_[i] = keys[i].group;
                            if (boxes) boxes_[i] = (*boxes)[keys[i].item];
                          }
                        });
    }
    leaves_ = (n + kLeaf - 1) / kLeaf;
    p_ = 1;
    while (p_ < leaves_) p_ *= 2;
    nodes_.assign(2 * p_, Box::empty());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves_, 1 << 10),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t j = r.begin(); j != r.end(); ++j) {
                          Box b = Box::empty();
                          for (std::size_t i = j * kLeaf; i < std::min(n, (j + 1) * kLeaf); ++i)
                            b.add(box(i));
                          nodes_[p_ + j] = b;
                        }
                      });
    for (std::size_t level = p_ / 2; level >= 1; level /= 2) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(level, 2 * level, 1 << 12),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t k = r.begin(); k != r.end(); ++k) {
                            Box b = nodes_[2 * k];
                            b.add(nodes_[2 * k + 1]);
                            nodes_[k] = b;
                          }
                        });
    }
  }

  std::size_t size() const { return faces_.size(); }
  std::uint32_t face(std::size_t i) const { return faces_[i]; }
  std::uint32_t group(std::size_t i) const { return groups_.empty() ? 0 : groups_[i]; }
  Box box(std::size_t i) const { return boxes_.empty() ? geo_.box(faces_[i]) : boxes_[i]; }

  // Visits the items at sorted positions ≥ from in every leaf reached: `enter(box, first, last)`
  // decides whether to enter a node holding positions [first, last); `visit(position)`.
  template <class Enter, class Visit>
  void traverse(std::size_t from, Enter&& enter, Visit&& visit) const {
    const std::size_t n = faces_.size();
    if (n == 0) return;
    std::size_t stack[128];
    int top = 0;
    stack[top++] = 1;
    while (top > 0) {
      const std::size_t k = stack[--top];
      const int level = 63 - __builtin_clzll(k);
      const std::size_t span = p_ >> level;  // leaves under k
      const std::size_t first = (k - (std::size_t{1} << level)) * span * kLeaf;
      const std::size_t last = std::min(n, first + span * kLeaf);
      if (last <= from || first >= n || !enter(nodes_[k], first, last)) continue;
      if (k >= p_) {
        for (std::size_t i = std::max(first, from); i < last; ++i) visit(i);
      } else {
        stack[top++] = 2 * k + 1;
        stack[top++] = 2 * k;
      }
    }
  }

  std::size_t leaves() const { return leaves_; }
  const Box& leaf_box(std::size_t j) const { return nodes_[p_ + j]; }

  // The leaves after leaf j whose boxes `enter` accepts (with every ancestor's on the way down):
  // walking up from j and into the right siblings of its ancestors. `visit(first, last)` gets the
  // sorted positions of each leaf reached.
  template <class Enter, class Visit>
  void leaves_after(std::size_t j, Enter&& enter, Visit&& visit) const {
    const std::size_t n = faces_.size();
    std::size_t stack[128];
    for (std::size_t k = p_ + j; k > 1; k /= 2) {
      if (k & 1) continue;  // a right child: its sibling holds earlier positions
      int top = 0;
      stack[top++] = k + 1;
      while (top > 0) {
        const std::size_t m = stack[--top];
        const int level = 63 - __builtin_clzll(m);
        const std::size_t span = p_ >> level;
        const std::size_t first = (m - (std::size_t{1} << level)) * span * kLeaf;
        if (first >= n || !enter(nodes_[m])) continue;
        if (m >= p_) {
          visit(first, std::min(n, first + kLeaf));
        } else {
          stack[top++] = 2 * m + 1;
          stack[top++] = 2 * m;
        }
      }
    }
  }

 private:
  const Geometry& geo_;
  std::vector<std::uint32_t> faces_, groups_;
  std::vector<Box> boxes_;
  std::vector<Box> nodes_;
  std::size_t leaves_ = 0, p_ = 1;
};

// The faces of one leaf of a FaceTree, their boxes held by coordinate (8 lanes; empty lanes never
// overlap) so that one face is tested against a whole leaf at once.
struct Leaf {
  static constexpr std::size_t L = FaceTree::kLeaf;
  std::size_t count = 0;
  std::uint32_t face[L];
  Tri tri[L];
  float lo[3][L], hi[3][L];
  void load(const Geometry& g, const FaceTree& tree, std::size_t first, std::size_t last) {
    count = last - first;
    for (std::size_t b = 0; b < L; ++b) {
      if (b >= count) {
        for (int k = 0; k < 3; ++k)
          lo[k][b] = std::numeric_limits<float>::infinity(),
          hi[k][b] = -std::numeric_limits<float>::infinity();
        continue;
      }
      face[b] = tree.face(first + b);
      tri[b] = g.tri(face[b]);
      const float* p0 = g.pos + 3 * std::size_t{tri[b][0]};
      const float* p1 = g.pos + 3 * std::size_t{tri[b][1]};
      const float* p2 = g.pos + 3 * std::size_t{tri[b][2]};
      for (int k = 0; k < 3; ++k)
        lo[k][b] = std::min({p0[k], p1[k], p2[k]}), hi[k][b] = std::max({p0[k], p1[k], p2[k]});
    }
  }
  // Bit b: item b's box meets item a's box of `other`.
  unsigned overlaps(const Leaf& other, std::size_t a) const {
    const float x0 = other.lo[0][a], x1 = other.hi[0][a], y0 = other.lo[1][a], y1 = other.hi[1][a],
                z0 = other.lo[2][a], z1 = other.hi[2][a];
    int hit[L];
    for (std::size_t b = 0; b < L; ++b)
      hit[b] = (lo[0][b] <= x1) & (x0 <= hi[0][b]) & (lo[1][b] <= y1) & (y0 <= hi[1][b]) &
               (lo[2][b] <= z1) & (z0 <= hi[2][b]);
    unsigned mask = 0;
    for (std::size_t b = 0; b < L; ++b) mask |= static_cast<unsigned>(hit[b]) << b;
    return mask;
  }
};
// Pieces of a long face: the triangle cut by slabs across its longest axis into pieces of about
// `target`, and each piece again across its next longest (at most kMaxPieces pieces a face). Each
// piece's box is rounded outward to float and grown by far more than the cuts' rounding, so that
// the pieces' boxes cover the face. Thin faces (a sliver along a depth step) make about
// length / target pieces, where halving the triangle would make the square of that.
constexpr std::size_t kMaxPieces = 1024;

using Polygon = std::vector<std::array<double, 3>>;

// The part of convex polygon `in` with lo ≤ x[axis] ≤ hi (Sutherland–Hodgman, both sides).
Polygon clip_slab(const Polygon& in, int axis, double lo, double hi) {
  const auto clip = [axis](const Polygon& poly, double bound, bool keep_above) {
    Polygon out;
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
      const auto &p = poly[i], &q = poly[(i + 1) % n];
      const bool pin = keep_above ? p[axis] >= bound : p[axis] <= bound;
      const bool qin = keep_above ? q[axis] >= bound : q[axis] <= bound;
      if (pin) out.push_back(p);
      if (pin != qin) {
        const double t = (bound - p[axis]) / (q[axis] - p[axis]);
        std::array<double, 3> x;
        for (int k = 0; k < 3; ++k) x[k] = p[k] + t * (q[k] - p[k]);
        x[axis] = bound;
        out.push_back(x);
      }
    }
    return out;
  };
  return clip(clip(in, lo, true), hi, false);
}

void face_pieces(const Polygon& poly, double target, std::size_t budget, std::uint32_t face,
                 std::vector<std::uint32_t>* faces, std::vector<Box>* boxes) {
  if (poly.empty()) return;
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) lo[k] = hi[k] = poly[0][k];
  for (const auto& p : poly)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  const double extent = hi[axis] - lo[axis];
  const std::size_t cuts =
      extent <= target
          ? 1
          : std::min<std::size_t>(
                budget, static_cast<std::size_t>(std::ceil(std::min(extent / target, 1e6))));
  if (cuts <= 1) {
    Box b;
    for (int k = 0; k < 3; ++k) {
      const double pad = 1e-6 * (hi[k] - lo[k] + std::abs(lo[k]) + std::abs(hi[k])) + 1e-300;
      b.lo[k] = std::nextafter(static_cast<float>(lo[k] - pad), -INFINITY);
      b.hi[k] = std::nextafter(static_cast<float>(hi[k] + pad), INFINITY);
    }
    faces->push_back(face);
    boxes->push_back(b);
    return;
  }
  const double width = extent / static_cast<double>(cuts);
  for (std::size_t j = 0; j < cuts; ++j) {
    const double a = j == 0 ? lo[axis] : lo[axis] + width * static_cast<double>(j);
    const double b = j + 1 == cuts ? hi[axis] : lo[axis] + width * static_cast<double>(j + 1);
    face_pieces(clip_slab(poly, axis, a, b), target, budget / cuts, face, faces, boxes);
  }
}

void split_face(const std::array<std::array<double, 3>, 3>& t, double target, std::uint32_t face,
                std::vector<std::uint32_t>* faces, std::vector<Box>* boxes) {
  face_pieces(Polygon{t[0], t[1], t[2]}, target, kMaxPieces, face, faces, boxes);
}

// ---- The search
// -----------------------------------------------------------------------------------

struct Collector {
  std::size_t limit;
  std::atomic<std::size_t> found{0};
  tbb::enumerable_thread_specific<std::vector<Pair>> pairs;
  bool full() const { return found.load(std::memory_order_relaxed) >= limit; }
  void add(std::uint32_t f, std::uint32_t g) {
    pairs.local().emplace_back(std::min(f, g), std::max(f, g));
    found.fetch_add(1, std::memory_order_relaxed);
  }
};

struct Search {
  const Geometry& geo;
  std::size_t nt;
  std::vector<char> degenerate, is_hub;  // per face, per vertex
  Collector* out;
  const std::vector<char>* flat;  // per vertex: flat_star

  bool shares_hub(std::uint32_t f, std::uint32_t g) const {
    const Tri t = geo.tri(f), u = geo.tri(g);
    for (std::uint32_t a : t)
      if (is_hub[a] && (a == u[0] || a == u[1] || a == u[2])) return true;
    return false;
  }
  void test(std::uint32_t f, std::uint32_t g) { test(f, geo.tri(f), g, geo.tri(g)); }
  // A pair sharing a vertex whose star is embedded (flat_star) meets only along what it shares.
  void test(std::uint32_t f, const Tri& t, std::uint32_t g, const Tri& u) {
    for (std::uint32_t a : t)
      if ((a == u[0] || a == u[1] || a == u[2]) && (*flat)[a]) return;
    if (faces_intersect(geo, f, g)) out->add(f, g);
  }
};

// Long faces against each other, but for pairs around a common hub (hub_candidates' turn). Long
// faces are cut into pieces of about the short faces' size: the boxes of long faces lying side by
// side (a wall of slivers that a depth step makes) overlap each other's, their pieces' do not. Each
// piece of f against the pieces of the faces after f; nodes holding only pieces of faces around
// f's own hub are skipped whole.
// `queries` (a subset of `long_faces`) against `long_faces`: all the pairs when `after_only` is
// false, else those whose second face comes after the first.
void long_long_pieces(const Geometry& geo, const std::vector<std::uint32_t>& long_faces,
                      const std::vector<std::uint32_t>& queries, bool after_only,
                      const std::vector<std::uint32_t>& group, std::uint32_t no_hub,
                      double threshold, const Box& world, Search& s) {
  Collector& collector = *s.out;
  {
    const double target = std::max(threshold, 1e-30);
    tbb::enumerable_thread_specific<std::pair<std::vector<std::uint32_t>, std::vector<Box>>>
        local_pieces;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, long_faces.size(), 64),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        auto& [faces, boxes] = local_pieces.local();
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          split_face(geo.corners(long_faces[i]), target, long_faces[i], &faces,
                                     &boxes);
                      });
    std::vector<std::uint32_t> piece_faces;
    std::vector<Box> piece_boxes;
    for (auto& [faces, boxes] : local_pieces) {
      piece_faces.insert(piece_faces.end(), faces.begin(), faces.end());
      piece_boxes.insert(piece_boxes.end(), boxes.begin(), boxes.end());
    }
    local_pieces.clear();
    const FaceTree tree(geo, piece_faces, &piece_boxes, &group, world);
    piece_faces = {};
    piece_boxes = {};
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, queries.size(), 4),
        [&](const tbb::blocked_range<std::size_t>& r) {
          if (collector.full()) return;
          std::vector<std::uint32_t> mine_faces, others;
          std::vector<Box> mine;
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const std::uint32_t f = queries[i], fg = group[f];
            const auto tri = geo.corners(f);
            mine_faces.clear(), mine.clear(), others.clear();
            split_face(tri, target, f, &mine_faces, &mine);
            for (const Box& pb : mine)
              tree.traverse(
                  0,
                  [&](const Box& b, std::size_t first, std::size_t last) {
                    if (fg != no_hub && tree.group(first) == fg && tree.group(last - 1) == fg)
                      return false;
                    return pb.overlaps(b);
                  },
                  [&](std::size_t j) {
                    const std::uint32_t g = tree.face(j);
                    if ((after_only ? g > f : g != f) && pb.overlaps(tree.box(j)))
                      others.push_back(g);
                  });
            std::sort(others.begin(), others.end());
            others.erase(std::unique(others.begin(), others.end()), others.end());
            const Box fb = geo.box(f);
            for (const std::uint32_t g : others) {
              if (s.shares_hub(f, g)) continue;
              const Box gb = geo.box(g);
              if (fb.overlaps(gb) && triangle_may_meet_box(tri, gb)) s.test(f, g);
            }
          }
        });
  }
}

// Long faces against each other when the mesh has a hub h (a spot or omni volume's apex): by
// their directions from h. A face not through h meets another at a point other than h only where
// both see that point's direction from h, so the boxes of their cones of directions (arcs for the
// faces around h) must overlap. A depth step's wall is a row of slivers pointing away from the
// light: long boxes lying side by side in space, small boxes apart in directions. Faces through h
// (exactly: h on the triangle, not a vertex of it) have no such cone: they go through the pieces.
void long_long_from_hub(const Geometry& geo, std::uint32_t h,
                        const std::vector<std::uint32_t>& long_faces,
                        const std::vector<std::uint32_t>& group, std::uint32_t no_hub,
                        double threshold, const Box& world, Search& s) {
  Collector& collector = *s.out;
  const float* ph = geo.pos + 3 * std::size_t{h};
  const Point hub = geo.point(h);
  std::vector<Box> dirs(long_faces.size());
  std::vector<char> through(long_faces.size(), 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, long_faces.size(), 256),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const Tri t = geo.tri(long_faces[i]);
          SphereBox sb;
          const int at = t[0] == h ? 0 : t[1] == h ? 1 : t[2] == h ? 2 : -1;
          if (at >= 0) {
            sb = arc_box(direction(ph, geo.pos + 3 * std::size_t{t[(at + 1) % 3]}),
                         direction(ph, geo.pos + 3 * std::size_t{t[(at + 2) % 3]}), 0);
          } else {
            if (CGAL::do_intersect(
                    Kernel::Triangle_3(geo.point(t[0]), geo.point(t[1]), geo.point(t[2])), hub))
              through[i] = 1;
            const Dir u[3] = {direction(ph, geo.pos + 3 * std::size_t{t[0]}),
                              direction(ph, geo.pos + 3 * std::size_t{t[1]}),
                              direction(ph, geo.pos + 3 * std::size_t{t[2]})};
            sb = cone_box(u, 0);
          }
          Box b;
          for (int k = 0; k < 3; ++k) {
            b.lo[k] = std::nextafter(static_cast<float>(sb.lo[k]), -INFINITY);
            b.hi[k] = std::nextafter(static_cast<float>(sb.hi[k]), INFINITY);
          }
          dirs[i] = b;
        }
      });
  std::vector<std::uint32_t> rest;  // through h
  for (std::size_t i = 0; i < long_faces.size(); ++i)
    if (through[i]) rest.push_back(long_faces[i]);
  const Box sphere{{-1.5f, -1.5f, -1.5f}, {1.5f, 1.5f, 1.5f}};
  const FaceTree tree(geo, long_faces, &dirs, &group, sphere);
  dirs = {};
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, tree.size(), 16),
      [&](const tbb::blocked_range<std::size_t>& r) {
        if (collector.full()) return;
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const std::uint32_t f = tree.face(i), fg = tree.group(i);
          const Box db = tree.box(i), fb = geo.box(f);
          const auto tri = geo.corners(f);
          tree.traverse(
              i + 1,
              [&](const Box& b, std::size_t first, std::size_t last) {
                if (fg != no_hub && tree.group(first) == fg && tree.group(last - 1) == fg)
                  return false;
                return db.overlaps(b);
              },
              [&](std::size_t j) {
                const std::uint32_t g = tree.face(j);
                if (!db.overlaps(tree.box(j)) || s.shares_hub(f, g)) return;
                const Box gb = geo.box(g);
                if (fb.overlaps(gb) && triangle_may_meet_box(tri, gb)) s.test(f, g);
              });
        }
      });
  if (rest.empty()) return;
  // Faces through h against every long face, through the pieces (rare: h is a vertex elsewhere).
  long_long_pieces(geo, long_faces, rest, false, group, no_hub, threshold, world, s);
}

std::vector<Pair> intersecting_pairs(const Geometry& geo, const VertexFaces& vf, std::size_t nv,
                                     std::size_t nt, double long_face_ratio,
                                     std::size_t min_hub_degree, std::size_t limit) {
  Collector collector;
  collector.limit = limit;

  std::vector<char> flat(nv, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1 << 12),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v != r.end(); ++v)
                        flat[v] = flat_star(geo, vf, static_cast<std::uint32_t>(v));
                    });
  Search s{geo, nt, std::vector<char>(nt, 0), std::vector<char>(nv, 0), &collector, &flat};

  // Degenerate faces: (f, f), and out of every other pair (CGAL's self_intersections).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t f = r.begin(); f != r.end(); ++f)
                        if (is_collinear(geo, static_cast<std::uint32_t>(f))) {
                          s.degenerate[f] = 1;
                          collector.add(static_cast<std::uint32_t>(f),
                                        static_cast<std::uint32_t>(f));
                        }
                    });

  // Hubs, and the group of each face around one (its least hub's rank).
  std::vector<std::uint32_t> hubs;
  for (std::size_t v = 0; v < nv; ++v) {
    const double d = static_cast<double>(vf.degree(static_cast<std::uint32_t>(v)));
    if (vf.degree(static_cast<std::uint32_t>(v)) >= min_hub_degree &&
        d * d >= static_cast<double>(nt)) {
      s.is_hub[v] = 1;
      hubs.push_back(static_cast<std::uint32_t>(v));
    }
  }
  std::vector<std::uint32_t> group(nt, kNone);
  for (std::size_t k = hubs.size(); k-- > 0;)
    for (std::uint32_t i = vf.first[hubs[k]]; i < vf.first[hubs[k] + 1]; ++i)
      group[vf.faces[i]] = static_cast<std::uint32_t>(k);

  // Long faces: a box more than long_face_ratio times the median's (from a sample).
  std::vector<float> sample;
  const std::size_t stride = std::max<std::size_t>(1, nt / 65536);
  for (std::size_t f = 0; f < nt; f += stride) {
    const Box b = geo.box(f);
    sample.push_back(std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]}));
  }
  std::nth_element(sample.begin(), sample.begin() + static_cast<std::ptrdiff_t>(sample.size() / 2),
                   sample.end());
  const double threshold = long_face_ratio * (sample.empty() ? 0.0 : sample[sample.size() / 2]);

  std::vector<std::uint32_t> short_faces, long_faces;  // long: also every face around a hub
  // In blocks on both cores, then joined in face order.
  struct Split {
    std::vector<std::uint32_t> short_faces, long_faces;
    Box world = Box::empty();
  };
  constexpr std::size_t kBlock = 1 << 16;
  std::vector<Split> blocks((nt + kBlock - 1) / kBlock);
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t k) {
    Split& out = blocks[k];
    for (std::size_t f = k * kBlock; f < std::min(nt, (k + 1) * kBlock); ++f) {
      if (s.degenerate[f]) continue;
      const Box b = geo.box(f);
      out.world.add(b);
      const double extent = std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
      (group[f] != kNone || extent > threshold ? out.long_faces : out.short_faces)
          .push_back(static_cast<std::uint32_t>(f));
    }
  });
  Box world = Box::empty();
  std::size_t shorts = 0, longs = 0;
  for (const Split& b : blocks)
    world.add(b.world), shorts += b.short_faces.size(), longs += b.long_faces.size();
  short_faces.reserve(shorts), long_faces.reserve(longs);
  for (Split& b : blocks) {
    short_faces.insert(short_faces.end(), b.short_faces.begin(), b.short_faces.end());
    long_faces.insert(long_faces.end(), b.long_faces.begin(), b.long_faces.end());
    b = Split();
  }
  const std::uint32_t no_hub = static_cast<std::uint32_t>(hubs.size());
  for (std::uint32_t& g : group)
    if (g == kNone) g = no_hub;

  // Short against short: each face's box against the faces after it in the tree's order.
  {
    const FaceTree tree(geo, short_faces, nullptr, nullptr, world);
    short_faces = {};
    // Leaf by leaf: the faces of a leaf against each other, then against those of every later
    // leaf whose box meets the leaf's (the leaves' boxes are walked once per leaf, not per face).
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, tree.leaves(), 32),
        [&](const tbb::blocked_range<std::size_t>& r) {
          if (collector.full()) return;
          Leaf here, there;
          for (std::size_t j = r.begin(); j != r.end(); ++j) {
            const std::size_t first = j * FaceTree::kLeaf;
            here.load(geo, tree, first, std::min(tree.size(), first + FaceTree::kLeaf));
            for (std::size_t a = 0; a < here.count; ++a) {
              unsigned mask = here.overlaps(here, a) >> (a + 1) << (a + 1);
              for (; mask != 0; mask &= mask - 1) {
                const int b = __builtin_ctz(mask);
                s.test(here.face[a], here.tri[a], here.face[b], here.tri[b]);
              }
            }
            const Box leaf = tree.leaf_box(j);
            tree.leaves_after(
                j, [&](const Box& b) { return leaf.overlaps(b); },
                [&](std::size_t mfirst, std::size_t mlast) {
                  there.load(geo, tree, mfirst, mlast);
                  for (std::size_t a = 0; a < here.count; ++a)
                    for (unsigned mask = there.overlaps(here, a); mask != 0; mask &= mask - 1) {
                      const int b = __builtin_ctz(mask);
                      s.test(here.face[a], here.tri[a], there.face[b], there.tri[b]);
                    }
                });
          }
        });
    // Long against short: each long face's triangle through the short faces' tree.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, long_faces.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        if (collector.full()) return;
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const std::uint32_t f = long_faces[i];
                          const Box fb = geo.box(f);
                          const auto tri = geo.corners(f);
                          tree.traverse(
                              0,
                              [&](const Box& b, std::size_t, std::size_t) {
                                return fb.overlaps(b) && triangle_may_meet_box(tri, b);
                              },
                              [&](std::size_t j) {
                                const Box gb = tree.box(j);
                                if (fb.overlaps(gb) && triangle_may_meet_box(tri, gb))
                                  s.test(f, tree.face(j));
                              });
                        }
                      });
  }
  // Long against long, but for pairs around a common hub (the hubs' turn, below).
  if (!hubs.empty()) {
    long_long_from_hub(geo, hubs.front(), long_faces, group, no_hub, threshold, world, s);
  } else {
    long_long_pieces(geo, long_faces, long_faces, true, group, no_hub, threshold, world, s);
  }
  // Around each hub: the pairs whose least shared hub it is.
  std::vector<Pair> candidates;
  for (std::uint32_t h : hubs) {
    if (collector.full()) break;
    candidates.clear();
    hub_candidates(geo, vf, h, s.degenerate, &candidates);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 64),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i) {
                          const auto [f, g] = candidates[i];
                          const Tri t = geo.tri(f), u = geo.tri(g);
                          bool mine = true;
                          for (std::uint32_t a : t)
                            if (a < h && s.is_hub[a] && (a == u[0] || a == u[1] || a == u[2]))
                              mine = false;
                          if (mine) s.test(f, g);
                        }
                      });
  }

  std::vector<Pair> pairs;
  for (const std::vector<Pair>& local : collector.pairs)
    pairs.insert(pairs.end(), local.begin(), local.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// ---- Validity as CGAL's Surface_mesh would see it, connected components, orientation ----------

// The first face repeating a vertex, or the first vertex (with its first face) where separate
// fans meet: cgal_checks' to_surface_mesh refuses the mesh for these, with these messages.
bool surface_mesh_valid(const Geometry& geo, const VertexFaces& vf, std::size_t nv, std::size_t nt,
                        std::string* why_not) {
  const std::size_t bad_face = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nt, 1 << 16), nt,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t first) {
        for (std::size_t t = r.begin(); t != r.end() && t < first; ++t) {
          const Tri f = geo.tri(t);
          if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return t;
        }
        return first;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
  if (bad_face < nt) {
    *why_not = "face " + std::to_string(bad_face) + " repeats a vertex";
    return false;
  }
  const std::size_t bad_vertex = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nv, 1 << 14), nv,
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t first) {
        for (std::size_t v = r.begin(); v != r.end() && v < first; ++v)
          if (!one_fan(geo, vf, static_cast<std::uint32_t>(v))) return v;
        return first;
      },
      [](std::size_t a, std::size_t b) { return std::min(a, b); });
  if (bad_vertex < nv) {
    *why_not = "face " + std::to_string(vf.faces[vf.first[bad_vertex]]) + " is at vertex " +
               std::to_string(bad_vertex) +
               ", where separate fans of faces meet (not a manifold surface)";
    return false;
  }
  return true;
}

// Connected components of the faces (every vertex being one fan, faces sharing a vertex share a
// path of edges): union-find over the vertices, linking each root to the lesser.
std::size_t components(const Geometry& geo, std::size_t nv, std::size_t nt) {
  std::vector<std::atomic<std::uint32_t>> parent(nv);
  for (std::size_t v = 0; v < nv; ++v) parent[v].store(static_cast<std::uint32_t>(v));
  const auto find = [&](std::uint32_t x) {
    for (;;) {
      const std::uint32_t p = parent[x].load(std::memory_order_relaxed);
      if (p == x) return x;
      const std::uint32_t gp = parent[p].load(std::memory_order_relaxed);
      std::uint32_t expected = p;  // path halving; losing the race only leaves a longer path
      parent[x].compare_exchange_weak(expected, gp, std::memory_order_relaxed);
      x = gp;
    }
  };
  const auto unite = [&](std::uint32_t a, std::uint32_t b) {
    for (;;) {
      a = find(a), b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      std::uint32_t expected = a;
      if (parent[a].compare_exchange_strong(expected, b)) return;
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t f = r.begin(); f != r.end(); ++f) {
                        const Tri t = geo.tri(f);
                        unite(t[0], t[1]);
                        unite(t[0], t[2]);
                      }
                    });
  std::vector<char> used(nv, 0);
  for (std::size_t k = 0; k < 3 * nt; ++k) used[geo.idx[k]] = 1;
  std::size_t n = 0;
  for (std::size_t v = 0; v < nv; ++v) n += used[v] && find(static_cast<std::uint32_t>(v)) == v;
  return n;
}

CgalChecks run(const Mesh& mesh, bool closed, std::size_t max_pairs, double long_face_ratio,
               std::size_t min_hub_degree, std::size_t limit) {
  CgalChecks out;
  const Geometry geo{mesh.positions.data(), mesh.indices.data()};
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
  const VertexFaces vf = vertex_faces(geo, nv, nt);
  if (!surface_mesh_valid(geo, vf, nv, nt, &out.why_not)) return out;
  out.built = true;
  const std::vector<Pair> pairs =
      intersecting_pairs(geo, vf, nv, nt, long_face_ratio, min_hub_degree, limit);
  out.intersecting_pairs = pairs.size();
  out.pairs_truncated = pairs.size() >= kMaxPairs;
  for (std::size_t i = 0; i < pairs.size() && i < max_pairs; ++i)
    out.first_pairs.push_back(pairs[i]);
  if (limit < kMaxPairs) return out;
  out.components = components(geo, nv, nt);
  if (closed && pairs.empty()) {
    out.ran_volume_test = true;
    // One component: CGAL's predicate (PMP::volume_connected_components) takes the component as
    // the outer boundary of a volume when it is oriented outward, and as bounding the unbounded
    // volume (its nesting level 0 read as odd) when it is oriented inward, so it bounds a volume
    // either way; the orientation is the linear "outward" check's business. Several components
    // (nesting, orientations relative to each other) go to CGAL.
    out.bounds_a_volume = out.components == 1 || cgal_bounds_a_volume(mesh);
  }
  return out;
}

}  // namespace

CgalChecks exact_checks(const Mesh& mesh, bool closed, std::size_t max_pairs,
                        double long_face_ratio, std::size_t min_hub_degree) {
  return run(mesh, closed, max_pairs, long_face_ratio, min_hub_degree, kMaxPairs);
}

bool exact_does_self_intersect(const Mesh& mesh) {
  const CgalChecks c = run(mesh, false, 1, kLongFaceRatio, kMinHubDegree, 1);
  return !c.built || c.intersecting_pairs > 0;
}

}  // namespace lightvol::detail

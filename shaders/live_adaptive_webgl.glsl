// lightvol's adaptive live volume in WebGL2 (web/live_adaptive.js, docs/web.md): the compute passes
// of shaders/live_adaptive.comp recast for a browser, which has neither compute shaders, nor
// atomics, nor doubles. The quadtree is `lightvol build --adaptive --tessellation quadtree`'s: the
// same cells, the same error pyramid thresholded at E, the same 2:1 balance, the same fix-up rounds
// and the same 16 edge-split configurations. The measures are float here: each is computed with a
// bound on its own rounding (below), and a cell splits when the measure plus that bound exceeds E,
// so the bound E holds at every texel; a cell whose double measure lies within that rounding of E
// (a few parts in a million of it) may split where build's does not.
//
// The host (web/live_adaptive.js) prepends "#version 300 es", the precision statements and one
// "#define LVA_<STAGE>" (the emission stages also "#define LIGHTVOL_LIVE_COMMON" and
// shaders/airlight.glsl, for live_grid_point, live_segment and live_ring_texel). Stages:
//   LVA_OWN         fragment, per cell of level L (1..top): split when a child did, or when a texel
//                   of the cell lies farther than E from the cell's two triangles.
//   LVA_BALANCE     fragment, per cell of level L (2..top): split when a child or a child's
//                   neighbour did (2:1); in fix-up round r, first the cells the round's test failed.
//   LVA_TEST        fragment, per cell of levels 2..top, fix-up round r: r when the leaf's split
//                   configuration breaks E (round 1 tests every leaf, later rounds those whose
//                   parent or a neighbour split in the round before).
//   LVA_CODE        fragment, per texel of the count pyramid's base (cell c = lva_first[L] + the
//                   cell's index in level L at texel c = y · base width + x): what the cell emits
//                   (code 0 nothing, 1 + configuration for a leaf, 17 for a split level-1 cell: its
//                   quads) and how many triangles, as code · 16 + count, and bit 31 when the last
//                   fix-up round split the cell (its mark in lva_fails).
//   LVA_REDUCE      fragment, per texel of pyramid level k >= 1 (a histopyramid, Ziegler et al.
//                   2006): the triangle counts of its four children in level k − 1 (x: (0, 0),
//                   y: (1, 0), z: (0, 1), w: (1, 1); 0 outside the level), each with bit 31 when a
//                   cell below it carries that bit. The top level's texel sums to the volume's grid
//                   triangles.
//   LVA_EMIT_GRID   vertex, drawn as 3 vertices a triangle (no vertex buffer): triangle
//                   gl_VertexID / 3 finds its cell and its index among the cell's triangles by
//                   descending the pyramid from the top, one fetch a level, then places its
//                   corner. Vertices past the top's count (a draw sized by a bound rather than by
//                   the read-back count) degenerate.
//   LVA_EMIT_CLOSE  vertex, 9 a border ring edge p: the edge that starts a leaf's border edge emits
//                   that edge's closing (spot: a triangle to the apex; directional: two wall
//                   triangles and one of the cap), others degenerate. Omni: 6 a unit edge of each
//                   of the 12 seams (its two triangles when it starts a leaf's border edge), 3 a
//                   corner.
// Omni lights (LVA_OMNI, six faces in one atlas; each stage above runs over all six) add:
//   LVA_FORCE       fragment, over the whole atlas at the start of a seam round: the thresholded
//                   pyramid (lva_threshold) plus the cells along a side that hold a position the
//                   last round's union forced (lva_forced), build's force_border; a face not
//                   re-tessellated (lva_dirty) keeps its cells.
//   LVA_UNITE       fragment, per position of each of the 24 face sides (lva_union, W × 24): 1 when
//                   the union of the seam's two borders holds it, 3 when this side lacks it (then
//                   LVA_CODE sets bit 30 of the pyramid: another seam round).
// The pyramid's base is lva_cells (R32UI, base width × height); levels 1..top lie in one RGBA32UI
// atlas, lva_pyramid, level k a rectangle of max(1, base >> k) texels at lva_px[k], lva_py[k].

uniform highp usampler2D lva_splits;
uniform ivec2 lva_map;  // W, H
uniform int lva_top;    // the root's level
uniform int lva_nx[16];
uniform int lva_ny[16];
uniform int lva_ox[16];
uniform int lva_oy[16];
uniform int lva_first[17];  // the first cell of level L; [top + 1]: cells in all
uniform ivec2 lva_base;     // the count pyramid's base, in texels (powers of two)
uniform int lva_levels;     // its top level (1 × 1)
uniform int lva_px[17];
uniform int lva_py[17];
uniform highp usampler2D lva_fails;    // the last fix-up round's marks (levels 2..top)
uniform highp usampler2D lva_cells;    // the pyramid's base
uniform highp usampler2D lva_pyramid;  // its levels 1..top
// Omni lights (LVA_OMNI): six faces' quadtrees in one atlas, level L's rectangle nx(L) × 6 ny(L),
// face f's cells in its rows f·ny(L) on; lva_f is the face a pass is working on.
uniform int lva_faces;  // 1, or 6 (LVA_OMNI)
int lva_f = 0;
// Bit 31 of a pyramid texel: the last fix-up round split a cell below; bit 30 (omni): a seam's
// border vertices were not yet on both its faces when the pyramid was built.
const uint kFlag = 0x80000000u, kSeam = 0x40000000u, kFlags = 0xc0000000u, kCount = 0x3fffffffu;

const uint kSplitTop = 1u, kSplitRight = 2u, kSplitBottom = 4u, kSplitLeft = 8u;
const uint kQuads = 17u;

bool in_level(int L, int i, int j) {
  return L >= 1 && L <= lva_top && i >= 0 && j >= 0 && i < lva_nx[L] && j < lva_ny[L];
}

// Cell (L, i, j) of face lva_f in the atlas.
ivec2 atlas_at(int L, int i, int j) { return ivec2(lva_ox[L] + i, lva_oy[L] + lva_f * lva_ny[L] + j); }

uint split_at(int L, int i, int j) {
  return in_level(L, i, j) ? texelFetch(lva_splits, atlas_at(L, i, j), 0).r : 0u;
}
bool is_split(int L, int i, int j) { return split_at(L, i, j) != 0u; }

// Cell box: texels x0..x1, y0..y1, clipped at the far edges.
ivec4 cell_box(int L, int i, int j) {
  int s = 1 << L;
  return ivec4(i * s, j * s, min(i * s + s, lva_map.x - 1), min(j * s + s, lva_map.y - 1));
}

// The edges of a leaf whose same-level neighbour is split and whose midpoint lies inside the
// (clipped) edge.
uint config_of(int L, int i, int j, ivec4 b) {
  int half_ = 1 << (L - 1);
  uint config = 0u;
  if (b.x + half_ < b.z) {
    if (is_split(L, i, j - 1)) config |= kSplitTop;
    if (is_split(L, i, j + 1)) config |= kSplitBottom;
  }
  if (b.y + half_ < b.w) {
    if (is_split(L, i - 1, j)) config |= kSplitLeft;
    if (is_split(L, i + 1, j)) config |= kSplitRight;
  }
  return config;
}

// The triangles of a cell in configuration `config` (detail::cell_triangles, in its order; lattice
// points, positively oriented in (col, row)). Returns the count.
int cell_triangles(ivec4 b, int half_, uint config, out ivec2 tri[18]) {
  ivec2 a = b.xy, bb = ivec2(b.z, b.y), c = ivec2(b.x, b.w), d = b.zw;
  ivec2 mt = ivec2(b.x + half_, b.y), mr = ivec2(b.z, b.y + half_), mb = ivec2(b.x + half_, b.w),
        ml = ivec2(b.x, b.y + half_);
  int n = 0;
  bool top_ = (config & kSplitTop) != 0u, right = (config & kSplitRight) != 0u,
       bottom = (config & kSplitBottom) != 0u, left = (config & kSplitLeft) != 0u;
  if (top_ && left) {
    tri[0] = a; tri[1] = mt; tri[2] = ml; tri[3] = mt; tri[4] = bb; tri[5] = ml;
    tri[6] = ml; tri[7] = bb; tri[8] = c; n = 3;
  } else if (top_) {
    tri[0] = a; tri[1] = mt; tri[2] = c; tri[3] = mt; tri[4] = bb; tri[5] = c; n = 2;
  } else if (left) {
    tri[0] = a; tri[1] = bb; tri[2] = ml; tri[3] = ml; tri[4] = bb; tri[5] = c; n = 2;
  } else {
    tri[0] = a; tri[1] = bb; tri[2] = c; n = 1;
  }
  int k = 3 * n;
  if (right && bottom) {
    tri[k] = mr; tri[k + 1] = d; tri[k + 2] = mb; tri[k + 3] = bb; tri[k + 4] = mr;
    tri[k + 5] = mb; tri[k + 6] = bb; tri[k + 7] = mb; tri[k + 8] = c; n += 3;
  } else if (right) {
    tri[k] = bb; tri[k + 1] = mr; tri[k + 2] = c; tri[k + 3] = mr; tri[k + 4] = d;
    tri[k + 5] = c; n += 2;
  } else if (bottom) {
    tri[k] = bb; tri[k + 1] = d; tri[k + 2] = mb; tri[k + 3] = bb; tri[k + 4] = mb;
    tri[k + 5] = c; n += 2;
  } else {
    tri[k] = bb; tri[k + 1] = d; tri[k + 2] = c; n += 1;
  }
  return n;
}

// The level and coordinates of the atlas texel p among levels first..top (x: 0 when none); sets
// lva_f to its face.
ivec3 atlas_cell(ivec2 p, int first) {
  for (int L = first; L <= lva_top; ++L) {
    ivec2 q = p - ivec2(lva_ox[L], lva_oy[L]);
    if (q.x >= 0 && q.y >= 0 && q.x < lva_nx[L] && q.y < lva_faces * lva_ny[L]) {
      lva_f = q.y / lva_ny[L];
      return ivec3(L, q.x, q.y - lva_f * lva_ny[L]);
    }
  }
  return ivec3(0);
}

// The triangles a cell of code `code` emits (LVA_CODE), its box b.
int code_triangles(uint code, ivec4 b) {
  if (code == 0u) return 0;
  if (code == kQuads) return 2 * (b.z - b.x) * (b.w - b.y);
  uint config = code - 1u;  // (GLSL ES 3.00 has no bitCount)
  return 2 + int(config & 1u) + int((config >> 1) & 1u) + int((config >> 2) & 1u) + int(config >> 3);
}

// The level and coordinates of cell c (lva_first's numbering, face by face); sets lva_f.
ivec3 cell_of(int c) {
  lva_f = c / lva_first[lva_top + 1];
  c -= lva_f * lva_first[lva_top + 1];
  int L = 1;
  while (L < lva_top && c >= lva_first[L + 1]) ++L;
  int k = c - lva_first[L];
  return ivec3(L, k % lva_nx[L], k / lva_nx[L]);
}

ivec2 level_size(int k) { return max(lva_base >> k, ivec2(1)); }

// Pyramid level k's texel q (q inside the level): its triangles, with bit 31 the flag.
uint pyramid_at(int k, ivec2 q) {
  if (k == 0) {
    uint v = texelFetch(lva_cells, q, 0).r;
    return (v & kFlags) | (v & 15u);
  }
  uvec4 c = texelFetch(lva_pyramid, ivec2(lva_px[k], lva_py[k]) + q, 0);
  uvec4 n = c & kCount;
  return (n.x + n.y + n.z + n.w) | ((c.x | c.y | c.z | c.w) & kFlags);
}

#ifdef LVA_OMNI
// The seams (build's omni_adaptive.cpp): positions along a face's side (GridSide: 0 top, 1 right,
// 2 bottom, 3 left; columns for top and bottom, rows for left and right, 0..W − 1).
// lva_union: W × 24 texels, row 4f + side (LVA_UNITE): 1 where the union of the seam's two borders
// has a vertex, 3 where that vertex is not yet on this side. lva_forced, the same layout: the
// border vertices a seam round forces (nonzero), build's BorderSplits: each side the union of the
// last seam round that found the side lacking a vertex (the host copies those rows over).
uniform highp usampler2D lva_forced;
uniform highp usampler2D lva_union;
// Per face side: the side across the seam, 8 g + 2 side + reversed.
uniform int lva_across[24];

// Cell (level L, index k along the side) of face lva_f's border row or column on `side`.
ivec2 side_cell(int L, int side, int k) {
  return side == 0 ? ivec2(k, 0) : side == 2 ? ivec2(k, lva_ny[L] - 1) : side == 3 ? ivec2(0, k)
                                                                                   : ivec2(lva_nx[L] - 1, k);
}

// Whether position p of side `side` of face f is a vertex of the face's quadtree: a corner, or a
// position inside (not at the ends of) the smallest cell along the side that has it inside, split.
bool border_vertex(int f, int side, int p) {
  int n = lva_map.x - 1;
  if (p <= 0 || p >= n) return true;
  int l = 0;
  while (((p >> l) & 1) == 0) ++l;
  int L = l + 1;
  lva_f = f;
  ivec2 c = side_cell(L, side, p >> L);
  return is_split(L, c.x, c.y);
}

// Face lva_f's leaf along `side` that holds the unit edge [k, k + 1] of the side: its edge's ends.
ivec2 side_leaf(int side, int k) {
  int n = lva_map.x - 1;
  for (int L = lva_top; L >= 1; --L) {
    ivec2 c = side_cell(L, side, k >> L);
    if (!is_split(L, c.x, c.y)) return ivec2((k >> L) << L, min(((k >> L) + 1) << L, n));
  }
  return ivec2(k, k + 1);
}
#endif

#if defined(LVA_OWN) || defined(LVA_BALANCE) || defined(LVA_TEST) || defined(LVA_CODE) || \
    defined(LVA_REDUCE) || defined(LVA_FORCE) || defined(LVA_UNITE)
uniform int lva_level;  // LVA_OWN, LVA_BALANCE, LVA_REDUCE
uniform int lva_round;  // LVA_BALANCE, LVA_TEST
// Omni: bit f set when face f is re-tessellated in this seam round (build's dirty faces: the
// first round all six, then those a side of which lacked a seam vertex); the others keep their
// quadtree as it is (LVA_FORCE copies it, LVA_BALANCE keeps it, LVA_TEST fails none of it).
uniform int lva_dirty;
bool clean() { return lva_faces == 6 && ((lva_dirty >> lva_f) & 1) == 0; }
#endif
#if defined(LVA_OWN) || defined(LVA_BALANCE) || defined(LVA_TEST) || defined(LVA_CODE) || \
    defined(LVA_FORCE) || defined(LVA_UNITE)
layout(location = 0) out uint lva_out;
#elif defined(LVA_REDUCE)
layout(location = 0) out uvec4 lva_out;
#endif

#if defined(LVA_OWN) || defined(LVA_TEST)
// The measure: TexelDepths::error (src/lightvol/tessellate/texel_depths.cpp), the world distance
// along texel (x, y)'s ray between its depth d and the depth dp of the triangle's plane there:
//   |dp − d| · G / |w(d) · w(dp)|,  w(z) = w0 + z · w1 (the homogeneous w of the ray's point),
// with G = |h1.xyz · h0.w − h0.xyz · h1.w| per texel. Perspective: with d∞ = −w0 / w1 (the depth of
// w = 0), |w(d) · w(dp)| = w1² · |d − d∞| · |dp − d∞|, and lva_rays holds, per texel in double
// rounded to float, K = G / w1² and d∞ as a sum hi + lo of two floats, so that d − d∞ = (d − hi) − lo
// loses nothing to cancellation. Orthographic (lva_uniform): the error is |dp − d| · lva_scale.
// The plane's dp − d = (d0 − d) + (d1 − d0)·β + (d2 − d0)·γ in the triangle's barycentrics: its
// rounding is at most a few units of 2^-24 times M = |d0 − d| + |d1 − d0|·β + |d2 − d0|·γ, and
// the rest of the measure's a few units relative; the margin allows 32 of each.
#ifdef LVA_OMNI
uniform highp sampler2D lva_depth[6];  // the six faces' maps (window depth), texture rows bottom-up
#else
uniform highp sampler2D lva_depth;  // the shadow map (window depth), texture rows bottom-up
#endif
uniform highp sampler2D lva_rays;   // per texel, build's rows: K, d∞ hi, d∞ lo
uniform int lva_uniform;
uniform float lva_scale;
uniform float lva_bound;  // the largest float <= E
const float kUnit = 5.9604645e-8;  // 2^-24

#ifdef LVA_OMNI
// (GLSL ES 3.00 indexes sampler arrays by constants only.)
float d_at(int x, int y) {
  ivec2 t = ivec2(x, lva_map.y - 1 - y);
  if (lva_f == 0) return texelFetch(lva_depth[0], t, 0).r;
  if (lva_f == 1) return texelFetch(lva_depth[1], t, 0).r;
  if (lva_f == 2) return texelFetch(lva_depth[2], t, 0).r;
  if (lva_f == 3) return texelFetch(lva_depth[3], t, 0).r;
  if (lva_f == 4) return texelFetch(lva_depth[4], t, 0).r;
  return texelFetch(lva_depth[5], t, 0).r;
}
#else
float d_at(int x, int y) { return texelFetch(lva_depth, ivec2(x, lva_map.y - 1 - y), 0).r; }
#endif

// Whether a texel of box b lies farther than E (with the margin) from the cell's triangles in
// configuration `config`.
bool cell_fails(ivec4 b, int half_, uint config) {
  ivec2 tri[18];
  int n = cell_triangles(b, half_, config, tri);
  ivec2 p0[6], e1[6], e2[6];
  int area[6];
  float d0[6], g1[6], g2[6], inv[6];
  for (int t = 0; t < n; ++t) {
    ivec2 a = tri[3 * t], u = tri[3 * t + 1] - a, v = tri[3 * t + 2] - a;
    int ar = u.x * v.y - u.y * v.x;
    if (ar < 0) {
      ivec2 s = u;
      u = v;
      v = s;
      ar = -ar;
    }
    p0[t] = a, e1[t] = u, e2[t] = v, area[t] = ar;
    d0[t] = d_at(a.x, a.y);
    g1[t] = d_at(a.x + u.x, a.y + u.y) - d0[t];
    g2[t] = d_at(a.x + v.x, a.y + v.y) - d0[t];
    inv[t] = 1.0 / float(ar);
  }
  for (int y = b.y; y <= b.w; ++y) {
    for (int x = b.x; x <= b.z; ++x) {
      for (int t = 0; t < n; ++t) {
        ivec2 q = ivec2(x, y) - p0[t];
        int bn = q.x * e2[t].y - q.y * e2[t].x, gn = e1[t].x * q.y - e1[t].y * q.x;
        if (bn < 0 || gn < 0 || bn + gn > area[t]) continue;
        float d = d_at(x, y);
        float beta = float(bn) * inv[t], gamma = float(gn) * inv[t];
        float a0 = d0[t] - d;
        float r = a0 + (g1[t] * beta + g2[t] * gamma);
        float m = abs(a0) + abs(g1[t]) * beta + abs(g2[t]) * gamma;
        float err, margin;
        if (lva_uniform == 1) {
          err = abs(r) * lva_scale;
          margin = 32.0 * kUnit * (err + m * lva_scale);
        } else {
          vec4 ray = texelFetch(lva_rays, ivec2(x, y), 0);
          float qd = (d - ray.y) - ray.z, qp = qd + r;
          float k = ray.x / (abs(qd) * abs(qp));
          err = abs(r) * k;
          margin = 32.0 * kUnit * (err + m * k * (1.0 + abs(r) / abs(qp)));
        }
        if (err + margin > lva_bound) return true;
        break;
      }
    }
  }
  return false;
}
#endif

#ifdef LVA_OWN
void main() {
  int L = lva_level;
  ivec2 c = ivec2(gl_FragCoord.xy) - ivec2(lva_ox[L], lva_oy[L]);
  lva_f = c.y / lva_ny[L];
  int i = c.x, j = c.y - lva_f * lva_ny[L];
  if (L > 1 && (is_split(L - 1, 2 * i, 2 * j) || is_split(L - 1, 2 * i + 1, 2 * j) ||
                is_split(L - 1, 2 * i, 2 * j + 1) || is_split(L - 1, 2 * i + 1, 2 * j + 1))) {
    lva_out = 1u;
    return;
  }
  lva_out = cell_fails(cell_box(L, i, j), 1 << (L - 1), 0u) ? 1u : 0u;
}
#endif

#ifdef LVA_BALANCE
void main() {
  int L = lva_level;
  ivec2 c = ivec2(gl_FragCoord.xy) - ivec2(lva_ox[L], lva_oy[L]);
  lva_f = c.y / lva_ny[L];
  int i = c.x, j = c.y - lva_f * lva_ny[L];
  uint mark = uint(lva_round) + 1u;
  uint old = split_at(L, i, j);
  if (clean()) {
    lva_out = old;
    return;
  }
  if (lva_round > 0 && texelFetch(lva_fails, atlas_at(L, i, j), 0).r == uint(lva_round)) {
    lva_out = mark;
    return;
  }
  if (old != 0u) {
    lva_out = old;
    return;
  }
  int l = L - 1, ci = 2 * i, cj = 2 * j;
  bool any = is_split(l, ci, cj) || is_split(l, ci + 1, cj) || is_split(l, ci, cj + 1) ||
             is_split(l, ci + 1, cj + 1) || is_split(l, ci - 1, cj) ||
             is_split(l, ci - 1, cj + 1) || is_split(l, ci + 2, cj) ||
             is_split(l, ci + 2, cj + 1) || is_split(l, ci, cj - 1) ||
             is_split(l, ci + 1, cj - 1) || is_split(l, ci, cj + 2) || is_split(l, ci + 1, cj + 2);
  lva_out = any ? mark : 0u;
}
#endif

#ifdef LVA_TEST
void main() {
  lva_out = 0u;
  ivec3 cl = atlas_cell(ivec2(gl_FragCoord.xy), 2);
  int L = cl.x, i = cl.y, j = cl.z;
  if (L < 2 || clean() || is_split(L, i, j)) return;
  uint parent = L == lva_top ? 1u : split_at(L + 1, i / 2, j / 2);
  if (parent == 0u) return;  // not a leaf
  if (lva_round > 1) {
    uint r = uint(lva_round);
    if (parent != r && split_at(L, i - 1, j) != r && split_at(L, i + 1, j) != r &&
        split_at(L, i, j - 1) != r && split_at(L, i, j + 1) != r)
      return;  // nothing around it changed since it passed
  }
  ivec4 b = cell_box(L, i, j);
  uint config = config_of(L, i, j, b);
  if (config == 0u) return;
  if (cell_fails(b, 1 << (L - 1), config)) lva_out = uint(lva_round);
}
#endif

#ifdef LVA_CODE
void main() {
  lva_out = 0u;
  ivec2 p = ivec2(gl_FragCoord.xy);
  int c = p.y * lva_base.x + p.x;
#ifdef LVA_OMNI
  // Texel c of lva_union (W × 24): whether a seam still lacks a vertex there.
  if (c < 24 * lva_map.x && texelFetch(lva_union, ivec2(c % lva_map.x, c / lva_map.x), 0).r == 3u)
    lva_out = kSeam;
#endif
  if (c >= lva_faces * lva_first[lva_top + 1]) return;
  ivec3 cl = cell_of(c);
  int L = cl.x, i = cl.y, j = cl.z;
  bool split = is_split(L, i, j);
  ivec4 b = cell_box(L, i, j);
  uint code = 0u;
  if (L == 1 && split) {
    code = kQuads;
  } else if (!split && (L == lva_top || is_split(L + 1, i / 2, j / 2))) {
    code = 1u + config_of(L, i, j, b);
  }
  uint mark = L >= 2 ? texelFetch(lva_fails, atlas_at(L, i, j), 0).r : 0u;
  lva_out |= code << 4 | uint(code_triangles(code, b)) | (mark != 0u ? kFlag : 0u);
}
#endif

#ifdef LVA_FORCE
// Omni, the start of a seam round, over the whole atlas: a cell splits when its threshold did, or
// when it lies along a side with a forced position inside it (RefinementPyramid::tessellate's
// force_border: every cell whose interior along the side holds the position).
uniform highp usampler2D lva_threshold;
void main() {
  lva_out = 0u;
  ivec2 p = ivec2(gl_FragCoord.xy);
  ivec3 cl = atlas_cell(p, 1);
  int L = cl.x, i = cl.y, j = cl.z;
  if (L == 0) return;
  if (clean()) {
    lva_out = texelFetch(lva_splits, p, 0).r;
    return;
  }
  if (texelFetch(lva_threshold, p, 0).r != 0u) {
    lva_out = 1u;
    return;
  }
  int s = 1 << L, n = lva_map.x - 1;
  for (int side = 0; side < 4; ++side) {
    bool on = side == 0 ? j == 0 : side == 2 ? j == lva_ny[L] - 1 : side == 3 ? i == 0 : i == lva_nx[L] - 1;
    if (!on) continue;
    int k = side == 0 || side == 2 ? i : j;
    for (int q = k * s + 1; q < min(k * s + s, n); ++q)
      if (texelFetch(lva_forced, ivec2(q, 4 * lva_f + side), 0).r != 0u) {
        lva_out = 1u;
        return;
      }
  }
}
#endif

#ifdef LVA_UNITE
// Omni, the end of a seam round, per position p of face f's side (texel (p, 4f + side)): the
// union of the seam's two borders (build's unite_seams), 3 where this side lacks it.
void main() {
  ivec2 t = ivec2(gl_FragCoord.xy);
  int f = t.y / 4, side = t.y - 4 * f, p = t.x;
  int across = lva_across[t.y], g = across / 8, gside = (across / 2) % 4;
  bool mine = border_vertex(f, side, p);
  bool theirs = border_vertex(g, gside, (across & 1) == 1 ? lva_map.x - 1 - p : p);
  lva_out = mine ? 1u : theirs ? 3u : 0u;
}
#endif

#ifdef LVA_REDUCE
void main() {
  int k = lva_level;  // the level written; k − 1 is read
  ivec2 p = 2 * (ivec2(gl_FragCoord.xy) - ivec2(lva_px[k], lva_py[k])), size = level_size(k - 1);
  bool right = p.x + 1 < size.x, down = p.y + 1 < size.y;
  lva_out = uvec4(pyramid_at(k - 1, p), right ? pyramid_at(k - 1, p + ivec2(1, 0)) : 0u,
                  down ? pyramid_at(k - 1, p + ivec2(0, 1)) : 0u,
                  right && down ? pyramid_at(k - 1, p + ivec2(1, 1)) : 0u);
}
#endif

#if defined(LVA_EMIT_GRID) || defined(LVA_EMIT_CLOSE)
uniform mat4 view_projection;
out vec3 world;
// For read-back by transform feedback (tests): kind << 28 | col << 14 | row; kind 0 none (a
// degenerate triangle's vertex), 1 grid vertex of texel (col, row), 2 the apex, 3 the near-plane
// copy of texel (col, row), 4 the cap's centre (col and row 0 for kinds 0, 2 and 4), 8 + f grid
// vertex of texel (col, row) of omni face f.
flat out uint lva_vertex;
uniform int lva_standard;  // omni: bit f set when face f's grid is wound as the standard one

void emit(int kind, ivec2 t) {
  lva_vertex = kind == 1 || kind == 3 || kind >= 8 ? uint(kind) << 28 | uint(t.x) << 14 | uint(t.y)
                                                   : uint(kind) << 28;
  if (kind >= 8) {
    world = (live_eye_to_world[kind - 8] * vec4(live_grid_point(kind - 8, t), 1.0)).xyz;
    gl_Position = view_projection * vec4(world, 1.0);
    return;
  }
  if (kind == 0) {
    world = vec3(0.0);
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: the triangle is culled
    return;
  }
  if (kind == 1) {
    world = (live_eye_to_world[0] * vec4(live_grid_point(0, t), 1.0)).xyz;
  } else if (kind == 2) {
    world = live_apex;
  } else if (kind == 3) {
    world = (live_eye_to_world[0] * vec4(live_segment(live_ndc(t), 0.0), 1.0)).xyz;
  } else {
    world = live_cap;
  }
  gl_Position = view_projection * vec4(world, 1.0);
}
#endif

#ifdef LVA_EMIT_GRID
void main() {
  int t = gl_VertexID / 3, corner = gl_VertexID - 3 * t;
  uint rest = uint(t);
  // Down the pyramid: at each level the child whose running count passes `rest`.
  ivec2 p = ivec2(0);
  for (int k = lva_levels; k >= 1; --k) {
    uvec4 n = texelFetch(lva_pyramid, ivec2(lva_px[k], lva_py[k]) + p, 0) & kCount;
    if (k == lva_levels && rest >= n.x + n.y + n.z + n.w) {
      emit(0, ivec2(0));
      return;
    }
    p *= 2;
    if (rest < n.x) continue;
    rest -= n.x;
    if (rest < n.y) {
      p.x += 1;
      continue;
    }
    rest -= n.y;
    if (rest < n.z) {
      p.y += 1;
      continue;
    }
    rest -= n.z;
    p += 1;
  }
  uint code = (texelFetch(lva_cells, p, 0).r & kCount) >> 4;
  ivec3 cl = cell_of(p.y * lva_base.x + p.x);
  int L = cl.x, i = cl.y, j = cl.z, tt = int(rest);
#ifdef LVA_OMNI
  int kind = 8 + lva_f;
  if (((lva_standard >> lva_f) & 1) == 0 && corner != 0) corner = 3 - corner;  // build's winding
#else
  int kind = 1;
  if (live_standard == 0 && corner != 0) corner = 3 - corner;  // build's winding
#endif
  ivec4 b = cell_box(L, i, j);
  ivec2 tri[18];
  if (code == kQuads) {
    int qx = b.z - b.x, q = tt / 2;  // the cell's quads inside the map, row by row
    ivec2 quad = b.xy + ivec2(q % qx, q / qx);
    cell_triangles(ivec4(quad, quad + 1), 0, 0u, tri);
    emit(kind, tri[3 * (tt % 2) + corner]);
    return;
  }
  cell_triangles(b, 1 << (L - 1), code - 1u, tri);
  emit(kind, tri[3 * tt + corner]);
}
#endif

#if defined(LVA_EMIT_CLOSE) && defined(LVA_OMNI)
// The omni closing (build's OmniRefinement::build): 6 vertices for each unit edge k of each seam's
// first side, the seam's two triangles between the border vertices at k and the next one (when
// k is one), then 3 for each of the eight corners.
uniform int lva_seam[72];    // per seam: face, side, face across, its side, reversed, flip
uniform int lva_corner[72];  // per corner, 3 × (face, last column, last row)

ivec2 side_texel(int side, int position) {
  int n = lva_map.x - 1;
  return side == 0 ? ivec2(position, 0) : side == 2 ? ivec2(position, n) : side == 3 ? ivec2(0, position)
                                                                                     : ivec2(n, position);
}

void main() {
  int n = lva_map.x - 1, id = gl_VertexID;
  if (id >= 72 * n) {
    int c = (id - 72 * n) / 3, m = id - 72 * n - 3 * c;
    int f = lva_corner[9 * c + 3 * m];
    emit(8 + f, ivec2(lva_corner[9 * c + 3 * m + 1] * n, lva_corner[9 * c + 3 * m + 2] * n));
    return;
  }
  int s = id / (6 * n), k = (id / 6) % n, v = id % 6;
  int fa = lva_seam[6 * s], sa = lva_seam[6 * s + 1], fb = lva_seam[6 * s + 2], sb = lva_seam[6 * s + 3];
  bool reversed = lva_seam[6 * s + 4] == 1, flip = lva_seam[6 * s + 5] == 1;
  lva_f = fa;
  ivec2 e = side_leaf(sa, k);
  if (e.x != k) {
    emit(0, ivec2(0));
    return;
  }
  // a0 = (fa, e.x), a1 = (fa, e.y), b0 = (fb, e.x), b1 = (fb, e.y); (a0, a1, b0), (a1, b1, b0),
  // the last two corners swapped when flip.
  int t = v / 3, corner = v - 3 * t;
  if (flip && corner != 0) corner = 3 - corner;
  bool across = t == 0 ? corner == 2 : corner != 0;
  int position = t == 0 ? (corner == 1 ? e.y : e.x) : (corner == 2 ? e.x : e.y);
  if (across) emit(8 + fb, side_texel(sb, reversed ? n - position : position));
  else emit(8 + fa, side_texel(sa, position));
}
#elif defined(LVA_EMIT_CLOSE)
void main() {
  int p = gl_VertexID / 9, v = gl_VertexID - 9 * p;
  int perimeter = 2 * (lva_map.x - 1) + 2 * (lva_map.y - 1);
  ivec2 u = live_ring_texel(p), w = live_ring_texel((p + 1) % perimeter);
  int wl = lva_map.x - 1, hl = lva_map.y - 1;
  // The quad inside the map along this unit edge, and the side it lies on (0 top, 1 bottom,
  // 2 left, 3 right).
  int side;
  ivec2 quad;
  if (u.y == 0 && w.y == 0) {
    side = 0, quad = ivec2(min(u.x, w.x), 0);
  } else if (u.y == hl && w.y == hl) {
    side = 1, quad = ivec2(min(u.x, w.x), hl - 1);
  } else if (u.x == 0 && w.x == 0) {
    side = 2, quad = ivec2(0, min(u.y, w.y));
  } else {
    side = 3, quad = ivec2(wl - 1, min(u.y, w.y));
  }
  // The leaf that holds the quad, and its edge on that side.
  ivec4 b = ivec4(quad, quad + 1);
  for (int L = lva_top; L >= 1; --L) {
    if (!is_split(L, quad.x >> L, quad.y >> L)) {
      b = cell_box(L, quad.x >> L, quad.y >> L);
      break;
    }
  }
  ivec2 e0 = side == 0 ? b.xy : side == 1 ? b.xw : side == 2 ? b.xy : b.zy;
  ivec2 e1 = side == 0 ? b.zy : side == 1 ? b.zw : side == 2 ? b.xw : b.zw;
  if (u != e0 && u != e1) {
    emit(0, ivec2(0));
    return;
  }
  ivec2 nxt = u == e0 ? e1 : e0;
  // Build's closing of the ring edge u -> nxt (closing.cpp): spot (nxt, u, apex); directional
  // (nxt, u, u'), (nxt, u', nxt'), (nxt', u', cap), ' the near-plane copy.
  int t = v / 3, corner = v - 3 * t;
  if (live_type == 0) {
    if (t > 0) emit(0, ivec2(0));
    else emit(corner == 0 ? 1 : corner == 1 ? 1 : 2, corner == 0 ? nxt : u);
    return;
  }
  if (t == 0) emit(corner == 2 ? 3 : 1, corner == 0 ? nxt : u);
  else if (t == 1) emit(corner == 0 ? 1 : 3, corner == 2 ? nxt : corner == 0 ? nxt : u);
  else emit(corner == 2 ? 4 : 3, corner == 0 ? nxt : u);
}
#endif

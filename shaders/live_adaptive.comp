// lightvol's adaptive live volume (docs/rendering.md, "Live volumes"): the compute passes that
// tessellate a shadow map at a bound E on the GPU, every frame, into a vertex and an index buffer
// and the indirect draw command that draws them. The quadtree is `lightvol build --adaptive
// --tessellation quadtree`'s (src/lightvol/tessellate/): the same cells, the same measures in
// double precision, the same 2:1 balance, the same fix-up rounds and the same 16 edge-split
// configurations, so the same triangles. (Without `precise`, which made the double arithmetic
// several times slower on llvmpipe: there the quadtree is the CPU's in every test; a GPU that
// fuses multiply-adds may round a measure in its last bit differently, which can only change a
// cell whose measure lies within that rounding of E.)
//
// The host prepends "#version 450 core", "#define LIGHTVOL_LIVE_COMMON", one "#define LV_<PASS>"
// and shaders/airlight.glsl (for live_grid_point, live_segment and live_ring_texel), then this
// file. Passes, in the order of a frame (render/live_adaptive.cpp):
//   LV_TEXELS    per texel: window depth and error scale in double (TexelDepths).
//   LV_OWN       per level 1..top, per cell and band of rows: a cell splits when a child did, or
//                when one of its texels lies farther than E from the cell's two triangles (the
//                pyramid's value above E).
//   LV_BALANCE   per level 2..top: a cell splits when a child or a child's neighbour did (2:1).
//   LV_CONTROL   one invocation before the fix-up rounds: round 1's face list and dispatch size
//                (without an omni face that sits the seam round out).
//   LV_TEST      fix-up round r: leaves whose split configuration breaks E (round 1 tests every
//                leaf, later rounds those whose parent or neighbour split in the round before;
//                omni: round 1 of a seam round after the first reuses the verdict on a leaf
//                that kept its configuration since the seam round before); a face's first
//                failure lists it for round r + 1 (no face listed: round r + 1's dispatches,
//                its LV_PROPAGATE's included, have zero work groups).
//   LV_PROPAGATE fix-up round r's balance in one pass, on the faces whose test failed a leaf:
//                each cell the test failed splits, and every cell that LV_BALANCE's rule then
//                splits, level after level upwards (the same closure that LV_BALANCE's
//                level-by-level passes reach).
//   LV_COUNT     per cell: triangles it emits, and its vertices marked in a bitmap.
//   LV_SCAN_*    exclusive prefix sums (triangle offsets; vertex ranks from the bitmap).
//   LV_TRIANGLES per emitting cell (listed by LV_COUNT): its triangles, as indices of vertex
//                ranks.
//   LV_VERTICES  per bitmap word: its vertices' world positions and texel ids.
//   LV_CLOSE     one invocation: the border ring's closing (spot fan, directional walls and cap),
//                the draw command and the statistics.
// LV_RESET, LV_BALANCE, LV_CONTROL, LV_TEST and LV_PROPAGATE run on all of an omni light's faces
// in one dispatch (LV_FACES_PASS below); the other per-face passes run one face after the other
// (the host binds each face's ranges of the per-face buffers and sets lv_face). In seam rounds as
// build_adaptive_omni_volume runs them (volume/omni_adaptive.cpp): each round tessellates every
// face from its threshold with its forced border vertices, then the seams' two borders are united
// and a side that lacks some of its seam's vertices takes the union as its forced vertices; the
// rounds end when no side changes. Passes of the omni volume:
//   LV_SEAM_CONTROL one invocation before seam round s: whether the round before changed a side;
//                the round's dispatch sizes (zero once the borders agree).
//   LV_RESET     per face and cell: the threshold's split, plus the forced border vertices.
//   LV_UNITE     per seam and border position: the union of the seam's two borders.
//   LV_APPLY     per face side and position: a side that lacked some takes the union.
//   LV_BASE      one invocation per face after its scans: the face's first vertex and triangle in
//                the volume, its fix-up statistics.
//   LV_SEAMS     one invocation: the seam strips and the corner triangles, the draw command and the
//                statistics (instead of LV_CLOSE).
// Cells: level L ≥ 1 holds nx(L) × ny(L) cells of 2^L quads a side, clipped at the far edges;
// split[] holds them level after level (offsets in Params), 0 for an unsplit cell and r + 1 for a
// cell split in round r (0: threshold and first balance).

layout(local_size_x = 64) in;

// The omni passes that need none of the per-texel buffers (a program holds 16 blocks at most).
#if defined(LV_UNITE) || defined(LV_APPLY) || defined(LV_SEAM_CONTROL)
#define LV_SEAM_PASS
#endif

// The passes that work on several faces in one dispatch (every face of a seam round, or a group
// of them: render/live_adaptive.cpp's faces_per_dispatch), each work group on one face: the face
// from the list control[group control + face_list + gl_WorkGroupID.z], its ranges of the per-face
// buffers at face stride offsets (the group's first face's ranges bound first), its Params read
// from the block as doubles (offsets of the members below; static_asserts in live_adaptive.cpp).
// The other passes run face by face with that face's ranges bound (lv_face a uniform).
#if defined(LV_RESET) || defined(LV_BALANCE) || defined(LV_CONTROL) || defined(LV_TEST) || \
    defined(LV_PROPAGATE)
#define LV_FACES_PASS
#endif

#ifdef LV_FACES_PASS
layout(std430, binding = 0) readonly buffer Params { double params_[]; };
#define w0_c params_[fp + 20]
#define w0_dc params_[fp + 21]
#define w0_dr params_[fp + 22]
#define w1 params_[fp + 23]
#define uniform_scale params_[fp + 24]
#define bound params_[fp + 31]
#define pyramid_bound params_[fp + 32]
#define p_width params_[fp + 33]
#define p_height params_[fp + 34]
#define p_flip_y params_[fp + 35]
#define p_encoding params_[fp + 36]
#define p_uniform_flag params_[fp + 37]
#define p_standard params_[fp + 38]
#define p_type params_[fp + 39]
#define p_cells_total params_[fp + 40]
#define nx_at(L) int(params_[fp + 41 + (L)])
#define ny_at(L) int(params_[fp + 57 + (L)])
#define offset_at(L) int(params_[fp + 73 + (L)])
uniform int lv_first_face;  // the first face of the dispatch's group (its ranges bound first)
uniform int face_list;      // the group's face list: control[group_control + face_list + ...]
// Elements between two faces' ranges: Params (doubles), depth[], scale[], the per-cell buffers
// (split[], fail[], verdict[], threshold_split[]), control[].
uniform int stride_params, stride_texels, stride_scales, stride_cells, stride_control;
int lv_face = 0;                               // the face this work group works on
int fp = 0, ft = 0, fs = 0, fc = 0, fk = 0;    // its Params, depth, scale, cell and control bases
int group_control = 0;  // control[] of the group (its first face's): round sizes, face lists
#else
layout(std430, binding = 0) readonly buffer Params {
  double m[16];  // clip to world, row-major (inverse(view) · inverse(projection))
  double h1[4];
  double w0_c, w0_dc, w0_dr, w1, uniform_scale;
  double pz, pzc, pw, pwc, near_d, far_d;
  double bound;          // E, for the fix-up's triangle tests
  double pyramid_bound;  // the largest float <= E: a value rounded up to float exceeds E iff
                         // the double exceeds this
  // The integers, as doubles: every member of the block 8-byte aligned (llvmpipe misread an int
  // at an offset of 4 mod 8 in this block, in some invocations).
  double p_width, p_height, p_flip_y, p_encoding;  // encoding: 0 window, 1 linear
  double p_uniform_flag, p_standard, p_type, p_cells_total;  // type: 0 spot, 1 directional, 2 omni
  double p_nx[16];
  double p_ny[16];
  double p_offset[17];  // first cell of level L (1..top) in split[]; [top + 1]: cells_total
};
#define nx_at(L) int(p_nx[L])
#define ny_at(L) int(p_ny[L])
#define offset_at(L) int(p_offset[L])
uniform int lv_face;  // the face the per-face passes run on (0: spot, directional)
const int fp = 0, ft = 0, fs = 0, fc = 0, fk = 0;
#endif

#define width int(p_width)
#define height int(p_height)
#define flip_y int(p_flip_y)
#define encoding int(p_encoding)
#define uniform_flag int(p_uniform_flag)
#define standard int(p_standard)
#define type int(p_type)
#define cells_total int(p_cells_total)

#ifndef LV_SEAM_PASS
layout(std430, binding = 1) buffer Depths { double depth[]; };
layout(std430, binding = 2) buffer Scales { double scale[]; };
#endif
layout(std430, binding = 3) coherent buffer Splits { uint split[]; };
layout(std430, binding = 4) buffer Fails { uint fail[]; };
// control[0..63]: fails per round; stats from control[160] on; control[kDraw..kDraw + 4]: the
// indirect draw command; control[kRoundArgs + 3 r..+2]: fix-up round r's dispatch size (its test
// and LV_PROPAGATE), written by LV_CONTROL (round 1) and by the round before (LV_PROPAGATE).
layout(std430, binding = 5) coherent buffer Control { uint control[]; };
layout(std430, binding = 6) buffer Bits { uint bits[]; };
#ifndef LV_SEAM_PASS
layout(std430, binding = 7) buffer Counts { uint tri_count[]; };   // per cell
layout(std430, binding = 16) buffer Offsets { uint tri_offset[]; };  // per cell: its first one
layout(std430, binding = 8) buffer Ranks { uint word_rank[]; };    // per bitmap word
layout(std430, binding = 9) buffer Indices { uint indices[]; };
layout(std430, binding = 10) buffer Positions { float positions[]; };
layout(std430, binding = 11) buffer TexelIds { uint texel_ids[]; };
layout(std430, binding = 13) buffer ScanSums { uint scan_sums[]; };
#endif
// The volume's state across faces (omni; zero for spot and directional lights): [0] the borders
// agree (no more seam rounds), [1] seam rounds run, [8 + 4 face + side] the side changed in this
// seam round, [32 + face] the face's first vertex ([38]: all the faces' vertices), [40 + face] its
// first triangle ([46]: all the faces' triangles), [48 + face] 1 when the face sits this seam
// round out (its forced vertices did not change: it would tessellate the same), [kOmniArgs +
// 3 (kSeamSlots face + slot)] the seam round's dispatch sizes per face (LV_UNITE's and
// LV_APPLY's: face 0's).
// (Each block declared only for the passes that use it: a compute program holds 16 at most.)
#if defined(LV_CONTROL) || defined(LV_TRIANGLES) || defined(LV_VERTICES) || \
    defined(LV_SEAM_CONTROL) || defined(LV_UNITE) || defined(LV_APPLY) || defined(LV_BASE) || \
    defined(LV_SEAMS)
layout(std430, binding = 17) coherent buffer Omni { uint omni[]; };
#endif
#ifdef LV_RESET
layout(std430, binding = 18) buffer Threshold { uint threshold_split[]; };  // per face: split[]
                                                                            // after LV_OWN
#endif
// Per face side (4 face + GridSide) and position along it: W values each.
#if defined(LV_RESET) || defined(LV_APPLY)
layout(std430, binding = 19) buffer Forced { uint forced[]; };
#endif
#if defined(LV_UNITE) || defined(LV_APPLY)
layout(std430, binding = 20) buffer Union { uint united[]; };
#endif
#ifdef LV_UNITE
layout(std430, binding = 21) buffer AllSplits { uint all_split[]; };  // every face's split[]
#endif
#if defined(LV_VERTICES) || defined(LV_SEAMS)
layout(std430, binding = 22) buffer BorderIndex { uint border_index[]; };  // vertex, or kNone
#endif
#ifdef LV_SEAM_CONTROL
layout(std430, binding = 23) buffer SeamTemplate { uint seam_template[]; };
#endif

// The root's level, as a uniform (read from Params it came back 0 in some invocations of some
// passes on llvmpipe).
uniform int top_level;
uniform int level;   // LV_OWN, LV_BALANCE
uniform int round_;  // LV_BALANCE, LV_TEST, LV_PROPAGATE
uniform int rounds;  // LV_CONTROL, LV_CLOSE: the most fix-up rounds a frame runs
uniform int split_stride;  // LV_UNITE: uints between two faces' split[] in all_split[]
// Omni: the cube's twelve seams (face a, its GridSide, face b, its side, reversed, flip) and eight
// corners (face, last_col, last_row, three times), as omni_adjacency lists them.
uniform int seam_desc[72];
uniform int corner_desc[72];

const uint kNone = 0xFFFFFFFFu;
const uint kOmniArgs = 128u;
const int kSideTop = 0, kSideRight = 1, kSideBottom = 2, kSideLeft = 3;  // GridSide

const int kBandRows = 16;
const uint kStats = 160u;  // control[kStats + ...]: rounds used, converged, grid vertices, grid
                           // triangles, closing triangles
const uint kDraw = 192u;
const uint kRoundArgs = 256u;
const uint kEmitting = kStats + 6u;  // cells that emit triangles (LV_COUNT)
const uint kTriangleArgs = 100u;     // LV_TRIANGLES' dispatch size (LV_SCAN_SUMS)
const uint kSplitTop = 1u, kSplitRight = 2u, kSplitBottom = 4u, kSplitLeft = 8u;
// control[kFaceLists + 8 r + k] (the group's control[]): the k-th face of fix-up round r's
// dispatch (r = 0: the balance's and LV_RESET's, the faces tessellated in this seam round).
const uint kFaceLists = 512u;

#ifdef LV_FACES_PASS
void select_face(int f) {
  lv_face = f;
  int k = f - lv_first_face;
  fp = k * stride_params, ft = k * stride_texels, fs = k * stride_scales, fc = k * stride_cells;
  fk = f * stride_control;  // control[] is bound whole
  group_control = lv_first_face * stride_control;
}
// This work group's face, from the dispatch's face list.
void select_listed_face() {
  group_control = lv_first_face * stride_control;
  select_face(int(control[group_control + face_list + int(gl_WorkGroupID.z)]));
}
#endif

// This invocation's index: dispatches of more than kMaxGroupsX groups run as rows of that many
// (a dimension holds at most 65535 groups).
const uint kMaxGroupsX = 32768u;
int invocation() {
  return int(gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x +
             gl_GlobalInvocationID.x);
}

// a / b (integer quotient) for 0 <= a < 2^31 and b > 0, through a double division, which llvmpipe
// vectorises where it divides integers one lane at a time. Exact: a quotient that is not an
// integer lies at least 1 / b from the next one, and the division rounds it by at most
// (a / b) · 2^-53, less than that for any a below 2^53; an integer quotient is exact.
int idiv(int a, int b) { return int(double(a) / double(b)); }

int cell_index(int L, int i, int j) { return offset_at(L) + j * nx_at(L) + i; }

bool in_level(int L, int i, int j) {
  return L >= 1 && L <= top_level && i >= 0 && j >= 0 && i < nx_at(L) && j < ny_at(L);
}

uint split_at(int L, int i, int j) {
  return in_level(L, i, j) ? split[fc + cell_index(L, i, j)] : 0u;
}
bool is_split(int L, int i, int j) { return split_at(L, i, j) != 0u; }

// Cell box: texels x0..x1, y0..y1 (build's rows: row 0 the top of the light's view).
ivec4 cell_box(int L, int i, int j) {
  int s = 1 << L;
  return ivec4(i * s, j * s, min(i * s + s, width - 1), min(j * s + s, height - 1));
}

#ifndef LV_SEAM_PASS
double d_at(int x, int y) { return depth[ft + y * width + x]; }
#endif

// The level and coordinates of flattened cell c (levels from `first` on).
ivec3 cell_of(int c, int first) {
  int L = first;
  while (L < top_level && c >= offset_at(L + 1)) ++L;
  int k = c - offset_at(L);
  int j = idiv(k, nx_at(L));
  return ivec3(L, k - j * nx_at(L), j);
}

// Configuration of a leaf: the edges whose same-level neighbour is split and whose midpoint lies
// inside the (clipped) edge.
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

// The triangles of a cell in configuration `config` (lattice points, positively oriented in
// (col, row)): detail::cell_triangles, in its order. Returns the count.
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

#ifdef LV_TEXELS
void main() {
  int v = invocation();
  if (v >= width * height) return;
  int row = idiv(v, width), col = v - row * width;
  int texture_row = flip_y == 1 ? row : height - 1 - row;
  double stored = double(live_fetch(lv_face, ivec2(col, texture_row)));
  // A NaN texel is the near plane's, as the static live volume places it (GLSL leaves clamp of a
  // NaN undefined: GPUs differ).
  if (isnan(stored)) stored = encoding == 0 ? 0.0LF : near_d;
  double d;
  if (encoding == 0) {
    d = clamp(stored, 0.0LF, 1.0LF);
  } else {
    double z = -clamp(stored, near_d, far_d);
    d = clamp(0.5LF * ((pz * z + pzc) / (pw * z + pwc) + 1.0LF), 0.0LF, 1.0LF);
  }
  depth[v] = d;
  if (uniform_flag == 0) {
    double x = 2.0LF * (double(col) + 0.5LF) / double(width) - 1.0LF;
    double y_down = 2.0LF * (double(row) + 0.5LF) / double(height) - 1.0LF;
    double y = flip_y == 1 ? y_down : -y_down;
    double h0[4];
    for (int k = 0; k < 4; ++k) h0[k] = m[4 * k] * x + m[4 * k + 1] * y - m[4 * k + 2] + m[4 * k + 3];
    double gx = h1[0] * h0[3] - h0[0] * h1[3];
    double gy = h1[1] * h0[3] - h0[1] * h1[3];
    double gz = h1[2] * h0[3] - h0[2] * h1[3];
    double len = sqrt(gx * gx + gy * gy + gz * gz);
    scale[v] = len / abs(h0[3] + d * h1[3]);
  }
}
#endif

#ifdef LV_OWN
// TexelDepths::error at texel (x, y) for the plane's depth dp, with the denominator's w0 given.
double texel_error(int x, int y, double dp, double w0) {
  double e = abs(dp - d_at(x, y));
  if (uniform_flag == 1) return e;  // times uniform_scale by the caller
  double r = e * scale[y * width + x] / abs(w0 + dp * w1);
  return r;
}

void main() {
  int L = level;
  int bands = ((1 << L) + kBandRows) / kBandRows;
  int task = invocation();
  if (task >= nx_at(L) * ny_at(L) * bands) return;
  int cell = idiv(task, bands), band = task - cell * bands;
  int j = idiv(cell, nx_at(L)), i = cell - j * nx_at(L);
  int c = cell_index(L, i, j);
  if (split[c] != 0u) return;
  if (L > 1 && (is_split(L - 1, 2 * i, 2 * j) || is_split(L - 1, 2 * i + 1, 2 * j) ||
                is_split(L - 1, 2 * i, 2 * j + 1) || is_split(L - 1, 2 * i + 1, 2 * j + 1))) {
    split[c] = 1u;
    return;
  }
  ivec4 b = cell_box(L, i, j);
  double worst = 0.0LF;
  if (L == 1 && b.z - b.x == 2 && b.w - b.y == 2) {
    // A whole level-1 cell: five texels, each halfway along an edge or the diagonal.
    int x = b.x, y = b.y;
    double da = d_at(x, y), db = d_at(x + 2, y), dc = d_at(x, y + 2),
                   dd = d_at(x + 2, y + 2);
    ivec2 p[5] = ivec2[5](ivec2(x + 1, y), ivec2(x, y + 1), ivec2(x + 1, y + 1),
                          ivec2(x + 2, y + 1), ivec2(x + 1, y + 2));
    double dp[5] = double[5](0.5LF * (da + db), 0.5LF * (da + dc), 0.5LF * (db + dc),
                                     0.5LF * (db + dd), 0.5LF * (dc + dd));
    for (int k = 0; k < 5; ++k) {
      double w0 = w0_c + double(p[k].x) * w0_dc + double(p[k].y) * w0_dr;
      worst = max(worst, texel_error(p[k].x, p[k].y, dp[k], w0));
    }
    if (uniform_flag == 1) worst *= uniform_scale;
    if (worst > pyramid_bound) split[c] = 1u;
    return;
  }
  int wx = b.z - b.x, wy = b.w - b.y;
  double da = d_at(b.x, b.y), db = d_at(b.z, b.y), dc = d_at(b.x, b.w),
                 dd = d_at(b.z, b.w);
  double g1x = (db - da) / double(wx), g1y = (dc - da) / double(wy);
  double g2x = (dd - dc) / double(wx), g2y = (dd - db) / double(wy);
  // The cell's 2^L + 1 rows shared out evenly between its bands (at most kBandRows each), so
  // that the lanes running a cell's bands side by side loop as often as each other.
  int per_band = ((1 << L) + bands) / bands;
  int y_begin = b.y + band * per_band, y_end = min(b.y + (band + 1) * per_band, b.w + 1);
  for (int y = y_begin; y < y_end; ++y) {
    int s = y - b.y;
    int xs = b.x + (wx == wy ? wy - s : idiv(wx * (wy - s), wy));
    double base1 = da + g1y * double(s), base2 = dd + g2y * double(y - b.w);
    double w0y = w0_c + 0.0LF * w0_dc + double(y) * w0_dr;
    for (int x = b.x; x <= b.z; ++x) {
      double dp =
          x <= xs ? base1 + g1x * double(x - b.x) : base2 + g2x * double(x - b.z);
      double w0 = w0y + w0_dc * double(x);
      worst = max(worst, texel_error(x, y, dp, w0));
    }
    // A texel above the bound decides the cell: stop the band (and the other bands of the cell).
    double scaled = uniform_flag == 1 ? worst * uniform_scale : worst;
    if (scaled > pyramid_bound) {
      split[c] = 1u;
      return;
    }
    if (split[c] != 0u) return;
  }
}
#endif

#ifdef LV_BALANCE
void main() {
  select_listed_face();
  int L = level;
  int cell = invocation();
  if (cell >= nx_at(L) * ny_at(L)) return;
  int j = idiv(cell, nx_at(L)), i = cell - j * nx_at(L);
  int c = fc + cell_index(L, i, j);
  uint mark = uint(round_) + 1u;
  if (split[c] != 0u) return;
  int l = L - 1, ci = 2 * i, cj = 2 * j;
  bool any = is_split(l, ci, cj) || is_split(l, ci + 1, cj) || is_split(l, ci, cj + 1) ||
             is_split(l, ci + 1, cj + 1) || is_split(l, ci - 1, cj) ||
             is_split(l, ci - 1, cj + 1) || is_split(l, ci + 2, cj) ||
             is_split(l, ci + 2, cj + 1) || is_split(l, ci, cj - 1) ||
             is_split(l, ci + 1, cj - 1) || is_split(l, ci, cj + 2) || is_split(l, ci + 1, cj + 2);
  if (any) split[c] = mark;
}
#endif

#ifdef LV_CONTROL
// Once per group of faces before the fix-up rounds: round 1's face list and dispatch size (the
// test's: the cells of levels 2..top of each listed face), every later round's with no face
// until the test of the round before lists one (a face whose test failed a leaf).
uniform int faces_per_group;
void main() {
  if (invocation() != 0) return;
  select_face(lv_first_face);
  // An omni face that sits the seam round out runs no fix-up round (omni[48 + face]; zero for
  // spot and directional lights).
  uint n = 0u;
  for (int f = lv_first_face; f < lv_first_face + faces_per_group; ++f)
    if (omni[48 + f] == 0u) control[group_control + int(kFaceLists) + 8 + int(n++)] = uint(f);
  int cells2 = cells_total - offset_at(min(2, top_level + 1));
  uint groups = uint((cells2 + 63) / 64);
  uint x = min(groups, kMaxGroupsX);
  for (int r = 1; r <= rounds + 1; ++r) {
    int k = group_control + int(kRoundArgs) + 3 * r;
    control[k] = x;
    control[k + 1] = (groups + x - 1u) / x;
    control[k + 2] = r == 1 ? n : 0u;  // the faces listed
  }
}
#endif

#ifdef LV_TEST
// The largest error (TexelDepths::error) over the texels of the closed triangle (a, b, c) whose
// window depth is the plane through its corners' depths: detail::triangle_error, early out above
// E (returns a value above E then).
// floor(a / b) for b > 0 and |a| < 2^31, through a double division (exact, as idiv's).
int floor_div(int a, int b) { return int(floor(double(a) / double(b))); }

bool triangle_fails(ivec2 a, ivec2 b, ivec2 c) {
  int area2 = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
  if (area2 < 0) {
    ivec2 t = b;
    b = c;
    c = t;
    area2 = -area2;
  }
  double da = d_at(a.x, a.y), db = d_at(b.x, b.y), dc = d_at(c.x, c.y);
  double inv = 1.0LF / double(area2);
  double gx = ((db - da) * double(c.y - a.y) - (dc - da) * double(b.y - a.y)) * inv;
  double gy = ((dc - da) * double(b.x - a.x) - (db - da) * double(c.x - a.x)) * inv;
  ivec2 v[3] = ivec2[3](a, b, c);
  int y0 = min(a.y, min(b.y, c.y)), y1 = max(a.y, max(b.y, c.y));
  double worst = 0.0LF;
  for (int y = y0; y <= y1; ++y) {
    int lo = -2147483647, hi = 2147483647;
    bool empty = false;
    for (int k = 0; k < 3; ++k) {
      ivec2 p = v[k], q = v[(k + 1) % 3];
      int ex = q.x - p.x, ey = q.y - p.y;
      int A = -ey, C = ex * (y - p.y) + ey * p.x;
      if (A > 0) {
        lo = max(lo, -floor_div(C, A));
      } else if (A < 0) {
        hi = min(hi, floor_div(C, -A));
      } else if (C < 0) {
        empty = true;
      }
    }
    if (empty || lo > hi) continue;
    double base = da + gy * double(y - a.y) + gx * double(lo - a.x);
    double w0 = w0_c + double(lo) * w0_dc + double(y) * w0_dr;
    for (int x = lo; x <= hi; ++x) {
      double dp = base + gx * double(x - lo);
      double e = abs(dp - d_at(x, y));
      if (uniform_flag == 0)
        e = e * scale[fs + y * width + x] / abs(w0 + w0_dc * double(x - lo) + dp * w1);
      worst = max(worst, e);
    }
    double scaled = uniform_flag == 1 ? worst * uniform_scale : worst;
    if (scaled > bound) return true;
  }
  return false;
}

// Omni: per cell of levels 2..top, fix-up round 1's verdict on it as a leaf of its configuration
// (kVerdict | config << 1 | failed; 0: not a configured leaf), kept from one seam round to the
// next: a leaf with the configuration it had in the round before has the same triangles over the
// same texels, so the same verdict (build tests it again: the same result).
layout(std430, binding = 12) buffer Verdicts { uint verdict[]; };
uniform int reuse;  // 1: round 1 of an omni seam round after the first (verdicts to reuse)
const uint kVerdict = 32u;

void main() {
  select_listed_face();
  int first = offset_at(min(2, top_level + 1));
  int c = first + invocation();
  if (c >= cells_total || top_level < 2) return;
  bool record = type == 2 && round_ == 1;
  uint previous = record ? verdict[fc + c] : 0u;
  uint code = 0u;
  ivec3 cl = cell_of(c, 2);
  int L = cl.x, i = cl.y, j = cl.z;
  uint parent = L == top_level ? 1u : split_at(L + 1, i / 2, j / 2);
  bool leaf = split[fc + c] == 0u && parent != 0u;
  if (leaf && round_ > 1) {
    uint r = uint(round_);
    // Later rounds test a leaf only when something around it changed since it passed.
    leaf = parent == r || split_at(L, i - 1, j) == r || split_at(L, i + 1, j) == r ||
           split_at(L, i, j - 1) == r || split_at(L, i, j + 1) == r;
  }
  if (leaf) {
    ivec4 b = cell_box(L, i, j);
    uint config = config_of(L, i, j, b);
    if (config != 0u) {
      bool fails = false;
      if (reuse == 1 && (previous & ~1u) == (kVerdict | (config << 1u))) {
        fails = (previous & 1u) != 0u;
      } else {
        ivec2 tri[18];
        int n = cell_triangles(b, 1 << (L - 1), config, tri);
        for (int t = 0; t < n && !fails; ++t)
          fails = triangle_fails(tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]);
      }
      code = kVerdict | (config << 1u) | (fails ? 1u : 0u);
      if (fails) {
        fail[fc + c] = uint(round_);
        // The face's first failure lists it for round + 1 (its LV_PROPAGATE and its test).
        if (atomicAdd(control[fk + round_], 1u) == 0u) {
          int next = group_control + int(kRoundArgs) + 3 * (round_ + 1);
          uint k = atomicAdd(control[next + 2], 1u);
          control[group_control + int(kFaceLists) + 8 * (round_ + 1) + int(k)] = uint(lv_face);
        }
      }
    }
  }
  if (record) verdict[fc + c] = code;
}
#endif

#ifdef LV_PROPAGATE
// LV_BALANCE's rule read backwards: a split cell (l, i, j) splits the cells (l + 1, I, J) whose
// children or children's edge neighbours include it: I in {(i - 1) >> 1, (i + 1) >> 1} with
// J = j >> 1, or I = i >> 1 with J in {(j - 1) >> 1, (j + 1) >> 1}. The tree before the round is
// balanced (LV_BALANCE's closure), so only this round's splits force more; each is followed by
// the invocation whose atomic compare-and-swap split it, so every forced cell is reached once and
// the result is LV_BALANCE's closure whatever the order. From one cell, the cells it forces at
// each level lie in a box of at most 3 × 3 cells (widths 1, 2, then at most 3). It runs on the
// faces whose test failed a leaf (round + 1's face list and dispatch size).
void main() {
  select_listed_face();
  int c = offset_at(min(2, top_level + 1)) + invocation();
  if (c >= cells_total || top_level < 2) return;
  if (fail[fc + c] != uint(round_)) return;
  uint mark = uint(round_) + 1u;
  if (atomicCompSwap(split[fc + c], 0u, mark) != 0u) return;
  ivec3 cl = cell_of(c, 2);
  ivec2 cur[9];
  cur[0] = cl.yz;
  int n = 1;
  for (int L = cl.x; L < top_level && n > 0; ++L) {
    ivec2 next[9];
    int m = 0;
    for (int k = 0; k < n; ++k) {
      ivec2 p = cur[k];
      ivec2 forced[5] = ivec2[5](ivec2(p.x >> 1, p.y >> 1), ivec2((p.x - 1) >> 1, p.y >> 1),
                                 ivec2((p.x + 1) >> 1, p.y >> 1), ivec2(p.x >> 1, (p.y - 1) >> 1),
                                 ivec2(p.x >> 1, (p.y + 1) >> 1));
      for (int f = 0; f < 5; ++f) {
        ivec2 q = forced[f];
        if (!in_level(L + 1, q.x, q.y)) continue;
        bool seen = false;
        for (int t = 0; t < m; ++t) seen = seen || next[t] == q;
        if (seen || m == 9) continue;
        if (atomicCompSwap(split[fc + cell_index(L + 1, q.x, q.y)], 0u, mark) != 0u) continue;
        next[m] = q;
        ++m;
      }
    }
    cur = next;
    n = m;
  }
}
#endif

#if defined(LV_COUNT) || defined(LV_TRIANGLES)
// Whether flattened cell (L, i, j) emits triangles: a split level-1 cell emits its quads (the
// level-0 leaves), a leaf of level ≥ 1 its configuration.
bool leaf(int L, int i, int j, int c) {
  return split[c] == 0u && (L == top_level || is_split(L + 1, i / 2, j / 2));
}

void mark(ivec2 p) {
  int words = (width + 31) / 32;
  atomicOr(bits[p.y * words + p.x / 32], 1u << uint(p.x % 32));
}
#endif

#ifdef LV_COUNT
void main() {
  int c = invocation();
  if (c >= cells_total) return;
  ivec3 cl = cell_of(c, 1);
  int L = cl.x, i = cl.y, j = cl.z;
  ivec4 b = cell_box(L, i, j);
  uint n = 0u;
  if (L == 1 && split[c] != 0u) {
    for (int y = b.y; y <= b.w; ++y)
      for (int x = b.x; x <= b.z; ++x) mark(ivec2(x, y));
    n = 2u * uint((b.z - b.x) * (b.w - b.y));
  } else if (leaf(L, i, j, c)) {
    uint config = config_of(L, i, j, b);
    int half_ = 1 << (L - 1);
    mark(b.xy), mark(ivec2(b.z, b.y)), mark(ivec2(b.x, b.w)), mark(b.zw);
    if ((config & kSplitTop) != 0u) mark(ivec2(b.x + half_, b.y));
    if ((config & kSplitBottom) != 0u) mark(ivec2(b.x + half_, b.w));
    if ((config & kSplitLeft) != 0u) mark(ivec2(b.x, b.y + half_));
    if ((config & kSplitRight) != 0u) mark(ivec2(b.z, b.y + half_));
    n = 2u + uint(bitCount(config));
  }
  tri_count[c] = n;
  // The emitting cells, listed (in any order: each writes at its own offset) in fail[], which the
  // rounds no longer need, so that LV_TRIANGLES runs over them alone.
  if (n > 0u) fail[atomicAdd(control[kEmitting], 1u)] = uint(c);
}
#endif

#if defined(LV_SCAN_CHUNKS) || defined(LV_SCAN_SUMS) || defined(LV_SCAN_WRITE)
// Exclusive prefix sums in three passes: chunks of 256 values summed, the sums scanned by one
// invocation (the total to control[scan_total]), the chunks rewritten. Values: scan_in[k], or
// its bit count (the vertex bitmap's words) when scan_popcount is 1. In place is allowed.
layout(std430, binding = 14) buffer ScanIn { uint scan_in[]; };
layout(std430, binding = 15) buffer ScanOut { uint scan_out[]; };
uniform int scan_n;
uniform int scan_popcount;
uniform int scan_total;
const int kChunk = 256;
uint scan_value(int k) { return scan_popcount == 1 ? uint(bitCount(scan_in[k])) : scan_in[k]; }
#endif

#ifdef LV_SCAN_CHUNKS
void main() {
  int chunk = invocation();
  if (chunk * kChunk >= scan_n) return;
  uint s = 0u;
  for (int k = chunk * kChunk; k < min(scan_n, (chunk + 1) * kChunk); ++k) s += scan_value(k);
  scan_sums[chunk] = s;
}
#endif

#ifdef LV_SCAN_SUMS
void main() {
  if (invocation() != 0) return;
  uint s = 0u;
  for (int chunk = 0; chunk * kChunk < scan_n; ++chunk) {
    uint v = scan_sums[chunk];
    scan_sums[chunk] = s;
    s += v;
  }
  control[scan_total] = s;
  if (scan_total == int(kStats) + 3) {  // the triangle scan: size LV_TRIANGLES' dispatch
    uint groups = (control[kEmitting] + 63u) / 64u, x = min(groups, kMaxGroupsX);
    control[kTriangleArgs] = x;
    control[kTriangleArgs + 1u] = x == 0u ? 1u : (groups + x - 1u) / x;
    control[kTriangleArgs + 2u] = 1u;
  }
}
#endif

#ifdef LV_SCAN_WRITE
void main() {
  int chunk = invocation();
  if (chunk * kChunk >= scan_n) return;
  uint s = scan_sums[chunk];
  for (int k = chunk * kChunk; k < min(scan_n, (chunk + 1) * kChunk); ++k) {
    uint v = scan_value(k);
    scan_out[k] = s;
    s += v;
  }
}
#endif

#if defined(LV_TRIANGLES) || defined(LV_CLOSE)
// The rank of vertex texel p among the vertices in texel order (row-major).
uint rank(ivec2 p) {
  int words = (width + 31) / 32;
  int k = p.y * words + p.x / 32;
  uint below = (1u << uint(p.x % 32)) - 1u;
  return word_rank[k] + uint(bitCount(bits[k] & below));
}

bool has(ivec2 p) {
  int words = (width + 31) / 32;
  return (bits[p.y * words + p.x / 32] & (1u << uint(p.x % 32))) != 0u;
}
#endif

#ifdef LV_TRIANGLES
void main() {
  int listed = invocation();
  if (listed >= int(control[kEmitting])) return;
  int c = int(fail[listed]);
  uint n = tri_count[c];
  uint first = tri_offset[c];
  ivec3 cl = cell_of(c, 1);
  int L = cl.x, i = cl.y, j = cl.z;
  ivec4 b = cell_box(L, i, j);
  ivec2 tri[18];
  uint out_ = 3u * (first + omni[40 + lv_face]);
  uint vb = omni[32 + lv_face];
  if (L == 1 && split[c] != 0u) {
    for (int y = b.y; y < b.w; ++y)
      for (int x = b.x; x < b.z; ++x) {
        int k = cell_triangles(ivec4(x, y, x + 1, y + 1), 0, 0u, tri);
        for (int t = 0; t < 3 * k; t += 3) {
          uint r0 = vb + rank(tri[t]), r1 = vb + rank(tri[t + 1]), r2 = vb + rank(tri[t + 2]);
          indices[out_] = r0;
          indices[out_ + 1u] = standard == 1 ? r1 : r2;
          indices[out_ + 2u] = standard == 1 ? r2 : r1;
          out_ += 3u;
        }
      }
    return;
  }
  int k = cell_triangles(b, 1 << (L - 1), config_of(L, i, j, b), tri);
  for (int t = 0; t < 3 * k; t += 3) {
    uint r0 = vb + rank(tri[t]), r1 = vb + rank(tri[t + 1]), r2 = vb + rank(tri[t + 2]);
    indices[out_] = r0;
    indices[out_ + 1u] = standard == 1 ? r1 : r2;
    indices[out_ + 2u] = standard == 1 ? r2 : r1;
    out_ += 3u;
  }
}
#endif

#ifdef LV_VERTICES
void main() {
  int words = (width + 31) / 32;
  int k = invocation();
  if (k >= words * height) return;
  int row = idiv(k, words), col0 = (k - row * words) * 32;
  uint r = omni[32 + lv_face] + word_rank[k];
  for (uint w = bits[k]; w != 0u; w &= w - 1u) {
    int col = col0 + findLSB(w);
    vec3 eye = live_grid_point(lv_face, ivec2(col, row));
    vec3 world = (live_eye_to_world[lv_face] * vec4(eye, 1.0)).xyz;
    positions[3u * r] = world.x;
    positions[3u * r + 1u] = world.y;
    positions[3u * r + 2u] = world.z;
    texel_ids[r] = uint((lv_face * height + row) * width + col);
    if (type == 2) {  // omni: the border vertices' indices, for LV_SEAMS
      uint side0 = uint(4 * lv_face) * uint(width);
      if (row == 0) border_index[side0 + uint(kSideTop * width + col)] = r;
      if (row == height - 1) border_index[side0 + uint(kSideBottom * width + col)] = r;
      if (col == 0) border_index[side0 + uint(kSideLeft * width + row)] = r;
      if (col == width - 1) border_index[side0 + uint(kSideRight * width + row)] = r;
    }
    ++r;
  }
}
#endif

#ifdef LV_CLOSE
// control[kStats + 2]: grid vertices (the vertex scan's total), [kStats + 3]: grid triangles
// (the triangle scan's total); this pass adds the closing after them.
void main() {
  if (invocation() != 0) return;
  uint nv = control[kStats + 2u], nt = control[kStats + 3u];
  int perimeter = 2 * (width - 1) + 2 * (height - 1);
  uint first = 0u, prev = 0u, n = 0u;
  uint out_ = 3u * nt;
  uint apex = nv;
  if (type == 0) {
    positions[3u * apex] = live_apex.x;
    positions[3u * apex + 1u] = live_apex.y;
    positions[3u * apex + 2u] = live_apex.z;
  }
  for (int p = 0; p <= perimeter; ++p) {
    uint cur;
    if (p < perimeter) {
      ivec2 t = live_ring_texel(p);
      if (!has(t)) continue;
      cur = rank(t);
      if (type == 1) {
        // The ring vertex's near-plane copy, nv + its position in the ring.
        vec3 eye = live_segment(live_ndc(t), 0.0);
        vec3 world = (live_eye_to_world[0] * vec4(eye, 1.0)).xyz;
        uint q = nv + n;
        positions[3u * q] = world.x;
        positions[3u * q + 1u] = world.y;
        positions[3u * q + 2u] = world.z;
      }
      if (n == 0u) {
        first = cur;
        prev = cur;
        n = 1u;
        continue;
      }
    } else {
      cur = first;
    }
    // The ring edge prev -> cur: edge k = n - 1 (cur is ring vertex n, or the first again).
    uint k = n - 1u;
    if (type == 0) {
      indices[out_] = cur, indices[out_ + 1u] = prev, indices[out_ + 2u] = apex;
      out_ += 3u;
    } else {
      uint ring_n = uint(0);
      uint cur_n = nv + k;
      uint next_n = p < perimeter ? nv + k + 1u : nv;
      // cap: nv + the ring's size, known at the end: written below.
      indices[out_] = cur, indices[out_ + 1u] = prev, indices[out_ + 2u] = cur_n;
      indices[out_ + 3u] = cur, indices[out_ + 4u] = cur_n, indices[out_ + 5u] = next_n;
      indices[out_ + 6u] = next_n, indices[out_ + 7u] = cur_n, indices[out_ + 8u] = ring_n;
      out_ += 9u;
    }
    prev = cur;
    if (p < perimeter) ++n;
  }
  uint closing_vertices = type == 0 ? 1u : n + 1u;
  if (type == 1) {
    uint cap = nv + n;
    positions[3u * cap] = live_cap.x;
    positions[3u * cap + 1u] = live_cap.y;
    positions[3u * cap + 2u] = live_cap.z;
    for (uint t = 3u * nt + 8u; t < out_; t += 9u) indices[t] = cap;
  }
  uint triangles = nt + (out_ - 3u * nt) / 3u;
  control[kDraw + 0u] = 3u * triangles;  // count
  control[kDraw + 1u] = 1u;              // instances
  control[kDraw + 2u] = 0u;              // first index
  control[kDraw + 3u] = 0u;              // base vertex
  control[kDraw + 4u] = 0u;              // base instance
  uint splitting = 0u;  // fix-up rounds that split a leaf (AdaptiveGrid::fixup_rounds)
  for (int r = 1; r <= rounds; ++r)
    if (control[r] != 0u) ++splitting;
  control[kStats] = splitting;
  control[kStats + 1u] = control[uint(rounds)] == 0u ? 1u : 0u;  // converged
  control[kStats + 4u] = nv + closing_vertices;
  control[kStats + 5u] = triangles;
}
#endif

#ifdef LV_SEAM_CONTROL
// Seam round round_ (1-based; the host's rounds + 1 after the last, to conclude): the round before
// changed no side → the borders agree and no more rounds run; else the faces with a changed side
// tessellate again (all six in round 1): per group of faces_per_group faces, their list
// (control[kFaceLists..] of the group's first face) and the dispatch sizes of LV_RESET and
// LV_BALANCE over them (none when the group has no such face).
uniform int seam_slots;  // dispatch slots of a group (3 uints each)
uniform int faces_per_group;
uniform int stride_control;  // uints between two faces' control[] (bound whole)
void main() {
  if (invocation() != 0) return;
  bool dirty[6] = bool[6](true, true, true, true, true, true);
  if (omni[0] == 0u && round_ > 1) {
    bool changed = false;
    for (int k = 0; k < 24; ++k) {
      if (k % 4 == 0) dirty[k / 4] = false;
      if (omni[8 + k] != 0u) changed = dirty[k / 4] = true;
      omni[8 + k] = 0u;
    }
    if (!changed) omni[0] = 1u;
  }
  bool run = omni[0] == 0u && round_ <= rounds;
  if (run) omni[1] = uint(round_);
  for (int f = 0; f < 6; ++f) omni[48 + f] = run && dirty[f] ? 0u : 1u;
  for (int g = 0; g * faces_per_group < 6; ++g) {
    int first = g * faces_per_group;
    uint n = 0u;
    for (int f = first; f < first + faces_per_group; ++f)
      if (run && dirty[f]) control[first * stride_control + int(kFaceLists) + int(n++)] = uint(f);
    for (int k = 0; k < 3 * seam_slots; ++k) {
      // LV_UNITE's and LV_APPLY's slots (group 0's) run whenever the round does.
      uint v = k / 3 >= 16 ? (run ? seam_template[k] : 0u)
                           : (n == 0u ? 0u : k % 3 == 2 ? n : seam_template[k]);
      omni[kOmniArgs + uint(3 * seam_slots * g + k)] = v;
    }
  }
}
#endif

#ifdef LV_RESET
// Refiner::threshold then Refiner::force_border: a cell on a side is split when a forced position
// lies strictly inside its span along that side.
bool forced_inside(int side, int from, int to) {
  uint base = uint(4 * lv_face + side) * uint(width);
  for (int p = from + 1; p < to; ++p)
    if (forced[base + uint(p)] != 0u) return true;
  return false;
}

void main() {
  select_listed_face();
  int c = invocation();
  if (c >= cells_total) return;
  if (c == 0)
    for (int k = 0; k < 64; ++k) control[fk + k] = 0u;  // the fix-up rounds' counts
  fail[fc + c] = 0u;
  uint s = threshold_split[fc + c];
  if (s == 0u) {
    ivec3 cl = cell_of(c, 1);
    int L = cl.x, i = cl.y, j = cl.z;
    ivec4 b = cell_box(L, i, j);
    if ((j == 0 && forced_inside(kSideTop, b.x, b.z)) ||
        (j == ny_at(L) - 1 && forced_inside(kSideBottom, b.x, b.z)) ||
        (i == 0 && forced_inside(kSideLeft, b.y, b.w)) ||
        (i == nx_at(L) - 1 && forced_inside(kSideRight, b.y, b.w)))
      s = 1u;
  }
  split[fc + c] = s;
}
#endif

#if defined(LV_UNITE)
// Whether position p along `side` of face f is a vertex of the face's tessellation: a corner, or
// the midpoint of a split cell's side (its level: one above p's alignment; deeper cells keep it a
// corner, and no configuration splits a side on the border).
bool border_vertex(int f, int side, int p) {
  if (p == 0 || p == width - 1) return true;
  int L = findLSB(p) + 1, k = p >> L;
  int i = side == kSideLeft ? 0 : side == kSideRight ? nx_at(L) - 1 : k;
  int j = side == kSideTop ? 0 : side == kSideBottom ? ny_at(L) - 1 : k;
  return all_split[f * split_stride + cell_index(L, i, j)] != 0u;
}

void main() {
  int id = invocation();
  if (id >= 12 * width) return;
  int s = id / width, p = id - s * width;
  int fa = seam_desc[6 * s], sa = seam_desc[6 * s + 1], fb = seam_desc[6 * s + 2],
      sb = seam_desc[6 * s + 3];
  int pb = seam_desc[6 * s + 4] == 1 ? width - 1 - p : p;
  bool va = border_vertex(fa, sa, p), vb = border_vertex(fb, sb, pb);
  bool u = va || vb;
  united[uint(4 * fa + sa) * uint(width) + uint(p)] = u ? 1u : 0u;
  united[uint(4 * fb + sb) * uint(width) + uint(pb)] = u ? 1u : 0u;
  if (u && !va) omni[8 + 4 * fa + sa] = 1u;
  if (u && !vb) omni[8 + 4 * fb + sb] = 1u;
}
#endif

#ifdef LV_APPLY
void main() {
  int id = invocation();
  if (id >= 24 * width) return;
  if (omni[8 + id / width] != 0u) forced[id] = united[id];
}
#endif

#ifdef LV_BASE
// After face lv_face's scans: where the next face's vertices and triangles begin; the face's
// fix-up statistics as LV_CLOSE writes them.
void main() {
  if (invocation() != 0) return;
  omni[32 + lv_face + 1] = omni[32 + lv_face] + control[kStats + 2u];
  omni[40 + lv_face + 1] = omni[40 + lv_face] + control[kStats + 3u];
  uint splitting = 0u;
  for (int r = 1; r <= rounds; ++r)
    if (control[r] != 0u) ++splitting;
  control[kStats] = splitting;
  control[kStats + 1u] = control[uint(rounds)] == 0u ? 1u : 0u;
}
#endif

#ifdef LV_SEAMS
uint out_;
void emit(uint a, uint b, uint c, bool flip) {
  indices[out_] = a;
  indices[out_ + 1u] = flip ? c : b;
  indices[out_ + 2u] = flip ? b : c;
  out_ += 3u;
}

uint border_at(int f, int side, int p) { return border_index[uint(4 * f + side) * uint(width) + uint(p)]; }

// The next vertex after position p (in face a's numbering) along the seam's side of face f, or
// width when none.
int next_on(int f, int side, bool reversed, int p) {
  for (int q = p + 1; q < width; ++q)
    if (border_at(f, side, reversed ? width - 1 - q : q) != kNone) return q;
  return width;
}

// Each seam zips its two borders from position 0 to W − 1, taking face a's next vertex first on a
// tie: where the borders agree (the rounds converged) build's strip, (A_k, A_k+1, B_k) and
// (A_k+1, B_k+1, B_k); closed either way.
void main() {
  if (invocation() != 0) return;
  uint nv = omni[38], nt = omni[46];
  out_ = 3u * nt;
  for (int s = 0; s < 12; ++s) {
    int fa = seam_desc[6 * s], sa = seam_desc[6 * s + 1], fb = seam_desc[6 * s + 2],
        sb = seam_desc[6 * s + 3];
    bool reversed = seam_desc[6 * s + 4] == 1, flip = seam_desc[6 * s + 5] == 1;
    int pa = 0, pb = 0;
    uint a0 = border_at(fa, sa, 0), b0 = border_at(fb, sb, reversed ? width - 1 : 0);
    while (pa < width - 1 || pb < width - 1) {
      int na = next_on(fa, sa, false, pa), nb = next_on(fb, sb, reversed, pb);
      if (na <= nb) {
        uint a1 = border_at(fa, sa, na);
        emit(a0, a1, b0, flip);
        a0 = a1, pa = na;
      } else {
        uint b1 = border_at(fb, sb, reversed ? width - 1 - nb : nb);
        emit(a0, b1, b0, flip);
        b0 = b1, pb = nb;
      }
    }
  }
  for (int k = 0; k < 8; ++k) {
    uint v[3];
    for (int m = 0; m < 3; ++m) {
      int f = corner_desc[9 * k + 3 * m], last_col = corner_desc[9 * k + 3 * m + 1],
          last_row = corner_desc[9 * k + 3 * m + 2];
      v[m] = border_at(f, last_row == 1 ? kSideBottom : kSideTop, last_col == 1 ? width - 1 : 0);
    }
    emit(v[0], v[1], v[2], false);
  }
  uint triangles = out_ / 3u;
  control[kDraw + 0u] = 3u * triangles;
  control[kDraw + 1u] = 1u;
  control[kDraw + 2u] = 0u;
  control[kDraw + 3u] = 0u;
  control[kDraw + 4u] = 0u;
  control[kStats + 4u] = nv;
  control[kStats + 5u] = triangles;
}
#endif

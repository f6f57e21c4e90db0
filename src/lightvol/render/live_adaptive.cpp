#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <limits>
#include <string>

#include <lightvol/core/check.h>
#include <lightvol/depth/cube_faces.h>
#include <lightvol/render/detail/airlight_glsl.h>
#include <lightvol/render/detail/live_adaptive_glsl.h>
#include <lightvol/render/live_adaptive.h>
#include <lightvol/volume/omni_volume.h>

namespace lightvol::detail {

using namespace gl;

namespace {

// Shaders/live_adaptive.comp's Params block (std430: the doubles, then the ints).
struct Params {
  double m[16] = {};
  double h1[4] = {};
  double w0_c = 1, w0_dc = 0, w0_dr = 0, w1 = 0, uniform_scale = 0;
  double pz = 0, pzc = 0, pw = 0, pwc = 0, near_d = 0, far_d = 0;
  double bound = 0, pyramid_bound = 0;
  // Integers as doubles (shaders/live_adaptive.comp: every member 8-byte aligned).
  double width = 0, height = 0, flip_y = 0, encoding = 0;
  double uniform_flag = 0, standard = 1, type = 0, cells_total = 0;
  double nx[16] = {}, ny[16] = {}, offset[17] = {};
};
static_assert(offsetof(Params, width) == 33 * sizeof(double));
// The passes that run on several faces read Params as doubles at these offsets
// (shaders/live_adaptive.comp, LV_FACES_PASS).
static_assert(offsetof(Params, w0_c) == 20 * sizeof(double));
static_assert(offsetof(Params, bound) == 31 * sizeof(double));
static_assert(offsetof(Params, cells_total) == 40 * sizeof(double));
static_assert(offsetof(Params, nx) == 41 * sizeof(double));
static_assert(offsetof(Params, ny) == 57 * sizeof(double));
static_assert(offsetof(Params, offset) == 73 * sizeof(double));
static_assert(sizeof(Params) == (33 + 8 + 16 + 16 + 17) * sizeof(double));

// The passes, in shaders/live_adaptive.comp's order.
enum Pass {
  kTexels,
  kOwn,
  kBalance,
  kControl,
  kTest,
  kCount,
  kScanChunks,
  kScanSums,
  kScanWrite,
  kTriangles,
  kVertices,
  kClose,
  kSeamControl,
  kReset,
  kUnite,
  kApply,
  kBase,
  kSeams,
  kPropagate,
  kPasses
};
// Profiling's names for the commands that are not passes (after the passes).
constexpr int kClearCommand = kPasses, kCopyCommand = kPasses + 1;
constexpr const char* kPhaseNames[] = {"clear", "pyramid", "tessellation", "emission"};
constexpr const char* kPassNames[kPasses] = {
    "LV_TEXELS",   "LV_OWN",         "LV_BALANCE",      "LV_CONTROL",    "LV_TEST",
    "LV_COUNT",    "LV_SCAN_CHUNKS", "LV_SCAN_SUMS",    "LV_SCAN_WRITE", "LV_TRIANGLES",
    "LV_VERTICES", "LV_CLOSE",       "LV_SEAM_CONTROL", "LV_RESET",      "LV_UNITE",
    "LV_APPLY",    "LV_BASE",        "LV_SEAMS",        "LV_PROPAGATE"};

// Buffer bindings (shaders/live_adaptive.comp).
enum Binding {
  kParams = 0,
  kDepths = 1,
  kScales = 2,
  kSplits = 3,
  kFails = 4,
  kControlBuf = 5,
  kBits = 6,
  kCounts = 7,
  kRanks = 8,
  kIndices = 9,
  kPositions = 10,
  kTexelIds = 11,
  kVerdicts = 12,  // omni: fix-up round 1's verdicts, kept across seam rounds
  kScanSumsBuf = 13,
  kScanIn = 14,
  kScanOut = 15,
  kOffsets = 16,
  kOmni = 17,
  kThreshold = 18,
  kForced = 19,
  kUnion = 20,
  kAllSplits = 21,  // kSplits' buffer whole (no buffer of its own)
  kBorderIndex = 22,
  kSeamTemplate = 23,
  kBuffers = 24
};

// The buffers that hold one range per face (an omni light's six; bound face by face).
constexpr Binding kPerFace[] = {kParams, kDepths, kScales, kSplits,  kFails,     kControlBuf,
                                kBits,   kCounts, kRanks,  kOffsets, kThreshold, kVerdicts};

constexpr GLuint kStats = 160;         // control[kStats + ...] (shaders/live_adaptive.comp)
constexpr GLuint kTriangleArgs = 100;  // LV_TRIANGLES' dispatch size, written by the GPU
constexpr GLuint kDrawCommand = 192;   // control[kDrawCommand..+4]: the indirect draw command
constexpr GLuint kRoundArgs = 256;  // control[kRoundArgs + 3 r..]: fix-up round r's dispatch size
// control[kFaceLists + 8 r..]: the faces of fix-up round r's dispatch (r = 0: the balance's).
// Both in the control[] of a group's first face (the group's).
constexpr GLuint kFaceLists = 512;
constexpr GLuint kControlSize = 1088;
static_assert(kRoundArgs + 3 * 64 + 3 <= kFaceLists);  // rounds + 1 <= 64
static_assert(kFaceLists + 8 * 64 + 8 <= kControlSize);
constexpr int kBandRows = 16;
constexpr int kChunk = 256;
constexpr GLuint kOmniSize = 512;  // shaders/live_adaptive.comp's omni[]
constexpr GLuint kOmniArgs = 128;
// The seam round's dispatch slots, per group of faces from kOmniArgs on: 0 LV_RESET, 2..top
// LV_BALANCE of that level, 16 LV_UNITE, 17 LV_APPLY (group 0's).
constexpr int kSlotReset = 0, kSlotUnite = 16, kSlotApply = 17, kSlots = 18;
static_assert(kOmniArgs + 3 * kSlots * kOmniFaces <= kOmniSize);

// Enough groups of 64 for `invocations`, as rows of at most kMaxGroupsX groups
// (shaders/live_adaptive.comp's invocation()).
constexpr std::uint64_t kMaxGroupsX = 32768;
std::array<GLuint, 3> groups_for(std::uint64_t invocations) {
  const std::uint64_t groups = std::max<std::uint64_t>((invocations + 63) / 64, 1);
  const std::uint64_t x = std::min(groups, kMaxGroupsX);
  return {static_cast<GLuint>(x), static_cast<GLuint>((groups + x - 1) / x), 1};
}
void dispatch_groups(std::uint64_t invocations) {
  const std::array<GLuint, 3> g = groups_for(invocations);
  glDispatchCompute(g[0], g[1], g[2]);
}

// The largest float ≤ b, as a double: a value rounded up to float exceeds b iff it exceeds this.
double float_floor(double b) {
  float f = static_cast<float>(b);
  if (static_cast<double>(f) > b) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

std::string live_adaptive_problem(const Light& light) {
  const Mat4d& pj = light.projection;
  const bool linear_fast = light.depth == DepthEncoding::linear && pj(2, 0) == 0 && pj(2, 1) == 0 &&
                           pj(3, 0) == 0 && pj(3, 1) == 0;
  if (light.depth != DepthEncoding::window && !linear_fast)
    return "live volume: adaptive tessellation (max_error) takes window depth, or linear depth "
           "with a projection whose depth row sees eye z only; the light's \"depth\" is \"" +
           std::string(to_string(light.depth)) + "\"";
  return "";
}

struct LiveAdaptive::State {
  double bound = 0;
  int rounds = 0, seam_rounds = 0;
  Program programs[kPasses];
  BufferHandle buffers[kBuffers];
  VertexArrayHandle vao;
  int faces = 1;  // 6: an omni light
  // Faces per dispatch of the tessellation's passes (LV_FACES_PASS): all six when their ranges
  // fit one storage block, else 3, 2 or 1 (spot, directional: 1); `requested`: a test's choice
  // (set_faces_per_dispatch), 0 for that.
  int per_dispatch = 1, requested_per_dispatch = 0;
  std::uint64_t max_block = 0;      // GL_MAX_SHADER_STORAGE_BLOCK_SIZE
  GLintptr stride[kBuffers] = {};   // bytes between two faces' ranges (per-face buffers)
  GLsizeiptr range[kBuffers] = {};  // bytes of one face's range
  int width = 0, height = 0, top = 0;
  std::uint64_t nx[16] = {}, ny[16] = {};  // cells per level, across and down
  std::uint64_t cells = 0, words = 0, max_vertices = 0, max_triangles = 0;
  std::uint64_t max_indices = 0, max_grid_vertices = 0;
  GLint seam_desc[72] = {}, corner_desc[72] = {};
  // Profiling (set_profiling): one query per timed command of the frames since it was turned on.
  struct Timed {
    int phase = 0, pass = 0;
    std::unique_ptr<GpuTimer> timer;
    double wall = 0, cpu = 0;  // seconds, glFinish before and after: clock, process CPU time
  };
  bool profiling = false;
  mutable std::vector<Timed> timed;

  bool omni() const { return faces == kOmniFaces; }
  // per_dispatch: the requested count, else the most faces (6, 3, 2) whose ranges of every
  // per-face buffer fit one storage block together, else 1.
  void choose_per_dispatch() {
    per_dispatch = 1;
    if (requested_per_dispatch != 0) {
      LV_CHECK_EQ(faces % requested_per_dispatch, 0);
      per_dispatch = requested_per_dispatch;
      return;
    }
    for (const int n : {6, 3, 2}) {
      if (n > faces) continue;
      bool fits = true;
      for (const Binding b : kPerFace)
        if (b != kControlBuf &&
            static_cast<std::uint64_t>((n - 1) * stride[b] + range[b]) > max_block)
          fits = false;
      if (fits) {
        per_dispatch = n;
        return;
      }
    }
  }
  // The uniforms of the passes that run on several faces: the elements between two faces'
  // ranges.
  void set_strides() const {
    for (const Pass pass : {kReset, kBalance, kControl, kTest, kPropagate, kSeamControl}) {
      const Program& program = programs[pass];
      program.use();
      const auto set = [&](const char* name, Binding b, int bytes) {
        LV_CHECK_LE(stride[b] / bytes, std::numeric_limits<GLint>::max());
        glUniform1i(program.uniform(name), static_cast<GLint>(stride[b] / bytes));
      };
      set("stride_params", kParams, 8);
      set("stride_texels", kDepths, 8);
      set("stride_scales", kScales, 8);
      set("stride_cells", kSplits, 4);
      set("stride_control", kControlBuf, 4);
    }
    glUseProgram(0);
  }
  // Binds face f's ranges of the per-face buffers, and every other buffer whole.
  void bind_face(int f) const {
    for (int b = 0; b < kBuffers; ++b) {
      if (b == kScanIn || b == kScanOut) continue;
      const GLuint id = buffers[b == kAllSplits ? kSplits : b].id();
      if (stride[b] > 0) {
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(b), id, f * stride[b],
                          range[b]);
      } else {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(b), id);
      }
    }
  }
  // Binds the ranges of faces first .. first + n − 1 of the per-face buffers (control[] whole),
  // and every other buffer whole: the tessellation's passes over a group of faces.
  void bind_group(int first, int n) const {
    for (int b = 0; b < kBuffers; ++b) {
      if (b == kScanIn || b == kScanOut) continue;
      const GLuint id = buffers[b == kAllSplits ? kSplits : b].id();
      if (stride[b] > 0 && b != kControlBuf) {
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(b), id, first * stride[b],
                          (n - 1) * stride[b] + range[b]);
      } else {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(b), id);
      }
    }
  }
  // Binds `b`'s range of face f at binding `at`.
  void bind_range(GLuint at, Binding b, int f) const {
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, at, buffers[b].id(), f * stride[b], range[b]);
  }
};

LiveAdaptive::~LiveAdaptive() = default;

Result<std::unique_ptr<LiveAdaptive>> LiveAdaptive::create(double bound, int rounds,
                                                           int seam_rounds) {
  LV_CHECK(std::isfinite(bound) && bound >= 0);
  LV_CHECK(rounds >= 1 && rounds <= 63);
  LV_CHECK(seam_rounds >= 1);
  std::unique_ptr<LiveAdaptive> live(new LiveAdaptive());
  live->state_ = std::make_unique<State>();
  State& s = *live->state_;
  s.bound = bound;
  s.rounds = rounds;
  s.seam_rounds = seam_rounds;
  for (int p = 0; p < kPasses; ++p) {
    const std::string source = std::string("#version 450 core\n#define LIGHTVOL_LIVE_COMMON\n") +
                               "#define " + kPassNames[p] + "\n" + kAirlightGlsl + "\n" +
                               kLiveAdaptiveGlsl;
    Result<Program> program = Program::compile_compute(
        source, std::string("live adaptive volume (") + kPassNames[p] + ")");
    if (!program) return program.error();
    s.programs[p] = std::move(*program);
  }
  GLuint ids[kBuffers];
  glGenBuffers(kBuffers, ids);
  for (int b = 0; b < kBuffers; ++b) s.buffers[b] = BufferHandle(ids[b]);
  GLuint id = 0;
  glGenVertexArrays(1, &id);
  s.vao = VertexArrayHandle(id);
  glBindVertexArray(id);
  glBindBuffer(GL_ARRAY_BUFFER, s.buffers[kPositions].id());
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s.buffers[kIndices].id());
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: setting up the live adaptive volume: " + e};
  return live;
}

namespace {

// Shaders/live_adaptive.comp's Params for face `face` of `light` (0: spot, directional): the
// constants of TexelDepths (tessellate/texel_depths.cpp), in the same order of operations.
Params face_params(const Light& light, int face, int width, int height, double bound) {
  Params p;
  const Mat4d view = light.type == LightType::omni ? omni_face_view(light, face) : light.view;
  bool ok = false;
  const Mat4d inv_view = inverse(view, &ok);
  LV_CHECK(ok);
  const Mat4d inv_proj = inverse(light.projection, &ok);
  LV_CHECK(ok);
  const Mat4d m = inv_view * inv_proj;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) p.m[4 * r + c] = m(r, c);
  for (int k = 0; k < 4; ++k) p.h1[k] = 2 * m(k, 2);
  const double sy = light.flip_y ? 1.0 : -1.0;
  const double x0 = 2.0 * (0 + 0.5) / width - 1.0;
  const double y_down = 2.0 * (0 + 0.5) / height - 1.0;
  const double y0 = light.flip_y ? y_down : -y_down;
  p.w0_dc = m(3, 0) * 2.0 / width;
  p.w0_dr = m(3, 1) * sy * 2.0 / height;
  p.w0_c = m(3, 0) * x0 + m(3, 1) * y0 - m(3, 2) + m(3, 3);
  p.w1 = p.h1[3];
  p.uniform_flag = m(3, 0) == 0 && m(3, 1) == 0 && p.h1[3] == 0 ? 1 : 0;
  if (p.uniform_flag)
    p.uniform_scale =
        std::sqrt(p.h1[0] * p.h1[0] + p.h1[1] * p.h1[1] + p.h1[2] * p.h1[2]) / std::abs(p.w0_c);
  const Mat4d& pj = light.projection;
  p.pz = pj(2, 2), p.pzc = pj(2, 3), p.pw = pj(3, 2), p.pwc = pj(3, 3);
  p.near_d = light.near, p.far_d = light.far;
  p.bound = bound;
  p.pyramid_bound = float_floor(bound);
  p.width = width, p.height = height;
  p.flip_y = light.flip_y ? 1 : 0;
  p.encoding = light.depth == DepthEncoding::window ? 0 : 1;
  p.standard = Unprojector(light, width, height, face, Space::world).standard_winding() ? 1 : 0;
  p.type = light.type == LightType::spot ? 0 : light.type == LightType::omni ? 2 : 1;
  return p;
}

int grid_side_of(FaceBorder border) {
  switch (border) {
    case FaceBorder::top:
      return 0;
    case FaceBorder::right:
      return 1;
    case FaceBorder::bottom:
      return 2;
    case FaceBorder::left:
      return 3;
  }
  return 0;
}

GLintptr round_up(std::uint64_t bytes, GLint alignment) {
  const std::uint64_t a = static_cast<std::uint64_t>(std::max(alignment, 256));
  return static_cast<GLintptr>((std::max<std::uint64_t>(bytes, 16) + a - 1) / a * a);
}

}  // namespace

Status LiveAdaptive::resize(const Light& light, int width, int height) {
  State& s = *state_;
  if (std::string problem = live_adaptive_problem(light); !problem.empty()) return Error{problem};
  s.faces = light.type == LightType::omni ? kOmniFaces : 1;
  // The quadtree (detail::Quadtree): levels 1..top (at least one level: a 2 × 2 map's one quad
  // is a level-1 cell's two triangles either way).
  const int cw = width - 1, ch = height - 1;
  int top = 0;
  while ((1 << top) < std::max(cw, ch)) ++top;
  top = std::max(top, 1);
  if (top > 15)
    return Error{"live volume: maps of more than 32769 texels a side are not supported"};
  s.top = top;
  std::vector<Params> params(static_cast<std::size_t>(s.faces));
  for (int f = 0; f < s.faces; ++f) params[f] = face_params(light, f, width, height, s.bound);
  std::uint64_t cells = 0;
  for (int level = 1; level <= top; ++level) {
    s.nx[level] = static_cast<std::uint64_t>((cw + (1 << level) - 1) >> level);
    s.ny[level] = static_cast<std::uint64_t>((ch + (1 << level) - 1) >> level);
    for (Params& p : params) {
      p.nx[level] = static_cast<double>(s.nx[level]);
      p.ny[level] = static_cast<double>(s.ny[level]);
      p.offset[level] = static_cast<double>(cells);
    }
    cells += s.nx[level] * s.ny[level];
  }
  for (Params& p : params) {
    p.offset[top + 1] = static_cast<double>(cells);
    p.cells_total = static_cast<double>(cells);
  }
  s.width = width, s.height = height;
  s.cells = cells;
  s.words = static_cast<std::uint64_t>((width + 31) / 32) * static_cast<std::uint64_t>(height);
  const std::uint64_t texels =
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  const std::uint64_t faces = static_cast<std::uint64_t>(s.faces);
  const std::uint64_t perimeter =
      2 * static_cast<std::uint64_t>(cw) + 2 * static_cast<std::uint64_t>(ch);
  s.max_grid_vertices = faces * texels;
  const std::uint64_t grid_triangles =
      faces * 2 * static_cast<std::uint64_t>(cw) * static_cast<std::uint64_t>(ch);
  if (s.omni()) {
    // Seams: a zip of two borders of W vertices at most, 2(W − 1) triangles; corners: 8.
    s.max_vertices = s.max_grid_vertices;
    s.max_triangles = grid_triangles + 12 * 2 * static_cast<std::uint64_t>(cw) + 8;
  } else {
    s.max_vertices = texels + perimeter + 1;
    s.max_triangles = grid_triangles + 3 * perimeter;
  }
  s.max_indices = 3 * s.max_triangles;
  if (s.max_indices >= std::uint64_t{1} << 31)
    return Error{"live volume: " + std::to_string(width) + "x" + std::to_string(height) +
                 " texels are more than one draw call holds"};

  GLint alignment = 16;
  glGetIntegerv(GL_SHADER_STORAGE_BUFFER_OFFSET_ALIGNMENT, &alignment);
  std::uint64_t bytes[kBuffers] = {};
  bytes[kParams] = sizeof(Params);
  bytes[kDepths] = 8 * texels;
  bytes[kScales] = params[0].uniform_flag ? 8 : 8 * texels;
  bytes[kSplits] = 4 * s.cells;
  bytes[kFails] = 4 * s.cells;
  bytes[kControlBuf] = 4 * kControlSize;
  bytes[kBits] = 4 * s.words;
  bytes[kCounts] = 4 * s.cells;
  bytes[kOffsets] = 4 * s.cells;
  bytes[kRanks] = 4 * s.words;
  bytes[kThreshold] = s.omni() ? 4 * s.cells : 16;
  bytes[kVerdicts] = s.omni() ? 4 * s.cells : 16;
  for (int b = 0; b < kBuffers; ++b) s.stride[b] = 0, s.range[b] = 0;
  for (const Binding b : kPerFace) {
    s.range[b] = static_cast<GLsizeiptr>(std::max<std::uint64_t>(bytes[b], 16));
    s.stride[b] = round_up(bytes[b], alignment);
    bytes[b] = static_cast<std::uint64_t>(s.stride[b]) * faces;
  }
  // The cell buffers share one stride in the shader (stride_cells).
  LV_CHECK(!s.omni() ||
           (s.stride[kThreshold] == s.stride[kSplits] && s.stride[kVerdicts] == s.stride[kSplits]));
  LV_CHECK(s.stride[kFails] == s.stride[kSplits]);
  GLint block = 0;  // (a size over 2^31 − 1 reads as that: enough)
  glGetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block);
  s.max_block = static_cast<std::uint64_t>(std::max(block, 0));
  s.choose_per_dispatch();
  s.set_strides();
  const std::uint64_t sides = 4 * static_cast<std::uint64_t>(width) * faces;
  bytes[kIndices] = 4 * s.max_indices;
  bytes[kPositions] = 12 * s.max_vertices;
  bytes[kTexelIds] = 4 * s.max_grid_vertices;
  bytes[kScanSumsBuf] = 4 * ((std::max(s.cells, s.words) + kChunk - 1) / kChunk + 1);
  bytes[kOmni] = 4 * kOmniSize;
  bytes[kForced] = s.omni() ? 4 * sides : 16;
  bytes[kUnion] = s.omni() ? 4 * sides : 16;
  bytes[kBorderIndex] = s.omni() ? 4 * sides : 16;
  bytes[kSeamTemplate] = 4 * 3 * kSlots;
  for (int b = 0; b < kBuffers; ++b) {
    if (b == kScanIn || b == kScanOut || b == kAllSplits || b == kParams) continue;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[b].id());
    glBufferData(GL_SHADER_STORAGE_BUFFER,
                 static_cast<GLsizeiptr>(std::max<std::uint64_t>(bytes[b], 16)), nullptr,
                 GL_DYNAMIC_COPY);
  }
  std::vector<unsigned char> param_bytes(static_cast<std::size_t>(bytes[kParams]), 0);
  for (int f = 0; f < s.faces; ++f)
    std::memcpy(param_bytes.data() + f * s.stride[kParams], &params[f], sizeof(Params));
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[kParams].id());
  glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(param_bytes.size()),
               param_bytes.data(), GL_STATIC_DRAW);
  // The seam round's dispatch sizes (omni).
  std::array<GLuint, 3 * kSlots> slots{};
  const auto slot = [&](int k, std::uint64_t invocations) {
    const std::array<GLuint, 3> g = groups_for(invocations);
    std::copy(g.begin(), g.end(), slots.begin() + 3 * k);
  };
  slot(kSlotReset, s.cells);
  for (int level = 2; level <= top; ++level) slot(level, s.nx[level] * s.ny[level]);
  slot(kSlotUnite, 12 * static_cast<std::uint64_t>(width));
  slot(kSlotApply, 24 * static_cast<std::uint64_t>(width));
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[kSeamTemplate].id());
  glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof slots, slots.data());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  if (s.omni()) {
    const OmniAdjacency adjacency = omni_adjacency(light);
    for (int k = 0; k < 12; ++k) {
      const OmniSeam& seam = adjacency.seams[static_cast<std::size_t>(k)];
      const GLint desc[6] = {seam.face[0],          grid_side_of(seam.border[0]),
                             seam.face[1],          grid_side_of(seam.border[1]),
                             seam.reversed ? 1 : 0, seam.flip ? 1 : 0};
      std::copy(desc, desc + 6, s.seam_desc + 6 * k);
    }
    for (int k = 0; k < 8; ++k) {
      const OmniCorner& corner = adjacency.corners[static_cast<std::size_t>(k)];
      for (int m = 0; m < 3; ++m) {
        GLint* out = s.corner_desc + 9 * k + 3 * m;
        out[0] = corner.face[static_cast<std::size_t>(m)];
        out[1] = corner.last_col[static_cast<std::size_t>(m)] ? 1 : 0;
        out[2] = corner.last_row[static_cast<std::size_t>(m)] ? 1 : 0;
      }
    }
  }
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: sizing the live adaptive volume's buffers for " + std::to_string(width) +
                 "x" + std::to_string(height) + " texels: " + e};
  return {};
}

// Long (over 80 lines) on purpose: one frame's passes in their order, with the seam rounds of an
// omni light around the per-face tessellation; split, the order would be harder to follow.
void LiveAdaptive::generate(const std::function<void(const Program&)>& bind) const {
  const State& s = *state_;
  const GLuint zero = 0, none = 0xFFFFFFFFu;
  // The phase and pass the next command belongs to (profiling), and the command, timed when
  // profiling.
  int phase = 0, current = kClearCommand;
  const auto timed = [&](const auto& command) {
    if (!s.profiling) {
      command();
      return;
    }
    State::Timed t{phase, current, std::make_unique<GpuTimer>(), 0, 0};
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    t.timer->begin();
    command();
    t.timer->end();
    glFinish();
    t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    t.cpu = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    s.timed.push_back(std::move(t));
  };
  const auto dispatch = [&](std::uint64_t invocations) {
    timed([&] { dispatch_groups(invocations); });
  };
  const auto clear = [&](Binding b, const GLuint* value) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[b].id());
    current = kClearCommand;
    timed([&] {
      glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, value);
    });
  };
  for (Binding b : {kSplits, kFails, kControlBuf, kBits, kOmni, kVerdicts}) clear(b, &zero);
  if (s.omni()) {
    clear(kForced, &zero);
    clear(kBorderIndex, &none);
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  const auto barrier = [] {
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  };
  int face = 0;
  const auto use = [&](Pass pass) -> const Program& {
    current = pass;
    s.programs[pass].use();
    glUniform1i(s.programs[pass].uniform("top_level"), s.top);
    glUniform1i(s.programs[pass].uniform("lv_face"), face);
    return s.programs[pass];
  };
  const auto indirect = [&](Binding b, std::uint64_t uint_offset) {
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, s.buffers[b].id());
    timed([&] {
      glDispatchComputeIndirect(static_cast<GLintptr>(
          (b == kControlBuf ? face * s.stride[kControlBuf] : 0) + 4 * uint_offset));
    });
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  };
  const std::uint64_t texels =
      static_cast<std::uint64_t>(s.width) * static_cast<std::uint64_t>(s.height);

  // Per face: the texels and the pyramid, thresholded at E, level by level from the finest.
  phase = 1;
  for (face = 0; face < s.faces; ++face) {
    s.bind_face(face);
    bind(use(kTexels));
    dispatch(texels);
    barrier();
    const Program& own = use(kOwn);
    for (int level = 1; level <= s.top; ++level) {
      const std::uint64_t bands =
          static_cast<std::uint64_t>(((1 << level) + kBandRows) / kBandRows);
      glUniform1i(own.uniform("level"), level);
      dispatch(s.nx[level] * s.ny[level] * bands);
      barrier();
    }
    if (s.omni()) {
      glBindBuffer(GL_COPY_READ_BUFFER, s.buffers[kSplits].id());
      glBindBuffer(GL_COPY_WRITE_BUFFER, s.buffers[kThreshold].id());
      current = kCopyCommand;
      timed([&] {
        glCopyBufferSubData(GL_COPY_READ_BUFFER, GL_COPY_WRITE_BUFFER, face * s.stride[kSplits],
                            face * s.stride[kThreshold], static_cast<GLsizeiptr>(4 * s.cells));
      });
      glBindBuffer(GL_COPY_READ_BUFFER, 0);
      glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
    }
  }
  // The balance and the fix-up rounds, each pass one dispatch per group of faces (all six faces
  // of an omni light in one, as a rule; each work group finds its face in the group's face list).
  // The fix-up rounds' face lists and dispatch sizes are written by the GPU: round 1's by
  // LV_CONTROL, each later one's by the round before's test (the faces it failed a leaf of: none
  // once a round split nothing, a dispatch of zero groups). Omni: from each face's threshold with
  // its forced border vertices, in seam rounds until the seams' borders agree (the seam round's
  // face lists and dispatch sizes written by the GPU too).
  int seam_round = 0;  // omni: the seam round being run
  const int groups = s.faces / s.per_dispatch;
  // Binds group g's ranges and uses `pass` on them with face list `list` (control[] offset).
  const auto use_group = [&](Pass pass, int g, GLuint list) -> const Program& {
    face = g * s.per_dispatch;
    s.bind_group(face, s.per_dispatch);
    const Program& program = use(pass);
    glUniform1i(program.uniform("lv_first_face"), face);
    glUniform1i(program.uniform("face_list"), static_cast<GLint>(list));
    return program;
  };
  const auto seam_args = [&](int g, int slot) {
    return kOmniArgs +
           3 * (kSlots * static_cast<std::uint64_t>(g) + static_cast<std::uint64_t>(slot));
  };
  const auto tessellate = [&] {
    for (int level = 2; level <= s.top; ++level) {
      for (int g = 0; g < groups; ++g) {
        const Program& balance = use_group(kBalance, g, kFaceLists);
        glUniform1i(balance.uniform("round_"), 0);
        glUniform1i(balance.uniform("level"), level);
        if (s.omni()) {
          indirect(kOmni, seam_args(g, level));
        } else {
          dispatch(s.nx[level] * s.ny[level]);
        }
      }
      barrier();
    }
    if (s.top < 2) return;
    // The fix-up rounds: round 1's faces and dispatch size from LV_CONTROL, each later one's from
    // the round before.
    for (int g = 0; g < groups; ++g) {
      const Program& control = use_group(kControl, g, 0);
      glUniform1i(control.uniform("rounds"), s.rounds);
      glUniform1i(control.uniform("faces_per_group"), s.per_dispatch);
      dispatch(1);
    }
    barrier();
    for (int round = 1; round <= s.rounds; ++round) {
      const auto args = [&](int r) { return kRoundArgs + 3 * static_cast<std::uint64_t>(r); };
      for (int g = 0; g < groups; ++g) {
        const Program& test = use_group(kTest, g, kFaceLists + 8 * static_cast<GLuint>(round));
        glUniform1i(test.uniform("round_"), round);
        glUniform1i(test.uniform("reuse"), round == 1 && seam_round > 1 ? 1 : 0);
        indirect(kControlBuf, args(round));
      }
      barrier();
      // The round's balance in one pass, on the faces whose test failed a leaf (round + 1's).
      for (int g = 0; g < groups; ++g) {
        const Program& propagate =
            use_group(kPropagate, g, kFaceLists + 8 * static_cast<GLuint>(round + 1));
        glUniform1i(propagate.uniform("round_"), round);
        indirect(kControlBuf, args(round + 1));
      }
      barrier();
    }
  };
  phase = 2;
  if (!s.omni()) {
    tessellate();
  } else {
    const auto seam_control = [&](int round) {
      const Program& control = use_group(kSeamControl, 0, 0);
      glUniform1i(control.uniform("round_"), round);
      glUniform1i(control.uniform("rounds"), s.seam_rounds);
      glUniform1i(control.uniform("seam_slots"), kSlots);
      glUniform1i(control.uniform("faces_per_group"), s.per_dispatch);
      dispatch(1);
      barrier();
    };
    for (int round = 1; round <= s.seam_rounds; ++round) {
      seam_round = round;
      seam_control(round);
      for (int g = 0; g < groups; ++g) {
        use_group(kReset, g, kFaceLists);
        indirect(kOmni, seam_args(g, kSlotReset));
      }
      barrier();
      tessellate();
      face = 0;
      s.bind_face(0);
      const Program& unite = use(kUnite);
      glUniform1i(unite.uniform("split_stride"), static_cast<GLint>(s.stride[kSplits] / 4));
      glUniform1iv(unite.uniform("seam_desc"), 72, s.seam_desc);
      indirect(kOmni, kOmniArgs + 3 * kSlotUnite);
      barrier();
      use(kApply);
      indirect(kOmni, kOmniArgs + 3 * kSlotApply);
      barrier();
    }
    seam_control(s.seam_rounds + 1);
  }
  // Emission, face by face: counts and the vertex bitmap, the two scans, the triangles and
  // vertices; then the closing (omni: the seams and corners) and the draw command.
  phase = 3;
  const auto scan = [&](Binding in, Binding out, std::uint64_t n, bool popcount, GLuint total) {
    s.bind_range(kScanIn, in, face);
    s.bind_range(kScanOut, out, face);
    const std::uint64_t chunks = (n + kChunk - 1) / kChunk;
    for (Pass pass : {kScanChunks, kScanSums, kScanWrite}) {
      const Program& program = use(pass);
      glUniform1i(program.uniform("scan_n"), static_cast<GLint>(n));
      glUniform1i(program.uniform("scan_popcount"), popcount ? 1 : 0);
      glUniform1i(program.uniform("scan_total"), static_cast<GLint>(total));
      dispatch(pass == kScanSums ? 1 : chunks);
      barrier();
    }
  };
  for (face = 0; face < s.faces; ++face) {
    s.bind_face(face);
    use(kCount);
    dispatch(s.cells);
    barrier();
    scan(kCounts, kOffsets, s.cells, false, kStats + 3);
    scan(kBits, kRanks, s.words, true, kStats + 2);
    if (s.omni()) {
      const Program& base = use(kBase);
      glUniform1i(base.uniform("rounds"), s.rounds);
      dispatch(1);
      barrier();
    }
    use(kTriangles);
    indirect(kControlBuf, kTriangleArgs);
    bind(use(kVertices));
    dispatch(s.words);
    barrier();
  }
  face = 0;
  s.bind_face(0);
  if (s.omni()) {
    const Program& seams = use(kSeams);
    glUniform1iv(seams.uniform("seam_desc"), 72, s.seam_desc);
    glUniform1iv(seams.uniform("corner_desc"), 72, s.corner_desc);
    dispatch(1);
  } else {
    const Program& close = use(kClose);
    bind(close);
    glUniform1i(close.uniform("rounds"), s.rounds);
    dispatch(1);
  }
  glMemoryBarrier(GL_ELEMENT_ARRAY_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT |
                  GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT |
                  GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);
  glBindVertexArray(0);
}

GLuint LiveAdaptive::vertex_array() const { return state_->vao.id(); }

void LiveAdaptive::set_faces_per_dispatch(int n) {
  LV_CHECK(n == 0 || n == 1 || n == 2 || n == 3 || n == 6);
  state_->requested_per_dispatch = n;
  if (state_->width > 0) state_->choose_per_dispatch();
}

int LiveAdaptive::faces_per_dispatch() const { return state_->per_dispatch; }

void LiveAdaptive::draw() const {
  const State& s = *state_;
  glBindVertexArray(s.vao.id());
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.buffers[kControlBuf].id());
  glDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT,
                         reinterpret_cast<const void*>(std::uintptr_t{4 * kDrawCommand}));
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
}

void LiveAdaptive::set_profiling(bool on) {
  state_->profiling = on;
  state_->timed.clear();
}

std::vector<LiveAdaptive::PassTime> LiveAdaptive::profile() const {
  std::vector<PassTime> r;
  for (const State::Timed& t : state_->timed) {
    const std::string phase = kPhaseNames[t.phase];
    const std::string pass = t.pass == kClearCommand  ? "clear"
                             : t.pass == kCopyCommand ? "copy"
                                                      : kPassNames[t.pass];
    auto it = std::find_if(r.begin(), r.end(),
                           [&](const PassTime& p) { return p.phase == phase && p.pass == pass; });
    if (it == r.end()) it = r.insert(r.end(), PassTime{phase, pass, 0, 0, 0, 0});
    ++it->dispatches;
    it->seconds += t.timer->seconds();
    it->wall_seconds += t.wall;
    it->cpu_seconds += t.cpu;
  }
  return r;
}

std::uint64_t LiveAdaptive::max_vertices() const { return state_->max_vertices; }
std::uint64_t LiveAdaptive::max_triangles() const { return state_->max_triangles; }
double LiveAdaptive::bound() const { return state_->bound; }

Result<LiveMesh> LiveAdaptive::read_back() const {
  const State& s = *state_;
  const auto read = [&](Binding b, std::size_t offset, std::size_t bytes, void* out) {
    glBindBuffer(GL_COPY_READ_BUFFER, s.buffers[b].id());
    glGetBufferSubData(GL_COPY_READ_BUFFER, static_cast<GLintptr>(offset),
                       static_cast<GLsizeiptr>(bytes), out);
  };
  LiveMesh r;
  std::uint64_t grid_vertices = 0, vertices = 0, triangles = 0;
  for (int f = 0; f < s.faces; ++f) {
    GLuint stats[6] = {};
    read(kControlBuf, static_cast<std::size_t>(f * s.stride[kControlBuf]) + 4 * kStats,
         sizeof stats, stats);
    r.fixup_rounds = std::max(r.fixup_rounds, static_cast<int>(stats[0]));
    r.converged = r.converged && stats[1] != 0;
    grid_vertices += stats[2];
    r.grid_triangles += stats[3];
    if (f == 0) vertices = stats[4], triangles = stats[5];
  }
  if (s.omni()) {
    GLuint omni[2] = {};
    read(kOmni, 0, sizeof omni, omni);
    r.seam_rounds = static_cast<int>(omni[1]);
    r.seams_agree = omni[0] != 0;
    r.converged = r.converged && r.seams_agree;
  }
  LV_CHECK_LE(vertices, s.max_vertices);
  LV_CHECK_LE(triangles, s.max_triangles);
  r.mesh.positions.resize(3 * vertices);
  r.mesh.indices.resize(3 * triangles);
  r.vertex_texels.resize(grid_vertices);
  read(kPositions, 0, r.mesh.positions.size() * sizeof(float), r.mesh.positions.data());
  read(kIndices, 0, r.mesh.indices.size() * sizeof(std::uint32_t), r.mesh.indices.data());
  read(kTexelIds, 0, r.vertex_texels.size() * sizeof(std::uint32_t), r.vertex_texels.data());
  glBindBuffer(GL_COPY_READ_BUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: reading the live adaptive volume back: " + e};
  return r;
}

}  // namespace lightvol::detail

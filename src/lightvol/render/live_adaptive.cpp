#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

#include <lightvol/core/check.h>
#include <lightvol/render/detail/airlight_glsl.h>
#include <lightvol/render/detail/live_adaptive_glsl.h>
#include <lightvol/render/live_adaptive.h>

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
  kPasses
};
constexpr const char* kPassNames[kPasses] = {
    "LV_TEXELS",      "LV_OWN",       "LV_BALANCE",    "LV_CONTROL",   "LV_TEST",     "LV_COUNT",
    "LV_SCAN_CHUNKS", "LV_SCAN_SUMS", "LV_SCAN_WRITE", "LV_TRIANGLES", "LV_VERTICES", "LV_CLOSE"};

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
  kUnused = 12,
  kScanSumsBuf = 13,
  kScanIn = 14,
  kScanOut = 15,
  kOffsets = 16,
  kBuffers = 17
};

constexpr GLuint kStats = 160;         // control[kStats + ...] (shaders/live_adaptive.comp)
constexpr GLuint kTriangleArgs = 100;  // LV_TRIANGLES' dispatch size, written by the GPU
constexpr GLuint kDrawCommand = 192;   // control[kDrawCommand..+4]: the indirect draw command
constexpr GLuint kControlSize = 256;
constexpr int kBandRows = 16;
constexpr int kChunk = 256;

// Dispatches enough groups of 64 for `invocations`, as rows of at most kMaxGroupsX groups
// (shaders/live_adaptive.comp's invocation()).
constexpr std::uint64_t kMaxGroupsX = 32768;
void dispatch(std::uint64_t invocations) {
  const std::uint64_t groups = std::max<std::uint64_t>((invocations + 63) / 64, 1);
  const std::uint64_t x = std::min(groups, kMaxGroupsX);
  glDispatchCompute(static_cast<GLuint>(x), static_cast<GLuint>((groups + x - 1) / x), 1);
}

// The largest float ≤ b, as a double: a value rounded up to float exceeds b iff it exceeds this.
double float_floor(double b) {
  float f = static_cast<float>(b);
  if (static_cast<double>(f) > b) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace

std::string live_adaptive_problem(const Light& light) {
  if (light.type == LightType::omni)
    return "live volume: adaptive tessellation (max_error) takes spot and directional lights; "
           "omni lights have static live volumes only";
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
  int rounds = 0;
  Program programs[kPasses];
  BufferHandle buffers[kBuffers];
  VertexArrayHandle vao;
  Params params;
  int width = 0, height = 0, top = 0;
  std::uint64_t nx[16] = {}, ny[16] = {};  // cells per level, across and down
  std::uint64_t cells = 0, words = 0, max_vertices = 0, max_triangles = 0;
  std::uint64_t max_indices = 0, max_grid_vertices = 0;
};

LiveAdaptive::~LiveAdaptive() = default;

Result<std::unique_ptr<LiveAdaptive>> LiveAdaptive::create(double bound, int rounds) {
  LV_CHECK(std::isfinite(bound) && bound >= 0);
  LV_CHECK(rounds >= 1 && rounds <= 63);
  std::unique_ptr<LiveAdaptive> live(new LiveAdaptive());
  live->state_ = std::make_unique<State>();
  State& s = *live->state_;
  s.bound = bound;
  s.rounds = rounds;
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

Status LiveAdaptive::resize(const Light& light, int width, int height) {
  State& s = *state_;
  if (std::string problem = live_adaptive_problem(light); !problem.empty()) return Error{problem};
  Params& p = s.params;
  p = Params{};
  // TexelDepths' constants (tessellate/texel_depths.cpp), in the same order of operations.
  const Mat4d view = light.view;
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
  p.bound = s.bound;
  p.pyramid_bound = float_floor(s.bound);
  p.width = width, p.height = height;
  p.flip_y = light.flip_y ? 1 : 0;
  p.encoding = light.depth == DepthEncoding::window ? 0 : 1;
  p.standard = Unprojector(light, width, height, 0, Space::world).standard_winding() ? 1 : 0;
  p.type = light.type == LightType::spot ? 0 : 1;
  // The quadtree (detail::Quadtree): levels 1..top (at least one level: a 2 × 2 map's one quad
  // is a level-1 cell's two triangles either way).
  const int cw = width - 1, ch = height - 1;
  int top = 0;
  while ((1 << top) < std::max(cw, ch)) ++top;
  top = std::max(top, 1);
  if (top > 15)
    return Error{"live volume: maps of more than 32769 texels a side are not supported"};
  s.top = top;
  std::uint64_t cells = 0;
  for (int level = 1; level <= top; ++level) {
    s.nx[level] = static_cast<std::uint64_t>((cw + (1 << level) - 1) >> level);
    s.ny[level] = static_cast<std::uint64_t>((ch + (1 << level) - 1) >> level);
    p.nx[level] = static_cast<double>(s.nx[level]);
    p.ny[level] = static_cast<double>(s.ny[level]);
    p.offset[level] = static_cast<double>(cells);
    cells += s.nx[level] * s.ny[level];
  }
  p.offset[top + 1] = static_cast<double>(cells);
  p.cells_total = static_cast<double>(cells);
  s.width = width, s.height = height;
  s.cells = cells;
  s.words = static_cast<std::uint64_t>((width + 31) / 32) * static_cast<std::uint64_t>(height);
  const std::uint64_t texels =
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  const std::uint64_t perimeter =
      2 * static_cast<std::uint64_t>(cw) + 2 * static_cast<std::uint64_t>(ch);
  s.max_grid_vertices = texels;
  s.max_vertices = texels + perimeter + 1;
  s.max_triangles =
      2 * static_cast<std::uint64_t>(cw) * static_cast<std::uint64_t>(ch) + 3 * perimeter;
  s.max_indices = 3 * s.max_triangles;
  if (s.max_indices >= std::uint64_t{1} << 31)
    return Error{"live volume: " + std::to_string(width) + "x" + std::to_string(height) +
                 " texels are more than one draw call holds"};

  const auto allocate = [&](Binding b, std::uint64_t bytes) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[b].id());
    glBufferData(GL_SHADER_STORAGE_BUFFER,
                 static_cast<GLsizeiptr>(std::max<std::uint64_t>(bytes, 16)), nullptr,
                 GL_DYNAMIC_COPY);
  };
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[kParams].id());
  glBufferData(GL_SHADER_STORAGE_BUFFER, sizeof(Params), &p, GL_STATIC_DRAW);
  allocate(kDepths, 8 * texels);
  allocate(kScales, p.uniform_flag ? 8 : 8 * texels);
  allocate(kSplits, 4 * s.cells);
  allocate(kFails, 4 * s.cells);
  allocate(kControlBuf, 4 * kControlSize);
  allocate(kBits, 4 * s.words);
  allocate(kCounts, 4 * s.cells);
  allocate(kOffsets, 4 * s.cells);
  allocate(kRanks, 4 * s.words);
  allocate(kIndices, 4 * s.max_indices);
  allocate(kPositions, 12 * s.max_vertices);
  allocate(kTexelIds, 4 * s.max_grid_vertices);
  allocate(kScanSumsBuf, 4 * ((std::max(s.cells, s.words) + kChunk - 1) / kChunk + 1));
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  if (std::string e = pending_error(); !e.empty())
    return Error{"OpenGL: sizing the live adaptive volume's buffers for " + std::to_string(width) +
                 "x" + std::to_string(height) + " texels: " + e};
  return {};
}

void LiveAdaptive::generate(const std::function<void(const Program&)>& bind) const {
  const State& s = *state_;
  for (int b = 0; b < kBuffers; ++b)
    if (b != kScanIn && b != kScanOut && b != kUnused)
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, s.buffers[b].id());
  const GLuint zero = 0;
  for (Binding b : {kSplits, kFails, kControlBuf, kBits}) {
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.buffers[b].id());
    glClearBufferData(GL_SHADER_STORAGE_BUFFER, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  }
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  const auto barrier = [] {
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  };
  const auto use = [&](Pass pass) -> const Program& {
    s.programs[pass].use();
    glUniform1i(s.programs[pass].uniform("top_level"), s.top);
    return s.programs[pass];
  };
  const std::uint64_t texels =
      static_cast<std::uint64_t>(s.width) * static_cast<std::uint64_t>(s.height);

  bind(use(kTexels));
  dispatch(texels);
  barrier();
  // The pyramid, thresholded at E: level by level from the finest.
  const Program& own = use(kOwn);
  for (int level = 1; level <= s.top; ++level) {
    const std::uint64_t bands = static_cast<std::uint64_t>(((1 << level) + kBandRows) / kBandRows);
    glUniform1i(own.uniform("level"), level);
    dispatch(s.nx[level] * s.ny[level] * bands);
    barrier();
  }
  const Program& balance = use(kBalance);
  glUniform1i(balance.uniform("round_"), 0);
  for (int level = 2; level <= s.top; ++level) {
    glUniform1i(balance.uniform("level"), level);
    dispatch(s.nx[level] * s.ny[level]);
    barrier();
  }
  // The fix-up rounds: each one's dispatch sizes written by the GPU (zero once a round split
  // nothing).
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, s.buffers[kControlBuf].id());
  for (int round = 1; round <= s.rounds && s.top >= 2; ++round) {
    const Program& control = use(kControl);
    glUniform1i(control.uniform("round_"), round);
    dispatch(1);
    barrier();
    const Program& test = use(kTest);
    glUniform1i(test.uniform("round_"), round);
    glDispatchComputeIndirect(64 * sizeof(GLuint));
    barrier();
    const Program& rebalance = use(kBalance);
    glUniform1i(rebalance.uniform("round_"), round);
    for (int level = 2; level <= s.top; ++level) {
      glUniform1i(rebalance.uniform("level"), level);
      glDispatchComputeIndirect(static_cast<GLintptr>((64 + 3 * (level - 1)) * sizeof(GLuint)));
      barrier();
    }
  }
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  // Emission: counts and the vertex bitmap, the two scans, the triangles and vertices, the
  // closing and the draw command.
  use(kCount);
  dispatch(s.cells);
  barrier();
  const auto scan = [&](Binding in, Binding out, std::uint64_t n, bool popcount, GLuint total) {
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kScanIn, s.buffers[in].id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kScanOut, s.buffers[out].id());
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
  scan(kCounts, kOffsets, s.cells, false, kStats + 3);
  scan(kBits, kRanks, s.words, true, kStats + 2);
  use(kTriangles);
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, s.buffers[kControlBuf].id());
  glDispatchComputeIndirect(static_cast<GLintptr>(kTriangleArgs * sizeof(GLuint)));
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  bind(use(kVertices));
  dispatch(s.words);
  barrier();
  const Program& close = use(kClose);
  bind(close);
  glUniform1i(close.uniform("rounds"), s.rounds);
  dispatch(1);
  glMemoryBarrier(GL_ELEMENT_ARRAY_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT |
                  GL_COMMAND_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT |
                  GL_BUFFER_UPDATE_BARRIER_BIT);
  glUseProgram(0);
  glBindVertexArray(0);
}

GLuint LiveAdaptive::vertex_array() const { return state_->vao.id(); }

void LiveAdaptive::draw() const {
  const State& s = *state_;
  glBindVertexArray(s.vao.id());
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, s.buffers[kControlBuf].id());
  glDrawElementsIndirect(GL_TRIANGLES, GL_UNSIGNED_INT,
                         reinterpret_cast<const void*>(std::uintptr_t{4 * kDrawCommand}));
  glBindBuffer(GL_DRAW_INDIRECT_BUFFER, 0);
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
  GLuint stats[6] = {};
  read(kControlBuf, 4 * kStats, sizeof stats, stats);
  LiveMesh r;
  r.fixup_rounds = static_cast<int>(stats[0]);
  r.converged = stats[1] != 0;
  const std::uint64_t grid_vertices = stats[2];
  r.grid_triangles = stats[3];
  const std::uint64_t vertices = stats[4], triangles = stats[5];
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

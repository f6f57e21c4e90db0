// The adaptive live volume's GPU side (LiveVolume with LiveOptions::max_error; docs/rendering.md,
// "Live volumes"): compute passes (shaders/live_adaptive.comp) that tessellate the shadow map at
// a bound E every frame, as `lightvol build --adaptive --tessellation quadtree` does on the CPU
// (the same quadtree: pyramid, 2:1 balance, fix-up rounds, 16 edge-split configurations, the
// closing through the border vertices; omni: the six faces in seam rounds until the seams' borders
// agree, then the seam strips and corners, as build_adaptive_omni_volume makes them), into a vertex
// and an index buffer sized once for the largest tessellation, and the indirect draw command that
// draws exactly what was made. No read-back and no allocation per frame. Internal to the render
// stage.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/gl/context.h>
#include <lightvol/light/light.h>
#include <lightvol/render/live_volume.h>

namespace lightvol::detail {

class LiveAdaptive {
 public:
  // Compiles the passes. `bound`: E in world units (finite, ≥ 0); `rounds`: the most fix-up
  // rounds a frame runs (1..63); `seam_rounds`: an omni light's most seam rounds (≥ 1).
  static Result<std::unique_ptr<LiveAdaptive>> create(double bound, int rounds, int seam_rounds);
  ~LiveAdaptive();

  // Sizes the buffers for W × H maps of `light` (spot or directional; omni: six W × W faces;
  // window or linear depth with a projection whose depth row sees eye z only). Errors name what
  // is not supported.
  Status resize(const Light& light, int width, int height);

  // Runs the passes. `bind` sets the live_* uniforms and shadow_maps samplers (LiveVolume::bind)
  // on the program in use.
  void generate(const std::function<void(const gl::Program&)>& bind) const;
  // Attribute 0: the positions (xyz floats); the element buffer: the triangles.
  GLuint vertex_array() const;
  // Draws what generate made: glDrawElementsIndirect with the GPU's count (vertex array bound).
  void draw() const;
  // The largest volume a map of this size can give.
  std::uint64_t max_vertices() const;
  std::uint64_t max_triangles() const;
  double bound() const;

  // The mesh the last generate made, and its statistics.
  Result<LiveMesh> read_back() const;

  // The faces each dispatch of the tessellation's passes works on: an omni light's six at once
  // when their ranges of the per-face buffers fit one storage block (GL_MAX_SHADER_STORAGE_BLOCK_
  // SIZE), else 3, 2 or 1 (spot, directional: 1). For tests: `n` (1, 2, 3 or 6 for an omni
  // light; 0: that default), from the next resize (or now, when sized); the volume is the same.
  void set_faces_per_dispatch(int n);
  int faces_per_dispatch() const;

  // For benchmarks, never in an engine's frame: while on, generate wraps every dispatch, clear
  // and copy in a GL_TIME_ELAPSED query (allocating them) and in glFinish calls, timed on the
  // CPU; profile() waits for the results and returns both per phase and pass, summed over the
  // frames since profiling was turned on. (llvmpipe runs a dispatch on the CPU outside its
  // queries, which time it near zero: there the wall time is the cost.)
  struct PassTime {
    std::string phase, pass;  // phase: "clear", "pyramid", "tessellation" (omni: the seam
                              // rounds), "emission"; pass: its LV_* name
    int dispatches = 0;
    double seconds = 0;       // GL_TIME_ELAPSED
    double wall_seconds = 0;  // clock from a glFinish before the command to one after
    double cpu_seconds = 0;   // the process's CPU time (all threads) over the same span
                              // (llvmpipe: the command's work, less sensitive to other load)
  };
  void set_profiling(bool on);
  std::vector<PassTime> profile() const;

 private:
  LiveAdaptive() = default;
  struct State;
  std::unique_ptr<State> state_;
};

// Why `light` cannot have an adaptive live volume, or "".
std::string live_adaptive_problem(const Light& light);

}  // namespace lightvol::detail

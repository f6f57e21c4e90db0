// The demo as one call: the bundled scene (data/: the middle of the Sponza atrium, a spot light, a
// camera, a homogeneous medium and a noise fog) through the whole pipeline — the light's shadow map
// and the camera's depth, the static and the adaptive volume (each checked before it is written),
// the web viewer's inputs and, with OpenGL, the airlight pictures — with one report row per step.
// What `lightvol demo` runs (docs/architecture.md).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <lightvol/airlight/airlight.h>
#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/core/stages.h>
#include <lightvol/depth/shadow_maps.h>
#include <lightvol/render/scene.h>
#include <lightvol/scene/depth_passes.h>

namespace lightvol {

// One step of the demo as its report shows it: the step, the file it wrote (or ""), its size (a
// triangle count, an image size), its result, and its seconds.
struct DemoRow {
  std::string step, file, size, result;
  double seconds = 0;
};

struct DemoReport {
  std::vector<DemoRow> rows;  // in the order the steps ran (the checks after the viewer's inputs)
};

// A volume the demo built: "static" or "adaptive", and its mesh.
struct DemoVolume {
  std::string name;
  Mesh mesh;
};

// What the demo's pictures are made of (DemoGpu::pictures): the camera's scene (its surface
// distances from the camera depth pass), the fog, the volumes, the light's shadow map and its
// window depth, and the folder they are written to.
struct DemoPictureInputs {
  const RenderScene& scene;
  const Medium& fog;
  const std::vector<DemoVolume>& volumes;
  const ShadowMaps& shadow;
  const std::vector<float>& shadow_window;
  const std::string& out_dir;
};

// The steps that need OpenGL, which lightvol::gl provides (gl_demo_steps, pipeline/gl_demo.h);
// without them the depth passes are the CPU's and no picture is rendered.
struct DemoGpu {
  // Depth passes of `scene` on the GPU (named `source` in messages), or an Error saying why they
  // cannot run (then the CPU's run, and the pictures are skipped).
  std::function<Result<std::unique_ptr<DepthPasses>>(const Mesh& scene, const std::string& source)>
      depth_passes;
  // Renders and writes the pictures, each step timed in `log` and reported in `rows`.
  std::function<Status(const DemoPictureInputs& in, StageLog& log, std::vector<DemoRow>* rows)>
      pictures;
};

struct DemoOptions {
  std::string data_dir;                   // the bundled data/ folder
  std::string out_dir = "lightvol-demo";  // created if missing; every output is written there
  int size = 512;                         // the shadow map's size; below 512 the camera's shrinks
  double max_error = 0.01;                // the adaptive volume's bound, world units
  DemoGpu gpu;                            // empty: CPU depth passes, no pictures
};

// Runs the demo: reads the scene, light, camera and media of `data_dir`; writes the light's shadow
// map (shadow_map.exr, .png) and the camera's depth (camera_depth.exr, .png); builds the static
// and the adaptive volume (build_volume_file: checked from the light before volume_static.ply and
// volume_adaptive.ply are written); writes the web viewer's inputs (the volumes as GLBs with their
// light and the medium, scene.glb, camera.json at the demo's image size, light.json, medium.json);
// then, with options.gpu, the pictures. Each step is timed in `log`. Errors name the file; a
// scene that cannot be read says to check DemoOptions::data_dir.
Result<DemoReport> run_demo(const DemoOptions& options, StageLog& log);

// The report as a table: a header line, then one line per row (step, file, size, seconds,
// result), each ending in a line break.
std::string demo_table(const DemoReport& report);

}  // namespace lightvol

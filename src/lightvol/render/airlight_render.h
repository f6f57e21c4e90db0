// `lightvol render` as library calls: the camera's scene read from its files, the airlight by one
// of the methods (the CPU reference here; every method on the GPU in gl_airlight_render.h), and
// what is said of the image (its mean and peak, its difference from a reference image file).
#pragma once

#include <string>
#include <vector>

#include <lightvol/core/mesh.h>
#include <lightvol/core/result.h>
#include <lightvol/core/stages.h>
#include <lightvol/render/scene.h>

namespace lightvol {

// How the airlight is rendered (docs/rendering.md): volume (a light volume mesh drawn with signed
// additive blending), live (the same, its volume made on the GPU every frame from the shadow
// maps), reference (the exact sum on the CPU, double precision), raymarch (steps through the
// shadow maps) and radial (a radial blur of the camera depth).
enum class RenderMethod { volume, live, reference, raymarch, radial };

// "volume", "live", "reference", "raymarch", "radial".
const char* to_string(RenderMethod method);

// Whether `method` draws a volume mesh the caller gives (volume, reference).
bool method_takes_mesh(RenderMethod method);

// A render: the files of the camera's scene, the method and its settings.
struct RenderRequest {
  RenderMethod method = RenderMethod::volume;
  std::string camera_path;  // load_camera
  std::string light_path;   // load_light
  std::string medium_path;  // load_medium
  std::string depth_path;   // the camera's depth image, in the camera's depth encoding
  std::string channel;      // DepthReadOptions::channel of every depth image read
  // The light's shadow map(s) (read_shadow_maps): live and raymarch need them; radial may take
  // them.
  std::vector<std::string> shadow_map_paths;
  int samples = 64;       // raymarch: steps per pixel; radial: blur samples (MarchOptions)
  int interleave = 1;     // raymarch: M for M×M interleaved sampling
  double max_error = -1;  // live: the adaptive volume at this bound (< 0: the static volume)
  int frames = 0;         // GPU methods: render this many more frames, timing each
  // Media of varying density (DensityGridOptions, OpacityMapOptions of render/gl_density.h).
  int grid_tile = 0;        // volume: pixels per in-scattering column side (0: automatic)
  int grid_slices = 128;    // volume: samples along each in-scattering column
  int opacity_size = 64;    // volume, raymarch: opacity map columns per side (per face)
  int opacity_layers = 64;  // volume, raymarch: opacity map layers along the light's depth
};

// Reads the camera, light and medium of `request`, and the camera's depth image as surface
// distances (that read timed in `log`). Errors name the file: a file the loaders refuse, a
// medium with a profile for a light that is not a spot, a medium of varying density for a method
// that renders homogeneous media only (live, radial).
Result<RenderScene> load_render_scene(const RenderRequest& request, StageLog& log);

// A rendered airlight image, and the timings of the frames rendered after it.
struct AirlightRender {
  Image image;
  std::vector<double> frame_seconds;       // request.frames GPU timings of a whole frame
  std::vector<double> generation_seconds;  // live: request.frames timings of the volume's
                                           // generation alone (LiveVolume::generate, glFinish)
  std::string renderer;                    // the OpenGL renderer's name ("" on the CPU)
};

// The CPU reference (request.method must be reference) of `volume` in `scene`, timed in `log`.
AirlightRender render_airlight_reference(const RenderScene& scene, const Mesh& volume,
                                         StageLog& log);

// The median of `values` (0 for none).
double median(std::vector<double> values);

// The mean of an image's values and their largest magnitude (0 for an empty image).
struct ImageLevels {
  double mean = 0;
  double peak = 0;
};
ImageLevels image_levels(const Image& image);

// `image` against the image file at `path` (read_image). Errors: the file's, or its size not the
// image's ("PATH: image is 128x128, the render is 64x48").
Result<ImageDifference> compare_with_image_file(const Image& image, const std::string& path);

}  // namespace lightvol

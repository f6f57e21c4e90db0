// `lightvol render` end to end on the analytic floor-and-box scene written to files: the volume
// method against the reference through --compare, PNG and EXR outputs, the alternatives (the radial
// blur as the library renders it, --composite's surfaces in closed form), and bad input rejected
// with a message naming the file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include <lightvol/export/export.h>
#include <lightvol/render/gl_marchers.h>
#include <lightvol/render/image_io.h>
#include <lightvol/volume/static_volume.h>

#include "support/analytic_scene.h"
#include "support/gl_test_context.h"
#include "support/omni_scene.h"
#include "support/test_support.h"

namespace lightvol {
namespace {

constexpr int kW = 64, kH = 48, kMap = 128;

// Writes light.json, shadow.exr, volume.ply, camera.json, camdepth.exr and medium.json into `dir`.
void write_scene(const std::string& dir, Vec3d eye, Vec3d target) {
  const std::string light_json = test::spot_json("linear");
  std::ofstream(dir + "/light.json") << light_json;
  const Light light = test::light_from_json(light_json);
  const DepthImage shadow = test::scene_shadow_map(light, kMap, kMap);
  ASSERT_TRUE(write_depth_image(dir + "/shadow.exr", shadow));
  Result<Mesh> volume = build_static_volume(light, shadow, {}, "shadow");
  ASSERT_TRUE(volume);
  ASSERT_TRUE(write_mesh(dir + "/volume.ply", *volume));
  std::ostringstream cam;
  const Vec3d d = target - eye;
  cam << R"({"position": [)" << eye.x << ", " << eye.y << ", " << eye.z << R"(], "direction": [)"
      << d.x << ", " << d.y << ", " << d.z << R"(], "up": [0, 1, 0], "fov_y_deg": 50, "aspect": )"
      << double(kW) / kH << R"(, "near": 0.05, "far": 100, "depth": "linear", "width": )" << kW
      << R"(, "height": )" << kH << "}";
  std::ofstream(dir + "/camera.json") << cam.str();
  Result<Camera> camera = parse_camera(cam.str(), "camera.json");
  ASSERT_TRUE(camera) << camera.error().message;
  DepthImage depth;
  depth.width = kW;
  depth.height = kH;
  for (int row = 0; row < kH; ++row)
    for (int col = 0; col < kW; ++col) {
      const Ray ray = pixel_ray(*camera, col, row);
      const double t = test::cast_scene(ray.origin, ray.direction);
      const double z = std::isfinite(t)
                           ? -camera->view.view.transform_point(ray.origin + t * ray.direction).z
                           : 100.0;
      depth.values.push_back(static_cast<float>(std::min(z, 100.0)));
    }
  ASSERT_TRUE(write_depth_image(dir + "/camdepth.exr", depth));
  std::ofstream(dir + "/medium.json")
      << R"({"scattering": 0.06, "absorption": 0.02, "intensity": 20, "phase": {"type": "hg", "g": 0.3}})";
}

std::string common_args(const std::string& dir) {
  return "--light '" + dir + "/light.json' --camera '" + dir + "/camera.json' --depth '" + dir +
         "/camdepth.exr' --medium '" + dir + "/medium.json' --quiet";
}

double number_after(const std::string& text, const std::string& key) {
  const auto at = text.find(key);
  if (at == std::string::npos) return NAN;
  return std::strtod(text.c_str() + at + key.size(), nullptr);
}

// Keeps the pictures when LIGHTVOL_RENDER_PICTURES names a directory (for the README).
std::string picture_dir(const test::TempDir& tmp) {
  const char* keep = std::getenv("LIGHTVOL_RENDER_PICTURES");
  return keep ? std::string(keep) : tmp.path();
}

TEST(RenderCommand, VolumeMatchesReferenceThroughCompare) {
  REQUIRE_GL_CONTEXT();
  test::TempDir tmp;
  const std::string dir = picture_dir(tmp);
  write_scene(dir, {6, 3, 6}, {0, 1, 0});
  const std::string args = common_args(dir);
  test::CommandResult ref =
      test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --method reference --out '" +
                         dir + "/reference.exr'");
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  test::CommandResult vol =
      test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --out '" + dir +
                         "/volume.exr' --compare '" + dir + "/reference.exr' --frames 2");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  EXPECT_LT(number_after(vol.out, "relative L2 "), 0.002) << vol.out;
  EXPECT_GT(number_after(vol.out, "PSNR "), 60) << vol.out;
  EXPECT_GT(number_after(vol.out, "time per frame: "), 0) << vol.out;
  Result<Image> exr = read_image(dir + "/volume.exr");
  ASSERT_TRUE(exr) << exr.error().message;
  EXPECT_EQ(exr->width, kW);
  EXPECT_EQ(exr->height, kH);
  // The raymarcher against the same reference, and the radial blur runs.
  test::CommandResult march =
      test::run_lightvol("render " + args + " --method raymarch --shadow-map '" + dir +
                         "/shadow.exr' --samples 1024 --out '" + dir +
                         "/raymarch.png' --compare '" + dir + "/reference.exr'");
  ASSERT_EQ(march.exit_code, 0) << march.err;
  EXPECT_LT(number_after(march.out, "relative L2 "), 0.03) << march.out;
  // The radial blur: the image the library's GlMarcher renders for the same files and --samples.
  test::CommandResult radial = test::run_lightvol(
      "render " + args + " --method radial --samples 48 --out '" + dir + "/radial.exr'");
  ASSERT_EQ(radial.exit_code, 0) << radial.err;
  Result<Image> radial_image = read_image(dir + "/radial.exr");
  ASSERT_TRUE(radial_image) << radial_image.error().message;
  Result<Camera> camera = load_camera(dir + "/camera.json");
  Result<DepthImage> camera_depth = read_depth_image(dir + "/camdepth.exr");
  Result<Medium> medium = load_medium(dir + "/medium.json");
  ASSERT_TRUE(camera && camera_depth && medium);
  Result<std::vector<double>> surface =
      surface_distances(*camera, camera_depth->values, kW, kH, "camdepth.exr");
  ASSERT_TRUE(surface) << surface.error().message;
  const RenderScene scene{*camera, *surface, test::light_from_json(test::spot_json("linear")),
                          *medium};
  MarchOptions radial_options;
  radial_options.method = MarchMethod::radial;
  radial_options.samples = 48;
  Result<std::unique_ptr<GlMarcher>> marcher = GlMarcher::create(scene, {}, {}, radial_options);
  ASSERT_TRUE(marcher) << marcher.error().message;
  const Image radial_expected = (*marcher)->render();
  double radial_peak = 0;
  for (const double v : radial_expected.values) radial_peak = std::max(radial_peak, v);
  EXPECT_GT(radial_peak, 0);
  ASSERT_EQ(radial_image->values.size(), radial_expected.values.size());
  for (std::size_t i = 0; i < radial_expected.values.size(); ++i)
    ASSERT_NEAR(radial_image->values[i], radial_expected.values[i], 1e-6 * radial_peak) << i;

  // --composite adds surfaces of radiance --background (0.1) seen through the medium: exactly
  // 0.1·e^(−σt·s) at the surface distance s (none where the ray hits nothing) on top of the
  // reference's airlight.
  test::CommandResult composite =
      test::run_lightvol("render '" + dir + "/volume.ply' " + args +
                         " --method reference --composite --out '" + dir + "/composite.exr'");
  ASSERT_EQ(composite.exit_code, 0) << composite.err;
  Result<Image> with_surfaces = read_image(dir + "/composite.exr");
  Result<Image> airlight = read_image(dir + "/reference.exr");
  ASSERT_TRUE(with_surfaces && airlight);
  ASSERT_EQ(with_surfaces->values.size(), static_cast<std::size_t>(kW) * kH);
  const double sigma_t = 0.06 + 0.02;
  int surfaces = 0;
  for (int row = 0; row < kH; ++row)
    for (int col = 0; col < kW; ++col) {
      const Ray ray = pixel_ray(*camera, col, row);
      const double t = test::cast_scene(ray.origin, ray.direction);
      const double z = -camera->view.view.transform_point(ray.origin + t * ray.direction).z;
      const bool hit = std::isfinite(t) && z < 100;  // the far plane: nothing hit
      surfaces += hit ? 1 : 0;
      const std::size_t i = static_cast<std::size_t>(row) * kW + col;
      EXPECT_NEAR(with_surfaces->values[i] - airlight->values[i],
                  hit ? 0.1 * std::exp(-sigma_t * t) : 0.0, 1e-6)
          << "pixel " << col << ", " << row;
    }
  EXPECT_GT(surfaces, kW * kH / 2);
  EXPECT_LT(surfaces, kW * kH);  // some sky
}

TEST(RenderCommand, LiveMakesTheVolumeOnTheGpuAndDrawsBuildsAirlight) {
  REQUIRE_GL_CONTEXT();
  test::TempDir tmp;
  const std::string dir = tmp.path();
  write_scene(dir, {6, 3, 6}, {0, 1, 0});
  const std::string args = common_args(dir);
  test::CommandResult vol = test::run_lightvol("render '" + dir + "/volume.ply' " + args +
                                               " --out '" + dir + "/volume.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  test::CommandResult live = test::run_lightvol(
      "render " + args + " --method live --shadow-map '" + dir + "/shadow.exr' --out '" + dir +
      "/live.exr' --compare '" + dir + "/volume.exr' --frames 2");
  ASSERT_EQ(live.exit_code, 0) << live.err;
  // The same vertices to float rounding, drawn by the same passes (tests/render/live_volume_test).
  EXPECT_LT(number_after(live.out, "relative L2 "), 1e-4) << live.out;
  EXPECT_NE(live.out.find("method live"), std::string::npos) << live.out;
  EXPECT_GT(number_after(live.out, "time per frame: "), 0) << live.out;
  // The generation alone is part of the frame (tests/bench/live_table1.sh reads both).
  EXPECT_GT(number_after(live.out, "volume generation alone: "), 0) << live.out;
}

TEST(RenderCommand, LiveAdaptiveDrawsTheAirlightOfBuildsQuadtreeVolume) {
  REQUIRE_GL_CONTEXT();
  test::TempDir tmp;
  const std::string dir = tmp.path();
  write_scene(dir, {6, 3, 6}, {0, 1, 0});
  const std::string args = common_args(dir);
  test::CommandResult built = test::run_lightvol(
      "build '" + dir + "/shadow.exr' --light '" + dir + "/light.json' --adaptive --tessellation " +
      "quadtree --max-error 0.01 --out '" + dir + "/adaptive.ply'");
  ASSERT_EQ(built.exit_code, 0) << built.err;
  test::CommandResult vol = test::run_lightvol("render '" + dir + "/adaptive.ply' " + args +
                                               " --out '" + dir + "/volume.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  test::CommandResult live = test::run_lightvol(
      "render " + args + " --method live --adaptive --max-error 0.01 --shadow-map '" + dir +
      "/shadow.exr' --out '" + dir + "/live.exr' --compare '" + dir + "/volume.exr' --frames 2");
  ASSERT_EQ(live.exit_code, 0) << live.err;
  // The same triangles (tests/render/live_adaptive_test), drawn by the same passes.
  EXPECT_LT(number_after(live.out, "relative L2 "), 1e-4) << live.out;
  test::CommandResult r =
      test::run_lightvol("render " + args + " --method live --adaptive " + "--shadow-map '" + dir +
                         "/shadow.exr' --out '" + dir + "/x.exr'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "lightvol: --adaptive: needs --max-error E (world units along the texel rays)\n");
  r = test::run_lightvol("render '" + dir + "/adaptive.ply' " + args + " --max-error 0.01 --out '" +
                         dir + "/x.exr'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "lightvol: --max-error: applies with --adaptive only\n");
}

TEST(RenderCommand, LiveOmniDrawsTheAirlightOfBuildsStaticAndQuadtreeVolumes) {
  REQUIRE_GL_CONTEXT();
  test::TempDir tmp;
  const std::string dir = tmp.path();
  write_scene(dir, {4, 3, 3}, {-1, 1, -3});
  // The room with a pillar and a ball (tests/support/omni_scene.h), six 24² faces.
  std::ofstream(dir + "/omni.json") << test::omni_scene_light_json();
  const CubeFaces cube = test::omni_scene(24);
  const char* names[kOmniFaces] = {"px", "nx", "py", "ny", "pz", "nz"};
  for (int f = 0; f < kOmniFaces; ++f)
    ASSERT_TRUE(write_depth_image(dir + "/omni_" + names[f] + ".exr", cube.faces[f]));
  const std::string faces = "'" + dir + "/omni_{face}.exr'";
  const std::string args = "--light '" + dir + "/omni.json' --camera '" + dir +
                           "/camera.json' --depth '" + dir + "/camdepth.exr' --medium '" + dir +
                           "/medium.json' --quiet";
  test::CommandResult built =
      test::run_lightvol("build " + faces + " --light '" + dir + "/omni.json' --adaptive " +
                         "--tessellation quadtree --max-error 0.01 --out '" + dir + "/omni.ply'");
  ASSERT_EQ(built.exit_code, 0) << built.err;
  test::CommandResult vol = test::run_lightvol("render '" + dir + "/omni.ply' " + args +
                                               " --out '" + dir + "/volume.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  test::CommandResult live = test::run_lightvol(
      "render " + args + " --method live --adaptive --max-error 0.01 --shadow-map " + faces +
      " --out '" + dir + "/live.exr' --compare '" + dir + "/volume.exr'");
  ASSERT_EQ(live.exit_code, 0) << live.err;
  // The same triangles (tests/render/live_adaptive_test), drawn by the same passes.
  EXPECT_LT(number_after(live.out, "relative L2 "), 1e-4) << live.out;
  EXPECT_GT(number_after(live.out, "mean "), 0) << live.out;
  // The static omni volume the same way: build's vertices to float rounding (12W² − 4
  // triangles), drawn by the same passes.
  built = test::run_lightvol("build " + faces + " --light '" + dir + "/omni.json' --out '" + dir +
                             "/omni_static.ply'");
  ASSERT_EQ(built.exit_code, 0) << built.err;
  vol = test::run_lightvol("render '" + dir + "/omni_static.ply' " + args + " --out '" + dir +
                           "/volume_static.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  live = test::run_lightvol("render " + args + " --method live --shadow-map " + faces + " --out '" +
                            dir + "/live_static.exr' --compare '" + dir + "/volume_static.exr'");
  ASSERT_EQ(live.exit_code, 0) << live.err;
  EXPECT_LT(number_after(live.out, "relative L2 "), 1e-4) << live.out;
  EXPECT_GT(number_after(live.out, "mean "), 0) << live.out;
}

TEST(RenderCommand, RejectsBadInputNamingTheFile) {
  test::TempDir tmp;
  write_scene(tmp.path(), {6, 3, 6}, {0, 1, 0});
  const std::string dir = tmp.path();
  std::ofstream(dir + "/bad_medium.json") << R"({"scattering": 0.1, "sigma": 1})";
  test::CommandResult r = test::run_lightvol(
      "render '" + dir + "/volume.ply' --light '" + dir + "/light.json' --camera '" + dir +
      "/camera.json' --depth '" + dir + "/camdepth.exr' --medium '" + dir +
      "/bad_medium.json' --out '" + dir + "/x.exr' --method reference");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "lightvol: " + dir +
                       "/bad_medium.json: key 'sigma': unknown key (known: "
                       "scattering, absorption, intensity, phase, profile, density)\n");
  r = test::run_lightvol("render " + common_args(dir) + " --out '" + dir + "/x.exr'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "lightvol: render: --method volume needs the light volume MESH\n");
  r = test::run_lightvol("render " + common_args(dir) + " --out '" + dir +
                         "/x.exr' --method raymarch");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err,
      "lightvol: render: --method raymarch needs --shadow-map DEPTH (the light's shadow map(s))\n");
  r = test::run_lightvol("render " + common_args(dir) + " --out '" + dir + "/x.exr' --method live");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err,
      "lightvol: render: --method live needs --shadow-map DEPTH (the light's shadow map(s))\n");
  r = test::run_lightvol("render '" + dir + "/volume.ply' " + common_args(dir) + " --out '" + dir +
                         "/x.exr' --method live --shadow-map '" + dir + "/shadow.exr'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "lightvol: render: --method live makes the volume from --shadow-map on the GPU; it "
            "takes no MESH\n");
  r = test::run_lightvol("render '" + dir + "/volume.ply' " + common_args(dir) + " --out '" + dir +
                         "/x.exr' --method reference --compare '" + dir + "/shadow.exr'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "lightvol: " + dir + "/shadow.exr: image is 128x128, the render is 64x48\n");
}

// A noise fog end to end: volume within 2 % of the reference through --compare, raymarch renders
// it, and every bad density is refused with one line, exit 2 and no output file.
TEST(RenderCommand, RendersANoiseDensity) {
  REQUIRE_GL_CONTEXT();
  test::TempDir tmp;
  const std::string dir = tmp.path();
  write_scene(dir, {6, 3, 6}, {0, 1, 0});
  std::ofstream(dir + "/fog.json")
      << R"({"scattering": 0.15, "absorption": 0.05, "intensity": 20, "phase": {"type": "hg", "g": 0.3},
            "density": {"type": "noise", "seed": 5, "frequency": 0.3, "octaves": 2, "offset": 0.5, "scale": 0.8}})";
  const std::string args = "--light '" + dir + "/light.json' --camera '" + dir +
                           "/camera.json' --depth '" + dir + "/camdepth.exr' --quiet";
  test::CommandResult ref =
      test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --medium '" + dir +
                         "/fog.json' --method reference --out '" + dir + "/reference.exr'");
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  test::CommandResult vol = test::run_lightvol(
      "render '" + dir + "/volume.ply' " + args + " --medium '" + dir + "/fog.json' --out '" + dir +
      "/volume.exr' --compare '" + dir + "/reference.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  EXPECT_LT(number_after(vol.out, "relative L2 "), 0.02) << vol.out;
  // The homogeneous medium of the same coefficients is far from it: the density is rendered.
  test::CommandResult flat = test::run_lightvol(
      "render '" + dir + "/volume.ply' " + args + " --medium '" + dir + "/medium.json' --out '" +
      dir + "/flat.exr' --compare '" + dir + "/reference.exr'");
  ASSERT_EQ(flat.exit_code, 0) << flat.err;
  EXPECT_GT(number_after(flat.out, "relative L2 "), 0.1) << flat.out;
  test::CommandResult march = test::run_lightvol(
      "render " + args + " --medium '" + dir + "/fog.json' --method raymarch --samples 256 " +
      "--shadow-map '" + dir + "/shadow.exr' --out '" + dir + "/march.exr' --compare '" + dir +
      "/reference.exr'");
  ASSERT_EQ(march.exit_code, 0) << march.err;
  EXPECT_LT(number_after(march.out, "relative L2 "), 0.1) << march.out;

  const std::pair<const char*, std::string> bad[] = {
      {R"({"scattering": 0.1, "density": {"type": "noise", "scale": -1}})",
       "key 'density.scale': must be >= 0, got -1"},
      {R"({"scattering": 0.1, "density": {"type": "cloud"}})",
       "key 'density.type': expected \"noise\" or \"vdb\", got \"cloud\""},
      {R"({"scattering": 0.1, "density": {"type": "noise", "seeds": 1}})",
       "key 'density.seeds': unknown key (known: type, seed, frequency, octaves, lacunarity, gain, "
       "offset, scale)"},
  };
  for (const auto& [text, why] : bad) {
    std::ofstream(dir + "/bad.json") << text;
    test::CommandResult r =
        test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --medium '" + dir +
                           "/bad.json' --out '" + dir + "/bad.exr'");
    EXPECT_EQ(r.exit_code, 2) << text;
    EXPECT_EQ(r.err, "lightvol: " + dir + "/bad.json: " + why + "\n");
    EXPECT_FALSE(std::filesystem::exists(dir + "/bad.exr"));
  }
  test::CommandResult radial =
      test::run_lightvol("render " + args + " --medium '" + dir +
                         "/fog.json' --method radial --out '" + dir + "/bad.exr'");
  EXPECT_EQ(radial.exit_code, 2);
  EXPECT_EQ(radial.err, "lightvol: " + dir +
                            "/fog.json: key 'density': --method radial renders homogeneous media "
                            "only (volume, reference and raymarch take a density)\n");
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.exr"));
}

// A sphere of smoke in an OpenVDB file (relative to the medium's file) end to end: volume within
// 2 % of the reference; every bad grid refused with one line naming the file, exit 2, no output.
TEST(RenderCommand, RendersAnOpenVdbGrid) {
  REQUIRE_GL_CONTEXT();
  REQUIRE_TEST_VDBS(folder);
  test::TempDir tmp;
  const std::string dir = tmp.path();
  write_scene(dir, {6, 3, 6}, {0, 1, 0});
  for (const char* name : {"sphere.vdb", "vec3.vdb", "huge.vdb", "negative.vdb", "nan.vdb"})
    std::filesystem::copy_file(folder + "/" + name, dir + "/" + name);
  const std::string sphere = test::slurp(dir + "/sphere.vdb");
  std::ofstream(dir + "/truncated.vdb", std::ios::binary) << sphere.substr(0, sphere.size() / 3);
  const auto medium = [&](const std::string& density) {
    return R"({"scattering": 0.15, "absorption": 0.05, "intensity": 20, "density": )" + density +
           "}";
  };
  std::ofstream(dir + "/smoke.json") << medium(R"({"type": "vdb", "file": "sphere.vdb"})");
  const std::string args = "--light '" + dir + "/light.json' --camera '" + dir +
                           "/camera.json' --depth '" + dir + "/camdepth.exr' --quiet";
  test::CommandResult ref =
      test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --medium '" + dir +
                         "/smoke.json' --method reference --out '" + dir + "/reference.exr'");
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  test::CommandResult vol = test::run_lightvol(
      "render '" + dir + "/volume.ply' " + args + " --medium '" + dir + "/smoke.json' --out '" +
      dir + "/volume.exr' --compare '" + dir + "/reference.exr'");
  ASSERT_EQ(vol.exit_code, 0) << vol.err;
  EXPECT_LT(number_after(vol.out, "relative L2 "), 0.02) << vol.out;

  const std::pair<std::string, std::string> bad[] = {
      {R"({"type": "vdb", "file": "missing.vdb"})", "missing.vdb: no such file"},
      {R"({"type": "vdb", "file": "truncated.vdb"})", "truncated.vdb: "},
      {R"({"type": "vdb", "file": "sphere.vdb", "grid": "smoke"})",
       "sphere.vdb: has no grid named 'smoke' (its grids: 'density', 'temperature')"},
      {R"({"type": "vdb", "file": "vec3.vdb"})",
       "vec3.vdb: grid 'density': holds vec3s values; a density grid holds scalars (float or "
       "double)"},
      {R"({"type": "vdb", "file": "huge.vdb"})",
       "huge.vdb: grid 'density': its 8192x8192x8192 voxels (dense floats, here and on the GPU) "
       "needs about "},
      {R"({"type": "vdb", "file": "negative.vdb"})",
       "negative.vdb: grid 'density': the voxel at index (2, 3, 4) is negative (-0.5); densities "
       "are finite and >= 0"},
      {R"({"type": "vdb", "file": "nan.vdb"})",
       "nan.vdb: grid 'density': the voxel at index (2, 3, 4) is NaN; densities are finite and >= "
       "0"},
  };
  for (const auto& [density, why] : bad) {
    std::ofstream(dir + "/bad.json") << medium(density);
    test::CommandResult r =
        test::run_lightvol("render '" + dir + "/volume.ply' " + args + " --medium '" + dir +
                           "/bad.json' --out '" + dir + "/bad.exr'");
    EXPECT_EQ(r.exit_code, 2) << density;
    EXPECT_EQ(
        r.err.rfind("lightvol: " + dir + "/bad.json: key 'density.file': " + dir + "/" + why, 0),
        0u)
        << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/bad.exr"));
  }
  // The budget names its flag.
  test::CommandResult small =
      test::run_lightvol("--max-memory 100K render '" + dir + "/volume.ply' " + args +
                         " --medium '" + dir + "/smoke.json' --out '" + dir + "/bad.exr'");
  EXPECT_EQ(small.exit_code, 2);
  EXPECT_NE(small.err.find("more than the budget of 100.0 KiB; raise it with --max-memory"),
            std::string::npos)
      << small.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad.exr"));
}

}  // namespace
}  // namespace lightvol

// A fast start: a command that reads no image loads no OpenImageIO (lightvol-image decodes images,
// a program of its own), and no command loads EGL unless it renders. The dynamic linker's own
// account (LD_DEBUG=files) says which libraries a run loaded.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include <lightvol/depth/depth_image.h>
#include <lightvol/export/export.h>
#include <lightvol/io/mesh_reader.h>
#include <lightvol/volume/static_volume.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

using test::TempDir;

// What the dynamic linker reports loading while lightvol runs `args` (its standard error with
// LD_DEBUG=files; lightvol-image, when started, reports its own libraries there too).
std::string loaded_libraries(const std::string& args, const TempDir& dir) {
  const std::string log = dir.file("ld_debug.txt");
  const std::string command = std::string("cd '") + dir.path() + "' && LD_DEBUG=files '" +
                              LIGHTVOL_EXE + "' " + args + " >/dev/null 2>'" + log + "' </dev/null";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  std::FILE* f = std::fopen(log.c_str(), "r");
  std::string text;
  if (f == nullptr) return text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
  std::fclose(f);
  return text;
}

bool loads(const std::string& log, const std::string& library) {
  return log.find("file=" + library) != std::string::npos;
}

TEST(Startup, CommandsThatReadNoImageLoadNeitherOpenImageIONorEgl) {
  TempDir dir;
  const Result<Mesh> volume = build_static_volume(
      test::light_from_json(test::spot_json()), test::constant_depth(5, 4, 0.98f), {}, "test.exr");
  ASSERT_TRUE(volume.ok());
  ASSERT_TRUE(write_mesh(dir.file("v.ply"), *volume).ok());
  for (const char* args : {"--version", "--help", "check v.ply"}) {
    const std::string log = loaded_libraries(args, dir);
    EXPECT_TRUE(loads(log, "libstdc++")) << args << ": LD_DEBUG reported nothing:\n" << log;
    EXPECT_FALSE(loads(log, "libOpenImageIO")) << args;
    EXPECT_FALSE(loads(log, "libEGL")) << args;
    EXPECT_FALSE(loads(log, "libGLdispatch")) << args;
  }
}

TEST(Startup, BuildReadsAPlainExrThroughLightvolExrAndOtherFormatsThroughLightvolImage) {
  TempDir dir;
  dir.write("light.json", test::spot_json());
  const DepthImage depth = test::make_depth(
      16, 12, [](int c, int r) { return 0.9f + 0.001f * static_cast<float>(c + r); });
  const Result<Mesh> expected =
      build_static_volume(test::light_from_json(test::spot_json()), depth, {}, "test.exr");
  ASSERT_TRUE(expected.ok());
  for (const char* name : {"d.exr", "d.png", "d.pfm", "d.tif"}) {
    ASSERT_TRUE(write_depth_image(dir.file(name), depth).ok()) << name;
    const std::string log =
        loaded_libraries(std::string("build ") + name + " --light light.json --out v.ply", dir);
    // A plain EXR was read by lightvol-exr, which loads OpenEXR's core and not OpenImageIO; every
    // other format by lightvol-image, which loads OpenImageIO; lightvol did not render.
    const bool exr = std::string(name) == "d.exr";
    EXPECT_EQ(loads(log, "libOpenImageIO"), !exr) << name;
    EXPECT_TRUE(!exr || loads(log, "libOpenEXRCore")) << name;
    EXPECT_FALSE(loads(log, "libEGL")) << name;
    const Result<Mesh> mesh = read_mesh(dir.file("v.ply"));
    ASSERT_TRUE(mesh.ok()) << name;
    EXPECT_EQ(mesh->num_triangles(), expected->num_triangles()) << name;
  }
}

}  // namespace
}  // namespace lightvol

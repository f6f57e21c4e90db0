#include <gtest/gtest.h>

#include <lightvol/airlight/airlight.h>
#include <lightvol/light/camera.h>
#include <lightvol/light/light.h>

#include "support/test_support.h"

namespace lightvol {
namespace {

Error parse_error(const std::string& json) {
  Result<Light> r = parse_light(json, "L.json");
  EXPECT_FALSE(r.ok()) << "accepted: " << json;
  return r.ok() ? Error{} : r.error();
}

// The message must name the file and the key.
void expect_rejected(const std::string& json, const std::string& key, const std::string& why) {
  const Error e = parse_error(json);
  EXPECT_NE(e.message.find("L.json"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("'" + key + "'"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find(why), std::string::npos) << e.message;
}

const char* kSpot =
    R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": 60, "near": 0.1, "far": 30)";
const char* kDir =
    R"("type": "directional", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "ortho": [-5, 5, -4, 4], "near": 0, "far": 10)";

std::string obj(const std::string& body) { return "{" + body + "}"; }

TEST(LightParse, Spot) {
  const Light l = test::light_from_json(test::spot_json("linear", 1.5));
  EXPECT_EQ(l.type, LightType::spot);
  EXPECT_EQ(l.depth, DepthEncoding::linear);
  EXPECT_FALSE(l.flip_y);
  EXPECT_DOUBLE_EQ(l.near, 0.1);
  EXPECT_DOUBLE_EQ(l.far, 30);
  EXPECT_DOUBLE_EQ(l.position.y, 4);
  EXPECT_DOUBLE_EQ(l.direction.y, -1);
  EXPECT_TRUE(l.is_perspective());
}

// The light in a volume's frame: the world light itself, or in light space at the origin looking
// down −Z (omni: world axes) with the identity view, which maps the light's eye (the origin) to
// the origin and its axis to −Z.
bool same(const Vec3d& a, const Vec3d& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

TEST(LightInSpace, WorldIsTheLightLightSpaceIsItsEye) {
  const Light lights[] = {
      test::light_from_json(obj(kSpot)), test::light_from_json(obj(kDir)),
      test::light_from_json(R"({"type": "omni", "position": [1, 2, 3], "near": 0.1, "far": 9})")};
  for (const Light& light : lights) {
    SCOPED_TRACE(std::string(to_string(light.type)));
    const Light world = light_in_space(light, Space::world);
    EXPECT_TRUE(same(world.position, light.position));
    EXPECT_TRUE(same(world.direction, light.direction));
    EXPECT_TRUE(same(world.view.transform_point({5, 6, 7}), light.view.transform_point({5, 6, 7})));
    const Light eye = light_in_space(light, Space::light);
    EXPECT_TRUE(same(eye.position, {0, 0, 0}));
    const Vec3d axis = light.type == LightType::omni ? light.direction : Vec3d{0, 0, -1};
    EXPECT_TRUE(same(eye.direction, axis));
    EXPECT_TRUE(same(eye.view.transform_point({5, 6, 7}), {5, 6, 7}));
    EXPECT_EQ(eye.near, light.near);
    EXPECT_EQ(eye.far, light.far);
  }
}

TEST(LightParse, DirectionalDefaultsToWindowDepth) {
  const Light l = test::light_from_json(obj(kDir));
  EXPECT_EQ(l.type, LightType::directional);
  EXPECT_EQ(l.depth, DepthEncoding::window);
  EXPECT_FALSE(l.is_perspective());
}

TEST(LightParse, OmniKnowsItsKeys) {
  const Light l = test::light_from_json(
      R"({"type": "omni", "position": [1, 2, 3], "near": 0.05, "far": 20, "depth": "radial"})");
  EXPECT_EQ(l.type, LightType::omni);
  EXPECT_EQ(l.depth, DepthEncoding::radial);
}

TEST(LightParse, MatrixFormMatchesParametricForm) {
  const Light p = test::light_from_json(test::spot_json());
  std::string view = "[", proj = "[";
  for (int i = 0; i < 16; ++i) {
    view += std::to_string(p.view.m[i]) + (i < 15 ? "," : "]");
    proj += std::to_string(p.projection.m[i]) + (i < 15 ? "," : "]");
  }
  // std::to_string has 6 decimals: enough to recover near and far closely.
  const Light m = test::light_from_json(R"({"type": "spot", "view": )" + view +
                                        R"(, "projection": )" + proj + "}");
  EXPECT_NEAR(m.near, 0.1, 1e-4);
  EXPECT_NEAR(m.far, 30, 0.1);
  EXPECT_NEAR(m.position.y, 4, 1e-9);
  EXPECT_NEAR(m.direction.y, -1, 1e-9);
}

TEST(LightParse, MatrixAsRowsOfFour) {
  const Light m = test::light_from_json(
      R"({"type": "directional", "view": [[1,0,0,0],[0,1,0,0],[0,0,1,-2],[0,0,0,1]],
          "projection": [[0.2,0,0,0],[0,0.25,0,0],[0,0,-0.2,-1],[0,0,0,1]]})");
  EXPECT_NEAR(m.near, 0, 1e-12);
  EXPECT_NEAR(m.far, 10, 1e-12);
  EXPECT_NEAR(m.position.z, 2, 1e-12);
}

TEST(LightParse, RejectsEachBadInputNamingFileAndKey) {
  expect_rejected(obj(std::string(kSpot) + R"(, "fov": 60)"), "fov", "unknown key");
  expect_rejected(R"({"position": [0,0,0]})", "type", "missing");
  expect_rejected(R"({"type": "laser"})", "type", "expected");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "near": 0.1, "far": 30)"),
      "fov_y_deg", "missing");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": 180, "near": 0.1, "far": 30)"),
      "fov_y_deg", "(0, 180)");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": 0, "near": 0.1, "far": 30)"),
      "fov_y_deg", "(0, 180)");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": 60, "near": 5, "far": 5)"),
      "far", "greater than near");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, 0], "fov_y_deg": 60, "near": 0.1, "far": 5)"),
      "up", "zero vector");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 2, 0], "fov_y_deg": 60, "near": 0.1, "far": 5)"),
      "up", "parallel");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, 0, 0], "up": [0, 0, 1], "fov_y_deg": 60, "near": 0.1, "far": 5)"),
      "direction", "zero vector");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": 60, "near": 0.1, "far": 5)"),
      "position", "3 finite numbers");
  expect_rejected(
      obj(R"("type": "spot", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "fov_y_deg": "60", "near": 0.1, "far": 5)"),
      "fov_y_deg", "expected a number");
  expect_rejected(
      obj(R"("type": "directional", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "ortho": [5, 5, -4, 4], "near": 0, "far": 10)"),
      "ortho", "left < right");
  expect_rejected(
      obj(R"("type": "directional", "position": [0, 4, 0], "direction": [0, -1, 0], "up": [0, 0, -1], "ortho": [-5, 5, 4, 4], "near": 0, "far": 10)"),
      "ortho", "bottom < top");
  expect_rejected(obj(std::string(kDir) + R"(, "fov_y_deg": 60)"), "fov_y_deg", "does not apply");
  expect_rejected(obj(std::string(kSpot) + R"(, "depth": "log")"), "depth", "expected");
  expect_rejected(obj(std::string(kSpot) + R"(, "flip_y": 1)"), "flip_y", "true or false");
  expect_rejected(obj(std::string(kSpot) + R"(, "view": [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1])"),
                  "direction", "does not go with");
  expect_rejected(
      R"({"type": "spot", "view": [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1], "projection": [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]})",
      "projection", "perspective");
  expect_rejected(
      R"({"type": "spot", "view": [0,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1], "projection": [1,0,0,0,0,1,0,0,0,0,1,0,0,0,-1,0]})",
      "view", "singular");
  expect_rejected(R"({"type": "omni", "position": [0,0,0], "near": 0, "far": 1})", "near", "> 0");
}

TEST(LightParse, NotJsonOrNotAnObject) {
  const Error e = parse_error("{\"type\": ");
  EXPECT_NE(e.message.find("L.json: not valid JSON"), std::string::npos) << e.message;
  const Error a = parse_error("[1, 2]");
  EXPECT_NE(a.message.find("expected a JSON object"), std::string::npos) << a.message;
}

TEST(LightParse, MissingFileIsNamed) {
  Result<Light> r = load_light("/nonexistent/light.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("/nonexistent/light.json"), std::string::npos);
}

// Before: duplicate keys were resolved silently (the last one won) and bytes after a NUL were
// ignored.
TEST(LightParse, DuplicateKeysAndNulBytesAreErrors) {
  const Error dup = parse_error(obj(std::string(kSpot) + R"(, "near": 0.2)"));
  EXPECT_NE(dup.message.find("L.json: key \"near\" appears twice"), std::string::npos)
      << dup.message;
  const Error nested = parse_error(R"({"type": "spot", "view": {"a": 1, "a": 2}})");
  EXPECT_NE(nested.message.find("appears twice"), std::string::npos) << nested.message;
  std::string with_nul = obj(kSpot);
  with_nul += std::string(1, '\0') + "garbage";
  const Error nul = parse_error(with_nul);
  EXPECT_NE(nul.message.find("is NUL"), std::string::npos) << nul.message;
  // The same for cameras and media.
  const Result<Camera> cam =
      parse_camera(obj(std::string(kSpot) + R"(, "width": 4, "height": 4, "width": 8)"), "C.json");
  ASSERT_FALSE(cam.ok());
  EXPECT_NE(cam.error().message.find("appears twice"), std::string::npos);
  const Result<Medium> med = parse_medium(
      R"({"scattering": 0.1, "scattering": 0.2, "absorption": 0, "intensity": 1})", "M.json");
  ASSERT_FALSE(med.ok());
  EXPECT_NE(med.error().message.find("appears twice"), std::string::npos);
}

// Before: a value nested 100,000 arrays deep under a known key crashed (SIGSEGV in the recursive
// dump that quoted it), and a 10 MiB string was echoed whole.
TEST(LightParse, DeepOrHugeValuesGiveShortMessages) {
  for (const char* key : {"flip_y", "aspect"}) {
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const Error e = parse_error(obj(std::string(kSpot) + ", \"" + key + "\": " + deep));
    EXPECT_NE(e.message.find("nested deeper than 32 levels"), std::string::npos) << e.message;
    const Result<Camera> cam =
        parse_camera(obj(std::string(kSpot) + R"(, "width": 4, "height": )" + deep), "C.json");
    ASSERT_FALSE(cam.ok());
    EXPECT_LT(cam.error().message.size(), 200u);
  }
  // Deep but within the limit: quoted, not dumped whole.
  const std::string deep30 = std::string(30, '[') + std::string(30, ']');
  const Error e30 = parse_error(obj(std::string(kSpot) + R"(, "flip_y": )" + deep30));
  EXPECT_NE(e30.message.find("'flip_y'"), std::string::npos) << e30.message;
  EXPECT_LT(e30.message.size(), 200u) << e30.message;
  const std::string huge(10 << 20, 'x');
  for (const std::string& body : {std::string(kSpot) + R"(, "depth": ")" + huge + "\"",
                                  std::string(kSpot) + R"(, "flip_y": ")" + huge + "\"",
                                  std::string(kSpot) + ", \"" + huge + "\": 1"}) {
    const Error h = parse_error(obj(body));
    EXPECT_LT(h.message.size(), 300u) << h.message.substr(0, 400);
    EXPECT_NE(h.message.find("L.json"), std::string::npos);
  }
}

// Before: a 128x64 image with a light of aspect 1 was accepted silently. The rule: texels must be
// square within a texel of rounding, else a note (build prints it as a warning).
TEST(LightParse, AspectMismatchIsNoted) {
  const Light spot = test::light_from_json(test::spot_json("window", 1.0));
  EXPECT_NE(aspect_mismatch(spot, 128, 64).find("128x64 (aspect 2)"), std::string::npos)
      << aspect_mismatch(spot, 128, 64);
  EXPECT_EQ(aspect_mismatch(spot, 64, 64), "");
  EXPECT_EQ(aspect_mismatch(spot, 65, 64), "");  // a texel of rounding
  const Light wide = test::light_from_json(test::spot_json("window", 1.5));
  EXPECT_EQ(aspect_mismatch(wide, 100, 67), "");  // shadowmap's N x round(N / aspect)
  EXPECT_NE(aspect_mismatch(wide, 100, 100), "");
  const Light dir = test::light_from_json(test::directional_json());  // ortho 10 x 8
  EXPECT_EQ(aspect_mismatch(dir, 10, 8), "");
  EXPECT_EQ(aspect_mismatch(dir, 125, 100), "");
  EXPECT_NE(aspect_mismatch(dir, 100, 100), "");
}

}  // namespace
}  // namespace lightvol

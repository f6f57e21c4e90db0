#include <gtest/gtest.h>

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

}  // namespace
}  // namespace lightvol

// raybridge-render far from the world origin: one small glTF scene (ground, a wall, boxes) rendered once at the
// origin and once under a root node translated by 5 km and 20 km (the camera moved along), with hard shadows
// (ray-traced in hybrid mode, the engine's shadow map in raster mode). The dumped depth (distance along each
// pixel-centre ray) and shadow images must match the origin render: the engine rasterizes camera-relative (model
// matrices rebased to the eye in double, a rotation-only view) and Raybridge traces a camera-relative TLAS, so nothing
// may depend on the distance.
//
// Measured with lavapipe, 192x108, hybrid mode, 5 km / 20 km. Before the camera-relative raster (world-space
// viewProj in float, also in depth.exr's reconstruction): depth within 1e-4 relative on 0.08% / 0.03% of the
// compared pixels (median relative error 1.3e-2 / 4.1e-2, max 4.2e-2 / 0.14), shadows equal on 98.5% / 70.3%,
// so every depth and shadow check failed. After it: the renders are bit-identical to the origin one (median and
// max error 0, shadows equal on 100%), in hybrid and in raster mode.
#include <catch2/catch_test_macros.hpp>
#include <catch2/generators/catch_generators.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "gltf_document_builder.h"
#include "render_command_support.h"
#include "unit_cube_gltf.h"

namespace fs = std::filesystem;
using nlohmann::json;
using rbRenderTest::readExrRed;

namespace {

constexpr uint32_t kWidth = 192, kHeight = 108;

// Boxes as nodes scaling and placing one unit cube (-0.5..0.5), under a root node at `offset`. Every number is a
// multiple of 1/64, so world positions are exact in float up to 32 km and the renders differ only by how the
// engine and the SDK handle the offset.
struct Box {
  glm::dvec3 center, size;
};
const Box kBoxes[] = {
    {{0.0, -0.25, 0.0}, {40.0, 0.5, 40.0}},  // ground, top at y = 0
    {{-2.0, 1.5, -4.0}, {10.0, 3.0, 0.5}},   // wall
    {{1.0, 0.5, 1.0}, {1.0, 1.0, 1.0}},     {{-3.0, 0.75, 2.0}, {1.5, 1.5, 1.5}},
    {{3.5, 1.0, -1.5}, {1.0, 2.0, 1.0}},    {{-0.5, 0.25, 4.0}, {2.0, 0.5, 0.75}},
};

std::string writeScene(const fs::path& path, const glm::dvec3& offset) {
  pose_reference::GltfDocumentBuilder b;
  rbRenderTest::addUnitCubeMesh(b);
  json& doc = b.document();
  json nodes = json::array({{{"name", "root"}, {"translation", {offset.x, offset.y, offset.z}}}});
  json children = json::array();
  for (const Box& box : kBoxes) {
    children.push_back(nodes.size());
    nodes.push_back({{"mesh", 0},
                     {"translation", {box.center.x, box.center.y, box.center.z}},
                     {"scale", {box.size.x, box.size.y, box.size.z}}});
  }
  nodes[0]["children"] = children;
  doc["nodes"] = nodes;
  doc["scenes"] = json::array({{{"nodes", json::array({0})}}});
  doc["scene"] = 0;
  return b.write(path.string());
}

struct Render {
  std::vector<float> depth, shadow;
};

Render render(const fs::path& dir, const glm::dvec3& offset, const std::string& mode) {
  fs::create_directories(dir);
  const fs::path scene = dir / "scene.gltf";
  const std::string error = writeScene(scene, offset);
  INFO(error);
  REQUIRE(error.empty());
  const glm::dvec3 eye = glm::dvec3(-9.0, 6.0, 14.0) + offset, target = glm::dvec3(0.0, 1.0, 0.0) + offset;
  char camera[256];
  std::snprintf(camera, sizeof camera, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,50", eye.x, eye.y, eye.z, target.x, target.y,
                target.z);
  REQUIRE(rbRenderTest::runRender(
              "--mode " + mode + " --preset hard-shadows --sun-radius 0 --gbuffer-normals geometric --dump --width " +
              std::to_string(kWidth) + " --height " + std::to_string(kHeight) + " --camera " + camera +
              " --sun 0.45,0.6,-0.5 --scene " + scene.string() + " --out " + dir.string()) == 0);
  Render r;
  int w = 0, h = 0;
  r.depth = readExrRed(dir / "depth.exr", w, h);
  REQUIRE((w == int(kWidth) && h == int(kHeight)));
  r.shadow = readExrRed(dir / "shadow.exr", w, h);
  REQUIRE((w == int(kWidth) && h == int(kHeight)));
  return r;
}

struct Comparison {
  uint32_t compared = 0, depthAgree = 0, shadowAgree = 0, shadowed = 0;
  double medianError = 0.0, maxError = 0.0;
};

// Pixels away from silhouettes and sky in the origin render: the 3x3 neighbourhood is all hit and smooth.
Comparison compare(const Render& origin, const Render& far) {
  Comparison c;
  std::vector<double> errors;
  for (uint32_t y = 1; y + 1 < kHeight; ++y) {
    for (uint32_t x = 1; x + 1 < kWidth; ++x) {
      const size_t i = size_t(y) * kWidth + x;
      const float d = origin.depth[i];
      bool edge = d <= 0.0f;
      for (int dy = -1; dy <= 1 && !edge; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const float n = origin.depth[size_t(int(y) + dy) * kWidth + size_t(int(x) + dx)];
          edge |= n <= 0.0f || std::fabs(n - d) > 0.05f * d;
        }
      const float left = origin.depth[i - 1], right = origin.depth[i + 1];
      const float up = origin.depth[i - kWidth], down = origin.depth[i + kWidth];
      edge |= std::fabs(left + right - 2 * d) > 1e-3f * d || std::fabs(up + down - 2 * d) > 1e-3f * d;
      if (edge) continue;
      ++c.compared;
      const double error = std::fabs(double(far.depth[i]) - d) / d;
      errors.push_back(error);
      c.depthAgree += error <= 1e-4;
      c.shadowAgree += std::fabs(far.shadow[i] - origin.shadow[i]) <= 1e-3f;
      c.shadowed += origin.shadow[i] < 0.5f;
    }
  }
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    c.medianError = errors[errors.size() / 2];
    c.maxError = errors.back();
  }
  return c;
}

}  // namespace

TEST_CASE("raybridge-render's depth and hard shadows do not depend on the distance from the origin",
          "[render][precision]") {
  // Hybrid: Raybridge's ray-traced shadows; raster: the engine's own shadow map (its light view-projection is
  // camera-relative too).
  const std::string mode = GENERATE(std::string("hybrid"), std::string("raster"));
  const fs::path dir = fs::temp_directory_path() / ("raybridge_far_origin_" + mode);
  fs::remove_all(dir);
  const Render origin = render(dir / "origin", glm::dvec3(0.0), mode);
  for (double distance : {5000.0, 20000.0}) {
    const Render far = render(dir / std::to_string(int(distance)), glm::dvec3(distance, 0.0, distance), mode);
    const Comparison c = compare(origin, far);
    const double depthShare = c.compared ? double(c.depthAgree) / c.compared : 0.0;
    const double shadowShare = c.compared ? double(c.shadowAgree) / c.compared : 0.0;
    // WARN: the measured numbers appear in the log even when the checks pass.
    WARN(mode << ", offset (" << distance << ", 0, " << distance << "): compared " << c.compared << " pixels ("
              << c.shadowed << " shadowed); depth within 1e-4 relative on " << depthShare * 100.0 << "% (median "
              << c.medianError << ", max " << c.maxError << "), shadow equal on " << shadowShare * 100.0 << "%");
    CHECK(c.compared > kWidth * kHeight / 3);
    CHECK(c.shadowed > 200);
    CHECK(depthShare >= 0.995);
    CHECK(shadowShare >= 0.995);
  }
}

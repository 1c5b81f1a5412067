// raybridge-render's local lights end to end against an independent tracer. A procedural room (floor, two walls,
// pillars, a box) with two point lights, a spot light and a directional light in KHR_lights_punctual is written as
// glTF, rendered headless with --gbuffer-normals geometric and --dump, and lights.exr (the shadowed irradiance of the
// punctual lights, no BRDF, no sun) is compared with Embree: at each primary hit, one shadow ray per light and the
// KHR_lights_punctual falloffs (point and spot E = I cos(theta) / d^2 times the range window and the spot's cone
// falloff, directional E = I cos(theta)).
#include <catch2/catch_test_macros.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtx/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "embree_reference.h"
#include "gltf_document_builder.h"
#include "render_command_support.h"
#include "unit_cube_gltf.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr uint32_t kWidth = 160, kHeight = 120;

struct Box {
  glm::vec3 center, size;
};
const Box kBoxes[] = {
    {{0.0f, -0.25f, 0.0f}, {12.0f, 0.5f, 12.0f}},  // floor, top at y = 0
    {{0.0f, 2.0f, -6.25f}, {12.0f, 4.0f, 0.5f}},   // back wall
    {{-6.25f, 2.0f, 0.0f}, {0.5f, 4.0f, 12.0f}},   // left wall
    {{-1.0f, 1.5f, -1.0f}, {0.4f, 3.0f, 0.4f}},    // pillars
    {{1.5f, 1.5f, -2.5f}, {0.4f, 3.0f, 0.4f}},    {{-3.0f, 1.5f, 1.5f}, {0.4f, 3.0f, 0.4f}},
    {{1.0f, 0.5f, 1.0f}, {1.0f, 1.0f, 1.0f}},  // box
};

// The lights as the test places them, in world space (what the glTF nodes encode).
struct TestLight {
  const char* type;
  glm::vec3 color;
  float intensity, range;
  glm::vec3 position, direction;  // direction: the way the light travels (node -Z)
  float inner, outer;             // spot cone angles, radians
};
const TestLight kLights[] = {
    {"point", {1.0f, 0.6f, 0.3f}, 20.0f, 0.0f, {-2.0f, 2.5f, 1.0f}, {0, 0, -1}, 0, 0},
    {"point", {0.3f, 0.6f, 1.0f}, 15.0f, 6.0f, {2.5f, 1.5f, -1.0f}, {0, 0, -1}, 0, 0},
    {"spot", {1.0f, 1.0f, 1.0f}, 40.0f, 0.0f, {0.0f, 3.5f, 2.5f}, {0.0f, -0.94f, -0.342f}, 0.3f, 0.6f},
    {"directional", {1.0f, 1.0f, 0.9f}, 2.0f, 0.0f, {0, 0, 0}, {-0.4f, -0.8f, -0.45f}, 0, 0},
};

std::string writeRoom(const fs::path& path) {
  pose_reference::GltfDocumentBuilder b;
  rbRenderTest::addUnitCubeMesh(b);
  json& doc = b.document();
  json nodes = json::array(), roots = json::array(), lights = json::array();
  for (const Box& box : kBoxes) {
    roots.push_back(nodes.size());
    nodes.push_back({{"mesh", 0},
                     {"translation", {box.center.x, box.center.y, box.center.z}},
                     {"scale", {box.size.x, box.size.y, box.size.z}}});
  }
  for (size_t i = 0; i < std::size(kLights); ++i) {
    const TestLight& l = kLights[i];
    json light = {{"type", l.type}, {"color", {l.color.r, l.color.g, l.color.b}}, {"intensity", l.intensity}};
    if (l.range > 0.0f) light["range"] = l.range;
    if (std::string(l.type) == "spot") light["spot"] = {{"innerConeAngle", l.inner}, {"outerConeAngle", l.outer}};
    lights.push_back(light);
    // The node's -Z is the light's direction.
    const glm::quat q = glm::rotation(glm::vec3(0, 0, -1), glm::normalize(l.direction));
    roots.push_back(nodes.size());
    nodes.push_back({{"translation", {l.position.x, l.position.y, l.position.z}},
                     {"rotation", {q.x, q.y, q.z, q.w}},
                     {"extensions", {{"KHR_lights_punctual", {{"light", i}}}}}});
  }
  doc["nodes"] = nodes;
  doc["extensionsUsed"] = json::array({"KHR_lights_punctual"});
  doc["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
  doc["scenes"] = json::array({{{"nodes", roots}}});
  doc["scene"] = 0;
  return b.write(path.string());
}

const glm::vec3 kEye(5.0f, 5.0f, 7.0f), kTarget(-1.0f, 0.8f, -1.5f);
constexpr float kFovY = 60.0f;

// Renders the room; returns lights.exr's RGB (and keeps stats.json in `stats`).
std::vector<float> renderLights(const fs::path& dir, const std::string& args, json& stats) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scene = dir / "room.gltf";
  const std::string error = writeRoom(scene);
  INFO(error);
  REQUIRE(error.empty());
  char camera[256];
  std::snprintf(camera, sizeof camera, "%g,%g,%g,%g,%g,%g,%g", kEye.x, kEye.y, kEye.z, kTarget.x, kTarget.y, kTarget.z,
                kFovY);
  REQUIRE(rbRenderTest::runRender(args + " --gbuffer-normals geometric --dump --width " + std::to_string(kWidth) +
                                  " --height " + std::to_string(kHeight) + " --camera " + camera + " --scene " +
                                  scene.string() + " --out " + dir.string()) == 0);
  std::ifstream in(dir / "stats.json");
  stats = json::parse(in);
  int w = 0, h = 0;
  std::vector<float> rgb = rbRenderTest::readExrRgb(dir / "lights.exr", w, h);
  REQUIRE((w == int(kWidth) && h == int(kHeight)));
  return rgb;
}

struct Reference {
  std::vector<glm::vec3> irradiance;
  std::vector<uint32_t> visibleMask;  // bit i: light i reaches and is unshadowed
  std::vector<uint32_t> instance;     // UINT32_MAX = sky
  std::vector<float> t;
};

// Embree: the room's geometry, the test's camera convention (up = +Y, pixel centres from the top-left).
Reference traceReference() {
  rbtest::EmbreeScene embree;
  rbsamples::CpuMesh cube;
  const rbRenderTest::UnitCube unit = rbRenderTest::makeUnitCube();  // the same cube as the glTF's
  cube.positions = unit.positions;
  cube.indices.assign(unit.indices.begin(), unit.indices.end());
  for (uint32_t i = 0; i < std::size(kBoxes); ++i) {
    const Box& b = kBoxes[i];
    const float m[12] = {b.size.x, 0, 0, b.center.x, 0, b.size.y, 0, b.center.y, 0, 0, b.size.z, b.center.z};
    embree.addInstance(cube, m, i);
  }
  embree.commit();

  const glm::vec3 forward = glm::normalize(kTarget - kEye);
  const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
  const glm::vec3 up = glm::cross(right, forward);
  const float tanHalf = std::tan(glm::radians(kFovY) * 0.5f), aspect = float(kWidth) / float(kHeight);
  Reference r;
  const size_t pixels = size_t(kWidth) * kHeight;
  r.irradiance.assign(pixels, glm::vec3(0.0f));
  r.visibleMask.assign(pixels, 0);
  r.instance.assign(pixels, UINT32_MAX);
  r.t.assign(pixels, 0.0f);
  for (uint32_t y = 0; y < kHeight; ++y) {
    for (uint32_t x = 0; x < kWidth; ++x) {
      const size_t i = size_t(y) * kWidth + x;
      const float nx = (x + 0.5f) / kWidth * 2 - 1, ny = (y + 0.5f) / kHeight * 2 - 1;
      const glm::vec3 d = glm::normalize(forward + nx * tanHalf * aspect * right - ny * tanHalf * up);
      const rbtest::ReferenceHit hit = embree.intersect(&kEye.x, &d.x, 0.0f, 1e30f);
      if (!hit.hit) continue;
      r.instance[i] = hit.instanceId, r.t[i] = hit.t;
      glm::vec3 n = glm::normalize(glm::vec3(hit.geometricNormal[0], hit.geometricNormal[1], hit.geometricNormal[2]));
      if (glm::dot(n, d) > 0) n = -n;
      const glm::vec3 p = kEye + d * hit.t;
      const glm::vec3 o = p + n * 1e-3f;
      for (uint32_t k = 0; k < std::size(kLights); ++k) {
        const TestLight& l = kLights[k];
        const bool directional = std::string(l.type) == "directional";
        glm::vec3 toLight = directional ? -glm::normalize(l.direction) : l.position - p;
        const float dist = directional ? 1e30f : glm::length(toLight);
        toLight = glm::normalize(toLight);
        const float cosTheta = glm::dot(n, toLight);
        if (cosTheta <= 0.0f) continue;
        float e = l.intensity * cosTheta;
        if (!directional) {
          e /= dist * dist;
          if (l.range > 0.0f) e *= std::clamp(1.0f - std::pow(dist / l.range, 4.0f), 0.0f, 1.0f);
          if (std::string(l.type) == "spot") {
            const float cd = glm::dot(glm::normalize(l.direction), -toLight);
            const float a = std::clamp((cd - std::cos(l.outer)) / (std::cos(l.inner) - std::cos(l.outer)), 0.0f, 1.0f);
            e *= a * a;
          }
        }
        if (e <= 0.0f) continue;
        if (embree.intersect(&o.x, &toLight.x, 0.0f, directional ? 1e30f : dist - 2e-3f).hit) continue;
        r.visibleMask[i] |= 1u << k;
        r.irradiance[i] += e * l.color;
      }
    }
  }
  return r;
}

struct Agreement {
  uint32_t compared = 0;
  double relRmse = 0.0, meanRendered = 0.0, meanReference = 0.0;
};

// Over pixels whose 3x3 neighbourhood hits the same box at a similar distance with the same lights visible: away
// from silhouettes and from every light's shadow edge.
Agreement compare(const std::vector<float>& rgb, const Reference& ref) {
  Agreement a;
  double num = 0.0, den = 0.0;
  for (uint32_t y = 1; y + 1 < kHeight; ++y) {
    for (uint32_t x = 1; x + 1 < kWidth; ++x) {
      const size_t i = size_t(y) * kWidth + x;
      if (ref.instance[i] == UINT32_MAX) continue;
      bool edge = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const size_t j = size_t(int(y) + dy) * kWidth + size_t(int(x) + dx);
          edge |= ref.instance[j] != ref.instance[i] || ref.visibleMask[j] != ref.visibleMask[i] ||
                  std::fabs(ref.t[j] - ref.t[i]) > 0.1f * ref.t[i];
        }
      if (edge) continue;
      ++a.compared;
      const glm::vec3 e(rgb[i * 3], rgb[i * 3 + 1], rgb[i * 3 + 2]);
      const glm::vec3 diff = e - ref.irradiance[i];
      num += glm::dot(diff, diff), den += glm::dot(ref.irradiance[i], ref.irradiance[i]);
      a.meanRendered += (e.r + e.g + e.b) / 3.0,
          a.meanReference += (ref.irradiance[i].r + ref.irradiance[i].g + ref.irradiance[i].b) / 3.0;
    }
  }
  a.relRmse = den > 0.0 ? std::sqrt(num / den) : 1.0;
  if (a.compared) a.meanRendered /= a.compared, a.meanReference /= a.compared;
  return a;
}

}  // namespace

TEST_CASE("raybridge-render's exact local lights match Embree in a room with four KHR lights", "[render][lights]") {
  const Reference ref = traceReference();
  uint32_t shadowedSomewhere = 0, lit = 0;
  for (size_t i = 0; i < ref.instance.size(); ++i) {
    if (ref.instance[i] == UINT32_MAX) continue;
    lit += ref.visibleMask[i] != 0;
    shadowedSomewhere += ref.visibleMask[i] != 0xF;
  }
  REQUIRE(lit > kWidth * kHeight / 3);                 // the lights light most of the view
  REQUIRE(shadowedSomewhere > kWidth * kHeight / 10);  // and the pillars and the box cast shadows

  const fs::path dir = fs::temp_directory_path() / "raybridge_lights_conformance";
  json stats;
  const std::vector<float> exact = renderLights(dir / "exact", "--mode hybrid --effects lights --light-rays 0", stats);
  CHECK(stats["lights"]["count"] == 4);
  CHECK(stats["lights"]["point"] == 2);
  CHECK(stats["lights"]["spot"] == 1);
  CHECK(stats["lights"]["directional"] == 1);
  CHECK(stats["lights"]["mode"] == "exact");
  CHECK(stats["lights"]["shadowed_by"] == "raybridge");
  REQUIRE(stats["raybridge"]["passes"].contains("local_lights"));
  CHECK(stats["raybridge"]["passes"]["local_lights"]["rays"].get<uint64_t>() > 0);
  CHECK_FALSE(stats["raybridge"]["passes"].contains("local_lights_denoise"));  // exact: nothing to denoise
  for (float v : exact) REQUIRE(std::isfinite(v));
  const Agreement a = compare(exact, ref);
  INFO("exact: compared " << a.compared << " pixels, relative RMSE " << a.relRmse << ", mean " << a.meanRendered
                          << " vs " << a.meanReference);
  REQUIRE(a.compared > kWidth * kHeight / 3);
  CHECK(a.relRmse <= 0.02);

  SECTION("one raw stochastic ray per pixel is unbiased") {
    const std::vector<float> raw = renderLights(dir / "stochastic",
                                                "--mode hybrid --effects lights --light-rays 1 --no-denoise", stats);
    CHECK(stats["lights"]["mode"] == "stochastic");
    CHECK(stats["lights"]["rays_per_pixel"] == 1);
    double sumRaw = 0.0, sumExact = 0.0;
    for (size_t i = 0; i < raw.size(); ++i) sumRaw += raw[i], sumExact += exact[i];
    INFO("image mean: stochastic " << sumRaw / raw.size() << ", exact " << sumExact / raw.size());
    CHECK(std::fabs(sumRaw / sumExact - 1.0) <= 0.03);
    const Agreement s = compare(raw, ref);
    CHECK(s.relRmse > a.relRmse);  // noisy: it really was sampled
  }
  SECTION("the engine's raster counterpart shadows the lights with shadow maps") {
    const std::vector<float> raster = renderLights(dir / "raster", "--mode raster --preset hard-shadows", stats);
    CHECK(stats["lights"]["shadowed_by"] == "engine shadow maps for the strongest lights");
    CHECK(stats["lights"]["shadow_mapped_lights"] == 4);
    const Agreement r = compare(raster, ref);
    INFO("raster: relative RMSE " << r.relRmse << ", mean " << r.meanRendered << " vs " << r.meanReference);
    CHECK(r.relRmse <= 0.1);  // shadow-map bias and resolution: close, not exact
  }
}

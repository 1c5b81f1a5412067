// KHR_lights_punctual: the glTF loader's lights (values, node placement, animation, errors), the engine's
// local-light irradiance against the analytic E = I cos(theta) / d^2 (spot cone, range window), the local shadow
// maps (a blocker darkens what it hides from a spot or point light), an external irradiance input and the HDR
// frame. The glTF files are generated here.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "engine_test_support.h"
#include "gltf_document_builder.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;
using nlohmann::json;
using pose_reference::GltfDocumentBuilder;
using test_support::makeEngine;

namespace {

constexpr int kArrayBuffer = 34962;
constexpr float kPi = 3.14159265358979f;

std::string tempPath(const std::string& name) { return (std::filesystem::temp_directory_path() / name).string(); }

bool near(const glm::vec3& a, const glm::vec3& b, float eps = 1e-4f) { return glm::length(a - b) <= eps; }
bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

// A one-triangle mesh on node 0 plus the given light nodes and KHR_lights_punctual lights; writes the file.
// With `animateNode1`, node 1's translation goes from (0, 1, 0) at t = 0 to (2, 1, 0) at t = 1 (LINEAR).
std::string writeLightsFile(const std::string& name, const json& lights, const json& lightNodes,
                            bool animateNode1 = false) {
  GltfDocumentBuilder b;
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 0, 1}, 3, kArrayBuffer, true);
  json& doc = b.document();
  doc["meshes"] = json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", pos}}}}})}}});
  json nodes = json::array({{{"mesh", 0}}});
  json roots = json::array({0});
  for (const json& n : lightNodes) {
    nodes.push_back(n);
    if (!n.contains("isChild")) roots.push_back(int(nodes.size()) - 1);
  }
  for (json& n : nodes) n.erase("isChild");
  doc["nodes"] = nodes;
  doc["scenes"] = json::array({{{"nodes", roots}}});
  doc["extensionsUsed"] = json::array({"KHR_lights_punctual"});
  doc["extensions"] = {{"KHR_lights_punctual", {{"lights", lights}}}};
  if (animateNode1) {
    const int times = b.addFloats({0.0f, 1.0f}, 1, 0, true);
    const int values = b.addFloats({0, 1, 0, 2, 1, 0}, 3, 0);
    doc["animations"] = json::array(
        {{{"samplers", json::array({{{"input", times}, {"output", values}, {"interpolation", "LINEAR"}}})},
          {"channels", json::array({{{"sampler", 0}, {"target", {{"node", 1}, {"path", "translation"}}}}})}}});
  }
  const std::string path = tempPath(name);
  const std::string e = b.write(path);
  INFO(e);
  REQUIRE(e.empty());
  return path;
}

json lightNode(int light, const json& extra = json::object()) {
  json n = extra;
  n["extensions"] = {{"KHR_lights_punctual", {{"light", light}}}};
  return n;
}

// --- Rendering fixtures ------------------------------------------------------------------------------------

constexpr uint32_t kWidth = 128, kHeight = 96;

// An 8 m ground (normal +Y) and optionally a blocker box, both rough white-ish dielectrics.
Scene groundScene(bool blocker, const glm::vec3& blockerCenter = {}, const glm::vec3& blockerSize = {}) {
  Scene s;
  s.materials.push_back(Material{.name = "ground", .baseColorFactor = {0.8f, 0.8f, 0.8f, 1.0f}, .roughnessFactor = 1});
  s.meshes.push_back(makePlane(8.0f, 8.0f, 1, 1));
  s.instances.push_back(Instance{0, glm::mat4(1.0f)});
  if (blocker) {
    s.meshes.push_back(makeBox(blockerSize));
    glm::mat4 m(1.0f);
    m[3] = glm::vec4(blockerCenter, 1.0f);
    s.instances.push_back(Instance{1, m});
  }
  return s;
}

Camera groundCamera() {
  return Camera{
      .eye = {0.0f, 6.0f, 5.0f}, .target = {0.0f, 0.0f, -0.5f}, .fovYDegrees = 60.0f, .zNear = 0.5f, .zFar = 30.0f};
}

struct Ray {
  glm::vec3 origin, direction;
};

// The camera ray through the centre of pixel (x, y), top row first (the engine's convention).
Ray pixelRay(const Camera& camera, uint32_t x, uint32_t y) {
  const glm::mat4 inv = glm::inverse(projectionMatrix(camera, float(kWidth) / float(kHeight)) * viewMatrix(camera));
  const glm::vec2 ndc = (glm::vec2(x, y) + 0.5f) / glm::vec2(kWidth, kHeight) * 2.0f - 1.0f;
  const glm::vec4 a = inv * glm::vec4(ndc, 0.0f, 1.0f), b = inv * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 n = glm::vec3(a) / a.w, f = glm::vec3(b) / b.w;
  return {n, glm::normalize(f - n)};
}

// Where the ray meets the ground square (|x|, |z| <= 4, y = 0); false for sky.
bool groundHit(const Ray& r, glm::vec3& p) {
  if (r.direction.y >= 0.0f) return false;
  p = r.origin + r.direction * (-r.origin.y / r.direction.y);
  return std::abs(p.x) <= 4.0f && std::abs(p.z) <= 4.0f;
}

// Slab test: does the segment from a to b (or the ray, t in [0, tMax]) cross the box?
bool hitsBox(const glm::vec3& a, const glm::vec3& b, const glm::vec3& lo, const glm::vec3& hi) {
  const glm::vec3 d = b - a;
  float t0 = 0.0f, t1 = 1.0f;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-9f) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    float ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

// glTF's point / spot irradiance on the ground (normal +Y) at p, unshadowed.
float analyticE(const PunctualLight& l, const glm::vec3& lightPos, const glm::vec3& travel, const glm::vec3& p) {
  if (l.type == PunctualLight::Type::Directional) return l.intensity * std::max(-travel.y, 0.0f);
  const glm::vec3 toLight = lightPos - p;
  const float d = glm::length(toLight);
  const glm::vec3 dir = toLight / d;
  const float cosTheta = std::max(dir.y, 0.0f);
  float e = l.intensity * cosTheta / (d * d);
  if (l.range > 0.0f) e *= std::clamp(1.0f - std::pow(d / l.range, 4.0f), 0.0f, 1.0f);
  if (l.type == PunctualLight::Type::Spot) {
    const float cosS = glm::dot(travel, -dir);
    const float t = std::clamp(
        (cosS - std::cos(l.outerConeAngle)) / (std::cos(l.innerConeAngle) - std::cos(l.outerConeAngle)), 0.0f, 1.0f);
    e *= t * t;
  }
  return e;
}

PunctualLight lightAt(PunctualLight::Type type, const glm::vec3& position, float intensity) {
  PunctualLight l;
  l.type = type;
  l.intensity = intensity;
  l.transform[3] = glm::vec4(position, 1.0f);
  // Pointing down: local -Z -> world -Y (rotation of -90 degrees about X).
  l.transform[1] = glm::vec4(0, 0, -1, 0);
  l.transform[2] = glm::vec4(0, 1, 0, 0);
  return l;
}

FrameParams groundParams(uint32_t maxShadowed) {
  FrameParams p;
  p.camera = groundCamera();
  p.shadow.enabled = false;
  p.localLights.maxShadowedLights = maxShadowed;
  p.outputLocalLightIrradiance = true;
  return p;
}

std::vector<glm::vec4> renderIrradiance(Engine& engine, const Scene& scene, const FrameParams& params) {
  REQUIRE(engine.setRenderSize(kWidth, kHeight).ok());
  Status s = engine.loadScene(scene);
  INFO(s.error);
  REQUIRE(s.ok());
  s = engine.renderFrame(params);
  INFO(s.error);
  REQUIRE(s.ok());
  auto e = engine.readbackLocalLightIrradiance();
  INFO(e.error);
  REQUIRE(e.ok());
  REQUIRE(e.value.size() == size_t(kWidth) * kHeight);
  return e.value;
}

float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

}  // namespace

// --- glTF --------------------------------------------------------------------------------------------------

TEST_CASE("glTF KHR_lights_punctual lights load with their values and follow their (animated) nodes",
          "[lights][gltf]") {
  const json lights = json::array(
      {{{"name", "lamp"}, {"type", "point"}, {"color", {1.0, 0.5, 0.25}}, {"intensity", 40.0}, {"range", 6.0}},
       {{"name", "torch"},
        {"type", "spot"},
        {"intensity", 12.0},
        {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.6}}}},
       {{"type", "directional"}, {"intensity", 3.0}},
       {{"type", "spot"}, {"spot", json::object()}}});
  const float s = std::sqrt(0.5f);
  const json nodes = json::array({
      lightNode(0, {{"translation", {0.0, 1.0, 0.0}}}),       // node 1, animated
      {{"translation", {5.0, 0.0, 0.0}}, {"children", {3}}},  // node 2
      lightNode(1, {{"isChild", true}, {"translation", {0.0, 3.0, 0.0}}, {"rotation", {-s, 0.0, 0.0, s}}}),  // 3
      lightNode(2),                                                                                          // node 4
      lightNode(3),                                                                                          // node 5
  });
  const std::string path = writeLightsFile("rb_lights.gltf", lights, nodes, true);
  const SceneLoadResult r = loadGltf(path);
  INFO(r.error);
  REQUIRE(r.ok());
  const Scene& scene = r.scene;
  REQUIRE(scene.lights.size() == 4);
  const PunctualLight& lamp = scene.lights[0];
  CHECK(lamp.name == "lamp");
  CHECK(lamp.type == PunctualLight::Type::Point);
  CHECK(near(lamp.color, {1.0f, 0.5f, 0.25f}));
  CHECK(lamp.intensity == 40.0f);
  CHECK(lamp.range == 6.0f);
  CHECK(lamp.node == 1);
  const PunctualLight& torch = scene.lights[1];
  CHECK(torch.type == PunctualLight::Type::Spot);
  CHECK(torch.range == 0.0f);  // absent: unlimited
  CHECK(std::abs(torch.innerConeAngle - 0.2f) < 1e-6f);
  CHECK(std::abs(torch.outerConeAngle - 0.6f) < 1e-6f);
  CHECK(torch.node == 3);
  CHECK(near(glm::vec3(torch.transform[3]), {5.0f, 3.0f, 0.0f}));  // parent * child
  CHECK(scene.lights[2].type == PunctualLight::Type::Directional);
  CHECK(near(scene.lights[2].color, glm::vec3(1.0f)));  // glTF default colour
  CHECK(scene.lights[3].innerConeAngle == 0.0f);        // glTF default cones
  CHECK(std::abs(scene.lights[3].outerConeAngle - kDefaultSpotOuterConeAngle) < 1e-6f);
  CHECK(scene.lights[3].intensity == 1.0f);

  auto engine = makeEngine();
  REQUIRE(engine->setRenderSize(32, 24).ok());
  REQUIRE(engine->loadScene(scene).ok());
  // Before the first frame: the rest pose.
  REQUIRE(engine->frameLights().size() == 4);
  CHECK(near(glm::vec3(engine->frameLights()[0].position), {0.0f, 1.0f, 0.0f}));
  FrameParams params;
  for (double time : {0.25, 0.75}) {
    params.time = time;
    std::vector<FrameLight> hookLights;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      hookLights.assign(info.lights.begin(), info.lights.end());
    });
    REQUIRE(engine->renderFrame(params).ok());
    const std::span<const FrameLight> f = engine->frameLights();
    REQUIRE(f.size() == 4);
    INFO("time " << time);
    CHECK(near(glm::vec3(f[0].position), {2.0f * float(time), 1.0f, 0.0f}));
    CHECK(f[0].light == 0);
    CHECK(near(f[0].color, {1.0f, 0.5f, 0.25f}));
    CHECK(f[0].range == 6.0f);
    CHECK(near(glm::vec3(f[1].position), {5.0f, 3.0f, 0.0f}));
    CHECK(near(f[1].direction, {0.0f, -1.0f, 0.0f}));  // the node's -Z, rotated to point down
    CHECK(near(f[2].direction, {0.0f, 0.0f, -1.0f}));
    REQUIRE(hookLights.size() == 4);
    CHECK(near(glm::vec3(hookLights[0].position), glm::vec3(f[0].position)));
  }
  params.localLights.enabled = false;
  engine->setPrepassHook({});
  REQUIRE(engine->renderFrame(params).ok());
  CHECK(engine->frameLights().empty());
  CHECK(engine->lastLocalShadowStats().lights == 0);
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("bad KHR_lights_punctual lights fail naming the light index and the field", "[lights][gltf]") {
  struct Case {
    const char* what;
    json light;
    const char* field;
  };
  const std::vector<Case> cases = {
      {"negative intensity", {{"type", "point"}, {"intensity", -1.0}}, "intensity"},
      {"negative colour", {{"type", "point"}, {"color", {1.0, -0.5, 1.0}}}, "color"},
      {"two colour components", {{"type", "point"}, {"color", {1.0, 0.5}}}, "color"},
      {"zero range", {{"type", "point"}, {"range", 0.0}}, "range"},
      {"negative range", {{"type", "spot"}, {"range", -2.0}, {"spot", json::object()}}, "range"},
      {"inner above outer",
       {{"type", "spot"}, {"spot", {{"innerConeAngle", 0.7}, {"outerConeAngle", 0.5}}}},
       "innerConeAngle"},
      {"outer above pi/2", {{"type", "spot"}, {"spot", {{"outerConeAngle", 1.7}}}}, "outerConeAngle"},
      {"unknown type", {{"type", "area"}}, "type"},
  };
  for (const Case& c : cases) {
    INFO(c.what);
    const json lights = json::array({{{"type", "point"}}, c.light});
    const SceneLoadResult r = loadGltf(writeLightsFile("rb_bad_light.gltf", lights, json::array({lightNode(1)})));
    INFO(r.error);
    REQUIRE_FALSE(r.ok());
    CHECK(contains(r.error, "light 1"));
    CHECK(contains(r.error, c.field));
  }
  {
    INFO("light index out of range");
    const SceneLoadResult r = loadGltf(
        writeLightsFile("rb_bad_light_index.gltf", json::array({{{"type", "point"}}}), json::array({lightNode(7)})));
    INFO(r.error);
    REQUIRE_FALSE(r.ok());
    CHECK(contains(r.error, "light 7"));
    CHECK(contains(r.error, "out of range"));
  }
  {
    INFO("more than kMaxPunctualLights");
    json lights = json::array();
    for (uint32_t i = 0; i <= kMaxPunctualLights; ++i) lights.push_back({{"type", "point"}});
    const SceneLoadResult r = loadGltf(writeLightsFile("rb_too_many_lights.gltf", lights, json::array({lightNode(0)})));
    INFO(r.error);
    REQUIRE_FALSE(r.ok());
    CHECK(contains(r.error, "kMaxPunctualLights"));
  }
  {
    INFO("procedural lights: checkLight and loadScene");
    PunctualLight l;
    l.intensity = std::numeric_limits<float>::quiet_NaN();
    const Status s = checkLight(l, 3);
    CHECK(contains(s.error, "light 3"));
    CHECK(contains(s.error, "intensity"));
    Scene scene = groundScene(false);
    scene.lights.push_back(PunctualLight{});
    scene.lights.push_back(
        PunctualLight{.type = PunctualLight::Type::Spot, .innerConeAngle = 0.9f, .outerConeAngle = 0.4f});
    auto engine = makeEngine();
    const Status load = engine->loadScene(scene);
    INFO(load.error);
    CHECK(contains(load.error, "light 1"));
    CHECK(contains(load.error, "innerConeAngle"));
    scene.lights[1] = PunctualLight{.node = 4};
    CHECK(contains(engine->loadScene(scene).error, "node"));
    CHECK(engine->validationErrorCount() == 0);
  }
}

// --- Irradiance --------------------------------------------------------------------------------------------

TEST_CASE("local-light irradiance of an unshadowed point light matches I cos(theta) / d^2", "[lights][render]") {
  auto engine = makeEngine();
  Scene scene = groundScene(false);
  const glm::vec3 lightPos(0.7f, 1.6f, -0.4f);
  scene.lights.push_back(lightAt(PunctualLight::Type::Point, lightPos, 10.0f));
  for (uint32_t maxShadowed : {0u, 4u}) {
    INFO("maxShadowedLights " << maxShadowed);
    const std::vector<glm::vec4> e = renderIrradiance(*engine, scene, groundParams(maxShadowed));
    const LocalShadowStats stats = engine->lastLocalShadowStats();
    CHECK(stats.lights == 1);
    CHECK(stats.shadowedLights == (maxShadowed ? 1u : 0u));
    CHECK(stats.shadowViews == (maxShadowed ? 6u : 0u));
    uint32_t ground = 0, sky = 0, off = 0, skyOff = 0;
    float worst = 0.0f;
    for (uint32_t y = 0; y < kHeight; ++y)
      for (uint32_t x = 0; x < kWidth; ++x) {
        const glm::vec4 got = e[y * kWidth + x];
        glm::vec3 p;
        if (!groundHit(pixelRay(groundCamera(), x, y), p)) {
          ++sky;
          if (glm::length(glm::vec3(got)) != 0.0f) ++skyOff;
          continue;
        }
        ++ground;
        const float want = analyticE(scene.lights[0], lightPos, {0, -1, 0}, p);
        const float err = std::abs(got.r - want) / want;
        worst = std::max(worst, err);
        // Unshadowed everywhere: with shadow maps (nothing blocks the light) only acne could darken a pixel.
        if (err > 0.01f) ++off;
        CHECK(got.a == 1.0f);
        CHECK(std::abs(got.g - got.r) <= 1e-3f * got.r);  // white light
      }
    INFO("worst relative error " << worst << ", ground " << ground << ", sky " << sky);
    CHECK(ground > kWidth * kHeight / 2);
    CHECK(sky > 0);
    CHECK(off == 0);
    CHECK(skyOff == 0);
  }
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("spot cone falloff and the range window are glTF's, zero outside the cone and beyond the range",
          "[lights][render]") {
  auto engine = makeEngine();
  Scene scene = groundScene(false);
  const glm::vec3 lightPos(0.3f, 2.5f, -0.5f);
  SECTION("spot") {
    PunctualLight spot = lightAt(PunctualLight::Type::Spot, lightPos, 30.0f);
    spot.innerConeAngle = 0.25f;
    spot.outerConeAngle = 0.45f;
    scene.lights.push_back(spot);
  }
  SECTION("range") {
    PunctualLight point = lightAt(PunctualLight::Type::Point, lightPos, 30.0f);
    point.range = 3.2f;
    scene.lights.push_back(point);
  }
  const PunctualLight& light = scene.lights[0];
  const std::vector<glm::vec4> e = renderIrradiance(*engine, scene, groundParams(0));
  uint32_t inside = 0, outside = 0, bad = 0, falloff = 0;
  for (uint32_t y = 0; y < kHeight; ++y)
    for (uint32_t x = 0; x < kWidth; ++x) {
      glm::vec3 p;
      if (!groundHit(pixelRay(groundCamera(), x, y), p)) continue;
      const float got = e[y * kWidth + x].r;
      const float want = analyticE(light, lightPos, {0, -1, 0}, p);
      const glm::vec3 toLight = lightPos - p;
      const bool beyond = light.type == PunctualLight::Type::Spot
                              ? glm::dot(glm::normalize(-toLight), glm::vec3(0, -1, 0)) < std::cos(light.outerConeAngle)
                              : glm::length(toLight) > light.range;
      if (beyond) {
        ++outside;
        if (got > 1e-5f) ++bad;  // the edge itself may round to a tiny positive value
        continue;
      }
      ++inside;
      const float unwindowed = light.intensity * std::max(glm::normalize(toLight).y, 0.0f) / glm::dot(toLight, toLight);
      if (want < 0.98f * unwindowed) ++falloff;  // pixels where the cone edge / range window is at work
      // 1%, plus an absolute term for the range window's edge, where E falls steeply: there the surface point's
      // reconstruction from depth (about 1e-4 m) moves E by up to ~1e-3 (14 pixels on the H200 with 1e-4).
      if (std::abs(got - want) > 0.01f * want + 2e-3f) ++bad;
    }
  INFO("inside " << inside << ", outside " << outside << ", in the falloff " << falloff);
  CHECK(inside > 300);
  CHECK(outside > 300);
  CHECK(falloff > 50);
  CHECK(bad == 0);
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("a blocker between a shadow-mapped light and the ground darkens the pixels it hides", "[lights][shadow]") {
  auto engine = makeEngine();
  const glm::vec3 center(0.2f, 1.5f, -0.6f), size(1.0f, 0.2f, 0.8f);
  Scene scene = groundScene(true, center, size);
  const glm::vec3 lightPos(0.0f, 3.5f, -0.5f);
  PunctualLight::Type type = PunctualLight::Type::Spot;
  float inner = 0.6f, outer = 0.9f, intensity = 20.0f;
  uint32_t views = 1, minShadowed = 100;
  const char* what = "spot";
  SECTION("spot") {}
  float range = 0.0f;
  SECTION("spot with a range (casters beyond it are culled)") {
    range = 4.6f;
    what = "ranged spot";
  }
  SECTION("wide spot: six views") {
    inner = 1.0f;
    outer = 1.3f;
    views = 6;
    what = "wide spot";
  }
  SECTION("point: six views") {
    type = PunctualLight::Type::Point;
    views = 6;
    what = "point";
  }
  SECTION("directional: orthographic") {
    type = PunctualLight::Type::Directional;
    intensity = 2.0f;
    minShadowed = 25;  // a box-sized shadow beside the box, not an enlarged one
    what = "directional";
  }
  PunctualLight light = lightAt(type, lightPos, intensity);
  light.innerConeAngle = inner;
  light.outerConeAngle = outer;
  light.range = range;
  // The directional light slants towards -x, so its shadow falls beside the box, in the camera's view.
  const glm::vec3 travel = type == PunctualLight::Type::Directional ? glm::normalize(glm::vec3(-0.6f, -1.0f, 0.0f))
                                                                    : glm::vec3(0, -1, 0);
  if (type == PunctualLight::Type::Directional)
    light.transform = glm::inverse(glm::lookAt(glm::vec3(0.0f), travel, glm::vec3(0, 0, 1)));  // local -Z = travel
  scene.lights.push_back(light);
  // Where the light comes from, as seen from a ground point.
  auto source = [&](const glm::vec3& p) {
    return type == PunctualLight::Type::Directional ? p - travel * 100.0f : lightPos;
  };
  const glm::vec3 lo = center - size * 0.5f, hi = center + size * 0.5f;
  const glm::vec3 margin(0.12f, 0.0f, 0.12f);  // keeps the PCF penumbra out of both classes
  for (uint32_t maxShadowed : {4u, 0u}) {
    INFO(what << ", maxShadowedLights " << maxShadowed);
    const std::vector<glm::vec4> e = renderIrradiance(*engine, scene, groundParams(maxShadowed));
    CHECK(engine->lastLocalShadowStats().shadowViews == (maxShadowed ? views : 0u));
    uint32_t shadowed = 0, lit = 0, wrongShadowed = 0, wrongLit = 0;
    for (uint32_t y = 0; y < kHeight; ++y)
      for (uint32_t x = 0; x < kWidth; ++x) {
        const Ray ray = pixelRay(groundCamera(), x, y);
        glm::vec3 p;
        if (!groundHit(ray, p) || hitsBox(ray.origin, p, lo - 0.01f, hi + 0.01f)) continue;  // sky or the box
        const float want = analyticE(light, lightPos, travel, p);
        if (want < 1e-3f) continue;
        const float got = e[y * kWidth + x].r;
        if (hitsBox(p, source(p), lo + margin, hi - margin)) {
          ++shadowed;
          const bool ok = maxShadowed ? got < 0.02f * want : std::abs(got - want) <= 0.01f * want;
          if (!ok) ++wrongShadowed;
        } else if (!hitsBox(p, source(p), lo - margin, hi + margin)) {
          ++lit;
          if (std::abs(got - want) > 0.01f * want + 2e-3f) ++wrongLit;  // the range window's edge, as above
        }
      }
    INFO("shadowed " << shadowed << " (wrong " << wrongShadowed << "), lit " << lit << " (wrong " << wrongLit << ")");
    CHECK(shadowed > minShadowed);
    CHECK(lit > 500);
    CHECK(wrongShadowed == 0);
    CHECK(wrongLit == 0);
  }
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("KHR lights brighten the HDR frame; an external irradiance replaces the engine's", "[lights][render]") {
  auto engine = makeEngine();
  REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
  FrameParams params = groundParams(4);
  params.outputLocalLightIrradiance = false;
  params.sun.intensity = 0.5f;
  auto meanLuminance = [&](const Scene& scene, const FrameParams& p) {
    REQUIRE(engine->loadScene(scene).ok());
    REQUIRE(engine->renderFrame(p).ok());
    auto hdr = engine->readbackHdr();
    REQUIRE(hdr.ok());
    std::vector<float> lum(size_t(kWidth) * kHeight);
    for (size_t i = 0; i < lum.size(); ++i)
      lum[i] = luminance({hdr.value.pixels[i * 4], hdr.value.pixels[i * 4 + 1], hdr.value.pixels[i * 4 + 2]});
    return lum;
  };
  const Scene dark = groundScene(false);
  Scene lit = dark;
  PunctualLight light = lightAt(PunctualLight::Type::Point, {0.5f, 1.5f, -0.5f}, 8.0f);
  light.color = {1.0f, 0.6f, 0.3f};
  lit.lights.push_back(light);
  const std::vector<float> base = meanLuminance(dark, params);
  const std::vector<float> brighter = meanLuminance(lit, params);
  uint32_t gained = 0, lost = 0;
  for (size_t i = 0; i < base.size(); ++i) {
    if (brighter[i] > base[i] * 1.05f + 1e-3f) ++gained;
    if (brighter[i] < base[i] - 1e-3f) ++lost;
  }
  CHECK(gained > base.size() / 4);
  CHECK(lost == 0);
  FrameParams off = params;
  off.localLights.enabled = false;
  const std::vector<float> disabled = meanLuminance(lit, off);
  for (size_t i = 0; i < base.size(); ++i) REQUIRE(std::abs(disabled[i] - base[i]) <= 1e-3f * base[i] + 1e-5f);

  // An external E: zero takes the light away (diffuse and, by the ratio, specular); a positive one adds
  // albedo / pi * E, and the engine draws no local shadow maps for it.
  test_support::ExternalMask external(*engine, kWidth, kHeight, VK_FORMAT_R16G16B16A16_SFLOAT);
  for (float value : {0.0f, 2.0f}) {
    INFO("external E " << value);
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs& inputs) {
      external.record(info.commandBuffer, glm::vec4(value, value, value, 1.0f));
      inputs.localLightIrradiance = external.view;
    });
    const std::vector<float> withExternal = meanLuminance(lit, params);
    CHECK(engine->lastLocalShadowStats().shadowedLights == 0);
    CHECK(engine->lastLocalShadowStats().lights == 1);
    uint32_t differs = 0, tooDark = 0;
    for (size_t i = 0; i < base.size(); ++i) {
      if (value == 0.0f && std::abs(withExternal[i] - base[i]) > 2e-3f * base[i] + 1e-4f) ++differs;
      // Diffuse alone: 0.8 / pi * 2 on the ground, plus specular scaled by the ratio.
      if (value > 0.0f && brighter[i] > base[i] * 1.05f && withExternal[i] < base[i] + 0.9f * 0.8f / kPi * value)
        ++tooDark;
    }
    CHECK(differs == 0);
    CHECK(tooDark == 0);
  }
  engine->setPrepassHook({});
  CHECK(engine->readbackLocalLightIrradiance().error.find("outputLocalLightIrradiance") != std::string::npos);
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("the strongest lights get the shadow maps; the others stay unshadowed", "[lights][shadow]") {
  auto engine = makeEngine();
  const glm::vec3 center(0.2f, 1.5f, -0.6f), size(1.0f, 0.2f, 0.8f);
  Scene scene = groundScene(true, center, size);
  // Light 0 is weaker at the eye than light 1 (a quarter of the intensity, about as far): only light 1 gets
  // the one map.
  const glm::vec3 weakPos(1.6f, 3.5f, -1.2f), strongPos(-0.8f, 3.5f, -0.3f);
  scene.lights.push_back(lightAt(PunctualLight::Type::Point, weakPos, 5.0f));
  scene.lights.push_back(lightAt(PunctualLight::Type::Point, strongPos, 20.0f));
  const std::vector<glm::vec4> e = renderIrradiance(*engine, scene, groundParams(1));
  CHECK(engine->lastLocalShadowStats().lights == 2);
  CHECK(engine->lastLocalShadowStats().shadowedLights == 1);
  const glm::vec3 lo = center - size * 0.5f, hi = center + size * 0.5f, margin(0.12f, 0.0f, 0.12f);
  uint32_t strongBlocked = 0, weakBlocked = 0, wrong = 0;
  for (uint32_t y = 0; y < kHeight; ++y)
    for (uint32_t x = 0; x < kWidth; ++x) {
      const Ray ray = pixelRay(groundCamera(), x, y);
      glm::vec3 p;
      if (!groundHit(ray, p) || hitsBox(ray.origin, p, lo - 0.01f, hi + 0.01f)) continue;
      const float weak = analyticE(scene.lights[0], weakPos, {0, -1, 0}, p);
      const float strong = analyticE(scene.lights[1], strongPos, {0, -1, 0}, p);
      const float got = e[y * kWidth + x].r;
      const bool inStrong = hitsBox(p, strongPos, lo + margin, hi - margin);
      const bool nearStrong = hitsBox(p, strongPos, lo - margin, hi + margin);
      const bool inWeak = hitsBox(p, weakPos, lo + margin, hi - margin);
      const bool nearWeak = hitsBox(p, weakPos, lo - margin, hi + margin);
      if (inStrong && !nearWeak) {  // the shadow-mapped light is blocked: only the weak one remains
        ++strongBlocked;
        if (std::abs(got - weak) > 0.02f * weak) ++wrong;
      } else if (inWeak && !nearStrong) {  // the unshadowed light's "shadow": it still lights the ground
        ++weakBlocked;
        if (std::abs(got - (weak + strong)) > 0.01f * (weak + strong)) ++wrong;
      }
    }
  INFO("blocked for the strong light " << strongBlocked << ", for the weak one " << weakBlocked);
  CHECK(strongBlocked > 50);
  CHECK(weakBlocked > 50);
  CHECK(wrong == 0);
  CHECK(engine->validationErrorCount() == 0);
}

// ShadowSettings: the map size and PCF kernel the engine reports having used, a frame without a shadow map,
// and the penumbra the kernels draw (wider with more taps, even kernels centred like odd ones).
#include <cmath>
#include <vector>

#include <catch2/catch_test_macros.hpp>

#include "engine_test_support.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;
using test_support::makeEngine;

namespace {

// A 6 m ground with a 1 m box at the origin; the sun comes from +x at 45 degrees, so the box's shadow covers
// x in [-1.5, 0.5], z in [-0.5, 0.5]. Its side edge z = 0.5 runs along one axis of the shadow map's texel
// grid (the light's horizontal axis is world z), unstretched by the sun's slant.
Scene makeShadowEdgeScene() {
  Scene s;
  s.materials.push_back(Material{
      .name = "ground", .baseColorFactor = {0.7f, 0.7f, 0.7f, 1.0f}, .metallicFactor = 0.0f, .roughnessFactor = 0.9f});
  auto add = [&](MeshData mesh, glm::vec3 at) {
    mesh.material = 0;
    s.meshes.push_back(std::move(mesh));
    glm::mat4 m(1.0f);
    m[3] = glm::vec4(at, 1.0f);
    s.instances.push_back(Instance{uint32_t(s.meshes.size() - 1), m});
  };
  add(makePlane(6.0f, 6.0f, 1, 1), {0, 0, 0});
  add(makeBox({1.0f, 1.0f, 1.0f}), {0, 0.5f, 0});
  s.sun = Sun{.direction = glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f)), .color = {1, 1, 1}, .intensity = 3.0f};
  return s;
}

constexpr float kEdgeZ = 0.5f;
// Straight down onto the edge at x = -1: 0.16 m of ground across the image, so a 2048 map's texel (8.5 mm)
// covers several pixels. Top-down onto a plane the pixel -> ground mapping is affine.
constexpr uint32_t kEdgeSize = 128;
constexpr float kEdgeView = 0.16f;
constexpr float kEdgeHeight = 2.0f;

Camera edgeCamera() {
  return Camera{.eye = {-1.0f, kEdgeHeight, kEdgeZ},
                .target = {-1.0f, 0.0f, kEdgeZ},
                .fovYDegrees = glm::degrees(2.0f * std::atan(0.5f * kEdgeView / kEdgeHeight)),
                .zNear = 0.5f,
                .zFar = 5.0f};
}

// Ground point (y = 0) seen at image position `p` (pixels, 0..size; top row first).
glm::vec3 groundAt(const Camera& camera, glm::vec2 p, glm::vec2 size) {
  const glm::mat4 inv = glm::inverse(projectionMatrix(camera, size.x / size.y) * viewMatrix(camera));
  const glm::vec2 ndc = p / size * 2.0f - 1.0f;
  glm::vec4 a = inv * glm::vec4(ndc, 0.0f, 1.0f), b = inv * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 near = glm::vec3(a) / a.w, far = glm::vec3(b) / b.w;
  return near + (far - near) * (near.y / (near.y - far.y));
}

struct EdgeProfile {
  uint32_t penumbraPixels = 0;  // pixels strictly between shadow and light
  float edgeZ = 0.0f;           // where the filtered edge is centred: zLow + integral of (1 - visibility) dz
};

struct ShadowFixture {
  std::unique_ptr<Engine> engine = makeEngine();
  FrameParams params;
  uint32_t width = kEdgeSize, height = kEdgeSize;

  ShadowFixture() {
    REQUIRE(engine->loadScene(makeShadowEdgeScene()).ok());
    params.sun = *engine->scene().sun;
    setView(edgeCamera(), kEdgeSize, kEdgeSize);
  }

  void setView(const Camera& camera, uint32_t w, uint32_t h) {
    params.camera = camera;
    width = w;
    height = h;
    REQUIRE(engine->setRenderSize(w, h).ok());
  }

  void render() {
    Status s = engine->renderFrame(params);
    INFO(s.error);
    REQUIRE(s.ok());
  }

  std::vector<float> visibility() {
    auto r = engine->readbackShadowVisibility();
    INFO(r.error);
    REQUIRE(r.ok());
    REQUIRE(r.value.size() == size_t(width) * height);
    return std::move(r.value);
  }

  ImageRGBA32F hdr() {
    auto r = engine->readbackHdr();
    INFO(r.error);
    REQUIRE(r.ok());
    return std::move(r.value);
  }

  // The shadow edge under the edge camera, rendered with `size` and `pcf`.
  EdgeProfile edge(uint32_t size, uint32_t pcf) {
    params.shadow.mapSize = size;
    params.shadow.pcfKernelSize = pcf;
    params.outputShadowVisibility = true;
    render();
    const std::vector<float> vis = visibility();
    const glm::vec2 extent{float(width), float(height)};
    const glm::vec3 c0 = groundAt(params.camera, {0, 0}, extent), c1 = groundAt(params.camera, extent, extent);
    const float zLow = std::min(c0.z, c1.z), zHigh = std::max(c0.z, c1.z);
    EdgeProfile e;
    double shadowed = 0;  // pixels are spread evenly over [zLow, zHigh]: mean(1 - v) = (edge - zLow) / range
    for (float v : vis) {
      shadowed += 1.0 - v;
      if (v > 0.02f && v < 0.98f) ++e.penumbraPixels;
    }
    e.edgeZ = zLow + float(shadowed / double(vis.size())) * (zHigh - zLow);
    return e;
  }

  float texel(uint32_t size) const { return 2.0f * engine->sceneBounds().radius() / float(size); }
};

float luminance(const glm::vec4& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// The pixel that shows world point `p`, at least one pixel away from the image border.
glm::ivec2 pixelOf(const Camera& camera, glm::vec3 p, uint32_t width, uint32_t height) {
  const glm::vec4 c = projectionMatrix(camera, float(width) / float(height)) * viewMatrix(camera) * glm::vec4(p, 1.0f);
  const glm::ivec2 at = glm::ivec2((glm::vec2(c) / c.w * 0.5f + 0.5f) * glm::vec2(width, height));
  REQUIRE((c.w > 0.0f && at.x >= 1 && at.y >= 1 && at.x + 1 < int(width) && at.y + 1 < int(height)));
  return at;
}

// Mean HDR luminance over the 3x3 pixels that show ground point `p`.
float groundLuminance(const ImageRGBA32F& img, const Camera& camera, glm::vec3 p) {
  const glm::ivec2 at = pixelOf(camera, p, img.width, img.height);
  double sum = 0;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) sum += luminance(img.at(uint32_t(at.x + x), uint32_t(at.y + y)));
  return float(sum / 9.0);
}

void checkStats(const Engine& engine, bool enabled, uint32_t mapSize, uint32_t pcfKernel) {
  const ShadowMapStats s = engine.lastShadowMapStats();
  CHECK(s.enabled == enabled);
  CHECK(s.mapSize == mapSize);
  CHECK(s.pcfKernel == pcfKernel);
  CHECK(s.frameNumber == engine.frameNumber());
}

}  // namespace

TEST_CASE("the engine reports the shadow-map size and PCF kernel it drew with", "[shadow][stats]") {
  ShadowFixture f;
  CHECK_FALSE(f.engine->lastShadowMapStats().enabled);
  CHECK(f.engine->lastShadowMapStats().frameNumber == 0);
  struct Case {
    bool enabled;
    uint32_t size, pcf;
    ShadowMapStats expected;
  };
  // The raster counterparts of the quality presets (none | 2048 | 4096 PCF 4 | 8192 PCF 8), PCF 0 and 1
  // (one tap), and clamping. The 8192 map (256 MiB of D32) is drawn once, at this small resolution.
  const Case cases[] = {
      {true, 2048, 0, {true, 2048, 1, 0}},
      {true, 2048, 1, {true, 2048, 1, 0}},
      {true, 4096, 4, {true, 4096, 4, 0}},
      {true, 8192, 8, {true, 8192, 8, 0}},
      {false, 4096, 4, {false, 0, 0, 0}},
      {true, 100, 30, {true, kMinShadowMapSize, kMaxShadowPcfKernel, 0}},
      {true, 1u << 20, 2, {true, kMaxShadowMapSize, 2, 0}},
  };
  for (const Case& c : cases) {
    INFO("enabled " << c.enabled << ", size " << c.size << ", pcf " << c.pcf);
    f.params.shadow.enabled = c.enabled;
    f.params.shadow.mapSize = c.size;
    f.params.shadow.pcfKernelSize = c.pcf;
    f.render();
    checkStats(*f.engine, c.expected.enabled, c.expected.mapSize, c.expected.pcfKernel);
  }
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("without a shadow map the sun is unshadowed, and the map comes back when re-enabled", "[shadow]") {
  ShadowFixture f;
  const Camera overview{
      .eye = {0.0f, 4.0f, 4.0f}, .target = {-1.0f, 0.0f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 20.0f};
  f.setView(overview, 96, 72);
  const glm::vec3 underBox{-1.0f, 0.0f, 0.0f}, open{-1.0f, 0.0f, 1.5f};
  f.params.shadow.mapSize = 2048;
  f.params.outputShadowVisibility = true;
  // The probe captures with the frame's shadow settings: it must cope with the placeholder too.
  f.params.reflectionProbe.enabled = true;
  f.params.reflectionProbe.resolution = 16;

  f.render();
  ImageRGBA32F shadowed = f.hdr();
  const float shadowedDark = groundLuminance(shadowed, overview, underBox);
  const float shadowedOpen = groundLuminance(shadowed, overview, open);
  INFO("with a map: under the box " << shadowedDark << ", open " << shadowedOpen);
  CHECK(shadowedDark < 0.5f * shadowedOpen);
  checkStats(*f.engine, true, 2048, 3);

  f.params.shadow.enabled = false;
  f.render();
  checkStats(*f.engine, false, 0, 0);
  ImageRGBA32F unshadowed = f.hdr();
  const float under = groundLuminance(unshadowed, overview, underBox);
  const float lit = groundLuminance(unshadowed, overview, open);
  INFO("without a map: under the box " << under << ", open " << lit);
  CHECK(std::abs(under - lit) < 0.03f * lit);
  CHECK(std::abs(lit - shadowedOpen) < 0.03f * shadowedOpen);
  // The shadow-visibility output agrees: the ground under the box is fully lit.
  const std::vector<float> vis = f.visibility();
  const glm::ivec2 px = pixelOf(overview, underBox, f.width, f.height);
  CHECK(vis[size_t(px.y) * f.width + size_t(px.x)] == 1.0f);
  REQUIRE(f.engine->waitIdle().ok());
  // Disabling the map changed the probe's lighting: that frame captured it again.
  if (f.engine->lastTimings().valid) CHECK(f.engine->lastTimings().probeCaptured);

  f.params.shadow.enabled = true;
  f.render();
  checkStats(*f.engine, true, 2048, 3);
  ImageRGBA32F again = f.hdr();
  CHECK(groundLuminance(again, overview, underBox) < 0.5f * groundLuminance(again, overview, open));
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("PCF kernels: more taps widen the penumbra, even kernels stay centred", "[shadow][pcf]") {
  ShadowFixture f;
  constexpr uint32_t kSize = 2048;
  const float texel = f.texel(kSize);
  const float pixel = kEdgeView / float(kEdgeSize);
  REQUIRE(pixel < 0.5f * texel);  // the penumbra of one tap (1 texel, a bilinear ramp) spans several pixels

  const EdgeProfile one = f.edge(kSize, 1), three = f.edge(kSize, 3), four = f.edge(kSize, 4), five = f.edge(kSize, 5),
                    eight = f.edge(kSize, 8), nine = f.edge(kSize, 9);
  // Penumbra of n taps: about n texels.
  INFO("penumbra pixels: 1 -> " << one.penumbraPixels << ", 3 -> " << three.penumbraPixels << ", 4 -> "
                                << four.penumbraPixels << ", 5 -> " << five.penumbraPixels << ", 8 -> "
                                << eight.penumbraPixels << ", 9 -> " << nine.penumbraPixels);
  CHECK(one.penumbraPixels > 0);
  CHECK(float(four.penumbraPixels) > 2.0f * float(one.penumbraPixels));  // "PCF 4 is softer than PCF 1"
  CHECK(three.penumbraPixels < four.penumbraPixels);                     // 4 is its own kernel, not rounded to 3 or 5
  CHECK(four.penumbraPixels < five.penumbraPixels);
  CHECK(four.penumbraPixels < eight.penumbraPixels);
  CHECK(eight.penumbraPixels < nine.penumbraPixels);

  // The filtered edge stays where the single tap puts it: an even kernel off-centre by half a texel would
  // move it by 0.5 texel.
  INFO("edge z (texels from " << kEdgeZ << "): 1 -> " << (one.edgeZ - kEdgeZ) / texel << ", 3 -> "
                              << (three.edgeZ - kEdgeZ) / texel << ", 4 -> " << (four.edgeZ - kEdgeZ) / texel
                              << ", 5 -> " << (five.edgeZ - kEdgeZ) / texel << ", 8 -> "
                              << (eight.edgeZ - kEdgeZ) / texel << ", 9 -> " << (nine.edgeZ - kEdgeZ) / texel);
  CHECK(std::abs(one.edgeZ - kEdgeZ) < 1.0f * texel);  // the map's rasterised edge is within a texel
  for (const EdgeProfile* e : {&three, &four, &five, &eight, &nine})
    CHECK(std::abs(e->edgeZ - one.edgeZ) < 0.2f * texel);
  CHECK(std::abs(four.edgeZ - 0.5f * (three.edgeZ + five.edgeZ)) < 0.15f * texel);

  // A bigger map draws the same kernel's penumbra narrower on the ground.
  const EdgeProfile four4096 = f.edge(4096, 4);
  INFO("4096, PCF 4: " << four4096.penumbraPixels << " penumbra pixels");
  CHECK(float(four4096.penumbraPixels) < 0.7f * float(four.penumbraPixels));
  checkStats(*f.engine, true, 4096, 4);
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

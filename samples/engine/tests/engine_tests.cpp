// Sample engine tests: headless rendering on whatever device exists (lavapipe in CI) with validation on.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <span>

#include <catch2/catch_test_macros.hpp>

#include "engine_test_support.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;
using test_support::ExternalMask;

namespace {

constexpr uint32_t kWidth = 160, kHeight = 120;

std::unique_ptr<Engine> makeEngine() {
  EngineConfig cfg;
  cfg.enableValidation = true;
  auto r = Engine::create(cfg);
  INFO(r.error);
  REQUIRE(r.ok());
  return std::move(r.value);
}

FrameParams paramsFor(const Engine& engine) {
  FrameParams p;
  p.camera = engine.scene().camera ? *engine.scene().camera : defaultCameraFor(engine.sceneBounds());
  if (engine.scene().sun) p.sun = *engine.scene().sun;
  p.shadow.mapSize = 1024;
  return p;
}

ImageRGBA32F renderHdr(Engine& engine, const FrameParams& params) {
  Status s = engine.renderFrame(params);
  INFO(s.error);
  REQUIRE(s.ok());
  auto hdr = engine.readbackHdr();
  INFO(hdr.error);
  REQUIRE(hdr.ok());
  return std::move(hdr.value);
}

float luminance(const glm::vec4& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// Average luminance of the bottom quarter of the image: ground only in the demo scene's camera.
float groundLuminance(const ImageRGBA32F& img) {
  double sum = 0;
  uint32_t n = 0;
  for (uint32_t y = img.height * 3 / 4; y < img.height; ++y)
    for (uint32_t x = 0; x < img.width; ++x, ++n) sum += luminance(img.at(x, y));
  return float(sum / n);
}

}  // namespace

TEST_CASE("procedural meshes have their documented triangle counts", "[procedural]") {
  CHECK(makePlane(2, 2, 4, 3).triangleCount() == planeTriangleCount(4, 3));
  CHECK(planeTriangleCount(4, 3) == 24);
  CHECK(makeBox({1, 1, 1}, 3).triangleCount() == boxTriangleCount(3));
  CHECK(boxTriangleCount(1) == 12);
  CHECK(makeSphere(1, 16, 8).triangleCount() == sphereTriangleCount(16, 8));
  CHECK(sphereTriangleCount(16, 8) == 224);
  CHECK(makeCylinder(1, 2, 12, 2, true).triangleCount() == cylinderTriangleCount(12, 2, true));
  CHECK(makeCylinder(1, 2, 12, 2, false).triangleCount() == 48);
  CHECK(makeArch(2, 0.3f, 3.14159f, 10, 6).triangleCount() == archTriangleCount(10, 6));
  for (const MeshData& m : makeDefaultDemoScene().meshes) {
    CHECK(m.normals.size() == m.positions.size());
    CHECK(m.tangents.size() == m.positions.size());
    for (uint32_t i : m.indices) REQUIRE(i < m.positions.size());
  }
}

TEST_CASE("default scene renders headless without validation errors", "[render]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
  FrameParams params = paramsFor(*engine);

  ImageRGBA32F shadowed = renderHdr(*engine, params);
  auto ldr = engine->readbackLdr();
  REQUIRE(ldr.ok());
  REQUIRE(ldr.value.width == kWidth);

  SECTION("sky pixels have the sky color") {
    for (uint32_t x : {2u, kWidth / 2, kWidth - 3}) {
      glm::vec4 hdr = shadowed.at(x, 1);
      CHECK(std::abs(hdr.r - params.skyColor.r) < 2e-3f);
      CHECK(std::abs(hdr.g - params.skyColor.g) < 2e-3f);
      CHECK(std::abs(hdr.b - params.skyColor.b) < 2e-3f);
      glm::u8vec3 expected = tonemapToSrgb8(params.skyColor, params.exposure);
      glm::u8vec4 got = ldr.value.at(x, 1);
      for (int c = 0; c < 3; ++c) CHECK(std::abs(int(got[c]) - int(expected[c])) <= 2);
    }
  }

  SECTION("shadow maps leave some geometry darker than when fully lit") {
    // Same frame with an all-lit external visibility: the difference is exactly the shadowed area.
    ExternalMask ones(*engine, kWidth, kHeight);
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs& inputs) {
      ones.record(info.commandBuffer, 1.0f);
      inputs.sunVisibility = ones.view;
    });
    ImageRGBA32F lit = renderHdr(*engine, params);
    engine->setPrepassHook({});
    uint32_t darker = 0;
    for (uint32_t y = 0; y < kHeight; ++y)
      for (uint32_t x = 0; x < kWidth; ++x) {
        float s = luminance(shadowed.at(x, y)), l = luminance(lit.at(x, y));
        CHECK(s <= l + 1e-3f);
        if (s < 0.6f * l) ++darker;
      }
    INFO("shadowed pixels: " << darker);
    CHECK(darker > kWidth * kHeight / 100);  // at least 1% of the image is in shadow
  }

  SECTION("external sun visibility of zeros darkens the ground") {
    ExternalMask mask(*engine, kWidth, kHeight);
    float value = 1.0f;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs& inputs) {
      mask.record(info.commandBuffer, value);
      inputs.sunVisibility = mask.view;
    });
    float lit = groundLuminance(renderHdr(*engine, params));
    value = 0.0f;
    float dark = groundLuminance(renderHdr(*engine, params));
    INFO("ground luminance, visibility 1: " << lit << ", visibility 0: " << dark);
    CHECK(dark < 0.6f * lit);
    CHECK(dark > 0.0f);  // ambient remains
  }

  SECTION("the pre-pass hook sees the documented images, layouts and matrices") {
    std::vector<uint32_t> frameIndices;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      frameIndices.push_back(info.frameIndex);
      CHECK(info.commandBuffer != VK_NULL_HANDLE);
      CHECK(info.extent.width == kWidth);
      CHECK(info.extent.height == kHeight);
      CHECK(info.depth.format == VK_FORMAT_D32_SFLOAT);
      CHECK(info.depth.layout == VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL);
      CHECK(info.normalRoughness.format == VK_FORMAT_R16G16B16A16_SFLOAT);
      CHECK(info.normalRoughness.layout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
      CHECK(info.geometricNormal.layout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
      CHECK(info.depth.view != VK_NULL_HANDLE);
      CHECK_FALSE(info.reversedZ);
      glm::mat4 identity = info.viewProj * info.invViewProj;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) CHECK(std::abs(identity[c][r] - (c == r ? 1.0f : 0.0f)) < 1e-3f);
      CHECK(std::abs(glm::length(info.sunDirection) - 1.0f) < 1e-4f);
    });
    for (int i = 0; i < 3; ++i) REQUIRE(engine->renderFrame(params).ok());
    REQUIRE(engine->waitIdle().ok());
    engine->setPrepassHook({});
    REQUIRE(frameIndices.size() == 3);
    CHECK(frameIndices[0] != frameIndices[1]);
    CHECK(frameIndices[0] == frameIndices[2]);
    PassTimings t = engine->lastTimings();
    CHECK(t.valid);
    CHECK(t.lightingMs > 0.0);
  }

  SECTION("meshes expose buffers for ray-tracing inputs") {
    REQUIRE(engine->meshes().size() == engine->scene().meshes.size());
    for (const GpuMesh& m : engine->meshes()) {
      CHECK(m.positionBuffer != VK_NULL_HANDLE);
      CHECK(m.positionStride == 12);
      CHECK(m.vertexCount == m.cpu->positions.size());
      CHECK(m.indexCount == m.cpu->indices.size());
      if (engine->deviceInfo().bufferDeviceAddress) CHECK(m.positionAddress != 0);
    }
  }

  engine->setPrepassHook({});
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("glTF loader reports errors instead of throwing", "[gltf]") {
  SceneLoadResult missing = loadGltf("/nonexistent/scene.gltf");
  CHECK_FALSE(missing.ok());
  CHECK(missing.error.find("not found") != std::string::npos);

  auto path = std::filesystem::temp_directory_path() / "sample_engine_malformed.gltf";
  std::ofstream(path) << "{ this is not json";
  SceneLoadResult malformed = loadGltf(path.string());
  CHECK_FALSE(malformed.ok());
  CHECK_FALSE(malformed.error.empty());
  std::filesystem::remove(path);
}

TEST_CASE("glTF Box sample loads and renders", "[gltf][render]") {
  const std::filesystem::path box = std::filesystem::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes" / "Box" /
                                    "Box.gltf";
  if (!std::filesystem::exists(box)) SKIP("glTF sample not present: " + box.string());
  SceneLoadResult r = loadGltf(box.string());
  INFO(r.error);
  REQUIRE(r.ok());
  REQUIRE(r.scene.meshes.size() == 1);
  CHECK(r.scene.meshes[0].triangleCount() == 12);
  CHECK(r.scene.instances.size() == 1);

  auto engine = makeEngine();
  REQUIRE(engine->loadScene(r.scene).ok());
  REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
  FrameParams params = paramsFor(*engine);
  ImageRGBA32F img = renderHdr(*engine, params);
  glm::vec4 center = img.at(kWidth / 2, kHeight / 2);
  CHECK(glm::length(glm::vec3(center) - params.skyColor) > 0.05f);  // the box covers the centre
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("scene textures are exposed as read-only views, parallel to Scene::textures", "[gltf][textures]") {
  const std::filesystem::path path = std::filesystem::path(RAYBRIDGE_SOURCE_DIR) / ".." / "shared" / "scenes" /
                                     "BoxTextured" / "BoxTextured.gltf";
  if (!std::filesystem::exists(path)) SKIP("glTF sample not present: " + path.string());
  SceneLoadResult r = loadGltf(path.string());
  INFO(r.error);
  REQUIRE(r.ok());
  REQUIRE_FALSE(r.scene.textures.empty());
  for (const TextureData& t : r.scene.textures) {
    // A copy of the models without their image files (the GPU machine gets geometry only) has nothing to test.
    if (t.rgba8.empty()) SKIP("texture image files not present next to " + path.string());
  }

  auto engine = makeEngine();
  CHECK(engine->textures().empty());  // no scene yet
  REQUIRE(engine->loadScene(r.scene).ok());
  const std::span<const GpuTexture> textures = engine->textures();
  REQUIRE(textures.size() == engine->scene().textures.size());
  for (size_t i = 0; i < textures.size(); ++i) {
    const GpuTexture& t = textures[i];
    INFO("texture " << i);
    CHECK(t.image != VK_NULL_HANDLE);
    CHECK(t.srgbView != VK_NULL_HANDLE);
    CHECK(t.unormView != VK_NULL_HANDLE);
    CHECK(t.srgbView != t.unormView);
    CHECK(t.width == engine->scene().textures[i].width);
    CHECK(t.height == engine->scene().textures[i].height);
    CHECK(t.mipLevels >= 1);
  }
  // The base-colour texture of the material is one of them.
  const Material& m = engine->scene().materials.at(engine->scene().meshes.at(0).material);
  REQUIRE(m.baseColorTexture >= 0);
  CHECK(size_t(m.baseColorTexture) < textures.size());

  REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
  renderHdr(*engine, paramsFor(*engine));
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

// ---------------------------------------------------------------------------------------------------------
// The engine's own raster effects: SSAO, reflection probe, shadow-visibility output.

namespace {

constexpr uint32_t kFxWidth = 320, kFxHeight = 240;

// A rough dielectric ground with a 2 m matte box at x = -3 and a polished metal sphere at x = +3; the sun
// comes from +x at 45 degrees, so the box's shadow covers the ground around (-5, 0, 0).
Scene makeEffectsScene() {
  Scene s;
  s.materials.push_back(Material{.name = "rough ground",
                                 .baseColorFactor = {0.7f, 0.7f, 0.7f, 1.0f},
                                 .metallicFactor = 0.0f,
                                 .roughnessFactor = 0.8f});
  s.materials.push_back(Material{.name = "matte box",
                                 .baseColorFactor = {0.2f, 0.3f, 0.7f, 1.0f},
                                 .metallicFactor = 0.0f,
                                 .roughnessFactor = 0.8f});
  s.materials.push_back(Material{.name = "polished metal",
                                 .baseColorFactor = {0.95f, 0.95f, 0.95f, 1.0f},
                                 .metallicFactor = 1.0f,
                                 .roughnessFactor = 0.05f});
  auto add = [&](MeshData mesh, uint32_t material, glm::vec3 at) {
    mesh.material = material;
    s.meshes.push_back(std::move(mesh));
    glm::mat4 m(1.0f);
    m[3] = glm::vec4(at, 1.0f);
    s.instances.push_back(Instance{uint32_t(s.meshes.size() - 1), m});
  };
  add(makePlane(40.0f, 40.0f, 8, 8), 0, {0, 0, 0});
  add(makeBox({2.0f, 2.0f, 2.0f}, 2), 1, {-3, 1, 0});
  add(makeSphere(1.0f, 64, 32), 2, {3, 1, 0});
  s.camera = Camera{
      .eye = {0.0f, 5.0f, 10.0f}, .target = {0.0f, 0.5f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 100.0f};
  s.sun = Sun{.direction = glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f)), .color = {1, 1, 1}, .intensity = 3.0f};
  return s;
}

struct EffectsFixture {
  std::unique_ptr<Engine> engine = makeEngine();
  FrameParams params;

  EffectsFixture() {
    REQUIRE(engine->loadScene(makeEffectsScene()).ok());
    REQUIRE(engine->setRenderSize(kFxWidth, kFxHeight).ok());
    params = paramsFor(*engine);
  }

  // Pixel that shows world point `p` (assumes it is visible).
  glm::ivec2 pixelOf(glm::vec3 p) const {
    glm::mat4 vp = projectionMatrix(params.camera, float(kFxWidth) / float(kFxHeight)) * viewMatrix(params.camera);
    glm::vec4 c = vp * glm::vec4(p, 1.0f);
    glm::vec2 uv = glm::vec2(c) / c.w * 0.5f + 0.5f;
    glm::ivec2 px(uv * glm::vec2(kFxWidth, kFxHeight));
    REQUIRE((c.w > 0.0f && px.x >= 3 && px.y >= 3 && px.x + 3 < int(kFxWidth) && px.y + 3 < int(kFxHeight)));
    return px;
  }

  void render() {
    Status s = engine->renderFrame(params);
    INFO(s.error);
    REQUIRE(s.ok());
  }

  std::vector<float> ssao() {
    auto r = engine->readbackSsao();
    INFO(r.error);
    REQUIRE(r.ok());
    REQUIRE(r.value.size() == size_t(kFxWidth) * kFxHeight);
    return std::move(r.value);
  }
};

float at(const std::vector<float>& img, glm::ivec2 p) { return img[size_t(p.y) * kFxWidth + size_t(p.x)]; }

// Mean over a (2r+1)^2 window.
float windowMean(const std::vector<float>& img, glm::ivec2 c, int r) {
  double sum = 0;
  int n = 0;
  for (int y = c.y - r; y <= c.y + r; ++y)
    for (int x = c.x - r; x <= c.x + r; ++x, ++n) sum += at(img, {x, y});
  return float(sum / n);
}

float windowLuminance(const ImageRGBA32F& img, glm::ivec2 c, int r) {
  double sum = 0;
  int n = 0;
  for (int y = c.y - r; y <= c.y + r; ++y)
    for (int x = c.x - r; x <= c.x + r; ++x, ++n) sum += luminance(img.at(uint32_t(x), uint32_t(y)));
  return float(sum / n);
}

// High-frequency energy among occluded pixels: mean |a(x) - a(x+1)| where either is below 1.
float roughness(const std::vector<float>& ao) {
  double sum = 0;
  uint32_t n = 0;
  for (uint32_t y = 0; y < kFxHeight; ++y)
    for (uint32_t x = 0; x + 1 < kFxWidth; ++x) {
      float a = ao[y * kFxWidth + x], b = ao[y * kFxWidth + x + 1];
      if (a > 0.999f && b > 0.999f) continue;
      sum += std::abs(a - b);
      ++n;
    }
  return n ? float(sum / n) : 0.0f;
}

}  // namespace

TEST_CASE("engine effects are off by default", "[effects]") {
  EffectsFixture f;
  f.render();
  CHECK_FALSE(f.engine->readbackSsao().ok());
  CHECK_FALSE(f.engine->readbackShadowVisibility().ok());
  PassTimings t = f.engine->lastTimings();
  CHECK_FALSE(t.probeCaptured);
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("SSAO darkens creases, leaves open ground open and feeds the lighting", "[effects][ssao]") {
  EffectsFixture f;
  const glm::ivec2 crease = f.pixelOf({-3.0f, 0.0f, 1.08f});  // ground touching the box's front face
  const glm::ivec2 open = f.pixelOf({0.0f, 0.0f, 4.0f});      // > 3 m from anything
  ImageRGBA32F without = renderHdr(*f.engine, f.params);

  f.params.ssao.enabled = true;
  f.params.ssao.radius = 1.0f;
  ImageRGBA32F with = renderHdr(*f.engine, f.params);
  std::vector<float> ao = f.ssao();
  INFO("AO crease " << windowMean(ao, crease, 1) << ", open " << windowMean(ao, open, 2));
  CHECK(windowMean(ao, crease, 1) < 0.8f);
  CHECK(windowMean(ao, open, 2) > 0.98f);
  CHECK(at(ao, {kFxWidth / 2, 2}) == 1.0f);  // sky
  for (float v : ao) REQUIRE((v >= 0.0f && v <= 1.0f));
  CHECK(f.engine->lastTimings().ssaoMs > 0.0);

  // The lighting multiplies the ambient terms by it: the crease darkens, open ground does not change.
  CHECK(windowLuminance(with, crease, 1) < windowLuminance(without, crease, 1) - 1e-3f);
  CHECK(std::abs(windowLuminance(with, open, 2) - windowLuminance(without, open, 2)) <
        0.01f * windowLuminance(without, open, 2));

  SECTION("an external AO input replaces it in the lighting, and it can still be read back") {
    ExternalMask ones(*f.engine, kFxWidth, kFxHeight);
    f.engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs& inputs) {
      ones.record(info.commandBuffer, 1.0f);
      inputs.ambientOcclusion = ones.view;
    });
    ImageRGBA32F external = renderHdr(*f.engine, f.params);
    f.engine->setPrepassHook({});
    CHECK(std::abs(windowLuminance(external, crease, 1) - windowLuminance(without, crease, 1)) < 1e-3f);
    CHECK(windowMean(f.ssao(), crease, 1) < 0.8f);
  }

  SECTION("the kernel size changes the result: fewer samples, more noise") {
    f.params.ssao.blur = false;
    f.params.ssao.kernelSize = 8;
    f.render();
    std::vector<float> few = f.ssao();
    f.params.ssao.kernelSize = 64;
    f.render();
    std::vector<float> many = f.ssao();
    float maxDiff = 0.0f;
    for (size_t i = 0; i < few.size(); ++i) maxDiff = std::max(maxDiff, std::abs(few[i] - many[i]));
    INFO("noise with 8 samples " << roughness(few) << ", with 64 " << roughness(many) << ", max diff " << maxDiff);
    CHECK(maxDiff > 0.05f);
    CHECK(roughness(few) > 1.3f * roughness(many));
    CHECK(windowMean(many, open, 2) > 0.98f);
    // The blur removes most of the remaining pattern.
    f.params.ssao.blur = true;
    f.render();
    CHECK(roughness(f.ssao()) < roughness(many));
  }

  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("the reflection probe changes polished metal, not rough ground far from objects", "[effects][probe]") {
  EffectsFixture f;
  ImageRGBA32F sky = renderHdr(*f.engine, f.params);
  f.params.reflectionProbe.enabled = true;
  ImageRGBA32F probe = renderHdr(*f.engine, f.params);
  PassTimings t = f.engine->lastTimings();
  CHECK(t.probeCaptured);
  CHECK(t.probeMs > 0.0);

  // The lower half of the metal sphere mirrors the lit ground instead of the sky.
  const glm::ivec2 sphereLow = f.pixelOf({3.0f, 0.45f, 0.8f});
  const float metalSky = windowLuminance(sky, sphereLow, 1), metalProbe = windowLuminance(probe, sphereLow, 1);
  INFO("metal: sky-only " << metalSky << ", probe " << metalProbe);
  CHECK(std::abs(metalProbe - metalSky) > 0.2f * metalSky);

  for (glm::vec3 p : {glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(-3.0f, 0.0f, 4.0f), glm::vec3(3.0f, 0.0f, 4.0f)}) {
    const glm::ivec2 px = f.pixelOf(p);
    const float a = windowLuminance(sky, px, 2), b = windowLuminance(probe, px, 2);
    INFO("ground at " << p.x << "," << p.z << ": sky-only " << a << ", probe " << b);
    CHECK(std::abs(a - b) < 0.02f * a);
  }

  SECTION("static: captured once, again when an input changes") {
    f.render();
    REQUIRE(f.engine->waitIdle().ok());
    CHECK_FALSE(f.engine->lastTimings().probeCaptured);
    f.params.reflectionProbe.resolution = 32;
    f.render();
    REQUIRE(f.engine->waitIdle().ok());
    CHECK(f.engine->lastTimings().probeCaptured);
  }

  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("shadow-visibility readback matches the shadow map", "[effects][shadow]") {
  EffectsFixture f;
  f.params.outputShadowVisibility = true;
  ImageRGBA32F hdr = renderHdr(*f.engine, f.params);
  auto vis = f.engine->readbackShadowVisibility();
  INFO(vis.error);
  REQUIRE(vis.ok());
  REQUIRE(vis.value.size() == size_t(kFxWidth) * kFxHeight);
  const glm::ivec2 shadowed = f.pixelOf({-5.0f, 0.0f, 0.0f});  // inside the box's shadow
  const glm::ivec2 lit = f.pixelOf({0.0f, 0.0f, 4.0f});
  INFO("shadowed " << windowMean(vis.value, shadowed, 1) << ", lit " << windowMean(vis.value, lit, 1));
  CHECK(windowMean(vis.value, shadowed, 1) < 0.05f);
  CHECK(windowMean(vis.value, lit, 1) > 0.95f);
  CHECK(at(vis.value, {kFxWidth / 2, 2}) == 1.0f);  // sky
  CHECK(windowLuminance(hdr, shadowed, 1) < 0.5f * windowLuminance(hdr, lit, 1));

  // Only produced on request.
  f.params.outputShadowVisibility = false;
  f.render();
  CHECK_FALSE(f.engine->readbackShadowVisibility().ok());
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("an external reflection replaces the environment term by its alpha (coverage)", "[effects][reflection]") {
  EffectsFixture f;
  const glm::ivec2 sphere = f.pixelOf({3.0f, 1.3f, 0.95f});  // polished metal, upper front of the sphere
  ExternalMask reflection(*f.engine, kFxWidth, kFxHeight, VK_FORMAT_R16G16B16A16_SFLOAT);
  glm::vec4 value(0.0f);
  auto useExternal = [&] {
    f.engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs& inputs) {
      reflection.record(info.commandBuffer, value);
      inputs.reflection = reflection.view;
    });
  };
  auto ldr = [&] {
    auto img = f.engine->readbackLdr();
    INFO(img.error);
    REQUIRE(img.ok());
    return std::move(img.value);
  };
  auto maxDifference = [](const ImageRGBA8& a, const ImageRGBA8& b) {
    int diff = 0;
    for (uint32_t y = 0; y < a.height; ++y)
      for (uint32_t x = 0; x < a.width; ++x)
        for (int c = 0; c < 3; ++c) diff = std::max(diff, std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c])));
    return diff;
  };

  SECTION("alpha 0 keeps the engine's own term (constant sky), whatever the colour") {
    ImageRGBA32F ownHdr = renderHdr(*f.engine, f.params);
    ImageRGBA8 own = ldr();
    useExternal();
    value = glm::vec4(20.0f, 0.0f, 20.0f, 0.0f);  // must not leak anywhere
    ImageRGBA32F externalHdr = renderHdr(*f.engine, f.params);
    INFO("max LDR difference " << maxDifference(own, ldr()));
    CHECK(maxDifference(own, ldr()) <= 1);
    CHECK(std::abs(windowLuminance(externalHdr, sphere, 1) - windowLuminance(ownHdr, sphere, 1)) <
          1e-3f * windowLuminance(ownHdr, sphere, 1) + 1e-4f);

    value = glm::vec4(8.0f, 8.0f, 8.0f, 1.0f);  // alpha 1: a bright environment brightens the metal
    ImageRGBA32F bright = renderHdr(*f.engine, f.params);
    INFO("metal: own " << windowLuminance(ownHdr, sphere, 1) << ", external bright "
                       << windowLuminance(bright, sphere, 1));
    CHECK(windowLuminance(bright, sphere, 1) > 2.0f * windowLuminance(ownHdr, sphere, 1));
  }

  SECTION("alpha 0 keeps the reflection probe when it is enabled") {
    f.params.reflectionProbe.enabled = true;
    renderHdr(*f.engine, f.params);
    ImageRGBA8 own = ldr();
    useExternal();
    value = glm::vec4(20.0f, 0.0f, 20.0f, 0.0f);
    renderHdr(*f.engine, f.params);
    INFO("max LDR difference " << maxDifference(own, ldr()));
    CHECK(maxDifference(own, ldr()) <= 1);
  }

  f.engine->setPrepassHook({});
  REQUIRE(f.engine->waitIdle().ok());
  CHECK(f.engine->validationErrorCount() == 0);
}

TEST_CASE("an external colour replaces the raster frame: the tonemap and the readbacks show the hook's image",
          "[render][external-color]") {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
  FrameParams params = paramsFor(*engine);
  params.externalColor = true;
  params.ssao.enabled = true;  // skipped with the rest of the raster shading

  SECTION("without a hook every pixel is the sky, and no shadow map is drawn") {
    ImageRGBA32F hdr = renderHdr(*engine, params);
    for (uint32_t y : {1u, kHeight / 2, kHeight - 2})
      for (uint32_t x : {1u, kWidth / 2, kWidth - 2})
        for (int c = 0; c < 3; ++c) CHECK(std::abs(hdr.at(x, y)[c] - params.skyColor[c]) < 2e-3f);
    CHECK_FALSE(engine->lastShadowMapStats().enabled);
    CHECK_FALSE(engine->readbackSsao().ok());
  }
  SECTION("the hook's colour, written into the HDR target it is handed") {
    const glm::vec4 colour(2.0f, 0.5f, 0.25f, 1.0f);
    bool handed = false;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      handed = info.hdrColor.view && info.hdrColor.layout == VK_IMAGE_LAYOUT_GENERAL &&
               info.hdrColor.format == VK_FORMAT_R16G16B16A16_SFLOAT;
      const VkClearColorValue value{{colour.r, colour.g, colour.b, colour.a}};
      const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
      vkCmdClearColorImage(info.commandBuffer, info.hdrColor.image, VK_IMAGE_LAYOUT_GENERAL, &value, 1, &all);
    });
    ImageRGBA32F hdr = renderHdr(*engine, params);
    auto ldr = engine->readbackLdr();
    REQUIRE(ldr.ok());
    engine->setPrepassHook({});
    CHECK(handed);
    const glm::u8vec3 expected = tonemapToSrgb8(glm::vec3(colour), params.exposure);
    for (uint32_t y : {1u, kHeight / 2, kHeight - 2}) {
      for (uint32_t x : {1u, kWidth / 2, kWidth - 2}) {
        for (int c = 0; c < 3; ++c) {
          CHECK(std::abs(hdr.at(x, y)[c] - colour[c]) < 2e-3f);
          CHECK(std::abs(int(ldr.value.at(x, y)[c]) - int(expected[c])) <= 1);
        }
      }
    }
  }
  SECTION("outputs of the raster shading cannot be asked for") {
    params.outputShadowVisibility = true;
    Status s = engine->renderFrame(params);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error.find("externalColor") != std::string::npos);
    CHECK(s.error.find("outputShadowVisibility") != std::string::npos);
  }
  (void)engine->waitIdle();
  CHECK(engine->validationErrorCount() == 0);
}

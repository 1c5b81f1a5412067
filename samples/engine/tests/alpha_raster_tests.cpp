// Material coverage and sidedness in the raster passes: MASK cut-outs (pre-pass, lighting, shadow map), the
// BLEND forward pass (analytic over-blend, back-to-front order, kept out of the G-buffer, its own lighting
// terms, hashed shadows), doubleSided culling (mirrored instances, the probe's mirrored cube faces, shadows of
// culled faces) and the separate occlusion texture. Small procedural scenes with generated RGBA textures.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <tuple>
#include <utility>
#include <vector>

#include <catch2/catch_test_macros.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include "engine_test_support.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;
using test_support::ExternalMask;
using test_support::makeEngine;

namespace {

constexpr uint32_t kWidth = 128, kHeight = 96;

// ---------------------------------------------------------------------------------------------------------
// Reading the pre-pass back from inside the hook, as an add-on sees it.

// A host-visible, coherent buffer of `size` bytes.
struct HostBuffer {
  VkDevice device = VK_NULL_HANDLE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;

  HostBuffer(Engine& engine, VkDeviceSize size) : device(engine.device()) {
    VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = size;
    bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    REQUIRE(vkCreateBuffer(device, &bi, nullptr, &buffer) == VK_SUCCESS);
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, buffer, &req);
    VkPhysicalDeviceMemoryProperties props;
    vkGetPhysicalDeviceMemoryProperties(engine.physicalDevice(), &props);
    const VkMemoryPropertyFlags need = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = UINT32_MAX;
    for (uint32_t i = 0; i < props.memoryTypeCount && ai.memoryTypeIndex == UINT32_MAX; ++i)
      if ((req.memoryTypeBits & (1u << i)) && (props.memoryTypes[i].propertyFlags & need) == need)
        ai.memoryTypeIndex = i;
    REQUIRE(ai.memoryTypeIndex != UINT32_MAX);
    REQUIRE(vkAllocateMemory(device, &ai, nullptr, &memory) == VK_SUCCESS);
    REQUIRE(vkBindBufferMemory(device, buffer, memory, 0) == VK_SUCCESS);
    REQUIRE(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &mapped) == VK_SUCCESS);
  }
  ~HostBuffer() {
    vkDeviceWaitIdle(device);
    vkDestroyBuffer(device, buffer, nullptr);
    vkFreeMemory(device, memory, nullptr);
  }
  HostBuffer(const HostBuffer&) = delete;
  HostBuffer& operator=(const HostBuffer&) = delete;
};

void barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to,
             VkAccessFlags2 dstAccess) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = b.dstStageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  b.srcAccessMask = VK_ACCESS_2_MEMORY_WRITE_BIT;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

// The pre-pass depth and normal images of the last frame whose hook called record().
struct PrepassReadback {
  uint32_t width, height;
  HostBuffer depthBuffer, normalBuffer, geometricBuffer;

  PrepassReadback(Engine& engine, uint32_t w, uint32_t h)
      : width(w),
        height(h),
        depthBuffer(engine, VkDeviceSize(w) * h * 4),
        normalBuffer(engine, VkDeviceSize(w) * h * 8),
        geometricBuffer(engine, VkDeviceSize(w) * h * 8) {}

  // Copies the images out and puts them back in the layouts the hook received them in.
  void record(const PrepassHookInfo& info) const {
    VkCommandBuffer cmd = info.commandBuffer;
    auto copy = [&](const PassImage& img, VkImageAspectFlags aspect, VkBuffer dst) {
      barrier(cmd, img.image, aspect, img.layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_ACCESS_2_TRANSFER_READ_BIT);
      VkBufferImageCopy region{};
      region.imageSubresource = {aspect, 0, 0, 1};
      region.imageExtent = {width, height, 1};
      vkCmdCopyImageToBuffer(cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, dst, 1, &region);
      barrier(cmd, img.image, aspect, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, img.layout, VK_ACCESS_2_MEMORY_READ_BIT);
    };
    copy(info.depth, VK_IMAGE_ASPECT_DEPTH_BIT, depthBuffer.buffer);
    copy(info.normalRoughness, VK_IMAGE_ASPECT_COLOR_BIT, normalBuffer.buffer);
    copy(info.geometricNormal, VK_IMAGE_ASPECT_COLOR_BIT, geometricBuffer.buffer);
    VkMemoryBarrier2 host{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
    host.srcStageMask = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
    host.srcAccessMask = VK_ACCESS_2_TRANSFER_WRITE_BIT;
    host.dstStageMask = VK_PIPELINE_STAGE_2_HOST_BIT;
    host.dstAccessMask = VK_ACCESS_2_HOST_READ_BIT;
    VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    dep.memoryBarrierCount = 1;
    dep.pMemoryBarriers = &host;
    vkCmdPipelineBarrier2(cmd, &dep);
  }

  // Valid once the frame completed (after a readback or waitIdle()).
  float depth(glm::ivec2 p) const {
    float d;
    std::memcpy(&d, static_cast<const char*>(depthBuffer.mapped) + (size_t(p.y) * width + size_t(p.x)) * 4, 4);
    return d;
  }
  static glm::vec4 half4(const HostBuffer& b, size_t texel) {
    uint16_t h[4];
    std::memcpy(h, static_cast<const char*>(b.mapped) + texel * 8, 8);
    return {glm::unpackHalf1x16(h[0]), glm::unpackHalf1x16(h[1]), glm::unpackHalf1x16(h[2]), glm::unpackHalf1x16(h[3])};
  }
  glm::vec4 normalRoughness(glm::ivec2 p) const { return half4(normalBuffer, size_t(p.y) * width + size_t(p.x)); }
  glm::vec4 geometricNormal(glm::ivec2 p) const { return half4(geometricBuffer, size_t(p.y) * width + size_t(p.x)); }
};

// ---------------------------------------------------------------------------------------------------------
// Scenes: 2 m quads facing +Z (a makePlane turned up), in front of a 12 m wall at z = -2 facing +Z.

// Rotation of +90 degrees about X: the plane's +Y normal becomes +Z, its first texture row the top edge and u
// the +X direction, so a texture reads unmirrored from the front.
glm::mat4 facingPlusZ(glm::vec3 at, glm::vec3 scale = glm::vec3(1.0f)) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), at);
  m = glm::rotate(m, glm::radians(90.0f), glm::vec3(1, 0, 0));
  return glm::scale(m, scale);
}

// Facing -Z: the same quad turned half a turn about Y.
glm::mat4 facingMinusZ(glm::vec3 at) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), at), glm::radians(180.0f), glm::vec3(0, 1, 0)) *
         facingPlusZ(glm::vec3(0.0f));
}

// 8x8 RGBA texture: columns 0..3 (u < 0.5, the quad's -X half) `left`, columns 4..7 `right`.
TextureData halvesTexture(glm::u8vec4 left, glm::u8vec4 right) {
  TextureData t{"halves", 8, 8, {}};
  for (uint32_t y = 0; y < 8; ++y)
    for (uint32_t x = 0; x < 8; ++x) {
      const glm::u8vec4 c = x < 4 ? left : right;
      t.rgba8.insert(t.rgba8.end(), {c.r, c.g, c.b, c.a});
    }
  return t;
}

Material wallMaterial() {
  return Material{.name = "wall", .baseColorFactor = {0.7f, 0.7f, 0.7f, 1.0f}, .roughnessFactor = 0.9f};
}

// A material lit only by its emission (base colour black): with the sun and the sky off, its radiance is
// exactly `emissive`, whatever the lighting model.
Material emissiveMaterial(const char* name, glm::vec3 emissive, float alpha, AlphaMode mode) {
  return Material{.name = name,
                  .baseColorFactor = {0.0f, 0.0f, 0.0f, alpha},
                  .metallicFactor = 0.0f,
                  .roughnessFactor = 0.9f,
                  .emissiveFactor = emissive,
                  .alphaMode = mode};
}

struct SceneBuilder {
  Scene scene;
  uint32_t wallMesh, quadMesh;

  SceneBuilder() {
    scene.meshes.push_back(makePlane(12.0f, 12.0f, 1, 1));
    wallMesh = 0;
    scene.meshes.push_back(makePlane(2.0f, 2.0f, 1, 1));
    quadMesh = 1;
  }
  uint32_t material(Material m) {
    scene.materials.push_back(std::move(m));
    return uint32_t(scene.materials.size() - 1);
  }
  int texture(TextureData t) {
    scene.textures.push_back(std::move(t));
    return int(scene.textures.size() - 1);
  }
  // Each instance gets its own mesh copy, so that it can have its own material.
  void add(uint32_t mesh, uint32_t material, const glm::mat4& transform) {
    MeshData m = scene.meshes[mesh];
    m.material = material;
    scene.meshes.push_back(std::move(m));
    scene.instances.push_back(Instance{uint32_t(scene.meshes.size() - 1), transform});
  }
  void wall(uint32_t material) { add(wallMesh, material, facingPlusZ({0.0f, 0.0f, -2.0f}, glm::vec3(1.0f))); }
  void quad(uint32_t material, const glm::mat4& transform = facingPlusZ({0.0f, 0.0f, 0.0f})) {
    add(quadMesh, material, transform);
  }
};

Camera frontCamera(float distance = 8.0f) {
  return Camera{
      .eye = {0.0f, 0.0f, distance}, .target = {0.0f, 0.0f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 50.0f};
}

Camera backCamera(float distance = 8.0f) {
  return Camera{
      .eye = {0.0f, 0.0f, -distance}, .target = {0.0f, 0.0f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 50.0f};
}

glm::vec4 clipOf(const Camera& camera, glm::vec3 p) {
  return projectionMatrix(camera, float(kWidth) / float(kHeight)) * viewMatrix(camera) * glm::vec4(p, 1.0f);
}

// The pixel showing world point `p`, at least 3 pixels inside the image.
glm::ivec2 pixelOf(const Camera& camera, glm::vec3 p) {
  const glm::vec4 c = clipOf(camera, p);
  const glm::ivec2 px(glm::floor((glm::vec2(c) / c.w * 0.5f + 0.5f) * glm::vec2(kWidth, kHeight)));
  REQUIRE((c.w > 0.0f && px.x >= 3 && px.y >= 3 && px.x + 3 < int(kWidth) && px.y + 3 < int(kHeight)));
  return px;
}

// Distance along the view axis of a depth-buffer value (standard Z, [0, 1]).
float viewDistance(const Camera& camera, float depth) {
  const float n = camera.zNear, f = camera.zFar;
  return n * f / (f - depth * (f - n));
}

float viewDistanceOf(const Camera& camera, glm::vec3 p) { return clipOf(camera, p).w; }

// Where the ray from the eye through `p` meets the wall plane z = -2.
glm::vec3 wallBehind(const Camera& camera, glm::vec3 p) {
  const float t = (-2.0f - camera.eye.z) / (p.z - camera.eye.z);
  return camera.eye + (p - camera.eye) * t;
}

float luminance(glm::vec4 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// Mean over the (2r+1)^2 pixels around `c`.
float windowMean(const std::vector<float>& img, glm::ivec2 c, int r) {
  double sum = 0;
  int n = 0;
  for (int y = c.y - r; y <= c.y + r; ++y)
    for (int x = c.x - r; x <= c.x + r; ++x, ++n) sum += img[size_t(y) * kWidth + size_t(x)];
  return float(sum / n);
}

glm::vec4 windowMean(const ImageRGBA32F& img, glm::ivec2 c, int r) {
  glm::dvec4 sum(0.0);
  int n = 0;
  for (int y = c.y - r; y <= c.y + r; ++y)
    for (int x = c.x - r; x <= c.x + r; ++x, ++n) sum += glm::dvec4(img.at(uint32_t(x), uint32_t(y)));
  return glm::vec4(sum / double(n));
}

bool near(glm::vec3 a, glm::vec3 b, float tolerance) {
  return glm::all(glm::lessThan(glm::abs(a - b), glm::vec3(tolerance)));
}

struct Fixture {
  std::unique_ptr<Engine> engine = makeEngine();
  FrameParams params;
  PrepassReadback prepass{*engine, kWidth, kHeight};
  std::function<void(const PrepassHookInfo&, LightingInputs&)> extraHook;

  Fixture() {
    REQUIRE(engine->setRenderSize(kWidth, kHeight).ok());
    params.camera = frontCamera();
    // From +x at 45 degrees: a quad's point (x, y, 0) shadows the wall at (x - 2, y, -2).
    params.sun = Sun{.direction = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f)), .color = {1, 1, 1}, .intensity = 3.0f};
    engine->setPrepassHook([this](const PrepassHookInfo& info, LightingInputs& inputs) {
      prepass.record(info);
      if (extraHook) extraHook(info, inputs);
    });
  }
  ~Fixture() { engine->setPrepassHook({}); }

  void load(const Scene& scene) {
    Status s = engine->loadScene(scene);
    INFO(s.error);
    REQUIRE(s.ok());
  }

  ImageRGBA32F render() {
    Status s = engine->renderFrame(params);
    INFO(s.error);
    REQUIRE(s.ok());
    auto hdr = engine->readbackHdr();  // waits: the pre-pass copies are complete too
    INFO(hdr.error);
    REQUIRE(hdr.ok());
    return std::move(hdr.value);
  }

  std::vector<float> shadowVisibility() {
    auto r = engine->readbackShadowVisibility();
    INFO(r.error);
    REQUIRE(r.ok());
    return std::move(r.value);
  }

  // The view distance the pre-pass depth holds at `p`'s pixel.
  float depthDistanceAt(glm::vec3 p) const {
    return viewDistance(params.camera, prepass.depth(pixelOf(params.camera, p)));
  }

  void finish() {
    engine->setPrepassHook({});
    REQUIRE(engine->waitIdle().ok());
    CHECK(engine->validationErrorCount() == 0);
  }
};

// Sun and sky off: only emission lights the scene.
void unlit(FrameParams& params) {
  params.sun.intensity = 0.0f;
  params.ambientIntensity = 0.0f;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// MASK

TEST_CASE("MASK cut-outs show what is behind in the pre-pass and the lit image, and let the sun through",
          "[alpha][mask]") {
  Fixture f;
  SceneBuilder b;
  b.wall(b.material(wallMaterial()));
  Material cutout{.name = "cut-out",
                  .baseColorFactor = {0.9f, 0.1f, 0.1f, 1.0f},
                  .roughnessFactor = 0.3f,
                  .baseColorTexture = b.texture(halvesTexture({255, 255, 255, 0}, {255, 255, 255, 255})),
                  .alphaMode = AlphaMode::Mask};
  b.quad(b.material(cutout));
  f.load(b.scene);
  f.params.outputShadowVisibility = true;
  const ImageRGBA32F hdr = f.render();
  const std::vector<float> visibility = f.shadowVisibility();

  const glm::vec3 hole{-0.5f, 0.0f, 0.0f}, solid{0.5f, 0.0f, 0.0f};
  const Camera& cam = f.params.camera;
  // Pre-pass: the wall through the hole (its depth and roughness), the quad on the other half.
  INFO("hole: depth distance " << f.depthDistanceAt(hole) << ", wall " << viewDistanceOf(cam, wallBehind(cam, hole)));
  CHECK(std::abs(f.depthDistanceAt(hole) - viewDistanceOf(cam, wallBehind(cam, hole))) < 0.02f);
  CHECK(std::abs(f.depthDistanceAt(solid) - viewDistanceOf(cam, solid)) < 0.02f);
  CHECK(std::abs(f.prepass.normalRoughness(pixelOf(cam, hole)).w - 0.9f) < 0.01f);
  CHECK(std::abs(f.prepass.normalRoughness(pixelOf(cam, solid)).w - 0.3f) < 0.01f);

  // Lighting: the wall through the hole (lit, as the open wall beside the quad), the red quad beside it.
  const glm::vec4 seenThrough = windowMean(hdr, pixelOf(cam, hole), 1),
                  seenQuad = windowMean(hdr, pixelOf(cam, solid), 1);
  const glm::vec4 openWall = windowMean(hdr, pixelOf(cam, {2.5f, 0.0f, -2.0f}), 1);
  INFO("through the hole " << seenThrough.r << "," << seenThrough.g << "; open wall " << openWall.r << "," << openWall.g
                           << "; quad " << seenQuad.r << "," << seenQuad.g);
  CHECK(near(glm::vec3(seenThrough), glm::vec3(openWall), 0.02f * luminance(openWall)));
  CHECK(seenQuad.r > 3.0f * seenQuad.g);

  // Shadow map: the sun (from +x, 45 degrees) projects the quad's point (x, y, 0) onto the wall at (x - 2, y).
  // Behind the hole's shadow the wall is lit, behind the solid half's it is not.
  const glm::vec3 wallUnderHole{-2.5f, 0.0f, -2.0f}, wallUnderSolid{-1.5f, 0.0f, -2.0f};
  const float litVis = windowMean(visibility, pixelOf(cam, wallUnderHole), 1);
  const float shadowVis = windowMean(visibility, pixelOf(cam, wallUnderSolid), 1);
  INFO("sun visibility on the wall: behind the hole " << litVis << ", behind the solid half " << shadowVis);
  CHECK(litVis > 0.95f);
  CHECK(shadowVis < 0.05f);
  CHECK(luminance(windowMean(hdr, pixelOf(cam, wallUnderHole), 1)) >
        2.0f * luminance(windowMean(hdr, pixelOf(cam, wallUnderSolid), 1)));
  f.finish();
}

TEST_CASE("MASK respects alphaCutoff and the base colour factor's alpha, in the camera and the shadow map",
          "[alpha][mask]") {
  Fixture f;
  f.params.outputShadowVisibility = true;
  const glm::vec3 left{-0.5f, 0.0f, 0.0f}, right{0.5f, 0.0f, 0.0f};
  const glm::vec3 wallUnderLeft{-2.5f, 0.0f, -2.0f}, wallUnderRight{-1.5f, 0.0f, -2.0f};
  struct Case {
    float cutoff, factorAlpha;
    bool leftKept, rightKept;
  };
  // Texture alpha 0.4 on the left, 0.6 on the right.
  const Case cases[] = {
      {0.5f, 1.0f, false, true},   // 0.4 < 0.5 cut, 0.6 kept
      {0.3f, 1.0f, true, true},    // nothing below 0.3
      {0.7f, 1.0f, false, false},  // both below 0.7
      {0.5f, 0.8f, false, false},  // 0.8 * 0.6 = 0.48 < 0.5
  };
  for (const Case& c : cases) {
    INFO("cutoff " << c.cutoff << ", factor alpha " << c.factorAlpha);
    SceneBuilder b;
    b.wall(b.material(wallMaterial()));
    b.quad(b.material(Material{.name = "cut-out",
                               .baseColorFactor = {1.0f, 1.0f, 1.0f, c.factorAlpha},
                               .baseColorTexture = b.texture(halvesTexture({255, 255, 255, 102}, {255, 255, 255, 153})),
                               .alphaMode = AlphaMode::Mask,
                               .alphaCutoff = c.cutoff}));
    f.load(b.scene);
    f.render();
    const std::vector<float> visibility = f.shadowVisibility();
    const Camera& cam = f.params.camera;
    for (auto [p, kept, shadowOf] :
         {std::tuple{left, c.leftKept, wallUnderLeft}, std::tuple{right, c.rightKept, wallUnderRight}}) {
      INFO("quad point x = " << p.x << ", expected " << (kept ? "kept" : "cut"));
      const float expected = viewDistanceOf(cam, kept ? p : wallBehind(cam, p));
      CHECK(std::abs(f.depthDistanceAt(p) - expected) < 0.02f);
      const float vis = windowMean(visibility, pixelOf(cam, shadowOf), 1);
      INFO("sun visibility of the wall behind its shadow " << vis);
      CHECK((kept ? vis < 0.05f : vis > 0.95f));
    }
  }
  f.finish();
}

// ---------------------------------------------------------------------------------------------------------
// BLEND

TEST_CASE("BLEND surfaces are blended over the opaque scene and stay out of the depth and G-buffer", "[alpha][blend]") {
  Fixture f;
  unlit(f.params);
  SceneBuilder b;
  Material white = emissiveMaterial("white", glm::vec3(1.0f), 1.0f, AlphaMode::Opaque);
  b.wall(b.material(white));
  Material red = emissiveMaterial("red glass", {1.0f, 0.0f, 0.0f}, 0.5f, AlphaMode::Blend);
  red.roughnessFactor = 0.2f;  // what the G-buffer would show if the quad were in it
  red.metallicFactor = 1.0f;
  b.quad(b.material(red));
  // Behind the wall: the blend pass's depth test (LESS against the pre-pass) must hide it.
  b.quad(b.material(emissiveMaterial("hidden green", {0.0f, 1.0f, 0.0f}, 0.5f, AlphaMode::Blend)),
         facingPlusZ({-3.0f, 0.0f, -3.0f}));
  f.load(b.scene);
  const ImageRGBA32F hdr = f.render();
  const Camera& cam = f.params.camera;

  // over(red, 0.5) on white: 0.5 * (1, 0, 0) + 0.5 * (1, 1, 1).
  const glm::ivec2 quad = pixelOf(cam, {0.0f, 0.0f, 0.0f});
  const glm::vec3 blended(windowMean(hdr, quad, 2));
  INFO("blended " << blended.r << ", " << blended.g << ", " << blended.b);
  CHECK(near(blended, {1.0f, 0.5f, 0.5f}, 0.01f));
  const glm::vec3 hidden(windowMean(hdr, pixelOf(cam, wallBehind(cam, {-3.0f, 0.0f, -3.0f})), 1));
  INFO("wall in front of the hidden quad " << hidden.r << ", " << hidden.g << ", " << hidden.b);
  CHECK(near(hidden, glm::vec3(1.0f), 0.01f));

  // The pre-pass never saw the quad: the wall's depth, roughness, metallic and normal.
  CHECK(std::abs(f.depthDistanceAt({0.0f, 0.0f, 0.0f}) - viewDistanceOf(cam, {0.0f, 0.0f, -2.0f})) < 0.02f);
  const glm::vec4 nr = f.prepass.normalRoughness(quad), gn = f.prepass.geometricNormal(quad);
  CHECK(std::abs(nr.w - 0.9f) < 0.01f);
  CHECK(std::abs(gn.w - 0.0f) < 0.01f);
  CHECK(near(glm::vec3(gn), {0.0f, 0.0f, 1.0f}, 0.01f));
  f.finish();
}

TEST_CASE("BLEND surfaces are drawn back to front, whatever their order in the scene", "[alpha][blend]") {
  Fixture f;
  unlit(f.params);
  for (bool nearFirst : {true, false}) {
    INFO("near quad first in the scene: " << nearFirst);
    SceneBuilder b;
    b.wall(b.material(emissiveMaterial("white", glm::vec3(1.0f), 1.0f, AlphaMode::Opaque)));
    const uint32_t red = b.material(emissiveMaterial("red", {1.0f, 0.0f, 0.0f}, 0.5f, AlphaMode::Blend));
    const uint32_t blue = b.material(emissiveMaterial("blue", {0.0f, 0.0f, 1.0f}, 0.5f, AlphaMode::Blend));
    if (nearFirst) b.quad(red, facingPlusZ({0.0f, 0.0f, 0.0f}));
    b.quad(blue, facingPlusZ({0.0f, 0.0f, -1.0f}));
    if (!nearFirst) b.quad(red, facingPlusZ({0.0f, 0.0f, 0.0f}));
    f.load(b.scene);
    const glm::vec3 c(windowMean(f.render(), pixelOf(f.params.camera, {0.0f, 0.0f, 0.0f}), 2));
    // over(red, over(blue, white)) = 0.5 red + 0.25 blue + 0.25 white; the other order gives (0.5, 0.25, 0.75).
    INFO("overlap " << c.r << ", " << c.g << ", " << c.b);
    CHECK(near(c, {0.75f, 0.25f, 0.5f}, 0.01f));
  }
  f.finish();
}

TEST_CASE("BLEND surfaces are lit like the forward pass, ignoring the screen-space sun visibility",
          "[alpha][blend][lighting]") {
  Fixture f;
  f.params.shadow.enabled = false;  // the sun reaches everything: nothing but the blend differs
  ExternalMask zeros(*f.engine, kWidth, kHeight);
  auto build = [](bool withQuad, AlphaMode mode) {
    SceneBuilder b;
    b.wall(b.material(wallMaterial()));
    if (withQuad)
      b.quad(b.material(Material{.name = "tinted glass",
                                 .baseColorFactor = {0.8f, 0.3f, 0.1f, 0.5f},
                                 .roughnessFactor = 0.4f,
                                 .emissiveFactor = {0.05f, 0.1f, 0.2f},
                                 .alphaMode = mode}));
    return b.scene;
  };
  const glm::ivec2 px = pixelOf(f.params.camera, {0.0f, 0.0f, 0.0f});
  auto colourOf = [&](const Scene& scene) {
    f.load(scene);
    return glm::vec3(windowMean(f.render(), px, 1));
  };
  for (bool externalShadow : {false, true}) {
    INFO("external sun visibility of 0: " << externalShadow);
    f.extraHook = externalShadow ? std::function<void(const PrepassHookInfo&, LightingInputs&)>(
                                       [&](const PrepassHookInfo& info, LightingInputs& inputs) {
                                         zeros.record(info.commandBuffer, 0.0f);
                                         inputs.sunVisibility = zeros.view;
                                       })
                                 : nullptr;
    const glm::vec3 background = colourOf(build(false, AlphaMode::Opaque));
    const glm::vec3 blended = colourOf(build(true, AlphaMode::Blend));
    f.extraHook = nullptr;  // the quad's own colour, fully lit: what a blended surface sees
    const glm::vec3 opaque = colourOf(build(true, AlphaMode::Opaque));
    const glm::vec3 expected = 0.5f * opaque + 0.5f * background;
    INFO("opaque " << opaque.r << "," << opaque.g << "," << opaque.b << "; background " << background.r << ","
                   << background.g << "," << background.b << "; blended " << blended.r << "," << blended.g << ","
                   << blended.b);
    CHECK(near(blended, expected, 0.01f * glm::length(expected) + 2e-3f));
  }
  f.finish();
}

TEST_CASE("BLEND surfaces cast hashed shadows: alpha of the light blocked in the mean", "[alpha][blend][shadow]") {
  Fixture f;
  f.params.outputShadowVisibility = true;
  f.params.shadow.mapSize = 2048;
  f.params.shadow.pcfKernelSize = 5;
  struct Case {
    glm::u8vec4 left, right;
    float expectedLeft, expectedRight;  // sun visibility on the wall behind each half's shadow
  };
  const Case cases[] = {
      {{255, 255, 255, 128}, {255, 255, 255, 128}, 0.5f, 0.5f},
      {{255, 255, 255, 0}, {255, 255, 255, 255}, 1.0f, 0.0f},
      {{255, 255, 255, 64}, {255, 255, 255, 191}, 0.75f, 0.25f},
  };
  for (const Case& c : cases) {
    INFO("texture alpha " << int(c.left.a) << " | " << int(c.right.a));
    SceneBuilder b;
    b.wall(b.material(wallMaterial()));
    b.quad(b.material(Material{.name = "glass",
                               .baseColorTexture = b.texture(halvesTexture(c.left, c.right)),
                               .alphaMode = AlphaMode::Blend}));
    f.load(b.scene);
    f.render();
    const std::vector<float> vis = f.shadowVisibility();
    const float left = windowMean(vis, pixelOf(f.params.camera, {-2.5f, 0.0f, -2.0f}), 2);
    const float right = windowMean(vis, pixelOf(f.params.camera, {-1.5f, 0.0f, -2.0f}), 2);
    INFO("visibility behind the left half " << left << ", the right half " << right);
    CHECK(std::abs(left - c.expectedLeft) < 0.1f);
    CHECK(std::abs(right - c.expectedRight) < 0.1f);
  }
  f.finish();
}

// ---------------------------------------------------------------------------------------------------------
// doubleSided

TEST_CASE("single-sided materials cull back faces, mirrored instances included; double-sided ones face the viewer",
          "[alpha][sided]") {
  Fixture f;
  struct Case {
    const char* name;
    bool doubleSided;
    glm::mat4 transform;
  };
  const Case cases[] = {
      {"single-sided", false, facingPlusZ({0.0f, 0.0f, 0.0f})},
      {"single-sided, mirrored (negative x scale)", false, facingPlusZ({0.0f, 0.0f, 0.0f}, {-1.0f, 1.0f, 1.0f})},
      {"single-sided, mirrored twice (x and z)", false, facingPlusZ({0.0f, 0.0f, 0.0f}, {-1.0f, 1.0f, -1.0f})},
      {"double-sided", true, facingPlusZ({0.0f, 0.0f, 0.0f})},
      {"double-sided, mirrored", true, facingPlusZ({0.0f, 0.0f, 0.0f}, {-1.0f, 1.0f, 1.0f})},
  };
  const glm::vec3 centre{0.0f, 0.0f, 0.0f};
  for (const Case& c : cases) {
    INFO(c.name);
    SceneBuilder b;
    b.quad(b.material(Material{.name = "quad",
                               .baseColorFactor = {0.8f, 0.8f, 0.8f, 1.0f},
                               .roughnessFactor = 0.3f,
                               .doubleSided = c.doubleSided}),
           c.transform);
    f.load(b.scene);
    for (bool front : {true, false}) {
      INFO((front ? "seen from the front (+z)" : "seen from behind (-z)"));
      f.params.camera = front ? frontCamera() : backCamera();
      const ImageRGBA32F hdr = f.render();
      const glm::ivec2 px = pixelOf(f.params.camera, centre);
      const bool drawn = front || c.doubleSided;
      if (drawn) {
        CHECK(std::abs(f.depthDistanceAt(centre) - 8.0f) < 0.02f);
        // Shading and geometric normals face the viewer.
        const glm::vec3 towardsViewer(0.0f, 0.0f, front ? 1.0f : -1.0f);
        CHECK(near(glm::vec3(f.prepass.normalRoughness(px)), towardsViewer, 0.01f));
        CHECK(near(glm::vec3(f.prepass.geometricNormal(px)), towardsViewer, 0.01f));
        CHECK(glm::length(glm::vec3(hdr.at(px.x, px.y)) - f.params.skyColor) > 0.05f);
      } else {
        CHECK(f.prepass.depth(px) == 1.0f);  // background: far plane
        CHECK(f.prepass.normalRoughness(px) == glm::vec4(0.0f));
        CHECK(near(glm::vec3(hdr.at(px.x, px.y)), f.params.skyColor, 2e-3f));
      }
    }
  }
  f.finish();
}

TEST_CASE("a single-sided surface culled from the camera still casts its shadow", "[alpha][sided][shadow]") {
  Fixture f;
  f.params.outputShadowVisibility = true;
  SceneBuilder b;
  b.wall(b.material(wallMaterial()));
  // Facing -Z: the camera (and the sun, from +x +z) see its back.
  b.quad(b.material(Material{.name = "one-sided", .doubleSided = false}), facingMinusZ({0.0f, 0.0f, 0.0f}));
  f.load(b.scene);
  f.render();
  const Camera& cam = f.params.camera;
  const glm::vec3 centre{0.0f, 0.0f, 0.0f};
  CHECK(std::abs(f.depthDistanceAt(centre) - viewDistanceOf(cam, wallBehind(cam, centre))) < 0.02f);  // culled
  const std::vector<float> vis = f.shadowVisibility();
  for (glm::vec3 wall : {glm::vec3(-2.5f, 0.0f, -2.0f), glm::vec3(-1.5f, 0.0f, -2.0f)}) {
    INFO("sun visibility at wall x = " << wall.x << ": " << windowMean(vis, pixelOf(cam, wall), 1));
    CHECK(windowMean(vis, pixelOf(cam, wall), 1) < 0.05f);
  }
  CHECK(windowMean(vis, pixelOf(cam, {2.5f, 0.0f, -2.0f}), 1) > 0.95f);  // beside the shadow
  f.finish();
}

TEST_CASE("the reflection probe culls single-sided back faces in its mirrored cube faces", "[alpha][sided][probe]") {
  Fixture f;
  f.params.sun.intensity = 0.0f;  // no highlight on the mirror
  f.params.camera = Camera{
      .eye = {0.0f, 1.0f, 6.0f}, .target = {0.0f, 0.0f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 50.0f};
  f.params.reflectionProbe.enabled = true;
  f.params.reflectionProbe.resolution = 32;
  f.params.reflectionProbe.position = glm::vec3(0.0f, 1.0f, 0.0f);
  // A mirror floor reflects, at (0, 0, 2), what the probe sees towards (0, 1, -4): a bright emissive panel at
  // z = -6 when its front faces the probe, else the probe's sky background.
  struct Case {
    const char* name;
    bool doubleSided;
    glm::mat4 transform;
    bool seen;
  };
  const glm::mat4 panel = glm::scale(facingPlusZ({0.0f, 4.0f, -6.0f}), glm::vec3(5.0f, 1.0f, 5.0f));
  const glm::mat4 turned = glm::rotate(glm::translate(glm::mat4(1.0f), {0.0f, 4.0f, -6.0f}), glm::radians(180.0f),
                                       glm::vec3(0, 1, 0)) *
                           glm::scale(facingPlusZ({0.0f, 0.0f, 0.0f}), glm::vec3(5.0f, 1.0f, 5.0f));
  const Case cases[] = {
      {"single-sided, facing the probe", false, panel, true},
      {"single-sided, mirrored, facing the probe", false, glm::scale(panel, {-1.0f, 1.0f, 1.0f}), true},
      {"single-sided, back to the probe", false, turned, false},
      {"double-sided, back to the probe", true, turned, true},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    Scene s;
    s.materials.push_back(Material{.name = "mirror",
                                   .baseColorFactor = {1.0f, 1.0f, 1.0f, 1.0f},
                                   .metallicFactor = 1.0f,
                                   .roughnessFactor = 0.0f});
    s.materials.push_back(emissiveMaterial("panel", glm::vec3(4.0f), 1.0f, AlphaMode::Opaque));
    s.materials.back().doubleSided = c.doubleSided;
    s.meshes.push_back(makePlane(20.0f, 20.0f, 1, 1));
    s.meshes.push_back(makePlane(2.0f, 2.0f, 1, 1));
    s.meshes.back().material = 1;
    s.instances = {Instance{0, glm::mat4(1.0f)}, Instance{1, c.transform}};
    f.load(s);
    const float floor = luminance(windowMean(f.render(), pixelOf(f.params.camera, {0.0f, 0.0f, 2.0f}), 1));
    INFO("mirror floor luminance " << floor);
    CHECK((c.seen ? floor > 2.0f : floor < 1.0f));
  }
  f.finish();
}

// ---------------------------------------------------------------------------------------------------------
// Occlusion texture

TEST_CASE("a separate occlusion texture darkens the ambient light where its R is low", "[alpha][occlusion]") {
  Fixture f;
  f.params.sun.intensity = 0.0f;  // ambient only: every term left scales with the occlusion
  f.params.ambientIntensity = 1.0f;
  struct Case {
    const char* name;
    int occlusion;  // 0: the halves texture (R 0 | 255), 1: the metallic-roughness texture, -1: none
    int metallicRoughness;
    float strength, expectedRatio;  // left / right ambient radiance
  };
  const Case cases[] = {
      {"separate occlusion, strength 1", 0, 1, 1.0f, 0.0f},
      {"separate occlusion, strength 0.5", 0, 1, 0.5f, 0.5f},
      {"packed in the metallic-roughness texture", 0, 0, 1.0f, 0.0f},
      {"none: the metallic-roughness texture's R is not occlusion", -1, 1, 1.0f, 1.0f},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    SceneBuilder b;
    // Texture 0: R 0 on the left, 1 on the right; G (roughness) 1, B (metallic) 0 everywhere.
    const int halves = b.texture(halvesTexture({0, 255, 0, 255}, {255, 255, 0, 255}));
    const int flatMr = b.texture(halvesTexture({0, 255, 0, 255}, {0, 255, 0, 255}));  // R 0 everywhere
    b.quad(b.material(Material{.name = "occluded",
                               .baseColorFactor = {0.8f, 0.8f, 0.8f, 1.0f},
                               .roughnessFactor = 0.9f,
                               .metallicRoughnessTexture = c.metallicRoughness == 0 ? halves : flatMr,
                               .occlusionTexture = c.occlusion < 0 ? -1 : halves,
                               .occlusionStrength = c.strength}));
    f.load(b.scene);
    const ImageRGBA32F hdr = f.render();
    const float left = luminance(windowMean(hdr, pixelOf(f.params.camera, {-0.5f, 0.0f, 0.0f}), 1));
    const float right = luminance(windowMean(hdr, pixelOf(f.params.camera, {0.5f, 0.0f, 0.0f}), 1));
    INFO("left " << left << ", right " << right);
    REQUIRE(right > 0.1f);
    CHECK(std::abs(left / right - c.expectedRatio) < 0.02f);
  }
  f.finish();
}

// ---------------------------------------------------------------------------------------------------------
// Winding of the procedural meshes (single-sided culling relies on counter-clockwise-outward triangles).

TEST_CASE("procedural meshes wind counter-clockwise around their outward normals", "[procedural][sided]") {
  const std::pair<const char*, MeshData> meshes[] = {
      {"plane", makePlane(2.0f, 3.0f, 3, 2)},     {"box", makeBox({1.0f, 2.0f, 3.0f}, 2)},
      {"sphere", makeSphere(1.0f, 12, 6)},        {"cylinder", makeCylinder(1.0f, 2.0f, 10, 2, true)},
      {"arch", makeArch(2.0f, 0.3f, 3.0f, 8, 6)},
  };
  for (const auto& [name, mesh] : meshes) {
    INFO(name);
    uint32_t wrong = 0, checked = 0;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
      const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
      const glm::vec3 n = glm::cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
      if (glm::length(n) < 1e-8f) continue;
      ++checked;
      if (glm::dot(n, mesh.normals[a] + mesh.normals[b] + mesh.normals[c]) <= 0.0f) ++wrong;
    }
    CHECK(checked > 0);
    CHECK(wrong == 0);
  }
}

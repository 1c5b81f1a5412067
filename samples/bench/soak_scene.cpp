#include "soak_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "scene_math.h"

namespace rbbench {

namespace {

constexpr VkBufferUsageFlags kGeometryUsage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                              VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;

// Surface roughness of the ground, in squares of 6 pixels: mirrors, glossy and rough (no reflection ray), so the
// reflection pass and its denoiser see every kind of pixel at every resolution.
float groundRoughness(uint32_t x, uint32_t y) {
  static constexpr float kRoughness[3] = {0.0f, 0.15f, 0.7f};
  return kRoughness[(x / 6 + y / 6) % 3];
}

}  // namespace

SoakSizes pickSoakSizes(const BenchOptions& o, bool isCpu) {
  SoakSizes s;
  if (o.quick || (isCpu && !o.full)) {
    s.resolutions = {{32, 18}, {48, 27}, {64, 36}, {40, 40}};
    s.sphereSlices = {12, 24};
    s.boxCells = {1, 5};
    s.bumpCells = {10, 20};
    s.cardCells = {1, 4};
    s.clothCells = {6, 10, 14};
    s.crowdCells = 8;
    s.dynamicSlots = 6;
    s.crowdKeys = 2;
    s.maxStaticMeshes = 24;
    s.maxInstances = 64;
    s.effectChurn = 0.25;
  } else {
    s.resolutions = {{1280, 720}, {1920, 1080}, {2560, 1440}, {1024, 1024}};
    s.sphereSlices = {48, 128};
    s.boxCells = {4, 24};
    s.bumpCells = {40, 90};
    s.cardCells = {1, 16};
    s.clothCells = {24, 36, 48};
    s.crowdCells = 32;
    s.dynamicSlots = 8;
    s.crowdKeys = 2;
    s.maxStaticMeshes = 64;
    s.maxInstances = 256;
  }
  return s;
}

SoakGBuffer uploadGroundGBuffer(BenchEnv& env, const FoliageView& view, const AnalyticGBuffer& g,
                                const std::string& what) {
  SoakGBuffer s;
  const uint32_t w = view.width, h = view.height;
  s.depth = uploadSampledImage(env, VK_FORMAT_D32_SFLOAT, VK_IMAGE_ASPECT_DEPTH_BIT, w, h, g.depth.data(),
                               g.depth.size() * sizeof(float), (what + " depth").c_str());
  s.normal = uploadSampledImage(env, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_ASPECT_COLOR_BIT, w, h, g.normal.data(),
                                g.normal.size() * sizeof(float), (what + " normal").c_str());
  s.desc.width = w;
  s.desc.height = h;
  s.desc.depth = {s.depth.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  s.desc.normal = {s.normal.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  s.desc.roughnessInNormalW = true;
  std::memcpy(s.desc.view, g.view, sizeof s.desc.view);
  std::memcpy(s.desc.projection, g.projection, sizeof s.desc.projection);
  for (int i = 0; i < 3; ++i) s.desc.cameraPosition[i] = view.eye[i];
  return s;
}

SoakScene::SoakScene(BenchEnv& env, const SoakSizes& sizes) : env_(env) {
  rb::HeadlessDevice& dev = env.device();

  // ---- static variants ----
  auto addStatic = [&](const std::string& name, const rbsamples::CpuMesh& cpu, bool nonOpaque, uint32_t material) {
    SoakStaticVariant v;
    v.name = name;
    v.mesh = env.upload(cpu, name);
    v.normals = check(dev.createBuffer(cpu.normals.size() * sizeof(float), kGeometryUsage, false, cpu.normals.data()),
                      "uploading the normals of " + name);
    v.nonOpaque = nonOpaque;
    v.material = material;
    v.desc = v.mesh.desc;
    v.desc.normalAddress = v.normals.address;
    v.desc.nonOpaque = nonOpaque;
    if (nonOpaque) {
      // Planar texture coordinates over the unit card: the leaf texture once across it.
      std::vector<float> uv;
      for (size_t i = 0; i + 2 < cpu.positions.size(); i += 3) {
        uv.push_back(cpu.positions[i] + 0.5f);
        uv.push_back(cpu.positions[i + 2] + 0.5f);
      }
      v.texcoords = check(dev.createBuffer(uv.size() * sizeof(float), kGeometryUsage, false, uv.data()),
                          "uploading the texture coordinates of " + name);
      v.desc.texcoordAddress = v.texcoords.address;
    }
    statics_.push_back(std::move(v));
  };
  for (uint32_t slices : sizes.sphereSlices) {
    addStatic("sphere " + std::to_string(slices), rbsamples::makeSphere(0.5f, slices, std::max(slices / 2, 3u)), false,
              statics_.size() % 2 ? 2u : 0u);
  }
  const float boxMin[3] = {-0.5f, -0.5f, -0.5f}, boxMax[3] = {0.5f, 0.5f, 0.5f};
  for (uint32_t cells : sizes.boxCells) {
    addStatic("box " + std::to_string(cells), rbsamples::makeBox(boxMin, boxMax, cells), false, 0);
  }
  for (uint32_t cells : sizes.bumpCells) {
    addStatic("tile " + std::to_string(cells), rbsamples::makeBumpyGrid(1.0f, cells, 0.05f), false, 2);
  }
  for (uint32_t cells : sizes.cardCells) {
    addStatic("leaf card " + std::to_string(cells), rbsamples::makeGrid(1.0f, cells), true, 1);
  }

  // ---- deforming meshes: cloth variants, the crowd's, and their vertex buffers ----
  auto makeCloth = [&](uint32_t cells) {
    SoakClothVariant c;
    c.cells = cells;
    const rbsamples::CpuMesh grid = rbsamples::makeGrid(1.0f, cells);
    c.rest = grid.positions;
    c.vertexCount = grid.vertexCount();
    c.triangleCount = grid.triangleCount();
    c.indices = check(dev.createBuffer(grid.indices.size() * sizeof(uint32_t), kGeometryUsage, false,
                                       grid.indices.data()),
                      "uploading the indices of a cloth of " + std::to_string(cells) + " cells");
    targetBytes_ = std::max<VkDeviceSize>(targetBytes_, VkDeviceSize(c.vertexCount) * 3 * sizeof(float));
    return c;
  };
  for (uint32_t cells : sizes.clothCells) cloths_.push_back(makeCloth(cells));
  crowd_ = makeCloth(sizes.crowdCells);
  for (uint32_t t = 0; t < sizes.dynamicSlots + sizes.crowdKeys; ++t) {
    targets_.push_back(check(dev.createBuffer(targetBytes_, kGeometryUsage, false), "creating a deforming mesh"));
  }
  for (uint32_t f = 0; f < env.ctx().framesInFlight(); ++f) {
    staging_.push_back(check(dev.createBuffer(targetBytes_ * targets_.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true),
                             "creating the deformation staging"));
  }

  // ---- G-buffers of the ground, one per resolution ----
  for (auto [w, h] : sizes.resolutions) {
    view_.width = w;
    view_.height = h;
    AnalyticGBuffer g = makeGroundGBuffer(view_);
    for (uint32_t y = 0; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) g.normal[(size_t(y) * w + x) * 4 + 3] = groundRoughness(x, y);
    }
    gbuffers_.push_back(uploadGroundGBuffer(env, view_, g, "a soak G-buffer"));
    if (gbuffers_.size() == 1) {
      // Objects float up to 1.2 above the ground the camera sees, shifted towards the sun so their shadows land
      // on it.
      const Vec3 sun = normalized(view_.toSun);
      const double run[2] = {sun[0] / sun[1], sun[2] / sun[1]};
      placeMin_[0] = g.groundMin[0] + std::min(0.0, run[0]);
      placeMax_[0] = g.groundMax[0] + std::max(0.0, run[0]);
      placeMin_[2] = g.groundMin[1] + std::min(0.0, run[1]);
      placeMax_[2] = g.groundMax[1] + std::max(0.0, run[1]);
      placeMin_[1] = 0.3;
      placeMax_[1] = 1.2;
    }
  }

  // ---- the leaf texture and the two material sets ----
  const LeafTexture leaf = makeLeafTexture();
  leaf_ = uploadSampledImage(env, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, leaf.width, leaf.height,
                             leaf.rgba.data(), leaf.rgba.size(), "the leaf texture");
  textureViews_ = {leaf_.view};
  rb::Material white, leafMask, mirror;
  leafMask.baseColorTexture = 0;
  leafMask.alphaMode = rb::AlphaMode::Mask;
  mirror.metallic = 1.0f;
  mirror.roughness = 0.05f;
  materialSets_[0] = {white, leafMask, mirror};
  rb::Material grey, leafBlend, gold;
  grey.baseColor[0] = grey.baseColor[1] = grey.baseColor[2] = 0.5f;
  leafBlend.baseColorTexture = 0;
  leafBlend.alphaMode = rb::AlphaMode::Blend;
  gold.baseColor[2] = 0.3f;
  gold.metallic = 1.0f;
  gold.roughness = 0.25f;
  materialSets_[1] = {grey, leafBlend, gold};
}

SoakScene::~SoakScene() {
  rb::HeadlessDevice& dev = env_.device();
  (void)dev.waitIdle();
  for (SoakStaticVariant& v : statics_) {
    env_.destroy(v.mesh);
    dev.destroyBuffer(v.normals);
    dev.destroyBuffer(v.texcoords);
  }
  for (SoakClothVariant& c : cloths_) dev.destroyBuffer(c.indices);
  dev.destroyBuffer(crowd_.indices);
  for (rb::HeadlessBuffer& b : targets_) dev.destroyBuffer(b);
  for (rb::HeadlessBuffer& b : staging_) dev.destroyBuffer(b);
  for (SoakGBuffer& g : gbuffers_) {
    destroySampledImage(env_, g.depth);
    destroySampledImage(env_, g.normal);
  }
  destroySampledImage(env_, leaf_);
}

rb::MeshDesc SoakScene::dynamicDesc(uint32_t target, const SoakClothVariant& variant) const {
  rb::MeshDesc d;
  d.vertexAddress = targets_.at(target).address;
  d.vertexBufferBytes = VkDeviceSize(variant.vertexCount) * 3 * sizeof(float);
  d.vertexCount = variant.vertexCount;
  d.indexAddress = variant.indices.address;
  d.indexBufferBytes = variant.indices.size;
  d.triangleCount = variant.triangleCount;
  d.role = rb::MeshRole::Dynamic;
  return d;
}

void SoakScene::recordDeform(VkCommandBuffer cmd, uint32_t frameSlot, std::span<const DeformRequest> requests,
                             float t) {
  if (requests.empty()) return;
  const rb::DeviceFunctions& vk = env_.vk();
  rb::HeadlessBuffer& staging = staging_.at(frameSlot);
  // Earlier frames read the vertex buffers (builds and refits, the refit measure's compute shader, reflection hits
  // shading with the positions) and wrote them (the previous copies): all done before this frame's copies.
  VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  before.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  before.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  constexpr VkPipelineStageFlags kReaders = VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR |
                                            VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                            VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  vk.vkCmdPipelineBarrier(cmd, kReaders | VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &before,
                          0, nullptr, 0, nullptr);
  for (const DeformRequest& r : requests) {
    const SoakClothVariant& v = *r.variant;
    float* out = reinterpret_cast<float*>(static_cast<char*>(staging.mapped) + targetBytes_ * r.target);
    // A travelling wave whose amplitude and stretch breathe: refits stretch the boxes, and now and then the
    // adaptive policy rebuilds.
    const float amplitude = 0.08f + 0.12f * std::sin(0.37f * t + r.phase) * std::sin(0.37f * t + r.phase);
    const float stretch = 1.0f + 0.5f * std::max(0.0f, std::sin(0.21f * t + 2.0f * r.phase));
    for (uint32_t i = 0; i < v.vertexCount; ++i) {
      const float x = v.rest[3 * i], z = v.rest[3 * i + 2];
      out[3 * i] = x * stretch;
      out[3 * i + 1] = amplitude * std::sin(9.0f * x + 2.3f * t + r.phase) * std::cos(7.0f * z + 1.1f * t);
      out[3 * i + 2] = z;
    }
    const VkDeviceSize bytes = VkDeviceSize(v.vertexCount) * 3 * sizeof(float);
    const VkBufferCopy region{targetBytes_ * r.target, 0, bytes};
    vk.vkCmdCopyBuffer(cmd, staging.buffer, targets_.at(r.target).buffer, 1, &region);
  }
  VkMemoryBarrier after{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  after.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  after.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_ACCELERATION_STRUCTURE_READ_BIT_KHR;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, kReaders, 0, 1, &after, 0, nullptr, 0, nullptr);
}

}  // namespace rbbench

#include "synthetic_gbuffer.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include <cmath>
#include <cstring>

namespace rbtest {

SyntheticView conformanceView(uint32_t width, uint32_t height, double fovYDegrees) {
  const rb::PrimaryRayCamera cam = conformanceCamera();
  SyntheticView v;
  v.eye = {cam.eye[0], cam.eye[1], cam.eye[2]};
  v.target = {cam.target[0], cam.target[1], cam.target[2]};
  v.fovYDegrees = fovYDegrees;
  v.width = width;
  v.height = height;
  return v;
}

SyntheticView motionTestView(uint32_t width, uint32_t height) {
  SyntheticView v;
  v.eye = {-6.0, 5.0, 8.0};
  v.target = {0.0, 0.5, 1.0};
  v.fovYDegrees = 45.0;
  v.width = width;
  v.height = height;
  return v;
}

CpuGBuffer traceGBuffer(const EmbreeScene& embree, const SyntheticView& v, const std::vector<float>& roughness) {
  CpuGBuffer g;
  g.view = v;
  const glm::dvec3 forward = glm::normalize(v.target - v.eye);
  g.viewMatrix = glm::mat4(glm::lookAtRH(glm::dvec3(0.0), forward, v.up));
  double aspect = double(v.width) / double(v.height);
  glm::dmat4 proj = glm::perspectiveRH_ZO(glm::radians(v.fovYDegrees), aspect, double(v.nearPlane), double(v.farPlane));
  if (v.reversedZ) {
    // Reversed-Z: map near to 1 and far to 0.
    glm::dmat4 flip(1.0);
    flip[2][2] = -1.0;
    flip[3][2] = 1.0;
    proj = flip * proj;
  }
  proj[1][1] *= -1.0;  // Vulkan: +Y down in NDC, so pixel row 0 is the top
  g.projection = glm::mat4(proj);
  const glm::dmat4 invViewProj = glm::inverse(proj * glm::dmat4(g.viewMatrix));
  const size_t n = size_t(v.width) * v.height;
  g.depth.assign(n, v.reversedZ ? 0.0f : 1.0f);
  g.normal.assign(n, glm::vec4(0.0f));
  g.hit.assign(n, 0);
  g.position.assign(n, glm::dvec3(0.0));
  g.instance.assign(n, 0xFFFFFFFFu);
  for (uint32_t y = 0; y < v.height; ++y) {
    for (uint32_t x = 0; x < v.width; ++x) {
      glm::dvec4 ndcFar((x + 0.5) / v.width * 2 - 1, (y + 0.5) / v.height * 2 - 1, 0.5, 1.0);
      glm::dvec4 p = invViewProj * ndcFar;
      glm::dvec3 dir = glm::normalize(glm::dvec3(p) / p.w);
      float o[3] = {float(v.eye.x), float(v.eye.y), float(v.eye.z)};
      float d[3] = {float(dir.x), float(dir.y), float(dir.z)};
      ReferenceHit h = embree.intersect(o, d, 0.0f, 1e30f);
      size_t i = size_t(y) * v.width + x;
      if (!h.hit || h.t > v.farPlane * 0.99f) continue;
      glm::dvec3 rel = glm::dvec3(dir) * double(h.t);
      glm::dvec4 clip = proj * glm::dmat4(g.viewMatrix) * glm::dvec4(rel, 1.0);
      g.depth[i] = float(clip.z / clip.w);
      glm::dvec3 ng = glm::normalize(glm::dvec3(h.geometricNormal[0], h.geometricNormal[1], h.geometricNormal[2]));
      if (glm::dot(ng, dir) > 0) ng = -ng;
      g.normal[i] = glm::vec4(glm::vec3(ng), h.instanceId < roughness.size() ? roughness[h.instanceId] : 0.0f);
      g.hit[i] = 1;
      g.position[i] = v.eye + rel;
      g.instance[i] = h.instanceId;
    }
  }
  return g;
}

SampledImage uploadSampledImage(GpuFixture& fx, VkFormat format, VkImageAspectFlags aspect, uint32_t width,
                                uint32_t height, const void* data, size_t bytes) {
  const rb::DeviceFunctions& vk = fx.vk();
  VkDevice device = fx.ctx().device();
  SampledImage img;
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = format;
  ici.extent = {width, height, 1};
  ici.mipLevels = ici.arrayLayers = 1;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  REQUIRE(vk.vkCreateImage(device, &ici, nullptr, &img.image) == VK_SUCCESS);
  VkMemoryRequirements req;
  vk.vkGetImageMemoryRequirements(device, img.image, &req);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = uint32_t(
      rb::internal::contextImpl(fx.ctx()).findMemoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0));
  REQUIRE(vk.vkAllocateMemory(device, &mai, nullptr, &img.memory) == VK_SUCCESS);
  vk.vkBindImageMemory(device, img.image, img.memory, 0);
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = img.image;
  vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {aspect, 0, 1, 0, 1};
  REQUIRE(vk.vkCreateImageView(device, &vci, nullptr, &img.view) == VK_SUCCESS);

  auto staging = fx.device().createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true, data);
  RB_REQUIRE_OK(staging);
  auto cmd = fx.device().beginCommands();
  RB_REQUIRE_OK(cmd);
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = img.image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  vk.vkCmdPipelineBarrier(cmd.value(), VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr,
                          0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {aspect, 0, 0, 1};
  region.imageExtent = {width, height, 1};
  vk.vkCmdCopyBufferToImage(cmd.value(), staging->buffer, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
  b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  vk.vkCmdPipelineBarrier(cmd.value(), VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, 0,
                          0, nullptr, 0, nullptr, 1, &b);
  RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));
  fx.device().destroyBuffer(staging.value());
  return img;
}

void destroySampledImage(GpuFixture& fx, SampledImage& image) {
  const rb::DeviceFunctions& vk = fx.vk();
  VkDevice device = fx.ctx().device();
  vk.vkDestroyImageView(device, image.view, nullptr);
  vk.vkDestroyImage(device, image.image, nullptr);
  vk.vkFreeMemory(device, image.memory, nullptr);
  image = {};
}

GpuGBuffer::GpuGBuffer(GpuFixture& fx, const CpuGBuffer& cpu) : fx_(fx) {
  desc_.width = cpu.view.width;
  desc_.height = cpu.view.height;
  depth_ = uploadSampledImage(fx, VK_FORMAT_D32_SFLOAT, VK_IMAGE_ASPECT_DEPTH_BIT, desc_.width, desc_.height,
                              cpu.depth.data(), cpu.depth.size() * 4);
  normal_ = uploadSampledImage(fx, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_ASPECT_COLOR_BIT, desc_.width, desc_.height,
                               cpu.normal.data(), cpu.normal.size() * 16);
  desc_.depth = {depth_.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  desc_.depthConvention = cpu.view.reversedZ ? rb::DepthConvention::ReversedZ : rb::DepthConvention::Standard;
  desc_.normal = {normal_.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  desc_.roughnessInNormalW = true;
  std::memcpy(desc_.view, &cpu.viewMatrix[0][0], sizeof desc_.view);
  std::memcpy(desc_.projection, &cpu.projection[0][0], sizeof desc_.projection);
  desc_.cameraPosition[0] = cpu.view.eye.x;
  desc_.cameraPosition[1] = cpu.view.eye.y;
  desc_.cameraPosition[2] = cpu.view.eye.z;
}

GpuGBuffer::~GpuGBuffer() {
  (void)fx_.device().waitIdle();
  destroySampledImage(fx_, depth_);
  destroySampledImage(fx_, normal_);
}

void runPassFrame(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu, bool shadingRecords,
                  const PassRecorder& record, const PassReadback& readback) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);
  rb::GBufferDesc desc = gbuffer.desc();
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto tlas = service.value()->recordTlasBuild(cmd, built.instances, gbuffer.cameraRelativeTlas(shadingRecords));
    RB_REQUIRE_OK(tlas);
    record(cmd, desc, tlas.value());
  });
  readback(desc);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
}

namespace {
float halfToFloat(uint16_t h) {
  uint32_t sign = (h >> 15) & 1, exp = (h >> 10) & 31, mant = h & 1023;
  float v;
  if (exp == 0) v = std::ldexp(float(mant), -24);
  else if (exp == 31)
    v = mant ? NAN : INFINITY;
  else
    v = std::ldexp(float(mant | 1024), int(exp) - 25);
  return sign ? -v : v;
}
}  // namespace

std::vector<uint8_t> readPassImage(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height,
                                   uint32_t bytesPerPixel) {
  const rb::DeviceFunctions& vk = fx.vk();
  VkDeviceSize bytes = VkDeviceSize(width) * height * bytesPerPixel;
  auto staging = fx.device().createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  RB_REQUIRE_OK(staging);
  auto cmd = fx.device().beginCommands();
  RB_REQUIRE_OK(cmd);
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vk.vkCmdPipelineBarrier(cmd.value(), VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                          nullptr, 0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {width, height, 1};
  vk.vkCmdCopyImageToBuffer(cmd.value(), image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging->buffer, 1, &region);
  // Back to the layout the pass promised, so later frames start from it.
  b.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  vk.vkCmdPipelineBarrier(cmd.value(), VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0,
                          nullptr, 0, nullptr, 1, &b);
  RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));
  std::vector<uint8_t> out(bytes);
  std::memcpy(out.data(), staging->mapped, bytes);
  fx.device().destroyBuffer(staging.value());
  return out;
}

std::vector<float> readR16f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height) {
  std::vector<uint8_t> raw = readPassImage(fx, image, width, height, 2);
  std::vector<float> out(size_t(width) * height);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t h;
    std::memcpy(&h, raw.data() + 2 * i, 2);
    out[i] = halfToFloat(h);
  }
  return out;
}

std::vector<float> readRgba16f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height) {
  std::vector<uint8_t> raw = readPassImage(fx, image, width, height, 8);
  std::vector<float> out(size_t(width) * height * 4);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t h;
    std::memcpy(&h, raw.data() + 2 * i, 2);
    out[i] = halfToFloat(h);
  }
  return out;
}

std::vector<float> readR32f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height) {
  std::vector<uint8_t> raw = readPassImage(fx, image, width, height, 4);
  std::vector<float> out(size_t(width) * height);
  std::memcpy(out.data(), raw.data(), raw.size());
  return out;
}

std::vector<float> historyFrames(GpuFixture& fx, const rb::Denoiser& denoiser) {
  const rb::DenoiseHistory h = denoiser.history();
  REQUIRE(h.meanImage != VK_NULL_HANDLE);
  // Scalar: RG16F (mean, frames); Rgb and Reflection: RGBA16F (mean colour, frames).
  const size_t texel = denoiser.signal() == rb::DenoiseSignal::Scalar ? 4 : 8;
  const std::vector<uint8_t> raw = readPassImage(fx, h.meanImage, h.width, h.height, uint32_t(texel));
  std::vector<float> frames(size_t(h.width) * h.height);
  for (size_t i = 0; i < frames.size(); ++i) {
    uint16_t half;
    std::memcpy(&half, raw.data() + texel * i + texel - 2, 2);
    frames[i] = glm::unpackHalf1x16(half);
  }
  return frames;
}

}  // namespace rbtest

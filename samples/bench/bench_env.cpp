#include "bench_env.h"

#include <cstdio>
#include <cstring>

namespace rbbench {

void check(const rb::Status& s, const std::string& what) {
  if (!s) throw BenchFailure(what + ": " + rb::toString(s.error().code) + ": " + s.error().message);
}

namespace {

BenchSizes pickSizes(const BenchOptions& o, bool isCpu) {
  BenchSizes s;
  if (o.quick) {
    s.buildTriangles = {1000, 10000};
    s.buildRepeats = 2;
    s.duplicationTriangles = 2000;
    s.duplicationCopies = {1, 4, 16, 64};
    s.fastTriangles = 10000;
    s.fastRepeats = 2;
    s.tlasInstances = {1000, 10000};
    s.tlasRepeats = 3;
    s.motionInstances = 1000;
    s.motionFrames = 4;
    s.traceTriangles = 20000;
    s.traceRepeats = 2;
    s.gltfRepeatsOnce = true;
  } else if (isCpu && !o.full) {  // sizes for a 2-core lavapipe run of a few minutes
    s.buildTriangles = {1000, 10000, 100000, 300000};
    s.buildRepeats = 9;
    s.duplicationTriangles = 20000;
    s.duplicationCopies = {1, 4, 16, 64};
    s.fastTriangles = 100000;
    s.fastRepeats = 9;
    s.tlasInstances = {1000, 10000, 100000};
    s.tlasRepeats = 9;
    s.motionInstances = 4000;
    s.motionFrames = 128;
    s.traceTriangles = 200000;
    s.traceRepeats = 5;
  } else {  // a GPU, or --full
    s.buildTriangles = {1000, 10000, 100000, 1000000};
    if (o.full && !isCpu) s.buildTriangles.push_back(4000000);
    s.buildRepeats = isCpu ? 3 : 7;
    s.duplicationTriangles = 100000;
    s.duplicationCopies = {1, 4, 16, 64};
    s.fastTriangles = 500000;
    s.fastRepeats = isCpu ? 3 : 7;
    s.tlasInstances = {1000, 10000, 100000};
    if (!isCpu) s.tlasInstances.push_back(1000000);
    s.tlasRepeats = isCpu ? 3 : 9;
    s.motionInstances = 10000;
    s.motionFrames = isCpu ? 128 : 1024;
    s.traceTriangles = 1000000;
    s.traceRepeats = isCpu ? 2 : 10;
  }
  if (o.width) {
    s.width = o.width;
    s.height = o.height;
  } else if (!isCpu) {
    s.width = 1920;
    s.height = 1080;
  } else if (o.quick) {
    s.width = 320;
    s.height = 180;
  } else {
    s.width = 640;
    s.height = 360;
  }
  return s;
}

}  // namespace

BenchEnv::BenchEnv(const BenchOptions& options) : options_(options) {
  rb::HeadlessDeviceDesc dd;
  dd.deviceNameFilter = options.device.empty() ? nullptr : options.device.c_str();
  device_ = check(rb::HeadlessDevice::create(dd), "creating the headless device");
  ctx_ = check(rb::Context::create(device_->contextDesc()), "creating the Raybridge context");
  sizes_ = pickSizes(options, info().isCpu);
  if (!info().timestampsSupported) {
    throw BenchFailure("device '" + info().deviceName + "' does not support timestamps on its queues");
  }
  uint32_t n = 0;
  vk().vkGetPhysicalDeviceQueueFamilyProperties(device_->physicalDevice(), &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vk().vkGetPhysicalDeviceQueueFamilyProperties(device_->physicalDevice(), &n, families.data());
  timestampValidBits_ = families.at(device_->queueFamily()).timestampValidBits;
  if (timestampValidBits_ == 0) throw BenchFailure("the queue family has no valid timestamp bits");
}

BenchEnv::~BenchEnv() {
  if (device_) (void)device_->waitIdle();
  ctx_.reset();
}

UploadedMesh BenchEnv::upload(const rbsamples::CpuMesh& mesh, const std::string& name) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                   VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  UploadedMesh out;
  out.vertices = check(device_->createBuffer(mesh.positions.size() * sizeof(float), usage, false,
                                             mesh.positions.data()),
                       "uploading the vertices of " + name);
  out.indices = check(device_->createBuffer(mesh.indices.size() * sizeof(uint32_t), usage, false, mesh.indices.data()),
                      "uploading the indices of " + name);
  out.desc.vertexAddress = out.vertices.address;
  out.desc.vertexBufferBytes = out.vertices.size;
  out.desc.vertexCount = mesh.vertexCount();
  out.desc.indexAddress = out.indices.address;
  out.desc.indexBufferBytes = out.indices.size;
  out.desc.triangleCount = mesh.triangleCount();
  out.triangles = mesh.triangleCount();
  return out;
}

void BenchEnv::destroy(UploadedMesh& mesh) {
  device_->destroyBuffer(mesh.vertices);
  device_->destroyBuffer(mesh.indices);
}

void BenchEnv::runFrame(const std::function<void(VkCommandBuffer)>& record) {
  ctx_->beginFrame();
  VkCommandBuffer cmd = check(device_->beginCommands(), "beginning a command buffer");
  record(cmd);
  check(device_->submitAndWait(cmd), "submitting a frame");
}

void BenchEnv::settle() {
  for (uint32_t i = 0; i < ctx_->framesInFlight(); ++i) ctx_->beginFrame();
}

BenchEnv::TraceTargets BenchEnv::makeTraceTargets(uint32_t width, uint32_t height) {
  TraceTargets t;
  t.distance = check(rb::createStorageImage(*ctx_, width, height, VK_FORMAT_R32_SFLOAT, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                            rb::MemoryCategory::PassImages, "bench hit distance"),
                     "creating the hit distance image");
  t.ids = check(rb::createStorageImage(*ctx_, width, height, VK_FORMAT_R32G32_UINT, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                       rb::MemoryCategory::PassImages, "bench hit ids"),
                "creating the hit id image");
  return t;
}

void BenchEnv::destroyTraceTargets(TraceTargets& t) {
  rb::destroyImage(*ctx_, t.distance);
  rb::destroyImage(*ctx_, t.ids);
}

void BenchEnv::recordTraceBarrier(VkCommandBuffer cmd, TraceTargets& t) {
  VkImageMemoryBarrier b[2] = {{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER}, {VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER}};
  const VkImage images[2] = {t.distance.image, t.ids.image};
  for (int i = 0; i < 2; ++i) {
    b[i].srcAccessMask = t.inGeneral ? VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT : 0;
    b[i].dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    b[i].oldLayout = t.inGeneral ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_UNDEFINED;
    b[i].newLayout = VK_IMAGE_LAYOUT_GENERAL;
    b[i].srcQueueFamilyIndex = b[i].dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b[i].image = images[i];
    b[i].subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  }
  VkPipelineStageFlags src = t.inGeneral ? VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_TRANSFER_BIT
                                         : VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT;
  vk().vkCmdPipelineBarrier(cmd, src, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, 0, 0, nullptr, 0, nullptr, 2, b);
  t.inGeneral = true;
}

double BenchEnv::hitFraction(const TraceTargets& t) {
  const uint32_t w = t.distance.width, h = t.distance.height;
  const VkDeviceSize bytes = VkDeviceSize(w) * h * sizeof(float);
  rb::HeadlessBuffer staging = check(device_->createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true),
                                     "creating a readback buffer");
  VkCommandBuffer cmd = check(device_->beginCommands(), "beginning a readback");
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.oldLayout = b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = t.distance.image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                            nullptr, 0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {w, h, 1};
  vk().vkCmdCopyImageToBuffer(cmd, t.distance.image, VK_IMAGE_LAYOUT_GENERAL, staging.buffer, 1, &region);
  check(device_->submitAndWait(cmd), "reading back the hit distance image");
  std::vector<float> d(size_t(w) * h);
  std::memcpy(d.data(), staging.mapped, bytes);
  device_->destroyBuffer(staging);
  size_t hits = 0;
  for (float v : d) hits += v > 0.0f;
  return d.empty() ? 0.0 : double(hits) / double(d.size());
}

void BenchEnv::progress(const std::string& line) const { std::fprintf(stderr, "[bench] %s\n", line.c_str()); }

}  // namespace rbbench

#include "test_support.h"

#include <cstring>

namespace rbtest {

GpuFixture::GpuFixture(uint32_t framesInFlight, bool requestAsyncComputeQueue) {
  rb::HeadlessDeviceDesc desc;
  desc.enableValidation = true;
  desc.requireValidation = true;
  desc.framesInFlight = framesInFlight;
  desc.requestAsyncComputeQueue = requestAsyncComputeQueue;
  auto device = rb::HeadlessDevice::create(desc);
  INFO((device.ok() ? std::string() : device.error().message));
  REQUIRE(device.ok());
  device_ = std::move(device.value());
  auto ctx = rb::Context::create(device_->contextDesc());
  INFO((ctx.ok() ? std::string() : ctx.error().message));
  REQUIRE(ctx.ok());
  ctx_ = std::move(ctx.value());
}

GpuFixture::~GpuFixture() {
  if (device_) (void)device_->waitIdle();
  ctx_.reset();
  if (device_) {
    uint32_t errors = device_->validationErrorCount();
    if (errors) {
      for (const std::string& e : device_->validationErrors()) UNSCOPED_INFO(e);
    }
    CHECK(errors == 0);
  }
  UNSCOPED_INFO(liveUploads_ << " mesh(es) from GpuFixture::upload were not destroyed: call destroyScene or "
                                "GpuFixture::destroy before the test ends");
  CHECK(liveUploads_ == 0);
}

UploadedMesh GpuFixture::upload(const rbsamples::CpuMesh& mesh, bool withHostCopies) {
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                   VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                   VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  UploadedMesh out;
  auto v = device_->createBuffer(mesh.positions.size() * sizeof(float), usage, false, mesh.positions.data());
  RB_REQUIRE_OK(v);
  auto i = device_->createBuffer(mesh.indices.size() * sizeof(uint32_t), usage, false, mesh.indices.data());
  RB_REQUIRE_OK(i);
  out.vertices = v.value();
  out.indices = i.value();
  ++liveUploads_;
  out.desc.vertexAddress = out.vertices.address;
  out.desc.vertexBufferBytes = out.vertices.size;
  out.desc.vertexCount = mesh.vertexCount();
  out.desc.indexAddress = out.indices.address;
  out.desc.indexBufferBytes = out.indices.size;
  out.desc.triangleCount = mesh.triangleCount();
  if (withHostCopies) {
    // Kept alive with the upload: callers often pass a temporary mesh.
    out.source = std::make_shared<const rbsamples::CpuMesh>(mesh);
    out.desc.hostVertices = out.source->positions.data();
    out.desc.hostIndices = out.source->indices.data();
  }
  return out;
}

void GpuFixture::destroy(UploadedMesh& mesh) {
  if (mesh.vertices.buffer && liveUploads_) --liveUploads_;
  device_->destroyBuffer(mesh.vertices);
  device_->destroyBuffer(mesh.indices);
}

void GpuFixture::runFrame(const std::function<void(VkCommandBuffer)>& record) {
  ctx_->beginFrame();
  auto cmd = device_->beginCommands();
  RB_REQUIRE_OK(cmd);
  record(cmd.value());
  RB_REQUIRE_OK(device_->submitAndWait(cmd.value()));
}

void GpuFixture::runAndSettle(const std::function<void(VkCommandBuffer)>& record) {
  runFrame(record);
  for (uint32_t i = 0; i < ctx_->framesInFlight(); ++i) ctx_->beginFrame();
}

rb::GpuImage GpuFixture::makeImage(uint32_t w, uint32_t h, VkFormat format) {
  auto img = rb::createStorageImage(*ctx_, w, h, format, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                    rb::MemoryCategory::PassImages, "test image");
  RB_REQUIRE_OK(img);
  return img.value();
}

void GpuFixture::toGeneral(VkCommandBuffer cmd, const rb::GpuImage& image) {
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = 0;
  b.dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, 0, 0,
                            nullptr, 0, nullptr, 1, &b);
}

std::vector<uint8_t> GpuFixture::readImage(const rb::GpuImage& image, uint32_t bytesPerPixel) {
  VkDeviceSize bytes = VkDeviceSize(image.width) * image.height * bytesPerPixel;
  auto staging = device_->createBuffer(bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  RB_REQUIRE_OK(staging);
  auto cmd = device_->beginCommands();
  RB_REQUIRE_OK(cmd);
  VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_GENERAL;
  b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image.image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vk().vkCmdPipelineBarrier(cmd.value(), VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                            nullptr, 0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {image.width, image.height, 1};
  vk().vkCmdCopyImageToBuffer(cmd.value(), image.image, VK_IMAGE_LAYOUT_GENERAL, staging->buffer, 1, &region);
  RB_REQUIRE_OK(device_->submitAndWait(cmd.value()));
  std::vector<uint8_t> out(bytes);
  std::memcpy(out.data(), staging->mapped, bytes);
  device_->destroyBuffer(staging.value());
  return out;
}

std::string sharedScenesDir() { return std::string(RAYBRIDGE_SOURCE_DIR) + "/../shared/scenes"; }

}  // namespace rbtest

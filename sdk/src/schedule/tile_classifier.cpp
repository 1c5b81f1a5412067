#include "tile_classifier.h"

#include "context_impl.h"
#include "memory_barrier.h"
#include "raybridge_shader_interface.glsl"

namespace rb {

namespace {
constexpr uint32_t kTileSize = RB_SHADOW_TILE_SIZE;
constexpr VkDeviceSize kHeaderBytes = RB_SHADOW_TILE_HEADER_UINTS * sizeof(uint32_t);
static_assert(kHeaderBytes >= sizeof(VkTraceRaysIndirectCommandKHR), "the header holds the trace arguments");
}  // namespace

Status TileClassifier::init(Context& ctx, const SpirvModule& shader,
                            const std::vector<VkDescriptorSetLayoutBinding>& bindings, uint32_t pushConstantBytes,
                            const char* name) {
  Result<ComputePipeline> p = ComputePipeline::create(ctx, shader, bindings, pushConstantBytes, name);
  if (!p) return p.error();
  pipeline_ = p.value();
  return {};
}

void TileClassifier::retire(Context& ctx) {
  pipeline_.retire(ctx);
  retireBuffer(ctx, list_);
  retireBuffer(ctx, state_);
  width_ = height_ = 0;
}

VkDeviceSize TileClassifier::listBytes(uint32_t width, uint32_t height) {
  const VkDeviceSize tiles = VkDeviceSize((width + kTileSize - 1) / kTileSize) * ((height + kTileSize - 1) / kTileSize);
  return kHeaderBytes + tiles * sizeof(uint32_t);
}

Status TileClassifier::ensure(Context& ctx, uint32_t width, uint32_t height, bool withList) {
  if (list_.valid() == withList && state_.valid() && width == width_ && height == height_) return {};
  retireBuffer(ctx, list_);
  retireBuffer(ctx, state_);
  if (withList) {
    Result<GpuBuffer> b = createBuffer(ctx, listBytes(width, height),
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                           VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers, "tile list");
    if (!b) return b.error();
    list_ = b.value();
  }
  const VkDeviceSize tiles = (listBytes(width, height) - kHeaderBytes) / sizeof(uint32_t);
  Result<GpuBuffer> st = createBuffer(ctx, tiles * sizeof(uint32_t),
                                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                      MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers, "tile state");
  if (!st) return st.error();
  state_ = st.value();
  stateReset_ = true;
  width_ = width;
  height_ = height;
  return {};
}

void TileClassifier::writeList(DescriptorWrites& w, uint32_t binding) const {
  w.storageBuffer(binding, list_.buffer, 0, list_.size);
}

void TileClassifier::writeState(DescriptorWrites& w, uint32_t binding) const {
  w.storageBuffer(binding, state_.buffer, 0, state_.size);
}

void TileClassifier::classify(Context& ctx, VkCommandBuffer cmd, const DescriptorWrites& w, const void* constants,
                              uint32_t constantBytes) const {
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  // The previous frame's launch and ray generation shaders are done with the list before it is reset.
  VkBufferMemoryBarrier reuse{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  reuse.srcAccessMask = VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
  reuse.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  reuse.srcQueueFamilyIndex = reuse.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  reuse.buffer = list_.buffer;
  reuse.size = VK_WHOLE_SIZE;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
                          VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 1,
                          &reuse, 0, nullptr);
  // No tile yet: width 0, and the rows of a tile.
  const uint32_t header[RB_SHADOW_TILE_HEADER_UINTS] = {0, kTileSize, 1, 0};
  vk.vkCmdUpdateBuffer(cmd, list_.buffer, 0, kHeaderBytes, header);
  VkBufferMemoryBarrier reset = reuse;
  reset.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  reset.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 1,
                          &reset, 0, nullptr);
  pipeline_.dispatch(ctx, cmd, w.writes, constants, constantBytes, width_, height_);
  // Everything the classifier wrote: the arguments (read by the launch), the list, the skipped tiles' outputs and
  // the counters (which the ray generation shaders write after it).
  recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                      VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT | VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR,
                      VK_ACCESS_INDIRECT_COMMAND_READ_BIT | VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
}

}  // namespace rb

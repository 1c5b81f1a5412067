// Host copies of the pre-pass and effect images, recorded in the pre-pass hook (see the header).
#include "frame_capture.h"

#include <cstring>
#include <string>

namespace rbRender {

namespace se = sample_engine;

namespace {

struct HostBuffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  VkDeviceSize size = 0;
};

float halfToFloat(uint16_t h) {
  const uint32_t sign = uint32_t(h >> 15) << 31, exp = (h >> 10) & 0x1f, mant = h & 0x3ff;
  float magnitude;
  if (exp == 0) magnitude = float(mant) * (1.0f / 16777216.0f);  // subnormal: mant * 2^-24
  else if (exp == 31)
    magnitude = mant ? __builtin_nanf("") : __builtin_inff();
  else {
    uint32_t bits = ((exp + 112) << 23) | (mant << 13);
    std::memcpy(&magnitude, &bits, 4);
  }
  return sign ? -magnitude : magnitude;
}

}  // namespace

struct FrameCapture::Impl {
  VkDevice device = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory{};
  PFN_vkCreateBuffer createBuffer = nullptr;
  PFN_vkDestroyBuffer destroyBuffer = nullptr;
  PFN_vkGetBufferMemoryRequirements getRequirements = nullptr;
  PFN_vkAllocateMemory allocate = nullptr;
  PFN_vkFreeMemory free = nullptr;
  PFN_vkBindBufferMemory bind = nullptr;
  PFN_vkMapMemory map = nullptr;
  PFN_vkCmdPipelineBarrier barrier = nullptr;
  PFN_vkCmdCopyImageToBuffer copy = nullptr;
  HostBuffer depth, normal;
  std::vector<HostBuffer> extra;  // one per distinct captured image
  struct Named {
    std::string name;
    size_t buffer;
    uint32_t channels;
    bool float32;
  };
  std::vector<Named> names;
  uint32_t width = 0, height = 0;

  std::string ensure(HostBuffer& b, VkDeviceSize size);
  void release(HostBuffer& b) {
    if (b.buffer) destroyBuffer(device, b.buffer, nullptr);
    if (b.memory) free(device, b.memory, nullptr);
    b = {};
  }
  ~Impl() {
    for (HostBuffer* b : {&depth, &normal}) release(*b);
    for (HostBuffer& b : extra) release(b);
  }
};

std::string FrameCapture::Impl::ensure(HostBuffer& b, VkDeviceSize size) {
  if (b.size == size) return {};
  release(b);
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = size;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  if (createBuffer(device, &bi, nullptr, &b.buffer) != VK_SUCCESS) return "vkCreateBuffer failed";
  VkMemoryRequirements req;
  getRequirements(device, b.buffer, &req);
  const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = UINT32_MAX;
  for (uint32_t i = 0; i < memory.memoryTypeCount && ai.memoryTypeIndex == UINT32_MAX; ++i) {
    if ((req.memoryTypeBits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & want) == want)
      ai.memoryTypeIndex = i;
  }
  if (ai.memoryTypeIndex == UINT32_MAX) return "no host-visible coherent memory type";
  if (allocate(device, &ai, nullptr, &b.memory) != VK_SUCCESS) return "vkAllocateMemory failed";
  if (bind(device, b.buffer, b.memory, 0) != VK_SUCCESS) return "vkBindBufferMemory failed";
  if (map(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped) != VK_SUCCESS) return "vkMapMemory failed";
  b.size = size;
  return {};
}

FrameCapture::FrameCapture(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FrameCapture::~FrameCapture() = default;

se::Result<std::unique_ptr<FrameCapture>> FrameCapture::create(se::Engine& engine) {
  using R = se::Result<std::unique_ptr<FrameCapture>>;
  auto impl = std::make_unique<Impl>();
  PFN_vkGetInstanceProcAddr gipa = engine.getInstanceProcAddr();
  VkInstance instance = engine.instance();
  auto gdpa = reinterpret_cast<PFN_vkGetDeviceProcAddr>(gipa(instance, "vkGetDeviceProcAddr"));
  auto memoryProps = reinterpret_cast<PFN_vkGetPhysicalDeviceMemoryProperties>(
      gipa(instance, "vkGetPhysicalDeviceMemoryProperties"));
  if (!gdpa || !memoryProps) return R::failure("frame capture: cannot load Vulkan entry points");
  memoryProps(engine.physicalDevice(), &impl->memory);
  Impl& c = *impl;
  c.device = engine.device();
  auto load = [&](auto& fn, const char* name) {
    fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(gdpa(c.device, name));
    return fn != nullptr;
  };
  bool ok = load(c.createBuffer, "vkCreateBuffer") && load(c.destroyBuffer, "vkDestroyBuffer") &&
            load(c.getRequirements, "vkGetBufferMemoryRequirements") && load(c.allocate, "vkAllocateMemory") &&
            load(c.free, "vkFreeMemory") && load(c.bind, "vkBindBufferMemory") && load(c.map, "vkMapMemory") &&
            load(c.barrier, "vkCmdPipelineBarrier") && load(c.copy, "vkCmdCopyImageToBuffer");
  if (!ok) return R::failure("frame capture: cannot load Vulkan device functions");
  return R::success(std::unique_ptr<FrameCapture>(new FrameCapture(std::move(impl))));
}

se::Status FrameCapture::record(const se::PrepassHookInfo& info, const se::PassImage& normal,
                                const std::vector<CaptureImage>& images) {
  Impl& c = *impl_;
  c.width = info.extent.width;
  c.height = info.extent.height;
  const VkDeviceSize pixels = VkDeviceSize(c.width) * c.height;
  std::string e = c.ensure(c.depth, pixels * 4);
  if (e.empty()) e = c.ensure(c.normal, pixels * 8);
  // Distinct images, each copied once.
  std::vector<const CaptureImage*> distinct;
  c.names.clear();
  for (const CaptureImage& img : images) {
    if (!img.image) continue;
    size_t k = 0;
    while (k < distinct.size() && distinct[k]->image != img.image) ++k;
    if (k == distinct.size()) distinct.push_back(&img);
    c.names.push_back({img.name, k, img.channels, img.float32});
  }
  if (c.extra.size() < distinct.size()) c.extra.resize(distinct.size());
  for (size_t k = 0; k < distinct.size() && e.empty(); ++k)
    e = c.ensure(c.extra[k], pixels * (distinct[k]->float32 ? 4 : 2) * distinct[k]->channels);
  if (!e.empty()) return se::Status::failure("frame capture: " + e);

  struct Target {
    VkImage image;
    VkImageAspectFlags aspect;
    VkImageLayout layout;
    VkBuffer buffer;
  };
  std::vector<Target> targets = {{info.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, info.depth.layout, c.depth.buffer},
                                 {normal.image, VK_IMAGE_ASPECT_COLOR_BIT, normal.layout, c.normal.buffer}};
  for (size_t k = 0; k < distinct.size(); ++k)
    targets.push_back(
        {distinct[k]->image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, c.extra[k].buffer});

  auto transition = [&](bool toTransfer) {
    std::vector<VkImageMemoryBarrier> barriers;
    for (const Target& t : targets) {
      VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
      b.srcAccessMask = toTransfer ? VK_ACCESS_MEMORY_WRITE_BIT : 0;
      b.dstAccessMask = toTransfer ? VK_ACCESS_TRANSFER_READ_BIT : VK_ACCESS_SHADER_READ_BIT;
      if (!toTransfer && t.aspect == VK_IMAGE_ASPECT_DEPTH_BIT)
        b.dstAccessMask |= VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
      b.oldLayout = toTransfer ? t.layout : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
      b.newLayout = toTransfer ? VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL : t.layout;
      b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
      b.image = t.image;
      b.subresourceRange = {t.aspect, 0, 1, 0, 1};
      barriers.push_back(b);
    }
    c.barrier(info.commandBuffer, toTransfer ? VK_PIPELINE_STAGE_ALL_COMMANDS_BIT : VK_PIPELINE_STAGE_TRANSFER_BIT,
              toTransfer ? VK_PIPELINE_STAGE_TRANSFER_BIT : VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, 0, 0, nullptr, 0,
              nullptr, uint32_t(barriers.size()), barriers.data());
  };
  transition(true);
  for (const Target& t : targets) {
    VkBufferImageCopy region{};
    region.imageSubresource = {t.aspect, 0, 0, 1};
    region.imageExtent = {c.width, c.height, 1};
    c.copy(info.commandBuffer, t.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, t.buffer, 1, &region);
  }
  transition(false);
  VkMemoryBarrier host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  c.barrier(info.commandBuffer, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &host, 0, nullptr, 0,
            nullptr);
  return se::Status::success();
}

CapturedFrame FrameCapture::read() const {
  const Impl& c = *impl_;
  CapturedFrame f;
  f.width = c.width;
  f.height = c.height;
  const size_t pixels = size_t(c.width) * c.height;
  if (!c.depth.mapped) return f;
  f.depth.resize(pixels);
  std::memcpy(f.depth.data(), c.depth.mapped, pixels * 4);
  f.normal.resize(pixels * 4);
  const auto* n = static_cast<const uint16_t*>(c.normal.mapped);
  for (size_t i = 0; i < pixels * 4; ++i) f.normal[i] = halfToFloat(n[i]);
  for (const Impl::Named& n : c.names) {
    std::vector<float>& out = f.images[n.name];
    out.resize(pixels * n.channels);
    if (n.float32) {
      std::memcpy(out.data(), c.extra[n.buffer].mapped, out.size() * sizeof(float));
      continue;
    }
    const auto* v = static_cast<const uint16_t*>(c.extra[n.buffer].mapped);
    for (size_t i = 0; i < out.size(); ++i) out[i] = halfToFloat(v[i]);
  }
  return f;
}

}  // namespace rbRender

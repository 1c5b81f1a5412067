#include "adaptive_rays.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "context_impl.h"
#include "denoiser_history.h"
#include "image_barriers.h"
#include "memory_barrier.h"
#include "pass_core.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {
// RbPlanCounters (adaptive_rays.glsl).
constexpr VkDeviceSize kCounterBytes = 4 * sizeof(uint32_t);
}  // namespace

uint32_t adaptiveMaxRays(const AdaptiveRaySettings& s, uint32_t raysPerPixel) {
  const uint32_t rays = s.maxRaysPerPixel ? s.maxRaysPerPixel
                                          : kDefaultAdaptiveMaxRaysFactor * std::max(raysPerPixel, 1u);
  return std::min(rays, kMaxAdaptiveRays);
}

uint32_t adaptiveTileWidth(const AdaptiveRaySettings& s) {
  return s.tileWidth ? s.tileWidth : kDefaultAdaptiveTileWidth;
}

uint32_t adaptiveTileHeight(const AdaptiveRaySettings& s) {
  return s.tileHeight ? s.tileHeight : kDefaultAdaptiveTileHeight;
}

Status AdaptiveRayPlanner::init(Context& ctx, AdaptiveRayGranularity granularity) {
  const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
  auto sampled = [&](uint32_t b) {
    return VkDescriptorSetLayoutBinding{b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, cs, nullptr};
  };
  auto storage = [&](uint32_t b, VkDescriptorType t = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE) {
    return VkDescriptorSetLayoutBinding{b, t, 1, cs, nullptr};
  };
  // Only what is missing: an earlier call may have failed half way.
  if (!estimate_.pipeline) {
    Result<ComputePipeline> e = ComputePipeline::create(
        ctx, SpirvModule::of(spirv::adaptive_estimate_comp),
        {sampled(RB_ADAPTIVE_BINDING_DEPTH), sampled(RB_ADAPTIVE_BINDING_MOTION), sampled(RB_ADAPTIVE_BINDING_HISTORY),
         sampled(RB_ADAPTIVE_BINDING_DISTANCE), storage(RB_ADAPTIVE_BINDING_WEIGHTS),
         storage(RB_ADAPTIVE_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
         sampled(RB_ADAPTIVE_BINDING_REACTIVE)},
        sizeof(DenoiseConstants), "adaptive rays: estimate");
    if (!e) return e.error();
    estimate_ = e.value();
  }
  const bool tiles = granularity == AdaptiveRayGranularity::Tile;
  ComputePipeline& allocate = tiles ? allocateTiles_ : allocate_;
  if (!allocate.pipeline) {
    Result<ComputePipeline> a = ComputePipeline::create(
        ctx,
        tiles ? SpirvModule::of(spirv::adaptive_allocate_tiles_comp) : SpirvModule::of(spirv::adaptive_allocate_comp),
        {storage(RB_ADAPTIVE_BINDING_WEIGHTS), storage(RB_ADAPTIVE_BINDING_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER),
         storage(RB_ADAPTIVE_BINDING_PLAN)},
        sizeof(AdaptivePlanConstants), tiles ? "adaptive rays: allocate per tile" : "adaptive rays: allocate");
    if (!a) return a.error();
    allocate = a.value();
  }
  if (!counters_.valid()) {
    Result<GpuBuffer> b = createBuffer(ctx, kCounterBytes,
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers,
                                       "adaptive ray counters");
    if (!b) return b.error();
    counters_ = b.value();
  }
  return {};
}

void AdaptiveRayPlanner::retire(Context& ctx) {
  estimate_.retire(ctx);
  allocate_.retire(ctx);
  allocateTiles_.retire(ctx);
  images_.retire(ctx);
  retireBuffer(ctx, counters_);
  controller_.reset();
}

Result<bool> AdaptiveRayPlanner::record(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                                        const AdaptiveRaySettings& s, const Denoiser* denoiser, uint32_t raysPerPixel,
                                        const PassStats& latest, const char* who, uint32_t cellPixels) {
  if (s.timeBudgetMs > 0.0f && !ctx.deviceInfo().timestampsSupported) {
    // Without a measurement the budget would stay where it started, frame after frame, whatever the target.
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 std::string(who) + ": timeBudgetMs " + std::to_string(s.timeBudgetMs) +
                     " needs GPU timestamps, which the Context's queue family does not have (timestampValidBits " +
                     std::to_string(ctx.deviceInfo().timestampValidBits) +
                     "): set timeBudgetMs = 0 and cap the rays with maxRaysPerFrame"};
  }
  const DenoiseHistory history = internal::historyFor(*denoiser, g);
  if (!history.mean) return false;
  DenoiseConstants dn{};
  if (Status st = internal::historyReprojection(history, g, ctx.frameIndex(), who, dn); !st) return st.error();
  if (Status st = init(ctx, s.granularity); !st) return st.error();
  if (Status st = images_.ensure(ctx, g.width, g.height,
                                 {{VK_FORMAT_R16G16_SFLOAT, "adaptive ray weights"},
                                  {VK_FORMAT_R16G16_SFLOAT, "adaptive ray plan"}});
      !st) {
    return st.error();
  }

  // The budget: the uniform rays per surface pixel (resolved on the GPU, which counts the surface), or the time
  // target's, under the cap.
  const uint32_t maxRays = adaptiveMaxRays(s, raysPerPixel);
  const double pixels = double(g.width) * g.height;
  double cap = std::min<double>(s.maxRaysPerFrame ? double(s.maxRaysPerFrame) : 1e300,
                                double(kMaxAdaptiveRaysPerFrame));
  AdaptivePlanConstants pc{};
  pc.size[0] = g.width;
  pc.size[1] = g.height;
  pc.minRays = s.minRaysPerPixel ? s.minRaysPerPixel : kDefaultAdaptiveMinRays;
  pc.maxRays = maxRays;
  pc.frameIndex = uint32_t(ctx.frameIndex());
  const bool tiles = s.granularity == AdaptiveRayGranularity::Tile;
  // A tile of launch cells, in pixels: at half resolution a warp's cells stand for twice the pixels per side.
  pc.tileSize[0] = adaptiveTileWidth(s) * cellPixels;
  pc.tileSize[1] = adaptiveTileHeight(s) * cellPixels;
  // The claim takes whole tiles: a cap under one tile's rays would trace nothing, frame after frame.
  if (tiles) cap = std::max(cap, double(pc.tileSize[0]) * pc.tileSize[1]);
  if (s.timeBudgetMs > 0.0f) {
    // Start from the uniform rays (or initialRaysPerPixel) over the whole image; never below one ray per 64 pixels, so
    // a measurement (which needs rays) always comes back, nor per tile below one ray in every pixel of a tile: the
    // claim takes whole tiles, and a budget under one tile's rays would trace nothing.
    const double initial =
        (s.initialRaysPerPixel > 0.0f ? double(s.initialRaysPerPixel) : double(std::max(raysPerPixel, 1u))) * pixels;
    const double tilePixels = tiles ? double(pc.tileSize[0]) * pc.tileSize[1] : 1.0;
    const uint64_t r = controller_.next(ctx.frameIndex(), latest, s.timeBudgetMs, initial,
                                        std::max(1.0, std::min(std::max(pixels / 64.0, tilePixels), cap)),
                                        std::min(double(maxRays) * pixels, cap));
    pc.budget = uint32_t(std::min<uint64_t>(r, kMaxAdaptiveRaysPerFrame));
    pc.uniformRays = 0.0f;
  } else {
    controller_.reset();
    pc.budget = uint32_t(cap);
    pc.uniformRays = float(std::max(raysPerPixel, 1u));
  }
  budget_ = pc.budget;

  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const VkPipelineStageFlags cs = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  const VkPipelineStageFlags rt = VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  const VkAccessFlags rw = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  // Last frame's planning and ray generation are done with the counters and images before they are reset.
  VkImageMemoryBarrier discard[2];
  for (int i = 0; i < 2; ++i) {
    discard[i] = colorImageBarrier(images_[i].image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, rw, rw);
  }
  VkBufferMemoryBarrier reuse{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  reuse.srcAccessMask = rw;
  reuse.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  reuse.srcQueueFamilyIndex = reuse.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  reuse.buffer = counters_.buffer;
  reuse.size = VK_WHOLE_SIZE;
  vk.vkCmdPipelineBarrier(cmd, cs | rt | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, cs | VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                          0, nullptr, 1, &reuse, 2, discard);
  vk.vkCmdFillBuffer(cmd, counters_.buffer, 0, kCounterBytes, 0);
  recordMemoryBarrier(vk, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, cs, rw);

  {
    DescriptorWrites w;
    const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    w.sampledImage(RB_ADAPTIVE_BINDING_DEPTH, g.depth.view, history.sampler, readLayout(g.depth));
    internal::writeReprojectionInputs(w, g, history.sampler, RB_ADAPTIVE_BINDING_MOTION, RB_ADAPTIVE_BINDING_REACTIVE);
    w.sampledImage(RB_ADAPTIVE_BINDING_HISTORY, history.mean, history.sampler, ro);
    w.sampledImage(RB_ADAPTIVE_BINDING_DISTANCE, history.distance, history.sampler, ro);
    w.storageImage(RB_ADAPTIVE_BINDING_WEIGHTS, images_[0].view);
    w.storageBuffer(RB_ADAPTIVE_BINDING_COUNTERS, counters_.buffer, 0, kCounterBytes);
    estimate_.dispatch(ctx, cmd, w.writes, &dn, sizeof dn, g.width, g.height);
  }
  recordMemoryBarrier(vk, cmd, cs, VK_ACCESS_SHADER_WRITE_BIT, cs, rw);
  {
    DescriptorWrites w;
    w.storageImage(RB_ADAPTIVE_BINDING_WEIGHTS, images_[0].view);
    w.storageBuffer(RB_ADAPTIVE_BINDING_COUNTERS, counters_.buffer, 0, kCounterBytes);
    w.storageImage(RB_ADAPTIVE_BINDING_PLAN, images_[1].view);
    if (tiles) {
      // One workgroup holds 16x16 pixels: the largest tile (kMaxAdaptiveTileSize cells of 2 pixels) or several.
      allocateTiles_.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height, 16);
    } else {
      allocate_.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
    }
  }
  // The plan, read by the ray generation shader (and by tools: AoOutputs::rayPlan).
  const VkImageMemoryBarrier planned = colorImageBarrier(images_[1].image, VK_IMAGE_LAYOUT_GENERAL,
                                                         VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                                                         VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT);
  vk.vkCmdPipelineBarrier(cmd, cs, rt | cs | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, 0, nullptr, 0, nullptr, 1,
                          &planned);
  return true;
}

Result<bool> AdaptiveRayPlanner::recordForPass(PassCore& core, Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g,
                                               const AdaptiveRaySettings& settings, const Denoiser* history,
                                               uint32_t raysPerPixel, const PassStats& latest, const char* who,
                                               DescriptorWrites& w, uint32_t cellPixels) {
  if (!settings.enabled) return false;
  Result<bool> planned = record(ctx, cmd, g, settings, history, raysPerPixel, latest, who, cellPixels);
  if (!planned) {
    core.end(ctx, cmd);
    return planned.error();
  }
  if (planned.value()) {
    w.sampledImage(RB_BINDING_RAY_PLAN, planView(), core.sampler, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  }
  return planned;
}

}  // namespace rb

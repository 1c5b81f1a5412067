#include "light_list_buffer.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "context_impl.h"
#include "light_validation.h"
#include "memory_barrier.h"

namespace rb {

namespace {

// Checks one light (validateLight, then what a LightSource adds) and converts it to the GPU's form in the TLAS's
// space; the error names the light and field.
Status convertLight(const LightSource& s, const std::string& who, const double originOffset[3], GpuLight& out) {
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, who + m}; };
  const Light& l = s.light;
  if (Status st = validateLight(l, who); !st) return st;
  if (!(std::isfinite(s.intensity) && s.intensity >= 0.0f))
    return invalid("intensity " + std::to_string(s.intensity) + " must be finite and >= 0");
  if (!finiteNonNegative3(s.color)) return invalid("color must be finite and >= 0");
  out = {};
  for (int i = 0; i < 3; ++i) out.intensity[i] = s.color[i] * s.intensity;
  lightDirection(l, out.direction);
  out.type = uint32_t(l.type);
  if (l.type == LightType::Directional) {
    out.softness = std::tan(l.angularRadiusDegrees * kRadiansPerDegree);
    return {};
  }
  for (int i = 0; i < 3; ++i) out.position[i] = float(l.position[i] - originOffset[i]);
  out.range = l.range;
  out.softness = l.radius;
  if (l.type == LightType::Point) return {};
  const float outer = spotOuterAngleDegrees(l);
  if (!(s.spotInnerAngleDegrees >= 0.0f && s.spotInnerAngleDegrees <= outer))
    return invalid("spotInnerAngleDegrees " + std::to_string(s.spotInnerAngleDegrees) +
                   " must be in [0, the outer angle " + std::to_string(outer) + "]");
  const float cosOuter = std::cos(outer * kRadiansPerDegree);
  const float cosInner = std::cos(s.spotInnerAngleDegrees * kRadiansPerDegree);
  out.cosOuter = cosOuter;
  out.coneScale = 1.0f / std::max(1e-3f, cosInner - cosOuter);  // KHR_lights_punctual's formula
  out.coneOffset = -cosOuter * out.coneScale;
  return {};
}

}  // namespace

Status LightListBuffer::stage(Context& ctx, std::span<const LightSource> lights, const TlasInfo& tlas,
                              const std::string& who) {
  if (lights.size() > kMaxLights) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 who + std::to_string(lights.size()) + " lights exceed kMaxLights (" + std::to_string(kMaxLights) +
                     "); pass the strongest or nearest ones"};
  }
  const uint32_t count = uint32_t(lights.size());
  staging_.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    if (Status st = convertLight(lights[i], who + "lights[" + std::to_string(i) + "]: ", tlas.originOffset,
                                 staging_[i]);
        !st) {
      staging_.clear();
      return st;
    }
  }
  for (int i = 0; i < 3; ++i) stagedOrigin_[i] = tlas.originOffset[i];
  const uint32_t wanted = std::max(count, 1u);
  if (wanted <= capacity_) return {};
  uint32_t grown = std::max(64u, capacity_);
  while (grown < wanted) grown *= 2;
  grown = std::min(grown, kMaxLights);
  retire(ctx);
  const VkDeviceSize slot = VkDeviceSize(grown) * sizeof(GpuLight);
  Result<GpuBuffer> r = createBuffer(ctx, slot * ctx.framesInFlight(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                     MemoryLocation::HostVisible, MemoryCategory::PassBuffers, "light list ring");
  if (!r) return r.error();
  ring_ = r.value();
  Result<GpuBuffer> d = createBuffer(ctx, slot, VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                     MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers, "light list");
  if (!d) return d.error();
  lights_ = d.value();
  capacity_ = grown;
  return {};
}

void LightListBuffer::recordUpload(Context& ctx, VkCommandBuffer cmd) {
  const uint32_t count = stagedCount();
  info_.buffer = lights_.buffer;
  info_.count = count;
  info_.frame = ctx.frameIndex();
  for (int i = 0; i < 3; ++i) info_.originOffset[i] = stagedOrigin_[i];
  if (count == 0) return;
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  // This frame's ring slot, copied to the device list once last frame's readers are done with it.
  const uint32_t slot = uint32_t(ctx.frameIndex() % ctx.framesInFlight());
  const VkDeviceSize slotBytes = VkDeviceSize(capacity_) * sizeof(GpuLight);
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  std::memcpy(static_cast<uint8_t*>(ring_.mapped) + slot * slotBytes, staging_.data(), count * sizeof(GpuLight));
  recordBufferBarrier(vk, cmd, lights_.buffer, readers, VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_TRANSFER_WRITE_BIT);
  VkBufferCopy region{slot * slotBytes, 0, count * sizeof(GpuLight)};
  vk.vkCmdCopyBuffer(cmd, ring_.buffer, lights_.buffer, 1, &region);
  recordBufferBarrier(vk, cmd, lights_.buffer, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, readers,
                      VK_ACCESS_SHADER_READ_BIT);
}

void LightListBuffer::retire(Context& ctx) {
  retireBuffer(ctx, ring_);
  retireBuffer(ctx, lights_);
  capacity_ = 0;
}

Result<LightListInfo> readLightList(const LightList& list, const TlasInfo& tlas, uint64_t frameIndex,
                                    const std::string& field) {
  const LightListInfo info = list.info();
  if (info.frame != frameIndex) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 field +
                     ": that LightList was not recorded this frame; record it (LightList::record) before this pass"};
  }
  for (int i = 0; i < 3; ++i) {
    if (info.originOffset[i] != tlas.originOffset[i]) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   field + ": that LightList was recorded for another TLAS space (TlasInfo::originOffset); record it "
                           "with the TlasInfo this pass traces"};
    }
  }
  return info;
}

}  // namespace rb

#include <raybridge/many_light_pass.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "compute_pipeline.h"
#include "context_impl.h"
#include "light_validation.h"
#include "many_light_pass_impl.h"
#include "pass_core.h"
#include "ray_schedule_stage.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {

static_assert(RB_ML_STOCHASTIC == uint32_t(ManyLightMode::Stochastic));
static_assert(RB_ML_EXACT == uint32_t(ManyLightMode::Exact));
static_assert(RB_ML_MAX_TILE_LIGHTS == kMaxTileLights && RB_ML_TILE_SIZE == kManyLightTileSize);
static_assert(kMaxLights <= 65536, "tile lists hold 16-bit light indices");
constexpr uint32_t kMaxRaysOrCandidates = 64;


bool finite3(const float v[3]) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// Checks one light (validateLight, then what a LightSource adds) and converts it to the GPU's form in the TLAS's
// space; the error names the light and field.
Status convertLight(const LightSource& s, uint32_t index, const double originOffset[3], GpuLight& out) {
  const std::string who = "ManyLightPass: lights[" + std::to_string(index) + "]: ";
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, who + m}; };
  const Light& l = s.light;
  if (Status st = validateLight(l, who); !st) return st;
  if (!(std::isfinite(s.intensity) && s.intensity >= 0.0f))
    return invalid("intensity " + std::to_string(s.intensity) + " must be finite and >= 0");
  if (!finite3(s.color) || s.color[0] < 0.0f || s.color[1] < 0.0f || s.color[2] < 0.0f)
    return invalid("color must be finite and >= 0");
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

VkBufferMemoryBarrier bufferBarrier(VkBuffer buffer, VkAccessFlags src, VkAccessFlags dst) {
  VkBufferMemoryBarrier b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
  b.srcAccessMask = src;
  b.dstAccessMask = dst;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.buffer = buffer;
  b.size = VK_WHOLE_SIZE;
  return b;
}

}  // namespace

struct ManyLightPass::Impl {
  Context& ctx;
  PassCore core;
  ComputePipeline cull;
  // The light ring (host-visible, one slot of `capacity` lights per frame in flight), its device copy and the
  // tile lists; grown on demand, retired when replaced.
  GpuBuffer ring, lights, tiles;
  uint32_t capacity = 0;
  std::vector<GpuLight> staging;
  ManyLightOutputs outputs;
  internal::LightListView recorded;  // what the latest record() uploaded, for reflection hits
  // Converged tiles (ManyLightSettings::schedule), created on first use: the launch that skips them
  // (many_lights_converged.rgen), the tile state and the dispatches. Set by create().
  std::unique_ptr<ScheduleStage> schedule;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still use them
    core.retire(ctx);
    cull.retire(ctx);
    retireBuffer(ctx, ring);
    retireBuffer(ctx, lights);
    retireBuffer(ctx, tiles);
    if (schedule) schedule->retire(ctx);
  }
  Status ensureLightBuffers(uint32_t lightCount);
  Status ensureTiles(VkDeviceSize tileBytes);
  // Checks and converts the lights, then records their upload into `lights` (the list the rays read).
  Status uploadLights(VkCommandBuffer cmd, const TlasInfo& tlas, std::span<const LightSource> lightList);
  // Copies `staging` into this frame's ring slot and records its copy into `lights`.
  void recordUpload(VkCommandBuffer cmd, uint32_t count);
  // What other passes read (internal::lightList) after an upload of `count` lights this frame.
  void remember(const TlasInfo& tlas, uint32_t count);
};

Status ManyLightPass::Impl::ensureLightBuffers(uint32_t lightCount) {
  if (lightCount > capacity) {
    uint32_t grown = std::max(64u, capacity);
    while (grown < lightCount) grown *= 2;
    grown = std::min(grown, kMaxLights);
    retireBuffer(ctx, ring);
    retireBuffer(ctx, lights);
    capacity = 0;
    const VkDeviceSize slot = VkDeviceSize(grown) * sizeof(GpuLight);
    Result<GpuBuffer> r = createBuffer(ctx, slot * ctx.framesInFlight(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                       MemoryLocation::HostVisible, MemoryCategory::PassBuffers, "many-light ring");
    if (!r) return r.error();
    ring = r.value();
    Result<GpuBuffer> d = createBuffer(ctx, slot, VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                       MemoryLocation::DeviceLocal, MemoryCategory::PassBuffers, "many-light list");
    if (!d) return d.error();
    lights = d.value();
    capacity = grown;
  }
  return {};
}

Status ManyLightPass::Impl::ensureTiles(VkDeviceSize tileBytes) {
  if (tiles.size != tileBytes) {
    retireBuffer(ctx, tiles);
    Result<GpuBuffer> t = createBuffer(ctx, tileBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryLocation::DeviceLocal,
                                       MemoryCategory::PassBuffers, "many-light tiles");
    if (!t) return t.error();
    tiles = t.value();
  }
  return {};
}

void ManyLightPass::Impl::recordUpload(VkCommandBuffer cmd, uint32_t count) {
  if (count == 0) return;
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  // This frame's ring slot, copied to the device list once last frame's readers are done with it.
  const uint32_t slot = uint32_t(ctx.frameIndex() % ctx.framesInFlight());
  const VkDeviceSize slotBytes = VkDeviceSize(capacity) * sizeof(GpuLight);
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT |
                                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  std::memcpy(static_cast<uint8_t*>(ring.mapped) + slot * slotBytes, staging.data(), count * sizeof(GpuLight));
  VkBufferMemoryBarrier before = bufferBarrier(lights.buffer, VK_ACCESS_SHADER_READ_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
  vk.vkCmdPipelineBarrier(cmd, readers, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 1, &before, 0, nullptr);
  VkBufferCopy region{slot * slotBytes, 0, count * sizeof(GpuLight)};
  vk.vkCmdCopyBuffer(cmd, ring.buffer, lights.buffer, 1, &region);
  VkBufferMemoryBarrier after = bufferBarrier(lights.buffer, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT);
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, readers, 0, 0, nullptr, 1, &after, 0, nullptr);
}

void ManyLightPass::Impl::remember(const TlasInfo& tlas, uint32_t count) {
  recorded.buffer = lights.buffer;
  recorded.count = count;
  recorded.frame = ctx.frameIndex();
  for (int i = 0; i < 3; ++i) recorded.originOffset[i] = tlas.originOffset[i];
}

Status ManyLightPass::Impl::uploadLights(VkCommandBuffer cmd, const TlasInfo& tlas,
                                         std::span<const LightSource> lightList) {
  const uint32_t count = uint32_t(lightList.size());
  staging.resize(count);
  for (uint32_t i = 0; i < count; ++i)
    if (Status st = convertLight(lightList[i], i, tlas.originOffset, staging[i]); !st) return st;
  if (Status st = ensureLightBuffers(std::max(count, 1u)); !st) return st;
  recordUpload(cmd, count);
  remember(tlas, count);
  return {};
}

namespace {

const std::vector<PassImages::Spec> kManyLightOutputs = {{VK_FORMAT_R16G16B16A16_SFLOAT, "many-light irradiance"}};

void nameOutputs(ManyLightPass::Impl& s) {
  s.outputs.irradiance = s.core.images[0].image;
  s.outputs.irradianceView = s.core.images[0].view;
  s.outputs.width = s.core.images[0].width;
  s.outputs.height = s.core.images[0].height;
}

}  // namespace

Status ManyLightPass::prepare(uint32_t width, uint32_t height) {
  Impl& s = *impl_;
  if (Status st = s.core.prepare(s.ctx, width, height, kManyLightOutputs, "ManyLightPass"); !st) return st;
  nameOutputs(s);
  return {};
}

ManyLightPass::ManyLightPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ManyLightPass::~ManyLightPass() = default;

Result<std::unique_ptr<ManyLightPass>> ManyLightPass::create(Context& context) {
  auto impl = std::make_unique<Impl>(context);
  RayTracingPipelineDesc p;
  p.name = "many-light pass";
  p.raygen = SpirvModule::of(spirv::many_lights_rgen);
  p.misses = {SpirvModule::of(spirv::occlusion_rmiss)};
  // Rays skip the closest-hit shader by flag; a hit group without shaders crashes validation layer 1.3.239.
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::occlusion_rchit), {}}};
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  p.bindings = PassCore::commonBindings();
  p.bindings.push_back({RB_ML_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr});
  p.bindings.push_back({RB_ML_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr});
  p.bindings.push_back({RB_ML_BINDING_IRRADIANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  p.pushConstantBytes = sizeof(ManyLightConstants);
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::many_lights_rahit)); !s) return s.error();
  // To the schedule stage: an Rgb signal whose launch skips converged tiles itself (adding the tile state).
  ScheduledEffect e;
  e.passName = "ManyLightPass";
  e.capabilities = kLocalLightScheduleCapabilities;
  e.signal = DenoiseSignal::Rgb;
  e.outputBinding = RB_ML_BINDING_IRRADIANCE;
  e.tileStateBinding = RB_ML_BINDING_TILE_STATE;
  e.variantMask = kVariantTiles;
  e.pipelineDesc = [p](uint32_t) {
    RayTracingPipelineDesc v = p;
    v.name = "many-light pass (converged tiles)";
    v.raygen = SpirvModule::of(spirv::many_lights_converged_rgen);
    v.bindings.push_back(
        {RB_ML_BINDING_TILE_STATE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_RAYGEN_BIT_KHR, nullptr});
    return v;
  };
  e.alphaAnyHit = SpirvModule::of(spirv::many_lights_rahit);
  e.constantBytes = sizeof(ManyLightConstants);
  impl->schedule = std::make_unique<ScheduleStage>(std::move(e));
  const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
  Result<ComputePipeline> cull =
      ComputePipeline::create(context, SpirvModule::of(spirv::many_lights_cull_comp),
                              {{RB_ML_CULL_BINDING_DEPTH, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, cs, nullptr},
                               {RB_ML_CULL_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, cs, nullptr},
                               {RB_ML_CULL_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, cs, nullptr}},
                              sizeof(ManyLightConstants), "many-light tile culling");
  if (!cull) return cull.error();
  impl->cull = cull.value();
  return std::unique_ptr<ManyLightPass>(new ManyLightPass(std::move(impl)));
}

Status ManyLightPass::record(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                             std::span<const LightSource> lightList, const ManyLightSettings& settings) {
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ManyLightPass: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (lightList.size() > kMaxLights)
    return invalid(std::to_string(lightList.size()) + " lights exceed kMaxLights (" + std::to_string(kMaxLights) +
                   "); pass the strongest or nearest ones");
  if (settings.mode != ManyLightMode::Stochastic && settings.mode != ManyLightMode::Exact)
    return invalid("ManyLightSettings::mode has an unknown value");
  if (settings.raysPerPixel > kMaxRaysOrCandidates || settings.candidates > kMaxRaysOrCandidates)
    return invalid("ManyLightSettings::raysPerPixel " + std::to_string(settings.raysPerPixel) + " and candidates " +
                   std::to_string(settings.candidates) + " must be at most 64");
  if (Status st = validateRaySchedule(settings.schedule, kLocalLightScheduleCapabilities, DenoiseSignal::Rgb,
                                      "ManyLightPass: ManyLightSettings::schedule");
      !st) {
    return st;
  }
  if (settings.schedule.convergedTiles.enabled && settings.mode != ManyLightMode::Stochastic) {
    return invalid("ManyLightSettings::schedule.convergedTiles skips converged noise: ManyLightMode::Exact has none "
                   "to skip (and no denoiser); use Stochastic or disable convergedTiles");
  }
  ManyLightConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ManyLightPass", pc.gbuffer); !st) return st;
  const uint32_t count = uint32_t(lightList.size());
  s.staging.resize(count);
  for (uint32_t i = 0; i < count; ++i)
    if (Status st = convertLight(lightList[i], i, tlas.originOffset, s.staging[i]); !st) return st;
  pc.lightCount = count;
  pc.mode = uint32_t(settings.mode);
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultLightRays;
  pc.candidates = settings.candidates ? settings.candidates : kDefaultLightCandidates;
  pc.tiles[0] = (g.width + kManyLightTileSize - 1) / kManyLightTileSize;
  pc.tiles[1] = (g.height + kManyLightTileSize - 1) / kManyLightTileSize;
  const VkDeviceSize tileBytes = VkDeviceSize(pc.tiles[0]) * pc.tiles[1] * RB_ML_TILE_UINTS * sizeof(uint32_t);
  if (Status st = s.ensureLightBuffers(std::max(count, 1u)); !st) return st;
  if (Status st = s.ensureTiles(tileBytes); !st) return st;
  if (Status st = s.schedule->prepare(s.ctx, s.core, g, settings.schedule); !st) return st;

  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "ManyLightPass", pc.gbuffer.flags); !st) return st;
  if (Status st = s.core.begin(s.ctx, cmd, g, kManyLightOutputs); !st) return st;
  const DeviceFunctions& vk = internal::deviceFunctions(s.ctx);
  s.recordUpload(cmd, count);
  // Tile culling: last frame's rays read the lists this overwrites.
  VkBufferMemoryBarrier tilesFree = bufferBarrier(s.tiles.buffer, VK_ACCESS_SHADER_READ_BIT,
                                                  VK_ACCESS_SHADER_WRITE_BIT);
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0,
                          nullptr, 1, &tilesFree, 0, nullptr);
  DescriptorWrites cw;
  cw.sampledImage(RB_ML_CULL_BINDING_DEPTH, g.depth.view, s.core.sampler, readLayout(g.depth));
  cw.storageBuffer(RB_ML_CULL_BINDING_LIGHTS, s.lights.buffer);
  cw.storageBuffer(RB_ML_CULL_BINDING_TILES, s.tiles.buffer);
  s.cull.dispatch(s.ctx, cmd, cw.writes, &pc, sizeof(pc), pc.tiles[0] * 8, pc.tiles[1] * 8);  // a group per tile
  VkBufferMemoryBarrier tilesReady = bufferBarrier(s.tiles.buffer, VK_ACCESS_SHADER_WRITE_BIT,
                                                   VK_ACCESS_SHADER_READ_BIT);
  vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, 0, 0,
                          nullptr, 1, &tilesReady, 0, nullptr);

  s.core.writeCommon(s.ctx, w, g, tlas);
  w.storageBuffer(RB_ML_BINDING_LIGHTS, s.lights.buffer);
  w.storageBuffer(RB_ML_BINDING_TILES, s.tiles.buffer);
  // The rays saved count raysPerPixel per skipped surface pixel: at most what it would have traced (a tile with
  // fewer lights than rays traces one per light).
  ScheduleFrame frame{g, settings.schedule, w, &pc, &pc.gbuffer, pc.raysPerPixel};
  if (Result<bool> traced = s.schedule->trace(s.ctx, s.core, cmd, frame); !traced) return traced.error();

  s.remember(tlas, count);
  nameOutputs(s);
  return {};
}

Status ManyLightPass::recordLightList(VkCommandBuffer cmd, const TlasInfo& tlas, std::span<const LightSource> lights) {
  if (!cmd)
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ManyLightPass::recordLightList: cmd is VK_NULL_HANDLE"};
  if (lights.size() > kMaxLights)
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "ManyLightPass::recordLightList: " + std::to_string(lights.size()) + " lights exceed kMaxLights (" +
                     std::to_string(kMaxLights) + "); pass the strongest or nearest ones"};
  return impl_->uploadLights(cmd, tlas, lights);
}

internal::LightListView internal::ManyLightPassAccess::lightList(const ManyLightPass& pass) {
  return pass.impl_->recorded;
}

const ManyLightOutputs& ManyLightPass::outputs() const { return impl_->outputs; }
PassStats ManyLightPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

#include <raybridge/many_light_pass.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "compute_pipeline.h"
#include "context_impl.h"
#include "initial_extent.h"
#include "light_list_buffer.h"
#include "memory_barrier.h"
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

}  // namespace

struct ManyLightPass::Impl {
  Context& ctx;
  PassCore core;
  ComputePipeline cull;
  GpuBuffer tiles;            // the per-tile light lists; grown on demand, retired when replaced
  LightListBuffer ownLights;  // record() given the lights themselves uploads them here
  ManyLightOutputs outputs;
  // Converged tiles (ManyLightSettings::schedule), created on first use: the launch that skips them
  // (many_lights_converged.rgen), the tile state and the dispatches. Set by create().
  std::unique_ptr<ScheduleStage> schedule;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still use them
    core.retire(ctx);
    cull.retire(ctx);
    ownLights.retire(ctx);
    retireBuffer(ctx, tiles);
    if (schedule) schedule->retire(ctx);
  }
  Status ensureTiles(VkDeviceSize tileBytes);
  // What record() does once the frame is checked: the culling and the rays over `list` (nullptr = ownLights, staged
  // and not yet uploaded: its upload is recorded inside the pass's time).
  Status trace(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas, const ManyLightSettings& settings,
               ManyLightConstants& pc, const LightListInfo* list);
};

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

Result<std::unique_ptr<ManyLightPass>> ManyLightPass::create(Context& context, const ManyLightPassDesc& desc) {
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
  std::unique_ptr<ManyLightPass> pass(new ManyLightPass(std::move(impl)));
  if (Status s = internal::prepareAtCreation(*pass, desc.width, desc.height, "ManyLightPassDesc"); !s) {
    return s.error();
  }
  return pass;
}

namespace {

// The settings' checks; the message names the field.
Status validateSettings(const ManyLightSettings& settings) {
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ManyLightPass: " + m};
  };
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
  return {};
}

}  // namespace

Status ManyLightPass::record(VkCommandBuffer cmd, const ManyLightFrame& frame) {
  Impl& s = *impl_;
  const GBufferDesc& g = frame.gbuffer;
  const TlasInfo& tlas = frame.tlas;
  if (!cmd) return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ManyLightPass: cmd is VK_NULL_HANDLE"};
  if (frame.lightList && !frame.lights.empty()) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "ManyLightPass: ManyLightFrame has both lightList and " + std::to_string(frame.lights.size()) +
                     " lights; give one of them (the list when reflections or primary shading read the same lights)"};
  }
  if (Status st = validateSettings(frame.settings); !st) return st;
  ManyLightConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ManyLightPass", pc.gbuffer); !st) return st;
  if (!frame.lightList) {
    // The lights as an array (or none): uploaded into the pass's own list, inside its time.
    if (Status st = s.ownLights.stage(s.ctx, frame.lights, tlas, "ManyLightPass: "); !st) return st;
    return s.trace(cmd, g, tlas, frame.settings, pc, nullptr);
  }
  Result<LightListInfo> list = readLightList(*frame.lightList, tlas, s.ctx.frameIndex(),
                                             "ManyLightPass: ManyLightFrame::lightList");
  if (!list) return list.error();
  return s.trace(cmd, g, tlas, frame.settings, pc, &list.value());
}

Status ManyLightPass::Impl::trace(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                                  const ManyLightSettings& settings, ManyLightConstants& pc,
                                  const LightListInfo* list) {
  pc.lightCount = list ? list->count : ownLights.stagedCount();
  pc.mode = uint32_t(settings.mode);
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultLightRays;
  pc.candidates = settings.candidates ? settings.candidates : kDefaultLightCandidates;
  pc.tiles[0] = (g.width + kManyLightTileSize - 1) / kManyLightTileSize;
  pc.tiles[1] = (g.height + kManyLightTileSize - 1) / kManyLightTileSize;
  const VkDeviceSize tileBytes = VkDeviceSize(pc.tiles[0]) * pc.tiles[1] * RB_ML_TILE_UINTS * sizeof(uint32_t);
  if (Status st = ensureTiles(tileBytes); !st) return st;
  if (Status st = schedule->prepare(ctx, core, g, settings.schedule); !st) return st;

  DescriptorWrites w;
  if (Status st = core.writeMaterials(w, tlas, settings.materials, "ManyLightPass", pc.gbuffer.flags); !st) return st;
  if (Status st = core.begin(ctx, cmd, g, kManyLightOutputs); !st) return st;
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  if (!list) ownLights.recordUpload(ctx, cmd);
  const VkBuffer lightBuffer = list ? list->buffer : ownLights.info().buffer;
  // Tile culling: last frame's rays read the lists this overwrites.
  recordBufferBarrier(vk, cmd, tiles.buffer, VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_ACCESS_SHADER_READ_BIT,
                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
  DescriptorWrites cw;
  cw.sampledImage(RB_ML_CULL_BINDING_DEPTH, g.depth.view, core.sampler, readLayout(g.depth));
  cw.storageBuffer(RB_ML_CULL_BINDING_LIGHTS, lightBuffer);
  cw.storageBuffer(RB_ML_CULL_BINDING_TILES, tiles.buffer);
  cull.dispatch(ctx, cmd, cw.writes, &pc, sizeof(pc), pc.tiles[0] * 8, pc.tiles[1] * 8);  // a group per tile
  recordBufferBarrier(vk, cmd, tiles.buffer, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                      VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR, VK_ACCESS_SHADER_READ_BIT);

  core.writeCommon(ctx, w, g, tlas);
  w.storageBuffer(RB_ML_BINDING_LIGHTS, lightBuffer);
  w.storageBuffer(RB_ML_BINDING_TILES, tiles.buffer);
  // The rays saved count raysPerPixel per skipped surface pixel: at most what it would have traced (a tile with
  // fewer lights than rays traces one per light).
  ScheduleFrame frame{g, settings.schedule, w, &pc, &pc.gbuffer, pc.raysPerPixel};
  if (Result<bool> traced = schedule->trace(ctx, core, cmd, frame); !traced) return traced.error();
  nameOutputs(*this);
  return {};
}

const ManyLightOutputs& ManyLightPass::outputs() const { return impl_->outputs; }
PassStats ManyLightPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

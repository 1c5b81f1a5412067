#include <raybridge/ao_pass.h>

#include <cmath>
#include <string>

#include "context_impl.h"
#include "initial_extent.h"
#include "pass_core.h"
#include "ray_schedule_stage.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {
// The pipelines of the pass: ao.rgen, and its variants (ScheduleVariant bits) that add the plan's binding (adaptive
// rays) and the tile classifier's list (converged tiles).
RayTracingPipelineDesc aoPipelineDesc(uint32_t variant) {
  const bool adaptive = variant & kVariantAdaptive, tiles = variant & kVariantTiles;
  RayTracingPipelineDesc p;
  p.name = adaptive ? (tiles ? "AO pass (adaptive rays, converged tiles)" : "AO pass (adaptive rays)")
                    : (tiles ? "AO pass (converged tiles)" : "AO pass");
  p.raygen = adaptive
                 ? (tiles ? SpirvModule::of(spirv::ao_adaptive_tiles_rgen) : SpirvModule::of(spirv::ao_adaptive_rgen))
                 : (tiles ? SpirvModule::of(spirv::ao_tiles_rgen) : SpirvModule::of(spirv::ao_rgen));
  p.misses = {SpirvModule::of(spirv::occlusion_rmiss)};
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::occlusion_rchit), {}}};
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  p.bindings = PassCore::commonBindings();
  p.bindings.push_back({RB_AO_BINDING_OUTPUT, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  if (adaptive) p.bindings.push_back({RB_BINDING_RAY_PLAN, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr});
  if (tiles) p.bindings.push_back({RB_AO_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr});
  p.pushConstantBytes = sizeof(AoConstants);
  return p;
}

// AO to the schedule stage: a Scalar signal with every stage but the classifier alone, whose classifier
// (ao_classify.comp, over the tile launch's bindings) runs on the frames whose converged tiles were marked.
ScheduledEffect aoSchedule() {
  ScheduledEffect e;
  e.passName = "AoPass";
  e.capabilities = kAoScheduleCapabilities;
  e.signal = DenoiseSignal::Scalar;
  e.halfSignal = HalfResolution::Signal::Ao;
  e.outputBinding = RB_AO_BINDING_OUTPUT;
  e.tileListBinding = RB_AO_BINDING_TILES;
  e.tileStateBinding = RB_AO_BINDING_TILE_STATE;
  e.variantMask = kVariantAdaptive | kVariantTiles;
  e.pipelineDesc = aoPipelineDesc;
  e.alphaAnyHit = SpirvModule::of(spirv::ao_rahit);
  e.classifierShader = SpirvModule::of(spirv::ao_classify_comp);
  e.classifierLaunchBindings = aoPipelineDesc(kVariantTiles).bindings;
  e.constantBytes = sizeof(AoConstants);
  e.classifierName = "AO tile classifier";
  return e;
}
}  // namespace

struct AoPass::Impl {
  Context& ctx;
  PassCore core;
  ScheduleStage schedule{aoSchedule()};  // adaptive rays, converged tiles, half resolution
  AoOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    schedule.retire(ctx);
  }
};

namespace {

const std::vector<PassImages::Spec> kAoOutputs = {{VK_FORMAT_R16_SFLOAT, "ambient occlusion"}};

void nameOutputs(AoPass::Impl& s) {
  s.outputs.ao = s.core.images[0].image;
  s.outputs.aoView = s.core.images[0].view;
  s.outputs.width = s.core.images[0].width;
  s.outputs.height = s.core.images[0].height;
}

}  // namespace

Status AoPass::prepare(uint32_t width, uint32_t height) {
  Impl& s = *impl_;
  if (Status st = s.core.prepare(s.ctx, width, height, kAoOutputs, "AoPass"); !st) return st;
  nameOutputs(s);
  return {};
}

AoPass::AoPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AoPass::~AoPass() = default;

Result<std::unique_ptr<AoPass>> AoPass::create(Context& context, const AoPassDesc& desc) {
  auto impl = std::make_unique<Impl>(context);
  if (Status s = impl->core.init(context, aoPipelineDesc(0), SpirvModule::of(spirv::ao_rahit)); !s) {
    return s.error();
  }
  std::unique_ptr<AoPass> pass(new AoPass(std::move(impl)));
  if (Status s = internal::prepareAtCreation(*pass, desc.width, desc.height, "AoPassDesc"); !s) return s.error();
  return pass;
}

Status AoPass::record(VkCommandBuffer cmd, const AoFrame& input) {
  const GBufferDesc& g = input.gbuffer;
  const TlasInfo& tlas = input.tlas;
  const AoSettings& settings = input.settings;
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "AoPass: " + m}; };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  float range = settings.range == 0.0f ? kDefaultAoRange : settings.range;
  if (!(range > 0.0f) || !std::isfinite(range)) {
    return invalid("AoSettings::range " + std::to_string(settings.range) + " must be a positive number");
  }
  if (settings.raysPerPixel > kMaxRaysPerPixel) {
    return invalid("AoSettings::raysPerPixel " + std::to_string(settings.raysPerPixel) + " exceeds " +
                   std::to_string(kMaxRaysPerPixel));
  }
  if (settings.estimator != AoEstimator::Binary && settings.estimator != AoEstimator::DistanceWeighted) {
    return invalid("AoSettings::estimator has an unknown value");
  }
  if (Status st = validateRaySchedule(settings.schedule, kAoScheduleCapabilities, DenoiseSignal::Scalar,
                                      "AoPass: AoSettings::schedule");
      !st) {
    return st;
  }
  AoConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "AoPass", pc.gbuffer); !st) return st;
  pc.range = range;
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultAoRays;
  pc.estimator = static_cast<uint32_t>(settings.estimator);  // RB_AO_*
  pc.halfResolution = settings.schedule.halfResolution ? 1u : 0u;
  pc.gbuffer.resetRays = settings.schedule.resetRays > pc.raysPerPixel ? settings.schedule.resetRays : 0u;

  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "AoPass", pc.gbuffer.flags); !st) return st;
  if (Status st = s.schedule.prepare(s.ctx, s.core, g, settings.schedule); !st) return st;
  const PassStats latest = s.core.metrics.latest(s.ctx);
  if (Status st = s.core.begin(s.ctx, cmd, g, kAoOutputs); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  ScheduleFrame frame{g, settings.schedule, w, &pc, &pc.gbuffer, pc.raysPerPixel, latest};
  Result<bool> planned = s.schedule.trace(s.ctx, s.core, cmd, frame);
  if (!planned) return planned.error();
  nameOutputs(s);
  s.outputs.rayPlan = planned.value() ? s.schedule.planImage() : VK_NULL_HANDLE;
  s.outputs.rayPlanView = planned.value() ? s.schedule.planView() : VK_NULL_HANDLE;
  return {};
}

const AoOutputs& AoPass::outputs() const { return impl_->outputs; }
PassStats AoPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

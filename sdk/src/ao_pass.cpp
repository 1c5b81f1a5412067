#include <raybridge/ao_pass.h>

#include <cmath>
#include <string>

#include "adaptive_rays.h"
#include "context_impl.h"
#include "pass_core.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {
// The pipeline of the pass: ao.rgen, or ao_adaptive.rgen (which adds the plan's binding).
RayTracingPipelineDesc aoPipelineDesc(bool adaptive) {
  RayTracingPipelineDesc p;
  p.name = adaptive ? "AO pass (adaptive rays)" : "AO pass";
  p.raygen = adaptive ? SpirvModule::of(spirv::ao_adaptive_rgen) : SpirvModule::of(spirv::ao_rgen);
  p.misses = {SpirvModule::of(spirv::occlusion_rmiss)};
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::occlusion_rchit), {}}};
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  p.bindings = PassCore::commonBindings();
  p.bindings.push_back({RB_AO_BINDING_OUTPUT, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  if (adaptive) p.bindings.push_back({RB_BINDING_RAY_PLAN, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr});
  p.pushConstantBytes = sizeof(AoConstants);
  return p;
}
}  // namespace

struct AoPass::Impl {
  Context& ctx;
  PassCore core;
  // Adaptive rays, created on first use.
  RayTracingPipeline adaptivePipeline;
  AdaptiveRayPlanner planner;
  // AoSettings::halfResolution: the sample image and the upsample, made on first use.
  HalfResolution half{HalfResolution::Signal::Ao};
  AoOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    adaptivePipeline.retire(ctx);
    planner.retire(ctx);
    half.retire(ctx);
  }
};

AoPass::AoPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AoPass::~AoPass() = default;

Result<std::unique_ptr<AoPass>> AoPass::create(Context& context) {
  auto impl = std::make_unique<Impl>(context);
  if (Status s = impl->core.init(context, aoPipelineDesc(false), SpirvModule::of(spirv::ao_rahit)); !s) {
    return s.error();
  }
  return std::unique_ptr<AoPass>(new AoPass(std::move(impl)));
}

Status AoPass::record(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas, const AoSettings& settings) {
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "AoPass: " + m}; };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  float range = settings.range == 0.0f ? kDefaultAoRange : settings.range;
  if (!(range > 0.0f) || !std::isfinite(range)) {
    return invalid("AoSettings::range " + std::to_string(settings.range) + " must be a positive number");
  }
  if (settings.raysPerPixel > 4096) {
    return invalid("AoSettings::raysPerPixel " + std::to_string(settings.raysPerPixel) + " exceeds 4096");
  }
  if (settings.estimator != AoEstimator::Binary && settings.estimator != AoEstimator::DistanceWeighted) {
    return invalid("AoSettings::estimator has an unknown value");
  }
  if (Status st = AdaptiveRayPlanner::validate(settings.adaptive, "AoPass: AoSettings::adaptive"); !st) return st;
  AoConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "AoPass", pc.gbuffer); !st) return st;
  pc.range = range;
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultAoRays;
  pc.estimator = static_cast<uint32_t>(settings.estimator);  // RB_AO_*
  pc.halfResolution = settings.halfResolution ? 1u : 0u;

  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "AoPass", pc.gbuffer.flags); !st) return st;
  if (settings.adaptive.enabled && !s.adaptivePipeline.pipeline) {
    Result<RayTracingPipeline> p = s.core.createVariant(s.ctx, aoPipelineDesc(true), SpirvModule::of(spirv::ao_rahit));
    if (!p) return p.error();
    s.adaptivePipeline = p.value();
  }
  if (settings.halfResolution) {
    if (Status st = s.half.ensure(s.ctx, g.width, g.height); !st) return st;
  } else {
    s.half.releaseImage(s.ctx);  // full resolution holds no sample image
  }
  const PassStats latest = s.core.metrics.latest(s.ctx);
  if (Status st = s.core.begin(s.ctx, cmd, g, {{VK_FORMAT_R16_SFLOAT, "ambient occlusion"}}); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  // With half resolution the plan covers every pixel and the traced quarter uses its entries: a quarter of the
  // budget is traced (a time target compensates: it scales the budget it planned by the time measured).
  // Its tiles are of launch cells: 2x2 pixels each at half resolution.
  Result<bool> plan = s.planner.recordForPass(s.core, s.ctx, cmd, g, settings.adaptive, pc.raysPerPixel, latest,
                                              "AoPass", w, settings.halfResolution ? 2u : 1u);
  if (!plan) return plan.error();
  const bool planned = plan.value();
  const RayTracingPipeline* variant = planned ? &s.adaptivePipeline : nullptr;
  if (settings.halfResolution) {
    w.storageImage(RB_AO_BINDING_OUTPUT, s.half.samplesView());
    s.core.traceHalfAndEnd(s.ctx, cmd, w, pc, g, s.half, 0.0f, variant);
  } else {
    w.storageImage(RB_AO_BINDING_OUTPUT, s.core.images[0].view);
    s.core.traceAndEnd(s.ctx, cmd, w, pc, g, variant);
  }
  s.outputs.ao = s.core.images[0].image;
  s.outputs.aoView = s.core.images[0].view;
  s.outputs.width = g.width;
  s.outputs.height = g.height;
  s.outputs.rayPlan = planned ? s.planner.planImage() : VK_NULL_HANDLE;
  s.outputs.rayPlanView = planned ? s.planner.planView() : VK_NULL_HANDLE;
  return {};
}

const AoOutputs& AoPass::outputs() const { return impl_->outputs; }
PassStats AoPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

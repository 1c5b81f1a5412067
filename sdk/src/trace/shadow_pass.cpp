#include <raybridge/shadow_pass.h>

#include <cmath>
#include <cstddef>
#include <string>

#include "context_impl.h"
#include "initial_extent.h"
#include "light_validation.h"
#include "pass_core.h"
#include "ray_schedule_stage.h"
#include "raybridge_shaders.h"

namespace rb {

struct ShadowPass::Impl {
  Context& ctx;
  ShadowPassDesc desc;
  PassCore core;
  // The tile classifier (its own: always bound), converged tiles and adaptive rays (soft lights).
  std::unique_ptr<ScheduleStage> schedule;
  ShadowOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    if (schedule) schedule->retire(ctx);
  }
};

namespace {

std::vector<PassImages::Spec> outputSpecs(const ShadowPassDesc& desc) {
  std::vector<PassImages::Spec> specs = {{VK_FORMAT_R16_SFLOAT, "shadow visibility"}};
  if (desc.outputHitDistance) specs.push_back({VK_FORMAT_R32_SFLOAT, "shadow hit distance"});
  return specs;
}

// outputs() from the images (the ray plan is the record's to name).
void nameOutputs(ShadowPass::Impl& s) {
  const PassImages& images = s.core.images;
  ShadowOutputs& o = s.outputs;
  o.visibility = images[0].image;
  o.visibilityView = images[0].view;
  o.hitDistance = s.desc.outputHitDistance ? images[1].image : VK_NULL_HANDLE;
  o.hitDistanceView = s.desc.outputHitDistance ? images[1].view : VK_NULL_HANDLE;
  o.width = images[0].width;
  o.height = images[0].height;
}

}  // namespace

ShadowPass::ShadowPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShadowPass::~ShadowPass() = default;

Result<std::unique_ptr<ShadowPass>> ShadowPass::create(Context& context, const ShadowPassDesc& desc) {
  auto impl = std::make_unique<Impl>(context);
  impl->desc = desc;
  RayTracingPipelineDesc p;
  p.name = "shadow pass";
  p.raygen = desc.outputHitDistance ? SpirvModule::of(spirv::shadow_distance_rgen)
                                    : SpirvModule::of(spirv::shadow_rgen);
  p.misses = {SpirvModule::of(spirv::occlusion_rmiss)};
  // The closest-hit shader runs only when the occluder distance is wanted; otherwise rays skip it by flag.
  // (A hit group without shaders would do, but crashes validation layer 1.3.239 in vkCmdTraceRaysKHR.)
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::occlusion_rchit), {}}};
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  p.bindings = PassCore::commonBindings();
  p.bindings.push_back({RB_SHADOW_BINDING_VISIBILITY, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  if (desc.outputHitDistance) {
    p.bindings.push_back({RB_SHADOW_BINDING_HIT_DISTANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr});
  }
  p.bindings.push_back({RB_SHADOW_BINDING_TILES, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr});
  p.pushConstantBytes = sizeof(ShadowConstants);
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::shadow_rahit)); !s) return s.error();

  // To the schedule stage: a Scalar signal whose classifier is its own (it reads the launch's bindings, not the
  // material ones), and whose adaptive variant adds the plan's binding (not with the occluder distance).
  ScheduledEffect e;
  e.passName = "ShadowPass";
  e.capabilities = kShadowScheduleCapabilities;
  e.outputBinding = RB_SHADOW_BINDING_VISIBILITY;
  e.tileListBinding = RB_SHADOW_BINDING_TILES;
  e.tileStateBinding = RB_SHADOW_BINDING_TILE_STATE;
  e.convergedFlagOffset = offsetof(ShadowConstants, convergedTiles);
  e.launchOverTilesOffset = offsetof(ShadowConstants, launchOverTiles);
  e.classifierAlwaysBound = true;
  e.variantMask = desc.outputHitDistance ? 0u : uint32_t(kVariantAdaptive);
  e.pipelineDesc = [p](uint32_t) {
    RayTracingPipelineDesc adaptive = p;
    adaptive.name = "shadow pass (adaptive rays)";
    adaptive.raygen = SpirvModule::of(spirv::shadow_adaptive_rgen);
    adaptive.bindings.push_back(
        {RB_BINDING_RAY_PLAN, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_RAYGEN_BIT_KHR, nullptr});
    return adaptive;
  };
  e.alphaAnyHit = SpirvModule::of(spirv::shadow_rahit);
  e.classifierShader = desc.outputHitDistance ? SpirvModule::of(spirv::shadow_classify_distance_comp)
                                              : SpirvModule::of(spirv::shadow_classify_comp);
  e.classifierLaunchBindings = p.bindings;
  e.constantBytes = sizeof(ShadowConstants);
  e.classifierName = "shadow tile classifier";
  impl->schedule = std::make_unique<ScheduleStage>(std::move(e));
  if (Status s = impl->schedule->init(context); !s) return s.error();
  std::unique_ptr<ShadowPass> pass(new ShadowPass(std::move(impl)));
  if (Status s = internal::prepareAtCreation(*pass, desc.width, desc.height, "ShadowPassDesc"); !s) return s.error();
  return pass;
}

Status ShadowPass::record(VkCommandBuffer cmd, const ShadowFrame& input) {
  const GBufferDesc& g = input.gbuffer;
  const TlasInfo& tlas = input.tlas;
  const Light& light = input.light;
  const ShadowSettings& settings = input.settings;
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ShadowPass: " + m}; };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  ShadowConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ShadowPass", pc.gbuffer); !st) return st;

  // Light parameters in the TLAS's space (the light checked as every effect checks it).
  if (Status st = validateLight(light, "ShadowPass: "); !st) return st;
  float dir[3];
  lightDirection(light, dir);
  bool soft;
  if (light.type == LightType::Directional) {
    for (int i = 0; i < 3; ++i) pc.lightDirection[i] = dir[i];
    pc.lightType = RB_LIGHT_DIRECTIONAL;
    pc.tanAngularRadius = std::tan(light.angularRadiusDegrees * kRadiansPerDegree);
    soft = light.angularRadiusDegrees > 0.0f;
  } else {
    for (int i = 0; i < 3; ++i) pc.lightPosition[i] = static_cast<float>(light.position[i] - tlas.originOffset[i]);
    pc.lightType = light.type == LightType::Point ? RB_LIGHT_POINT : RB_LIGHT_SPOT;
    pc.lightRadius = light.radius;
    pc.range = light.range;
    pc.cosSpotOuterAngle = std::cos(spotOuterAngleDegrees(light) * kRadiansPerDegree);
    for (int i = 0; i < 3; ++i) pc.spotDirection[i] = dir[i];
    soft = light.radius > 0.0f;
  }
  if (settings.raysPerPixel > kMaxRaysPerPixel) {
    return invalid("ShadowSettings::raysPerPixel " + std::to_string(settings.raysPerPixel) + " exceeds " +
                   std::to_string(kMaxRaysPerPixel));
  }
  pc.raysPerPixel = soft ? (settings.raysPerPixel ? settings.raysPerPixel : kDefaultSoftShadowRays) : 1u;
  if (Status st = validateRaySchedule(settings.schedule, kShadowScheduleCapabilities, DenoiseSignal::Scalar,
                                      "ShadowPass: ShadowSettings::schedule");
      !st) {
    return st;
  }
  if (s.desc.outputHitDistance && (settings.schedule.adaptive.enabled || settings.schedule.convergedTiles.enabled)) {
    return invalid("ShadowSettings::schedule: adaptive rays and converged tiles do not write the occluder distance: "
                   "create the pass without ShadowPassDesc::outputHitDistance, or disable them");
  }
  // A hard light's one ray per pixel is exact: nothing to adapt.
  RaySchedule schedule = settings.schedule;
  schedule.adaptive.enabled = schedule.adaptive.enabled && soft;
  pc.gbuffer.resetRays = soft && schedule.resetRays > pc.raysPerPixel ? schedule.resetRays : 0u;
  const std::vector<PassImages::Spec> specs = outputSpecs(s.desc);
  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "ShadowPass", pc.gbuffer.flags); !st) return st;
  // What the schedule needs (the tile list among it) before begin(), so that a failed allocation records nothing.
  if (Status st = s.schedule->prepare(s.ctx, s.core, g, schedule); !st) return st;
  const PassStats latest = s.core.metrics.latest(s.ctx);
  if (Status st = s.core.begin(s.ctx, cmd, g, specs); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  const PassImages& images = s.core.images;
  auto writeHitDistance = [&](DescriptorWrites& writes) {
    if (s.desc.outputHitDistance) writes.storageImage(RB_SHADOW_BINDING_HIT_DISTANCE, images[1].view);
  };
  writeHitDistance(w);
  ScheduleFrame frame{g, schedule, w, &pc, &pc.gbuffer, pc.raysPerPixel, latest};
  frame.writeExtraOutputs = writeHitDistance;
  Result<bool> plan = s.schedule->trace(s.ctx, s.core, cmd, frame);
  if (!plan) return plan.error();
  const bool planned = plan.value();

  nameOutputs(s);
  ShadowOutputs& o = s.outputs;
  o.rayPlan = planned ? s.schedule->planImage() : VK_NULL_HANDLE;
  o.rayPlanView = planned ? s.schedule->planView() : VK_NULL_HANDLE;
  return {};
}

Status ShadowPass::prepare(uint32_t width, uint32_t height) {
  Impl& s = *impl_;
  if (Status st = s.core.prepare(s.ctx, width, height, outputSpecs(s.desc), "ShadowPass"); !st) return st;
  nameOutputs(s);
  return {};
}

const ShadowOutputs& ShadowPass::outputs() const { return impl_->outputs; }
PassStats ShadowPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

#include <raybridge/shadow_pass.h>

#include <cmath>
#include <string>

#include "adaptive_rays.h"
#include "context_impl.h"
#include "converged_tiles.h"
#include "light_validation.h"
#include "pass_core.h"
#include "raybridge_shaders.h"
#include "tile_classifier.h"

namespace rb {

namespace {}

struct ShadowPass::Impl {
  Context& ctx;
  ShadowPassDesc desc;
  PassCore core;
  TileClassifier classifier;
  ConvergedTiles converged;  // ShadowSettings::convergedTiles, pipelines created on first use
  // Adaptive rays (soft lights), created on first use: shadow_adaptive.rgen and its planner.
  RayTracingPipelineDesc adaptiveDesc;
  RayTracingPipeline adaptivePipeline;
  AdaptiveRayPlanner planner;
  ShadowOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    classifier.retire(ctx);
    converged.retire(ctx);
    adaptivePipeline.retire(ctx);
    planner.retire(ctx);
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
  if (!desc.outputHitDistance) {
    impl->adaptiveDesc = p;
    impl->adaptiveDesc.name = "shadow pass (adaptive rays)";
    impl->adaptiveDesc.raygen = SpirvModule::of(spirv::shadow_adaptive_rgen);
    impl->adaptiveDesc.bindings.push_back(
        {RB_BINDING_RAY_PLAN, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, rg, nullptr});
  }
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::shadow_rahit)); !s) return s.error();

  // The classifier: the ray generation shader's bindings but the TLAS and the material bindings, in a compute
  // stage (PassCore::writeGBuffer and writeOutputs in record() fill them).
  std::vector<VkDescriptorSetLayoutBinding> cb;
  for (const VkDescriptorSetLayoutBinding& b : p.bindings) {
    if (b.binding == RB_BINDING_TLAS) continue;
    cb.push_back({b.binding, b.descriptorType, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  cb.push_back(
      {RB_SHADOW_BINDING_TILE_STATE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  const SpirvModule classify = desc.outputHitDistance ? SpirvModule::of(spirv::shadow_classify_distance_comp)
                                                      : SpirvModule::of(spirv::shadow_classify_comp);
  if (Status s = impl->classifier.init(context, classify, cb, sizeof(ShadowConstants), "shadow tile classifier"); !s) {
    return s.error();
  }
  return std::unique_ptr<ShadowPass>(new ShadowPass(std::move(impl)));
}

Status ShadowPass::record(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas, const Light& light,
                          const ShadowSettings& settings) {
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
  if (Status st = AdaptiveRayPlanner::validate(settings.adaptive, "ShadowPass: ShadowSettings::adaptive"); !st) {
    return st;
  }
  if (settings.adaptive.enabled && s.desc.outputHitDistance) {
    return invalid("adaptive rays do not write the occluder distance: create the pass without "
                   "ShadowPassDesc::outputHitDistance, or disable ShadowSettings::adaptive");
  }
  // A hard light's one ray per pixel is exact: nothing to adapt.
  const bool adaptive = settings.adaptive.enabled && soft;
  if (adaptive && !s.adaptivePipeline.pipeline) {
    Result<RayTracingPipeline> p = s.core.createVariant(s.ctx, s.adaptiveDesc, SpirvModule::of(spirv::shadow_rahit));
    if (!p) return p.error();
    s.adaptivePipeline = p.value();
  }
  if (Status st = s.converged.validate(settings.convergedTiles, "ShadowPass: ShadowSettings::convergedTiles"); !st) {
    return st;
  }
  if (settings.convergedTiles.enabled && s.desc.outputHitDistance) {
    return invalid("converged tiles have no occluder distance: create the pass without "
                   "ShadowPassDesc::outputHitDistance, or disable ShadowSettings::convergedTiles");
  }
  const PassStats latest = s.core.metrics.latest(s.ctx);

  const std::vector<PassImages::Spec> specs = outputSpecs(s.desc);
  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "ShadowPass", pc.gbuffer.flags); !st) return st;
  // The tile list before begin(), so that a failed allocation records nothing.
  if (Status st = s.classifier.ensure(s.ctx, g.width, g.height); !st) return st;
  if (Status st = s.core.begin(s.ctx, cmd, g, specs); !st) return st;
  const PassImages& images = s.core.images;
  auto writeOutputs = [&](DescriptorWrites& writes) {
    writes.storageImage(RB_SHADOW_BINDING_VISIBILITY, images[0].view);
    if (s.desc.outputHitDistance) writes.storageImage(RB_SHADOW_BINDING_HIT_DISTANCE, images[1].view);
    // Bound without the classifier too: the ray generation shader statically uses it.
    s.classifier.writeList(writes, RB_SHADOW_BINDING_TILES);
  };
  s.core.writeCommon(s.ctx, w, g, tlas);
  writeOutputs(w);
  AdaptiveRaySettings planning = settings.adaptive;
  planning.enabled = adaptive;  // a hard light traces its one ray uniformly
  Result<bool> plan = s.planner.recordForPass(s.core, s.ctx, cmd, g, planning, pc.raysPerPixel, latest, "ShadowPass",
                                              w);
  if (!plan) return plan.error();
  const bool planned = plan.value();
  const RayTracingPipeline* variant = planned ? &s.adaptivePipeline : nullptr;
  if (!settings.tileClassifier && !settings.convergedTiles.enabled) {
    s.core.traceAndEnd(s.ctx, cmd, w, pc, g, variant);
  } else {
    bool converged = false;
    if (settings.convergedTiles.enabled) {
      Result<bool> c = s.converged.record(s.ctx, cmd, g, settings.convergedTiles, pc.raysPerPixel, s.classifier,
                                          images[0].view, "ShadowPass");
      if (!c) {
        s.core.end(s.ctx, cmd);
        return c.error();
      }
      converged = c.value();
    }
    pc.convergedTiles = converged ? 1u : 0u;
    DescriptorWrites cw;
    s.core.writeGBuffer(s.ctx, cw, g);
    writeOutputs(cw);
    s.classifier.writeState(cw, RB_SHADOW_BINDING_TILE_STATE);
    s.classifier.classify(s.ctx, cmd, cw, &pc, sizeof pc);
    pc.launchOverTiles = 1;
    if (!converged) {
      s.core.traceIndirectAndEnd(s.ctx, cmd, w, pc, s.classifier.traceArguments(), variant);
    } else {
      // The check reads the traced visibility, so it comes after the outputs are readable, inside the pass's time.
      s.core.traceIndirect(s.ctx, cmd, w, pc, s.classifier.traceArguments(), variant);
      s.core.images.endWrite(s.ctx, cmd);
      s.converged.check(s.ctx, cmd, g, s.classifier, images[0].view);
      s.core.metrics.writeEnd(s.ctx, cmd);
    }
  }

  nameOutputs(s);
  ShadowOutputs& o = s.outputs;
  o.rayPlan = planned ? s.planner.planImage() : VK_NULL_HANDLE;
  o.rayPlanView = planned ? s.planner.planView() : VK_NULL_HANDLE;
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

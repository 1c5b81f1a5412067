#include <raybridge/ao_pass.h>

#include <cmath>
#include <string>

#include "adaptive_rays.h"
#include "context_impl.h"
#include "converged_tiles.h"
#include "pass_core.h"
#include "raybridge_shaders.h"
#include "tile_classifier.h"

namespace rb {

namespace {
// The pipelines of the pass: ao.rgen, ao_adaptive.rgen (which adds the plan's binding), and both over the tile
// classifier's list (ao_tiles.rgen, ao_adaptive_tiles.rgen: which add the list's binding).
RayTracingPipelineDesc aoPipelineDesc(bool adaptive, bool tiles = false) {
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

// The classifier's bindings (ao_classify.comp): the G-buffer, counters, output and tile list of the ray generation
// shader, and the tile state, in a compute stage.
std::vector<VkDescriptorSetLayoutBinding> aoClassifierBindings() {
  std::vector<VkDescriptorSetLayoutBinding> b;
  for (const VkDescriptorSetLayoutBinding& c : aoPipelineDesc(false, true).bindings) {
    if (c.binding == RB_BINDING_TLAS) continue;
    b.push_back({c.binding, c.descriptorType, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  b.push_back({RB_AO_BINDING_TILE_STATE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  return b;
}
}  // namespace

struct AoPass::Impl {
  Context& ctx;
  PassCore core;
  // Adaptive rays, created on first use.
  RayTracingPipeline adaptivePipeline;
  AdaptiveRayPlanner planner;
  // AoSettings::convergedTiles, created on first use: the launches over the tile list (uniform, adaptive), the
  // classifier with its list and tile state, and the converged-tile dispatches.
  RayTracingPipeline tilesPipeline, adaptiveTilesPipeline;
  TileClassifier classifier;
  bool classifierReady = false;
  ConvergedTiles converged;
  // AoSettings::halfResolution: the sample image and the upsample, made on first use.
  HalfResolution half{HalfResolution::Signal::Ao};
  AoOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    adaptivePipeline.retire(ctx);
    planner.retire(ctx);
    half.retire(ctx);
    retireTiles();
  }
  void retireTiles() {
    tilesPipeline.retire(ctx);
    adaptiveTilesPipeline.retire(ctx);
    classifier.retire(ctx);
    converged.retire(ctx);
    classifierReady = false;
  }
  // What converged tiles need, before the pass's recording begins (so that a failure records nothing).
  // The uniform launch always (a frame without history to plan from traces uniformly), the adaptive one with
  // adaptive rays.
  Status ensureTiles(const GBufferDesc& g, bool adaptive) {
    for (bool a : {false, true}) {
      RayTracingPipeline& p = a ? adaptiveTilesPipeline : tilesPipeline;
      if (p.pipeline || (a && !adaptive)) continue;
      Result<RayTracingPipeline> r = core.createVariant(ctx, aoPipelineDesc(a, true), SpirvModule::of(spirv::ao_rahit));
      if (!r) return r.error();
      p = r.value();
    }
    if (!classifierReady) {
      if (Status st = classifier.init(ctx, SpirvModule::of(spirv::ao_classify_comp), aoClassifierBindings(),
                                      sizeof(AoConstants), "AO tile classifier");
          !st) {
        return st;
      }
      classifierReady = true;
    }
    return classifier.ensure(ctx, g.width, g.height);
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
  if (settings.raysPerPixel > kMaxRaysPerPixel) {
    return invalid("AoSettings::raysPerPixel " + std::to_string(settings.raysPerPixel) + " exceeds " +
                   std::to_string(kMaxRaysPerPixel));
  }
  if (settings.estimator != AoEstimator::Binary && settings.estimator != AoEstimator::DistanceWeighted) {
    return invalid("AoSettings::estimator has an unknown value");
  }
  if (Status st = AdaptiveRayPlanner::validate(settings.adaptive, "AoPass: AoSettings::adaptive"); !st) return st;
  if (Status st = s.converged.validate(settings.convergedTiles, "AoPass: AoSettings::convergedTiles"); !st) {
    return st;
  }
  if (settings.convergedTiles.enabled && settings.halfResolution) {
    return invalid("AoSettings::convergedTiles skips tiles of full-resolution pixels: disable halfResolution or "
                   "convergedTiles");
  }
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
  if (settings.convergedTiles.enabled) {
    if (Status st = s.ensureTiles(g, settings.adaptive.enabled); !st) return st;
  } else if (s.classifierReady) {
    s.retireTiles();  // no tile list nor state while converged tiles are off
  }
  const PassStats latest = s.core.metrics.latest(s.ctx);
  if (Status st = s.core.begin(s.ctx, cmd, g, kAoOutputs); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  // With half resolution the plan covers every pixel and the traced quarter uses its entries: a quarter of the
  // budget is traced (a time target compensates: it scales the budget it planned by the time measured).
  // Its tiles are of launch cells: 2x2 pixels each at half resolution.
  Result<bool> plan = s.planner.recordForPass(s.core, s.ctx, cmd, g, settings.adaptive, pc.raysPerPixel, latest,
                                              "AoPass", w, settings.halfResolution ? 2u : 1u);
  if (!plan) return plan.error();
  const bool planned = plan.value();
  const RayTracingPipeline* variant = planned ? &s.adaptivePipeline : nullptr;
  bool converged = false;
  if (settings.convergedTiles.enabled) {
    Result<bool> c = s.converged.record(s.ctx, cmd, g, settings.convergedTiles, pc.raysPerPixel, s.classifier,
                                        s.core.images[0].view, "AoPass");
    if (!c) {
      s.core.end(s.ctx, cmd);
      return c.error();
    }
    converged = c.value();
  }
  if (converged) {
    // The classifier lists the tiles with a surface pixel that did not converge; the launch covers them alone.
    DescriptorWrites cw;
    s.core.writeGBuffer(s.ctx, cw, g);
    cw.storageImage(RB_AO_BINDING_OUTPUT, s.core.images[0].view);
    s.classifier.writeList(cw, RB_AO_BINDING_TILES);
    s.classifier.writeState(cw, RB_AO_BINDING_TILE_STATE);
    s.classifier.classify(s.ctx, cmd, cw, &pc, sizeof pc);
    w.storageImage(RB_AO_BINDING_OUTPUT, s.core.images[0].view);
    s.classifier.writeList(w, RB_AO_BINDING_TILES);
    s.core.traceIndirect(s.ctx, cmd, w, pc, s.classifier.traceArguments(),
                         planned ? &s.adaptiveTilesPipeline : &s.tilesPipeline);
    // The check reads the traced output, so it comes after the output is readable, inside the pass's time.
    s.core.images.endWrite(s.ctx, cmd);
    s.converged.check(s.ctx, cmd, g, s.classifier, s.core.images[0].view);
    s.core.metrics.writeEnd(s.ctx, cmd);
  } else if (settings.halfResolution) {
    w.storageImage(RB_AO_BINDING_OUTPUT, s.half.samplesView());
    s.core.traceHalfAndEnd(s.ctx, cmd, w, pc, g, s.half, 0.0f, variant);
  } else {
    w.storageImage(RB_AO_BINDING_OUTPUT, s.core.images[0].view);
    s.core.traceAndEnd(s.ctx, cmd, w, pc, g, variant);
  }
  nameOutputs(s);
  s.outputs.rayPlan = planned ? s.planner.planImage() : VK_NULL_HANDLE;
  s.outputs.rayPlanView = planned ? s.planner.planView() : VK_NULL_HANDLE;
  return {};
}

const AoOutputs& AoPass::outputs() const { return impl_->outputs; }
PassStats AoPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

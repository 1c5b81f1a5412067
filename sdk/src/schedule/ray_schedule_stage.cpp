#include "ray_schedule_stage.h"

#include <cmath>
#include <cstring>
#include <string>

#include "context_impl.h"
#include "raybridge_shader_interface.glsl"

namespace rb {

namespace {

const char* signalName(DenoiseSignal s) {
  return s == DenoiseSignal::Reflection ? "Reflection" : s == DenoiseSignal::Rgb ? "Rgb" : "Scalar";
}

Status validateAdaptive(const AdaptiveRaySettings& s, const std::string& field) {
  auto invalid = [&](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, field + ".adaptive." + m};
  };
  if (!(s.timeBudgetMs >= 0.0f) || !std::isfinite(s.timeBudgetMs)) {
    return invalid("timeBudgetMs " + std::to_string(s.timeBudgetMs) + " must be a finite number >= 0 (0 = no target)");
  }
  if (!(s.initialRaysPerPixel >= 0.0f) || s.initialRaysPerPixel > float(kMaxAdaptiveRays)) {
    return invalid("initialRaysPerPixel " + std::to_string(s.initialRaysPerPixel) + " must be a number from 0 to " +
                   std::to_string(kMaxAdaptiveRays) + " (0 = raysPerPixel)");
  }
  if (s.maxRaysPerPixel > kMaxAdaptiveRays) {
    return invalid("maxRaysPerPixel " + std::to_string(s.maxRaysPerPixel) + " exceeds " +
                   std::to_string(kMaxAdaptiveRays));
  }
  if (s.minRaysPerPixel > kMaxAdaptiveRays) {
    return invalid("minRaysPerPixel " + std::to_string(s.minRaysPerPixel) + " exceeds " +
                   std::to_string(kMaxAdaptiveRays));
  }
  if (s.maxRaysPerPixel && s.minRaysPerPixel > s.maxRaysPerPixel) {
    return invalid("minRaysPerPixel " + std::to_string(s.minRaysPerPixel) + " exceeds maxRaysPerPixel " +
                   std::to_string(s.maxRaysPerPixel));
  }
  if (s.granularity != AdaptiveRayGranularity::Tile && s.granularity != AdaptiveRayGranularity::Pixel) {
    return invalid("granularity has an unknown value (" + std::to_string(uint32_t(s.granularity)) + ")");
  }
  for (auto [name, side] : {std::pair{"tileWidth", s.tileWidth}, std::pair{"tileHeight", s.tileHeight}}) {
    if (side > kMaxAdaptiveTileSize || (side & (side - 1)) != 0) {
      return invalid(std::string(name) + " " + std::to_string(side) + " must be 0 (default " +
                     std::to_string(kDefaultAdaptiveTileWidth) + "x" + std::to_string(kDefaultAdaptiveTileHeight) +
                     ") or a power of two at most " + std::to_string(kMaxAdaptiveTileSize));
    }
  }
  return {};
}

Status validateConverged(const ConvergedTileSettings& s, const std::string& field) {
  auto invalid = [&](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, field + ".convergedTiles." + m};
  };
  if (s.minFrames > RB_TILE_HOLD_MASK) {
    return invalid("minFrames " + std::to_string(s.minFrames) + " exceeds " + std::to_string(RB_TILE_HOLD_MASK));
  }
  if (!(s.maxNoise >= 0.0f) || !std::isfinite(s.maxNoise)) {
    return invalid("maxNoise " + std::to_string(s.maxNoise) + " must be a finite number >= 0 (0 = default)");
  }
  return {};
}

}  // namespace

Status validateRaySchedule(const RaySchedule& s, uint32_t capabilities, DenoiseSignal signal, const std::string& field,
                           bool historyFilled) {
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, field + "." + m}; };
  struct Stage {
    bool on;
    RayScheduleCapability capability;
    const char* member;
    const char* what;
  };
  const Stage stages[] = {
      {s.adaptive.enabled, kScheduleAdaptiveRays, "adaptive.enabled", "adaptive rays"},
      {s.convergedTiles.enabled, kScheduleConvergedTiles, "convergedTiles.enabled", "converged tiles"},
      {s.halfResolution, kScheduleHalfResolution, "halfResolution", "half resolution"},
      {s.tileClassifier, kScheduleTileClassifier, "tileClassifier", "tile classifier"},
      {s.resetRays != 0u, kScheduleResetRays, "resetRays", "reset rays"},
  };
  for (const Stage& stage : stages) {
    if (stage.on && !(capabilities & stage.capability)) {
      return invalid(std::string(stage.member) + ": this effect has no " + stage.what +
                     " (ray_schedule.h lists each effect's stages); set it to " +
                     (stage.capability == kScheduleResetRays ? "0" : "false"));
    }
  }
  if (s.adaptive.enabled) {
    if (Status st = validateAdaptive(s.adaptive, field); !st) return st;
  }
  if (s.convergedTiles.enabled) {
    if (Status st = validateConverged(s.convergedTiles, field); !st) return st;
  }
  if (s.resetRays > kMaxRaysPerPixel) {
    return invalid("resetRays " + std::to_string(s.resetRays) + " exceeds kMaxRaysPerPixel (" +
                   std::to_string(kMaxRaysPerPixel) + ")");
  }
  if (s.resetRays != 0u && s.adaptive.enabled) {
    return invalid("resetRays: adaptive rays already plan the most rays where a history restarts; set resetRays to 0 "
                   "or disable adaptive rays");
  }
  if (s.resetRays != 0u && s.halfResolution) {
    return invalid("resetRays traces more rays in the changed full-resolution pixels: set it to 0 or disable "
                   "halfResolution");
  }
  if (s.convergedTiles.enabled && s.halfResolution) {
    return invalid("convergedTiles skips tiles of full-resolution pixels: disable halfResolution or convergedTiles");
  }
  if ((s.adaptive.enabled || s.convergedTiles.enabled) && !historyFilled) {
    const char* user = s.adaptive.enabled ? "adaptive rays plan from" : "converged tiles are read from";
    if (!s.history) {
      return invalid(std::string("history is nullptr; ") + user +
                     " the history of the Denoiser that filters this effect's output: set it, or disable " +
                     (s.adaptive.enabled ? "adaptive rays" : "convergedTiles"));
    }
    if (s.history->signal() != signal) {
      return invalid(std::string("history must be a DenoiseSignal::") + signalName(signal) +
                     " Denoiser (the one filtering this effect's output)");
    }
  }
  return {};
}

ScheduleStage::ScheduleStage(ScheduledEffect effect)
    : effect_(std::move(effect)), converged_(effect_.signal), half_(effect_.halfSignal) {}

Status ScheduleStage::init(Context& ctx) {
  if (!effect_.classifierAlwaysBound) return {};
  return initClassifier(ctx);
}

Status ScheduleStage::initClassifier(Context& ctx) {
  std::vector<VkDescriptorSetLayoutBinding> bindings;
  for (const VkDescriptorSetLayoutBinding& b : effect_.classifierLaunchBindings) {
    if (b.binding == RB_BINDING_TLAS) continue;
    bindings.push_back({b.binding, b.descriptorType, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  }
  bindings.push_back(
      {effect_.tileStateBinding, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  if (Status st = classifier_.init(ctx, effect_.classifierShader, bindings, effect_.constantBytes,
                                   effect_.classifierName);
      !st) {
    return st;
  }
  classifierReady_ = true;
  return {};
}

void ScheduleStage::retire(Context& ctx) {
  for (RayTracingPipeline& p : variants_) p.retire(ctx);
  planner_.retire(ctx);
  half_.retire(ctx);
  classifier_.retire(ctx);
  converged_.retire(ctx);
  classifierReady_ = false;
}

void ScheduleStage::retireTiles(Context& ctx) {
  for (uint32_t v = 0; v < kVariantCount; ++v)
    if (v & kVariantTiles) variants_[v].retire(ctx);
  converged_.retire(ctx);
  if (!effect_.classifierAlwaysBound) {
    classifier_.retire(ctx);
    classifierReady_ = false;
  }
}

Status ScheduleStage::ensureVariant(Context& ctx, const PassCore& core, uint32_t variant) {
  variant &= effect_.variantMask;
  if (variant == 0 || variants_[variant].pipeline) return {};
  Result<RayTracingPipeline> p = core.createVariant(ctx, effect_.pipelineDesc(variant), effect_.alphaAnyHit,
                                                    effect_.recordStages);
  if (!p) return p.error();
  variants_[variant] = p.value();
  return {};
}

const RayTracingPipeline* ScheduleStage::pipeline(uint32_t variant) const {
  variant &= effect_.variantMask;
  return variant ? &variants_[variant] : nullptr;
}

bool ScheduleStage::classifierOn(const RaySchedule& s) const {
  // Converged tiles turn the classifier on where it is the effect's own (shadows); elsewhere (AO) it runs on the
  // frames whose converged tiles were marked.
  return (effect_.capabilities & kScheduleTileClassifier) && (s.tileClassifier || s.convergedTiles.enabled);
}

Status ScheduleStage::prepare(Context& ctx, const PassCore& core, const GBufferDesc& g, const RaySchedule& s,
                              uint32_t variant) {
  const bool tiles = s.convergedTiles.enabled;
  for (uint32_t a : {0u, s.adaptive.enabled ? uint32_t(kVariantAdaptive) : 0u})
    for (uint32_t t : {0u, tiles ? uint32_t(kVariantTiles) : 0u})
      if (Status st = ensureVariant(ctx, core, a | t | variant); !st) return st;
  if (effect_.capabilities & kScheduleHalfResolution) {
    if (s.halfResolution) {
      if (Status st = half_.ensure(ctx, g.width, g.height); !st) return st;
    } else {
      half_.releaseImage(ctx);  // full resolution holds no sample image
    }
  }
  const bool scalar = effect_.signal == DenoiseSignal::Scalar;
  if (effect_.classifierAlwaysBound) {
    if (!tiles) converged_.retire(ctx);
    return classifier_.ensure(ctx, g.width, g.height);
  }
  if (!tiles) {
    retireTiles(ctx);  // no tile list nor state while converged tiles are off
    return {};
  }
  if (scalar && !classifierReady_) {
    if (Status st = initClassifier(ctx); !st) return st;
  }
  // RGB signals skip converged tiles in their own launch: the tile state alone.
  return classifier_.ensure(ctx, g.width, g.height, scalar);
}

void ScheduleStage::setConstant(void* constants, uint32_t offset, uint32_t value) const {
  if (offset != kNoConstant) std::memcpy(static_cast<char*>(constants) + offset, &value, sizeof value);
}

Result<bool> ScheduleStage::traceClassified(Context& ctx, PassCore& core, VkCommandBuffer cmd, ScheduleFrame& f,
                                            bool converged, uint32_t variant) {
  const VkImageView output = core.images[0].view;
  setConstant(f.constants, effect_.convergedFlagOffset, converged ? 1u : 0u);
  DescriptorWrites cw;
  core.writeGBuffer(ctx, cw, f.g);
  cw.storageImage(effect_.outputBinding, output);
  if (f.writeExtraOutputs) f.writeExtraOutputs(cw);
  classifier_.writeList(cw, effect_.tileListBinding);
  classifier_.writeState(cw, effect_.tileStateBinding);
  classifier_.classify(ctx, cmd, cw, f.constants, effect_.constantBytes);
  setConstant(f.constants, effect_.launchOverTilesOffset, 1u);
  f.w.storageImage(effect_.outputBinding, output);
  if (!effect_.classifierAlwaysBound) classifier_.writeList(f.w, effect_.tileListBinding);
  core.bind(ctx, cmd, f.w, f.constants, effect_.constantBytes, pipeline(variant | kVariantTiles));
  const RayTracingPipeline* p = pipeline(variant | kVariantTiles);
  (p ? *p : core.pipeline).traceIndirect(ctx, cmd, classifier_.traceArguments());
  if (!converged) {
    core.end(ctx, cmd);
    return true;
  }
  // The check reads the traced output, so it comes after the output is readable, inside the pass's time.
  core.images.endWrite(ctx, cmd);
  converged_.check(ctx, cmd, f.g, classifier_, output);
  core.metrics.writeEnd(ctx, cmd);
  return true;
}

Result<bool> ScheduleStage::trace(Context& ctx, PassCore& core, VkCommandBuffer cmd, ScheduleFrame& f) {
  const RaySchedule& s = f.schedule;
  const char* who = effect_.passName;
  const VkImageView output = core.images[0].view;
  if (effect_.classifierAlwaysBound) classifier_.writeList(f.w, effect_.tileListBinding);  // statically read

  // 1. Plan. Its tiles are of launch cells: 2x2 pixels each at half resolution, where the plan covers every pixel
  // and the traced quarter uses its entries.
  bool planned = false;
  if (s.adaptive.enabled) {
    Result<bool> plan = planner_.recordForPass(core, ctx, cmd, f.g, s.adaptive, s.history, f.raysPerPixel, f.latest,
                                               who, f.w, s.halfResolution ? 2u : 1u);
    if (!plan) return plan.error();
    planned = plan.value();
  }
  const uint32_t variant = f.variant | (planned ? uint32_t(kVariantAdaptive) : 0u);

  if (effect_.signal != DenoiseSignal::Scalar) {
    // 2-5 for RGB signals: the launch over every pixel skips the converged tiles itself.
    if (s.convergedTiles.enabled) {
      f.w.storageImage(effect_.outputBinding, output);
      Result<bool> c = converged_.traceSkipping(core, ctx, cmd, f.g, s.convergedTiles, s.history, f.raysPerPixel,
                                                classifier_, f.w, f.constants, effect_.constantBytes,
                                                *pipeline(variant | kVariantTiles), effect_.tileStateBinding, who,
                                                f.roughnessThreshold);
      if (!c) return c.error();
      if (c.value()) return planned;
    }
  } else {
    // 2. Mark converged tiles, 3. classify, 4-5. trace over the list and check.
    bool converged = false;
    if (s.convergedTiles.enabled) {
      Result<bool> c = converged_.record(ctx, cmd, f.g, s.convergedTiles, s.history, f.raysPerPixel, classifier_,
                                         output, who);
      if (!c) {
        core.end(ctx, cmd);
        return c.error();
      }
      converged = c.value();
    }
    if (classifierOn(s) || converged) {
      Result<bool> t = traceClassified(ctx, core, cmd, f, converged, variant);
      if (!t) return t.error();
      return planned;
    }
  }
  // 4-5. Every pixel, or every 2x2 block and the upsample.
  if (s.halfResolution) {
    f.w.storageImage(effect_.outputBinding, half_.samplesView());
    core.traceHalfAndEnd(ctx, cmd, f.w, f.constants, effect_.constantBytes, *f.traced, f.g, half_, f.roughnessThreshold,
                         pipeline(variant));
  } else {
    f.w.storageImage(effect_.outputBinding, output);
    core.traceAndEnd(ctx, cmd, f.w, f.constants, effect_.constantBytes, f.g, pipeline(variant));
  }
  return planned;
}

}  // namespace rb

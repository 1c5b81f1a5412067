#include <raybridge/reflection_pass.h>

#include <cmath>
#include <cstring>
#include <string>

#include "context_impl.h"
#include "converged_tiles.h"
#include "many_light_pass_impl.h"
#include "material_table_impl.h"
#include "pass_core.h"
#include "raybridge_shaders.h"
#include "tile_classifier.h"  // the tile state

namespace rb {

namespace {
const VkShaderStageFlags kRaygen = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
const VkShaderStageFlags kHit = VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR;

// The pipelines of the pass: reflect.rgen, reflect_reorder.rgen (shader execution reordering), and both skipping
// the converged tiles (reflect_converged.rgen, reflect_reorder_converged.rgen: which add the tile state's binding).
RayTracingPipelineDesc reflectionPipelineDesc(bool reorder, bool tiles = false) {
  RayTracingPipelineDesc p;
  p.name = reorder ? (tiles ? "reflection pass (invocation reorder, converged tiles)"
                            : "reflection pass (invocation reorder)")
                   : (tiles ? "reflection pass (converged tiles)" : "reflection pass");
  p.raygen = reorder ? (tiles ? SpirvModule::of(spirv::reflect_reorder_converged_rgen)
                              : SpirvModule::of(spirv::reflect_reorder_rgen))
                     : (tiles ? SpirvModule::of(spirv::reflect_converged_rgen) : SpirvModule::of(spirv::reflect_rgen));
  p.misses = {SpirvModule::of(spirv::reflect_rmiss), SpirvModule::of(spirv::occlusion_rmiss)};
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::reflect_rchit), {}}};
  p.maxRecursionDepth = 2;
  p.bindings = PassCore::commonBindings();
  p.bindings[RB_BINDING_TLAS].stageFlags |= kHit;          // shadow rays from hits
  p.bindings[RB_BINDING_RAY_COUNTERS].stageFlags |= kHit;  // and their count
  p.bindings.push_back(
      {RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kRaygen, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_RADIANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, kRaygen, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, kHit, nullptr});
  if (tiles) {
    p.bindings.push_back({RB_REFLECTION_BINDING_TILE_STATE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, kRaygen, nullptr});
  }
  p.pushConstantBytes = sizeof(ReflectionConstants);
  return p;
}

}  // namespace

struct ReflectionPass::Impl {
  Context& ctx;
  PassCore core;
  std::unique_ptr<MaterialTable> ownMaterials;  // setMaterials(); retires its buffer and set itself
  // ReflectionSettings::halfResolution: the sample image and the upsample, made on first use.
  HalfResolution half{HalfResolution::Signal::Reflection};
  ReflectionOutputs outputs;
  // The same pipeline with reflect_reorder.rgen: only on a context with DeviceInfo::invocationReorder.
  RayTracingPipeline reorderPipeline;
  bool reordered = false;  // the latest record() traced with reorderPipeline
  // ReflectionSettings::convergedTiles, created on first use: the launches that skip converged tiles (plain, and
  // with reordering where the context has it), the tile state (a TileClassifier without list nor pipeline: the
  // launch stays one invocation per pixel, see reflection_raygen.glsl), and the converged-tile dispatches.
  RayTracingPipeline tilesPipeline, reorderTilesPipeline;
  TileClassifier tileState;
  ConvergedTiles converged{DenoiseSignal::Reflection};
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    half.retire(ctx);
    reorderPipeline.retire(ctx);
    retireTiles();
  }
  void retireTiles() {
    tilesPipeline.retire(ctx);
    reorderTilesPipeline.retire(ctx);
    tileState.retire(ctx);
    converged.retire(ctx);
  }
  // What converged tiles need, before the pass's recording begins (so that a failure records nothing): the launch
  // that skips them (reordered too when `reorder`), and the tile state for this size.
  Status ensureTiles(const GBufferDesc& g, bool reorder) {
    for (bool r : {false, true}) {
      RayTracingPipeline& p = r ? reorderTilesPipeline : tilesPipeline;
      if (p.pipeline || (r && !reorder)) continue;
      Result<RayTracingPipeline> v = core.createVariant(ctx, reflectionPipelineDesc(r, true),
                                                        SpirvModule::of(spirv::reflect_rahit), kHit);
      if (!v) return v.error();
      p = v.value();
    }
    return tileState.ensure(ctx, g.width, g.height, false);
  }
};

namespace {

const std::vector<PassImages::Spec> kReflectionOutputs = {{VK_FORMAT_R16G16B16A16_SFLOAT, "reflection radiance"}};

void nameOutputs(ReflectionPass::Impl& s) {
  s.outputs.radiance = s.core.images[0].image;
  s.outputs.radianceView = s.core.images[0].view;
  s.outputs.width = s.core.images[0].width;
  s.outputs.height = s.core.images[0].height;
}

}  // namespace

Status ReflectionPass::prepare(uint32_t width, uint32_t height) {
  Impl& s = *impl_;
  if (Status st = s.core.prepare(s.ctx, width, height, kReflectionOutputs, "ReflectionPass"); !st) return st;
  nameOutputs(s);
  return {};
}

ReflectionPass::ReflectionPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ReflectionPass::~ReflectionPass() = default;

Result<std::unique_ptr<ReflectionPass>> ReflectionPass::create(Context& context) {
  Context::Impl& c = internal::contextImpl(context);
  if (c.info.maxRayRecursionDepth < 2) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "ReflectionPass needs a ray recursion depth of 2 (a shadow ray from each hit); the device allows " +
                     std::to_string(c.info.maxRayRecursionDepth)};
  }
  auto impl = std::make_unique<Impl>(context);
  Result<std::unique_ptr<MaterialTable>> table = MaterialTable::create(context);
  if (!table) return table.error();
  impl->ownMaterials = std::move(table.value());
  RayTracingPipelineDesc p = reflectionPipelineDesc(false);
  // Shading records and materials: read by the hits (shading) and the any-hits (alpha).
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::reflect_rahit), kHit); !s) return s.error();
  if (c.info.invocationReorder) {
    Result<RayTracingPipeline> r = impl->core.createVariant(context, reflectionPipelineDesc(true),
                                                            SpirvModule::of(spirv::reflect_rahit), kHit);
    if (!r) return r.error();
    impl->reorderPipeline = r.value();
  }
  // The own table holds one white material until the engine gives its own.
  return std::unique_ptr<ReflectionPass>(new ReflectionPass(std::move(impl)));
}

Status ReflectionPass::setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures) {
  if (Status st = impl_->ownMaterials->setMaterials(materials, textures); !st) {
    return Error{st.error().code, st.error().vkResult, "ReflectionPass::setMaterials: " + st.error().message};
  }
  return {};
}

Status ReflectionPass::record(VkCommandBuffer cmd, const GBufferDesc& g, const TlasInfo& tlas,
                              const ReflectionSettings& settings) {
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ReflectionPass: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (!tlas.shadingRecords) {
    return invalid("the TLAS has no shading records; build it with TlasBuildOptions::writeShadingRecords = true");
  }
  if (!g.roughnessInNormalW && !g.roughnessMetalness.view) {
    return invalid("the G-buffer has no roughness: set GBufferDesc::roughnessInNormalW or roughnessMetalness");
  }
  float threshold = settings.roughnessThreshold == 0.0f ? kDefaultReflectionRoughnessThreshold
                                                        : settings.roughnessThreshold;
  if (!(threshold > 0.0f && threshold <= 1.0f)) {
    return invalid("ReflectionSettings::roughnessThreshold " + std::to_string(threshold) + " is outside (0, 1]");
  }
  if (settings.raysPerPixel > 64) return invalid("ReflectionSettings::raysPerPixel exceeds 64");
  if (Status st = s.converged.validate(settings.convergedTiles, "ReflectionPass: ReflectionSettings::convergedTiles");
      !st) {
    return st;
  }
  if (settings.convergedTiles.enabled && settings.halfResolution) {
    return invalid("ReflectionSettings::convergedTiles skips tiles of full-resolution pixels: disable halfResolution "
                   "or convergedTiles");
  }
  const bool sunUnset = settings.sunDirection[0] == 0.0f && settings.sunDirection[1] == 0.0f &&
                        settings.sunDirection[2] == 0.0f;
  const float sunDirection[3] = {settings.sunDirection[0], sunUnset ? 1.0f : settings.sunDirection[1],
                                 settings.sunDirection[2]};
  float sunLen = std::sqrt(sunDirection[0] * sunDirection[0] + sunDirection[1] * sunDirection[1] +
                           sunDirection[2] * sunDirection[2]);
  if (!std::isfinite(sunLen)) return invalid("ReflectionSettings::sunDirection must be finite");
  // Zero means the default, unless the engine says its zeros are meant (a black sky, no sky light).
  const bool explicitLighting = (settings.flags & kReflectionExplicitLighting) != 0;
  auto isZero = [](const float c[3]) { return c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f; };
  const bool defaultSun = !explicitLighting && isZero(settings.sunRadiance);
  const bool defaultSky = !explicitLighting && isZero(settings.skyRadiance);
  ReflectionConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ReflectionPass", pc.gbuffer); !st) return st;
  for (int i = 0; i < 3; ++i) {
    pc.sunDirection[i] = sunDirection[i] / sunLen;
    pc.sunRadiance[i] = (settings.flags & kReflectionNoSun) ? 0.0f
                        : defaultSun                        ? kDefaultSunRadiance
                                                            : settings.sunRadiance[i];
    pc.skyRadiance[i] = defaultSky ? kDefaultSkyRadiance[i] : settings.skyRadiance[i];
  }
  pc.roughnessThreshold = threshold;
  pc.ambientIntensity = settings.ambientIntensity == 0.0f && !explicitLighting ? kDefaultAmbientIntensity
                                                                               : settings.ambientIntensity;
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultReflectionRays;
  pc.halfResolution = settings.halfResolution ? 1u : 0u;

  internal::LightListView lights;
  if (settings.lights) {
    lights = internal::lightList(*settings.lights);
    if (lights.frame != s.ctx.frameIndex())
      return invalid("ReflectionSettings::lights: that ManyLightPass was not recorded this frame; record it before "
                     "the reflection pass");
    for (int i = 0; i < 3; ++i)
      if (lights.originOffset[i] != tlas.originOffset[i])
        return invalid("ReflectionSettings::lights: that ManyLightPass traced another TLAS space (originOffset)");
    if (settings.lightCandidates > 64)
      return invalid("ReflectionSettings::lightCandidates " + std::to_string(settings.lightCandidates) + " exceeds 64");
    pc.lightCount = lights.count;
    pc.lightCandidates = settings.lightCandidates ? settings.lightCandidates : kDefaultReflectionLightCandidates;
  }
  DescriptorWrites w;
  const MaterialTable* table = settings.materials ? settings.materials : s.ownMaterials.get();
  if (Status st = s.core.writeMaterials(w, tlas, table, "ReflectionPass", pc.gbuffer.flags); !st) return st;
  if (settings.halfResolution) {
    if (Status st = s.half.ensure(s.ctx, g.width, g.height); !st) return st;
  } else {
    s.half.releaseImage(s.ctx);  // full resolution holds no sample image
  }
  s.reordered = s.reorderPipeline.pipeline && settings.invocationReorder;
  if (settings.convergedTiles.enabled) {
    if (Status st = s.ensureTiles(g, s.reordered); !st) return st;
  } else if (s.tilesPipeline.pipeline) {
    s.retireTiles();  // no tile state while converged tiles are off
  }
  if (Status st = s.core.begin(s.ctx, cmd, g, kReflectionOutputs); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  const GBufferImage& rm = g.roughnessMetalness.view ? g.roughnessMetalness : g.normal;
  w.sampledImage(RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, rm.view, s.core.sampler, readLayout(rm));
  w.storageImage(RB_REFLECTION_BINDING_RADIANCE,
                 settings.halfResolution ? s.half.samplesView() : s.core.images[0].view);
  // The local lights' list when given, else any valid buffer (never read: lightCount is 0).
  w.storageBuffer(RB_REFLECTION_BINDING_LIGHTS,
                  pc.lightCount ? lights.buffer : internal::materialTableImpl(*table).materials.buffer);
  const RayTracingPipeline* variant = s.reordered ? &s.reorderPipeline : nullptr;
  bool converged = false;
  if (settings.convergedTiles.enabled) {
    Result<bool> c = s.converged.traceSkipping(s.core, s.ctx, cmd, g, settings.convergedTiles, pc.raysPerPixel,
                                               s.tileState, w, &pc, sizeof pc,
                                               s.reordered ? s.reorderTilesPipeline : s.tilesPipeline,
                                               RB_REFLECTION_BINDING_TILE_STATE, "ReflectionPass", threshold);
    if (!c) return c.error();
    converged = c.value();
  }
  if (converged) {
    // Traced, checked and ended by traceSkipping().
  } else if (settings.halfResolution) {
    s.core.traceHalfAndEnd(s.ctx, cmd, w, pc, g, s.half, threshold, variant);
  } else {
    s.core.traceAndEnd(s.ctx, cmd, w, pc, g, variant);
  }
  nameOutputs(s);
  return {};
}

const ReflectionOutputs& ReflectionPass::outputs() const { return impl_->outputs; }
PassStats ReflectionPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }
bool ReflectionPass::reordered() const { return impl_->reordered; }

}  // namespace rb

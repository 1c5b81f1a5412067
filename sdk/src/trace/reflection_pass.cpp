#include <raybridge/reflection_pass.h>

#include <cmath>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "changed_box.h"
#include "context_impl.h"
#include "initial_extent.h"
#include "light_list_buffer.h"
#include "material_table_impl.h"
#include "pass_constants.h"
#include "pass_core.h"
#include "ray_schedule_stage.h"
#include "raybridge_shaders.h"
#include "scene_lighting_resolve.h"

namespace rb {

namespace {
const VkShaderStageFlags kRaygen = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
const VkShaderStageFlags kHit = VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR;
// ReflectionConstants::sunCacheRoughness without ReflectionFrame::sunVisibility: rougher than any pixel.
constexpr float kNoSunCache = 2.0f;
static_assert(kReflectionSunCacheDistanceTolerance == float(RB_REFLECTION_SUN_CACHE_DISTANCE_TOLERANCE) &&
                  kReflectionSunCacheMinNormalCos == float(RB_REFLECTION_SUN_CACHE_MIN_NORMAL_COS),
              "reflect.rchit tests the surface with the values reflection_pass.h documents");

// The pipelines of the pass: reflect.rgen, and its variants (ScheduleVariant bits) with shader execution
// reordering and skipping the converged tiles (which adds the tile state's binding).
RayTracingPipelineDesc reflectionPipelineDesc(uint32_t variant) {
  const bool reorder = variant & kVariantReorder, tiles = variant & kVariantTiles;
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
  // Hits that read the sun's visibility from the screen find their pixel's surface (reflect.rchit).
  p.bindings[RB_BINDING_DEPTH].stageFlags |= kHit;
  p.bindings[RB_BINDING_GEOMETRIC_NORMAL].stageFlags |= kHit;
  p.bindings.push_back(
      {RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kRaygen, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_RADIANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, kRaygen, nullptr});
  p.bindings.push_back({RB_REFLECTION_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, kHit, nullptr});
  p.bindings.push_back(
      {RB_REFLECTION_BINDING_SUN_VISIBILITY, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, kHit, nullptr});
  if (tiles) {
    p.bindings.push_back({RB_REFLECTION_BINDING_TILE_STATE, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, kRaygen, nullptr});
  }
  p.pushConstantBytes = sizeof(ReflectionConstants);
  return p;
}


// Reflections to the schedule stage: a Reflection signal with half resolution and converged tiles, skipped inside
// its launch (one invocation per pixel, see reflection_raygen.glsl), with reordered variants.
ScheduledEffect reflectionSchedule() {
  ScheduledEffect e;
  e.passName = "ReflectionPass";
  e.capabilities = kReflectionScheduleCapabilities;
  e.signal = DenoiseSignal::Reflection;
  e.halfSignal = HalfResolution::Signal::Reflection;
  e.outputBinding = RB_REFLECTION_BINDING_RADIANCE;
  e.tileStateBinding = RB_REFLECTION_BINDING_TILE_STATE;
  e.variantMask = kVariantReorder | kVariantTiles;
  e.pipelineDesc = reflectionPipelineDesc;
  e.alphaAnyHit = SpirvModule::of(spirv::reflect_rahit);
  e.recordStages = kHit;
  e.constantBytes = sizeof(ReflectionConstants);
  return e;
}

}  // namespace

struct ReflectionPass::Impl {
  Context& ctx;
  PassCore core;
  std::unique_ptr<MaterialTable> ownMaterials;   // setMaterials(); retires its buffer and set itself
  ScheduleStage schedule{reflectionSchedule()};  // half resolution, converged tiles, the reordered variants
  ReflectionOutputs outputs;
  bool reordered = false;  // the latest record() traced with a reordered variant
  // ReflectionSettings::changedBoxes and relitBoxes: kMaxReflectionChangedBoxes a frame in flight, host-visible,
  // created with the first frame that gives any.
  GpuBuffer changedRing;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still trace with it
    core.retire(ctx);
    schedule.retire(ctx);
    if (changedRing.valid()) retireBuffer(ctx, changedRing);
  }
};

namespace {

const std::vector<PassImages::Spec> kReflectionOutputs = {{VK_FORMAT_R16G16B16A16_SFLOAT, "reflection radiance"}};

// Mirrors RbReflectionChangedBox (shaders/reflection_changes.glsl): a box in the TLAS's space.
struct ReflectionChangedBox {
  float lo[3];
  uint32_t relit;  // 0: geometry (path and sun ray tested), 1: lighting (the hit point tested)
  float hi[3];
  float pad;
};
static_assert(sizeof(ReflectionChangedBox) == 32);

// ReflectionSettings::changedBoxes and relitBoxes checked, into this frame's slot of the ring, moved into the TLAS's
// space; sets pc's count and address (nothing when both are empty, or at half resolution: the upsample writes
// coverage, not the stale mark).
Status writeChangedBoxes(ReflectionPass::Impl& s, const ReflectionSettings& settings, const TlasInfo& tlas,
                         ReflectionConstants& pc) {
  const size_t count = settings.changedBoxes.size() + settings.relitBoxes.size();
  if (count > kMaxReflectionChangedBoxes) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "ReflectionPass: ReflectionSettings::changedBoxes and relitBoxes hold " + std::to_string(count) +
                     " boxes, more than kMaxReflectionChangedBoxes (" + std::to_string(kMaxReflectionChangedBoxes) +
                     "); merge neighbouring boxes"};
  }
  std::vector<ReflectionChangedBox> boxes;
  boxes.reserve(count);
  for (const auto& [list, relit, field] :
       {std::tuple{settings.changedBoxes, 0u, "changedBoxes"}, std::tuple{settings.relitBoxes, 1u, "relitBoxes"}}) {
    for (size_t i = 0; i < list.size(); ++i) {
      const ChangedBox& b = list[i];
      if (invalidChangedBoxAxis(b) >= 0) {
        return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                     std::string("ReflectionPass: ReflectionSettings::") + field + "[" + std::to_string(i) +
                         "] is not a box (min <= max, finite, on every axis); fix or drop it"};
      }
      ReflectionChangedBox g{};
      g.relit = relit;
      for (int a = 0; a < 3; ++a) {
        // Rounded outwards: a float box never leaves out what the double one holds.
        g.lo[a] = std::nextafter(float(b.min[a] - tlas.originOffset[a]), -INFINITY);
        g.hi[a] = std::nextafter(float(b.max[a] - tlas.originOffset[a]), INFINITY);
      }
      boxes.push_back(g);
    }
  }
  if (boxes.empty() || settings.schedule.halfResolution) return {};
  const VkDeviceSize slotBytes = VkDeviceSize(kMaxReflectionChangedBoxes) * sizeof(ReflectionChangedBox);
  if (!s.changedRing.valid()) {
    Result<GpuBuffer> r = createBuffer(s.ctx, slotBytes * s.ctx.framesInFlight(),
                                       VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                                       MemoryLocation::HostVisible, MemoryCategory::PassBuffers,
                                       "ReflectionPass: changed boxes");
    if (!r) return r.error();
    s.changedRing = r.value();
  }
  const VkDeviceSize offset = (s.ctx.frameIndex() % s.ctx.framesInFlight()) * slotBytes;
  std::memcpy(static_cast<uint8_t*>(s.changedRing.mapped) + offset, boxes.data(),
              boxes.size() * sizeof(ReflectionChangedBox));
  pc.changedBoxes = s.changedRing.address + offset;
  pc.changedBoxCount = uint32_t(boxes.size());
  return {};
}

// ReflectionFrame::sunVisibility against its contract (reflection_pass.h): a G-buffer image's, at the G-buffer's
// size; "" when it holds or is not given.
std::string sunVisibilityProblem(const GBufferImage& image, const GBufferDesc& g) {
  if (!image.view) return {};
  const std::string name = "ReflectionFrame::sunVisibility";
  if (std::string problem = checkImage(image, name, false); !problem.empty()) return problem;
  if ((image.width != 0 || image.height != 0) && (image.width != g.width || image.height != g.height)) {
    return name + " is " + std::to_string(image.width) + "x" + std::to_string(image.height) + ", not the G-buffer's " +
           std::to_string(g.width) + "x" + std::to_string(g.height) +
           ": a hit reads the pixel it projects to, so the image must cover the G-buffer pixel for pixel";
  }
  return {};
}

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

Result<std::unique_ptr<ReflectionPass>> ReflectionPass::create(Context& context, const ReflectionPassDesc& desc) {
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
  RayTracingPipelineDesc p = reflectionPipelineDesc(0);
  // Shading records and materials: read by the hits (shading) and the any-hits (alpha).
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::reflect_rahit), kHit); !s) return s.error();
  if (c.info.invocationReorder) {
    if (Status s = impl->schedule.ensureVariant(context, impl->core, kVariantReorder); !s) return s.error();
  }
  // The own table holds one white material until the engine gives its own.
  std::unique_ptr<ReflectionPass> pass(new ReflectionPass(std::move(impl)));
  if (Status s = internal::prepareAtCreation(*pass, desc.width, desc.height, "ReflectionPassDesc"); !s) {
    return s.error();
  }
  return pass;
}

Status ReflectionPass::setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures) {
  if (Status st = impl_->ownMaterials->setMaterials(materials, textures); !st) {
    return Error{st.error().code, st.error().vkResult, "ReflectionPass::setMaterials: " + st.error().message};
  }
  return {};
}

Status ReflectionPass::record(VkCommandBuffer cmd, const ReflectionFrame& input) {
  const GBufferDesc& g = input.gbuffer;
  const TlasInfo& tlas = input.tlas;
  const ReflectionSettings& settings = input.settings;
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "ReflectionPass: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (Status st = validateRaySchedule(settings.schedule, kReflectionScheduleCapabilities, DenoiseSignal::Reflection,
                                      "ReflectionPass: ReflectionSettings::schedule");
      !st) {
    return st;
  }
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
  const float sunCacheRoughness = settings.sunVisibilityMinRoughness == 0.0f ? kDefaultReflectionSunCacheRoughness
                                                                             : settings.sunVisibilityMinRoughness;
  if (!(sunCacheRoughness > 0.0f && sunCacheRoughness <= 1.0f)) {
    return invalid("ReflectionSettings::sunVisibilityMinRoughness " + std::to_string(sunCacheRoughness) +
                   " is outside (0, 1]");
  }
  if (std::string problem = sunVisibilityProblem(input.sunVisibility, g); !problem.empty()) return invalid(problem);
  Result<ResolvedLighting> lighting = resolveSceneLighting(settings.lighting,
                                                           "ReflectionPass: ReflectionSettings::lighting");
  if (!lighting) return lighting.error();
  ReflectionConstants pc{};
  if (Status st = fillGBufferConstants(g, tlas, s.ctx.frameIndex(), "ReflectionPass", pc.gbuffer); !st) return st;
  fillLighting(lighting.value(), pc);
  pc.roughnessThreshold = threshold;
  pc.raysPerPixel = settings.raysPerPixel ? settings.raysPerPixel : kDefaultReflectionRays;
  pc.halfResolution = settings.schedule.halfResolution ? 1u : 0u;
  pc.sunCacheRoughness = input.sunVisibility.view ? sunCacheRoughness : kNoSunCache;

  LightListInfo lights;
  if (settings.lights) {
    Result<LightListInfo> read = readLightList(*settings.lights, tlas, s.ctx.frameIndex(),
                                               "ReflectionPass: ReflectionSettings::lights");
    if (!read) return read.error();
    lights = read.value();
    if (settings.lightCandidates > 64)
      return invalid("ReflectionSettings::lightCandidates " + std::to_string(settings.lightCandidates) + " exceeds 64");
    pc.lightCount = lights.count;
    pc.lightCandidates = settings.lightCandidates ? settings.lightCandidates : kDefaultReflectionLightCandidates;
  }
  if (Status st = writeChangedBoxes(s, settings, tlas, pc); !st) return st;
  DescriptorWrites w;
  const MaterialTable* table = settings.materials ? settings.materials : s.ownMaterials.get();
  if (Status st = s.core.writeMaterials(w, tlas, table, "ReflectionPass", pc.gbuffer.flags); !st) return st;
  s.reordered = s.ctx.deviceInfo().invocationReorder && settings.invocationReorder;
  const uint32_t variant = s.reordered ? uint32_t(kVariantReorder) : 0u;
  if (Status st = s.schedule.prepare(s.ctx, s.core, g, settings.schedule, variant); !st) return st;
  if (Status st = s.core.begin(s.ctx, cmd, g, kReflectionOutputs); !st) return st;
  s.core.writeCommon(s.ctx, w, g, tlas);
  const GBufferImage& rm = g.roughnessMetalness.view ? g.roughnessMetalness : g.normal;
  w.sampledImage(RB_REFLECTION_BINDING_ROUGHNESS_METALNESS, rm.view, s.core.sampler, readLayout(rm));
  // The local lights' list when given, else any valid buffer (never read: lightCount is 0).
  w.storageBuffer(RB_REFLECTION_BINDING_LIGHTS, pc.lightCount ? lights.buffer : table->info().materials);
  // The sun's visibility when given, else the depth image (never read: no pixel reaches kNoSunCache).
  const GBufferImage& sun = input.sunVisibility.view ? input.sunVisibility : g.depth;
  w.sampledImage(RB_REFLECTION_BINDING_SUN_VISIBILITY, sun.view, s.core.sampler, readLayout(sun));
  ScheduleFrame frame{g, settings.schedule, w, &pc, &pc.gbuffer, pc.raysPerPixel, {}, threshold, variant};
  if (Result<bool> traced = s.schedule.trace(s.ctx, s.core, cmd, frame); !traced) return traced.error();
  // Stale marks (a = 2) where a ray met a change: the Denoiser filtering this view reads them (RB_DN_KEPT_MARKS).
  if (pc.changedBoxCount != 0u) internal::contextImpl(s.ctx).markKeptHistory(s.core.images[0].view);
  nameOutputs(s);
  return {};
}

const ReflectionOutputs& ReflectionPass::outputs() const { return impl_->outputs; }
PassStats ReflectionPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }
bool ReflectionPass::reordered() const { return impl_->reordered; }

}  // namespace rb

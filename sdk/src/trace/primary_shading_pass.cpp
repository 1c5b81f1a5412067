#include <raybridge/primary_shading_pass.h>

#include <cmath>
#include <string>

#include "context_impl.h"
#include "initial_extent.h"
#include "light_list_buffer.h"
#include "material_table_impl.h"
#include "pass_core.h"
#include "raybridge_shaders.h"
#include "scene_lighting_resolve.h"

namespace rb {

struct PrimaryShadingPass::Impl {
  Context& ctx;
  PassCore core;  // pipeline, images (radiance unless the caller gives one, distance), metrics, material bindings
  PrimaryShadingOutputs outputs;
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() { core.retire(ctx); }  // frames in flight may still trace with it
};

namespace {

// The pass's own images: the radiance unless the caller writes it into its own image, and the distance.
std::vector<PassImages::Spec> ownImages(bool callerRadiance) {
  std::vector<PassImages::Spec> specs;
  if (!callerRadiance) specs.push_back({VK_FORMAT_R16G16B16A16_SFLOAT, "primary shading radiance"});
  specs.push_back({VK_FORMAT_R32_SFLOAT, "primary shading distance"});
  return specs;
}

}  // namespace

PrimaryShadingPass::PrimaryShadingPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PrimaryShadingPass::~PrimaryShadingPass() = default;

Result<std::unique_ptr<PrimaryShadingPass>> PrimaryShadingPass::create(Context& context,
                                                                       const PrimaryShadingPassDesc& desc) {
  Context::Impl& c = internal::contextImpl(context);
  if (c.info.maxRayRecursionDepth < 2) {
    return Error{ErrorCode::MissingFeature, VK_SUCCESS,
                 "PrimaryShadingPass needs a ray recursion depth of 2 (a shadow ray from each hit); the device "
                 "allows " +
                     std::to_string(c.info.maxRayRecursionDepth)};
  }
  RayTracingPipelineDesc p;
  p.name = "primary shading pass";
  p.raygen = SpirvModule::of(spirv::primary_shading_rgen);
  p.misses = {SpirvModule::of(spirv::primary_shading_rmiss), SpirvModule::of(spirv::occlusion_rmiss)};
  p.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::primary_shading_rchit), {}}};
  p.maxRecursionDepth = 2;
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  const VkShaderStageFlags hit = VK_SHADER_STAGE_CLOSEST_HIT_BIT_KHR;
  p.bindings = {
      {RB_BINDING_TLAS, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, rg | hit, nullptr},  // shadow rays too
      {RB_PRIMARY_SHADING_BINDING_RADIANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr},
      {RB_PRIMARY_SHADING_BINDING_DISTANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr},
      {RB_BINDING_RAY_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr},
      {RB_PRIMARY_SHADING_BINDING_LIGHTS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, hit, nullptr},
  };
  p.pushConstantBytes = sizeof(PrimaryShadingConstants);
  auto impl = std::make_unique<Impl>(context);
  // Shading records and materials: read by the hits (shading) and the any-hits (alpha).
  if (Status s = impl->core.init(context, p, SpirvModule::of(spirv::primary_shading_rahit), hit); !s) return s.error();
  std::unique_ptr<PrimaryShadingPass> pass(new PrimaryShadingPass(std::move(impl)));
  if (Status s = internal::prepareAtCreation(*pass, desc.width, desc.height, "PrimaryShadingPassDesc"); !s) {
    return s.error();
  }
  return pass;
}

Status PrimaryShadingPass::prepare(uint32_t width, uint32_t height) {
  Impl& s = *impl_;
  if (Status st = s.core.prepare(s.ctx, width, height, ownImages(false), "PrimaryShadingPass"); !st) return st;
  PrimaryShadingOutputs& o = s.outputs;
  o = {};
  o.radiance = s.core.images[0].image;
  o.radianceView = s.core.images[0].view;
  o.distance = s.core.images[1].image;
  o.distanceView = s.core.images[1].view;
  o.width = width;
  o.height = height;
  return {};
}

Status PrimaryShadingPass::record(VkCommandBuffer cmd, const PrimaryShadingFrame& frame) {
  const TlasInfo& tlas = frame.tlas;
  const PrimaryRayCamera& worldCamera = frame.camera;
  const PrimaryShadingTargets& targets = frame.targets;
  const PrimaryShadingSettings& settings = frame.settings;
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "PrimaryShadingPass: " + m};
  };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (!tlas.tlas) return invalid("the TLAS is VK_NULL_HANDLE; build one with recordTlasBuild()");
  if (!tlas.shadingRecords)
    return invalid("the TLAS has no shading records; build it with TlasBuildOptions::writeShadingRecords = true");
  if (targets.width == 0 || targets.height == 0)
    return invalid("PrimaryShadingTargets::width and height are required (got " + std::to_string(targets.width) + "x" +
                   std::to_string(targets.height) + ")");
  PrimaryRayCamera camera = worldCamera;  // in the TLAS's space
  for (int i = 0; i < 3; ++i) {
    camera.eye[i] = float(double(worldCamera.eye[i]) - tlas.originOffset[i]);
    camera.target[i] = float(double(worldCamera.target[i]) - tlas.originOffset[i]);
  }
  Result<CameraBasis> basis = computeCameraBasis(camera, targets.width, targets.height);
  if (!basis) return invalid("camera: " + basis.error().message);
  Result<ResolvedLighting> lighting = resolveSceneLighting(settings.lighting,
                                                           "PrimaryShadingPass: PrimaryShadingSettings::lighting");
  if (!lighting) return lighting.error();
  if (settings.lightCandidates > kMaxPrimaryShadingLightCandidates)
    return invalid("PrimaryShadingSettings::lightCandidates " + std::to_string(settings.lightCandidates) +
                   " exceeds 64");

  PrimaryShadingConstants pc{};
  for (int i = 0; i < 3; ++i) {
    pc.camera.eye[i] = basis->eye[i];
    pc.camera.right[i] = basis->right[i];
    pc.camera.up[i] = basis->up[i];
    pc.camera.forward[i] = basis->forward[i];
  }
  pc.camera.width = targets.width;
  pc.camera.height = targets.height;
  pc.camera.tMin = camera.tMin;
  pc.camera.tMax = camera.tMax > 0.0f ? camera.tMax : 1e30f;
  pc.camera.frameIndex = uint32_t(s.ctx.frameIndex());
  fillLighting(lighting.value(), pc);
  LightListInfo lights;
  if (settings.lights) {
    Result<LightListInfo> read = readLightList(*settings.lights, tlas, s.ctx.frameIndex(),
                                               "PrimaryShadingPass: PrimaryShadingSettings::lights");
    if (!read) return read.error();
    lights = read.value();
    pc.lightCount = lights.count;
    pc.lightCandidates = settings.lightCandidates ? settings.lightCandidates : kDefaultPrimaryShadingLightCandidates;
  }

  DescriptorWrites w;
  if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "PrimaryShadingPass", pc.camera.flags); !st)
    return st;
  const std::vector<PassImages::Spec> specs = ownImages(targets.radiance != VK_NULL_HANDLE);
  GBufferDesc size;  // only the launch and image size
  size.width = targets.width;
  size.height = targets.height;
  if (Status st = s.core.begin(s.ctx, cmd, size, specs); !st) return st;
  const GpuImage& distance = s.core.images[specs.size() - 1];
  w.accelerationStructure(RB_BINDING_TLAS, tlas.tlas);
  w.storageImage(RB_PRIMARY_SHADING_BINDING_RADIANCE, targets.radiance ? targets.radiance : s.core.images[0].view);
  w.storageImage(RB_PRIMARY_SHADING_BINDING_DISTANCE, distance.view);
  w.storageBuffer(RB_BINDING_RAY_COUNTERS, s.core.metrics.counterBuffer(), s.core.metrics.counterOffset(s.ctx),
                  s.core.metrics.counterBytes());
  // The local lights' list when given, else any valid buffer (never read: lightCount is 0).
  const MaterialTable& table = settings.materials ? *settings.materials : *s.core.fallbackMaterials;
  w.storageBuffer(RB_PRIMARY_SHADING_BINDING_LIGHTS, pc.lightCount ? lights.buffer : table.info().materials);
  s.core.traceAndEnd(s.ctx, cmd, w, pc, size);

  PrimaryShadingOutputs& o = s.outputs;
  o = {};
  if (!targets.radiance) o.radiance = s.core.images[0].image, o.radianceView = s.core.images[0].view;
  o.distance = distance.image;
  o.distanceView = distance.view;
  o.width = targets.width;
  o.height = targets.height;
  return {};
}

const PrimaryShadingOutputs& PrimaryShadingPass::outputs() const { return impl_->outputs; }
PassStats PrimaryShadingPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

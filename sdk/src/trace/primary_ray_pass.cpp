#include <raybridge/primary_ray_pass.h>

#include <cmath>
#include <string>

#include "context_impl.h"
#include "pass_constants.h"
#include "pass_core.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {

void cross(const float a[3], const float b[3], float out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

float normalize(float v[3]) {
  float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (len > 0.0f) {
    v[0] /= len;
    v[1] /= len;
    v[2] /= len;
  }
  return len;
}

}  // namespace

Result<CameraBasis> computeCameraBasis(const PrimaryRayCamera& camera, uint32_t width, uint32_t height) {
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, m}; };
  if (width == 0 || height == 0) {
    return invalid("image size " + std::to_string(width) + "x" + std::to_string(height) + " is empty");
  }
  float fov = camera.verticalFovDegrees == 0.0f ? 60.0f : camera.verticalFovDegrees;
  if (!(fov > 0.0f && fov < 180.0f)) {
    return invalid("verticalFovDegrees " + std::to_string(fov) + " is outside (0, 180)");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(camera.eye[i]) || !std::isfinite(camera.target[i])) {
      return invalid("camera eye and target must be finite numbers");
    }
  }
  CameraBasis b;
  for (int i = 0; i < 3; ++i) {
    b.eye[i] = camera.eye[i];
    b.forward[i] = camera.target[i] - camera.eye[i];
  }
  if (normalize(b.forward) == 0.0f) return invalid("camera eye equals target; they must differ to define a view");
  float up[3] = {camera.upHint[0], camera.upHint[1], camera.upHint[2]};
  cross(b.forward, up, b.right);
  if (normalize(b.right) < 1e-6f) {
    return invalid("camera up hint is parallel to the view direction; choose another up vector");
  }
  cross(b.right, b.forward, b.up);
  normalize(b.up);
  float tanHalf = std::tan(fov * 0.5f * 3.14159265358979f / 180.0f);
  float aspect = float(width) / float(height);
  for (int i = 0; i < 3; ++i) {
    b.right[i] *= tanHalf * aspect;
    b.up[i] *= tanHalf;
  }
  return b;
}

struct PrimaryRayPass::Impl {
  Context& ctx;
  PassCore core;  // pipeline, metrics and material bindings; no G-buffer, no output images of its own
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() { core.retire(ctx); }  // frames in flight may still trace with it
};

PrimaryRayPass::PrimaryRayPass(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PrimaryRayPass::~PrimaryRayPass() = default;

Result<std::unique_ptr<PrimaryRayPass>> PrimaryRayPass::create(Context& context, const PrimaryRayPassDesc& passDesc) {
  RayTracingPipelineDesc desc;
  desc.name = "primary ray pass";
  desc.raygen = SpirvModule::of(spirv::primary_rgen);
  desc.misses = {SpirvModule::of(spirv::primary_rmiss)};
  desc.hitGroups = {HitGroupDesc{SpirvModule::of(spirv::primary_rchit), {}}};
  const VkShaderStageFlags rg = VK_SHADER_STAGE_RAYGEN_BIT_KHR;
  desc.bindings = {
      {RB_PRIMARY_BINDING_TLAS, VK_DESCRIPTOR_TYPE_ACCELERATION_STRUCTURE_KHR, 1, rg, nullptr},
      {RB_PRIMARY_BINDING_HIT_DISTANCE, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr},
      {RB_PRIMARY_BINDING_HIT_IDS, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, rg, nullptr},
      {RB_BINDING_RAY_COUNTERS, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, rg, nullptr},
  };
  desc.pushConstantBytes = sizeof(PrimaryConstants);
  auto impl = std::make_unique<Impl>(context);
  // Opaque only: no any-hit shader, so PassCore adds neither the material bindings nor its fallback table.
  const SpirvModule alphaTest = passDesc.opaqueOnly ? SpirvModule{} : SpirvModule::of(spirv::primary_rahit);
  if (Status s = impl->core.init(context, desc, alphaTest); !s) return s.error();
  return std::unique_ptr<PrimaryRayPass>(new PrimaryRayPass(std::move(impl)));
}

Status PrimaryRayPass::record(VkCommandBuffer cmd, const PrimaryRayFrame& frame) {
  const TlasInfo& tlas = frame.tlas;
  const PrimaryRayCamera& worldCamera = frame.camera;
  const PrimaryRayTargets& targets = frame.targets;
  const PrimaryRaySettings& settings = frame.settings;
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, m}; };
  if (!cmd) return invalid("PrimaryRayPass::record: cmd is VK_NULL_HANDLE");
  if (!tlas.tlas) return invalid("PrimaryRayPass::record: tlas is VK_NULL_HANDLE; build one with recordTlasBuild()");
  PrimaryRayCamera camera = worldCamera;  // in the TLAS's space
  for (int i = 0; i < 3; ++i) {
    camera.eye[i] = float(double(worldCamera.eye[i]) - tlas.originOffset[i]);
    camera.target[i] = float(double(worldCamera.target[i]) - tlas.originOffset[i]);
  }
  if (!targets.hitDistance || !targets.hitIds) {
    return invalid("PrimaryRayPass::record: targets.hitDistance and targets.hitIds are required");
  }
  Result<CameraBasis> basis = computeCameraBasis(camera, targets.width, targets.height);
  if (!basis) return Error{basis.error().code, VK_SUCCESS, "PrimaryRayPass::record: " + basis.error().message};
  PrimaryConstants pc{};
  for (int i = 0; i < 3; ++i) {
    pc.eye[i] = basis->eye[i];
    pc.right[i] = basis->right[i];
    pc.up[i] = basis->up[i];
    pc.forward[i] = basis->forward[i];
  }
  pc.width = targets.width;
  pc.height = targets.height;
  pc.tMin = camera.tMin;
  pc.tMax = camera.tMax > 0.0f ? camera.tMax : 1e30f;
  pc.frameIndex = uint32_t(impl_->ctx.frameIndex());
  Impl& s = *impl_;
  DescriptorWrites w;
  if (s.core.alphaTested()) {
    if (Status st = s.core.writeMaterials(w, tlas, settings.materials, "PrimaryRayPass", pc.flags); !st) return st;
  } else if (settings.materials) {
    return invalid("PrimaryRayPass::record: PrimaryRaySettings::materials is set, but the pass was created with "
                   "PrimaryRayPassDesc::opaqueOnly (no alpha test); create it without opaqueOnly to alpha-test");
  }
  w.accelerationStructure(RB_PRIMARY_BINDING_TLAS, tlas.tlas);
  w.storageImage(RB_PRIMARY_BINDING_HIT_DISTANCE, targets.hitDistance);
  w.storageImage(RB_PRIMARY_BINDING_HIT_IDS, targets.hitIds);
  w.storageBuffer(RB_BINDING_RAY_COUNTERS, s.core.metrics.counterBuffer(), s.core.metrics.counterOffset(s.ctx),
                  s.core.metrics.counterBytes());
  if (Status st = s.core.metrics.beginRecording(s.ctx, cmd); !st) return st;
  s.core.metrics.writeStart(s.ctx, cmd);
  s.core.bind(s.ctx, cmd, w, &pc, sizeof(pc));
  s.core.pipeline.trace(s.ctx, cmd, targets.width, targets.height);
  // One ray per pixel, counted here: the shader adds none (primary.rgen).
  s.core.metrics.addHostRays(s.ctx, uint64_t(targets.width) * targets.height);
  s.core.metrics.writeEnd(s.ctx, cmd);
  return {};
}

PassStats PrimaryRayPass::stats() const { return impl_->core.metrics.latest(impl_->ctx); }

}  // namespace rb

// The first trace: one primary ray per pixel through the TLAS, writing hit distance and ids. It proves the
// acceleration-structure service end to end and is the reference for conformance tests; the effect passes
// start from the engine's G-buffer instead of primary rays. Given a MaterialTable and a TLAS with non-opaque
// instances, primary rays alpha-test like every other ray (material_table.h): they pass through Mask cut-outs,
// and Blend surfaces are invisible to them, as they are to an engine's G-buffer (blended surfaces are drawn in a
// forward pass after lighting). Otherwise they take the opaque fast path.
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipeline and shader
// binding table are handed to the Context's deferred release (see context.h) and freed once those frames are
// done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/context.h>
#include <raybridge/effects.h>
#include <raybridge/material_table.h>

#include <memory>

namespace rb {

// Pinhole camera, right-handed. Pixel (x, y) counts from the top-left; the ray goes through the pixel centre:
//   ndc = ((x + 0.5) / width * 2 - 1, (y + 0.5) / height * 2 - 1)
//   dir = normalize(forward + ndc.x * tan(fovY/2) * aspect * right - ndc.y * tan(fovY/2) * up)
// where forward = normalize(target - eye), right = normalize(cross(forward, upHint)), up = cross(right, forward).
struct PrimaryRayCamera {
  float eye[3] = {0, 0, 0};
  float target[3] = {0, 0, -1};
  float upHint[3] = {0, 1, 0};
  float verticalFovDegrees = 0.0f;  // 0 = 60 degrees
  float tMin = 0.0f;                // ray start distance
  float tMax = 0.0f;                // 0 = 1e30 (unbounded)
};

struct PrimaryRayTargets {
  // R32_SFLOAT storage image in VK_IMAGE_LAYOUT_GENERAL: distance from the eye to the hit, 0 on a miss.
  VkImageView hitDistance = VK_NULL_HANDLE;
  // R32G32_UINT storage image in VK_IMAGE_LAYOUT_GENERAL: (primitive id, instance custom index), 0xFFFFFFFF
  // on a miss.
  VkImageView hitIds = VK_NULL_HANDLE;
  uint32_t width = 0;   // required
  uint32_t height = 0;  // required
};

struct PrimaryRaySettings {
  // The engine's materials, for alpha-tested geometry (MeshDesc::nonOpaque); null = every hit counts. The TLAS
  // then needs shading records (TlasBuildOptions::writeShadingRecords) when it has non-opaque instances.
  const MaterialTable* materials = nullptr;
};

// Fixed for the pass's life. Zero-initialised = a pipeline that alpha-tests when given materials.
struct PrimaryRayPassDesc {
  // true = never alpha-test: the pipeline has no any-hit shader and the pass allocates no fallback material table
  // (a buffer and a descriptor set it would otherwise hold); every hit counts, and record() refuses
  // PrimaryRaySettings::materials by name. For conformance runs and scenes without cut-outs.
  bool opaqueOnly = false;
};

// What one record() traces. The TLAS and targets have no defaults: a zero-initialised frame is refused by name.
struct PrimaryRayFrame {
  // recordTlasBuild()'s, earlier in submission order; an engine's own TLAS as TlasInfo{.tlas = handle}.
  TlasInfo tlas{};
  PrimaryRayCamera camera{};  // world space
  PrimaryRayTargets targets{};
  PrimaryRaySettings settings{};
};

class PrimaryRayPass {
 public:
  static Result<std::unique_ptr<PrimaryRayPass>> create(Context& context, const PrimaryRayPassDesc& desc = {});
  // Retires its pipeline to the context, without waiting for the frames that traced with it.
  ~PrimaryRayPass();

  // Records the trace of frame.tlas, alpha-testing through frame.settings.materials. The pass subtracts
  // TlasInfo::originOffset from the camera's eye and target (in double) to trace a camera-relative TLAS. The images
  // stay in VK_IMAGE_LAYOUT_GENERAL and the caller orders their reads after
  // VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR / VK_ACCESS_SHADER_WRITE_BIT.
  Status record(VkCommandBuffer cmd, const PrimaryRayFrame& frame);
  // The latest measurement whose frame has finished (rays, any-hit invocations, GPU time).
  PassStats stats() const;

  struct Impl;

 private:
  explicit PrimaryRayPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Computes the camera basis exactly as the raygen shader uses it (forward, right and up pre-scaled by
// tan(fovY/2) and the aspect ratio). Fails on eye == target, an up hint parallel to the view direction, or a
// field of view outside (0, 180).
struct CameraBasis {
  float eye[3], forward[3], right[3], up[3];
};
Result<CameraBasis> computeCameraBasis(const PrimaryRayCamera& camera, uint32_t width, uint32_t height);

}  // namespace rb

// The push constants every G-buffer pass shares (mirrors PassConstants in shaders/pass_inputs.glsl), and the
// code that fills their camera and G-buffer part.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/gbuffer.h>

#include <string>

namespace rb {

struct PassConstants {
  float inverseProjection[16];
  float viewToWorld[3][4];  // columns
  float cameraToTlas[4];    // xyz camera position in TLAS space, w depth quantum
  uint32_t gbuffer[4];      // width, height, flags, frame index
  float p0[4], p1[4], p2[4];
  uint32_t u0[4];
};
static_assert(sizeof(PassConstants) == 208, "must match shaders/pass_inputs.glsl");

enum GBufferFlags : uint32_t {
  kGbReversedZ = 1,
  kGbOctahedral = 2,
  kGbGeometricNormal = 4,
  kGbRoughnessInNormalW = 8,
  kGbRoughnessImage = 16,
  kGbAlbedoImage = 32,
};

// Checks the description (names the offending field) and fills the camera and G-buffer part of `out`.
// `passName` prefixes messages.
Status fillGBufferConstants(const GBufferDesc& gbuffer, const TlasInfo& tlas, uint64_t frame, const char* passName,
                            PassConstants& out);

// The world-space camera position: GBufferDesc::cameraPosition, or the translation of inverse(view).
void cameraPosition(const GBufferDesc& gbuffer, double out[3]);

VkImageLayout readLayout(const GBufferImage& image);

}  // namespace rb

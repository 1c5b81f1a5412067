// The G-buffer contract: what the engine's rasterizer hands to the effect passes instead of primary rays.
// Positions are reconstructed camera-relative from depth and the inverse projection, and the passes trace a
// TLAS built with TlasBuildOptions::originOffset = the camera position, so precision does not degrade far
// from the world origin. GLSL helpers that write exactly what Raybridge reads: shaders/raybridge_gbuffer.glsl.
//
// Far from the origin (open worlds reach 10-20 km) the engine's raster must be camera-relative as well, or the
// depth the passes read is already wrong: rebase each model matrix to the camera on the host in double
// (translation minus camera position, then rounded to float), give `view` no translation (rotation only), and
// pass GBufferDesc::cameraPosition in double. A world-space `viewProj * world` in float loses about
// |eye| * 2^-24 of position per operation (1 mm at 20 km), which the perspective divide turns into depth errors
// growing with the distance: the sample engine measured 1.3% median relative depth error at 5 km and hard
// shadows differing on 30% of the pixels at 20 km before it did this (adapters/tests/far_origin_test.cpp).
// Instance transforms given to the TLAS stay world-space: TlasBuildOptions::originOffset is subtracted in double.
//
// Sides: the normals (shading and geometric) must face the viewer, as rasterised: for a double-sided surface
// seen from behind, write the flipped normal (gl_FrontFacing). The passes offset ray origins and orient their
// hemispheres by them. Rays themselves hit both sides of every triangle (no face culling), so a closed or
// single-sided mesh still occludes from behind; the engine's raster culling of single-sided surfaces does not
// change what the rays see.
//
// Thread safety: plain data.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>

namespace rb {

enum class DepthConvention : uint8_t {
  Standard = 0,  // default: 0 at the near plane, 1 at the far plane (cleared to 1)
  ReversedZ,     // 1 at the near plane, 0 at the far plane or infinity (cleared to 0)
};

enum class NormalEncoding : uint8_t {
  WorldFloat = 0,  // default: world-space unit normal in .xyz of a float/half/snorm image (w free for roughness)
  Octahedral,      // world-space normal octahedral-encoded in .xy (snorm or float, [-1, 1]); rbEncodeOctahedral
};

// One engine image read by the passes through a sampler (texelFetch, no filtering).
struct GBufferImage {
  VkImageView view = VK_NULL_HANDLE;  // VK_NULL_HANDLE = not provided
  // The layout the image is in while the passes read it; it must allow sampled reads, e.g.
  // SHADER_READ_ONLY_OPTIMAL, DEPTH_STENCIL_READ_ONLY_OPTIMAL, DEPTH_READ_ONLY_OPTIMAL or GENERAL.
  // UNDEFINED (0) = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL.
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
};

struct GBufferDesc {
  uint32_t width = 0;   // required: size of every G-buffer image and of the pass outputs
  uint32_t height = 0;  // required

  // Required: hardware depth (D32_SFLOAT, D24 or D16, depth aspect view) as written by the rasterizer with
  // the projection below. Pixels at the clear value (1 Standard, 0 ReversedZ) are sky: no rays are traced.
  GBufferImage depth;
  DepthConvention depthConvention = DepthConvention::Standard;
  // Format of the depth image, which sets the quantum ray origins are offset by. UNDEFINED = D32_SFLOAT.
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;

  // Required: the normal the passes shade with (use the geometric normal for conformance checks).
  GBufferImage normal;
  NormalEncoding normalEncoding = NormalEncoding::WorldFloat;
  // Optional geometric (face) normal, same encoding: used to offset ray origins robustly. Not given = normal.
  GBufferImage geometricNormal;
  // Optional: perceptual roughness in .x and metalness in .y (reflections; see also roughnessInNormalW).
  GBufferImage roughnessMetalness;
  bool roughnessInNormalW = false;  // true: roughness is in normal.w (WorldFloat encoding only)
  GBufferImage albedo;              // optional: base colour in .rgb
  GBufferImage motionVectors;       // optional: screen-space motion in pixels (current - previous) in .xy

  // Camera, column-major 4x4 (GLM layout) as used to rasterize the G-buffer, Vulkan clip space (depth 0..1,
  // +Y down in NDC unless the projection flips it). Any projection works, including reversed-Z and infinite
  // far, as long as it is invertible.
  float view[16] = {};
  float projection[16] = {};
  // World-space camera position in double precision. All zero = taken from the inverse of `view`.
  double cameraPosition[3] = {0.0, 0.0, 0.0};
};

}  // namespace rb

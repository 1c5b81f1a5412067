// The G-buffer contract: what the engine's rasterizer hands to the effect passes instead of primary rays.
// Positions are reconstructed camera-relative from depth and the inverse projection, and the passes trace a
// TLAS built with TlasBuildOptions::originOffset = the camera position, so precision does not degrade far
// from the world origin. GLSL helpers that write exactly what Raybridge reads: shaders/public/raybridge_gbuffer.glsl.
//
// Far from the origin (open worlds reach 10-20 km) the engine's raster must be camera-relative as well, or the
// depth the passes read is already wrong: rebase each model matrix to the camera on the host in double
// (translation minus camera position, then rounded to float), give `view` no translation (rotation only), and
// pass GBufferDesc::cameraPosition in double. A world-space `viewProj * world` in float loses about
// |eye| * 2^-24 of position per operation (1 mm at 20 km), which the perspective divide turns into depth errors
// growing with the distance: the sample engine measured 1.3% median relative depth error at 5 km and hard
// shadows differing on 30% of the pixels at 20 km before it did this (tools/tests/far_origin_test.cpp).
// Instance transforms given to the TLAS stay world-space: TlasBuildOptions::originOffset is subtracted in double.
//
// Sides: the normals (shading and geometric) must face the viewer, as rasterised: for a double-sided surface
// seen from behind, write the flipped normal (gl_FrontFacing). The passes offset ray origins and orient their
// hemispheres by them. Rays themselves hit both sides of every triangle (no face culling), so a closed or
// single-sided mesh still occludes from behind; the engine's raster culling of single-sided surfaces does not
// change what the rays see.
//
// The hand-over (docs/quickstart.md shows it in code). Raybridge records into the engine's command buffer after
// the G-buffer pass; the engine's one barrier before HybridEffects::record (or a pass's record) must make every
// G-buffer image below available to, and visible at:
//   stages   VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
//            (the passes trace; the denoisers, tile classifiers, adaptive planners and upsamplers are compute)
//   access   VK_ACCESS_SHADER_READ_BIT
//   layout   GBufferImage::layout (default SHADER_READ_ONLY_OPTIMAL; depth may stay DEPTH_READ_ONLY_OPTIMAL,
//            DEPTH_STENCIL_READ_ONLY_OPTIMAL or DEPTH_READ_ONLY_STENCIL_ATTACHMENT_OPTIMAL)
// and the vertex, index and instance data of the meshes (when record() builds BLASes and the TLAS) to
// VK_PIPELINE_STAGE_ACCELERATION_STRUCTURE_BUILD_BIT_KHR with VK_ACCESS_SHADER_READ_BIT.
// Raybridge reads the G-buffer only in those stages and writes none of it; it ends its own work with a barrier
// from them, so the engine's next write of the G-buffer needs only its usual execution dependency on
// RAY_TRACING_SHADER | COMPUTE_SHADER (tests/handover_test.cpp runs exactly this under synchronization validation).
// Outputs (HybridOutputs, the passes' outputs) are left in SHADER_READ_ONLY_OPTIMAL, written by ray tracing and
// compute shaders and made visible to FRAGMENT_SHADER | COMPUTE_SHADER | RAY_TRACING_SHADER reads: the engine's
// lighting samples them with no barrier of its own.
//
// Images: every G-buffer image is created with VK_IMAGE_USAGE_SAMPLED_BIT (the passes read it with texelFetch
// through an unfiltered sampler) and its view has one aspect: COLOR, or DEPTH alone for the depth buffer (a view
// of a depth-stencil image with both aspects cannot be sampled). Each is the G-buffer's size (GBufferDesc::width,
// height), and its format is one a float sampler reads (no UINT/SINT): a depth format for depth, a colour format
// for the others. Vulkan cannot be asked a view's aspect or format or an image's usage or size, so
// GBufferImage::usage, ::aspectMask, ::format, ::width and ::height state them; where stated they are checked before
// anything is recorded, with an error naming the field. A combined depth-stencil depthFormat requires
// depth.aspectMask.
//
// Conventions: none of its own. Raybridge inverts the view and projection it is given, so a left- or right-handed
// world, Y-up or Y-down, a projection that flips Y and reversed-Z (DepthConvention) all work, as long as the
// matrices are the ones the G-buffer was rasterised with. "Up" appears only in defaults, all +Y: Light's zero
// direction is the sun overhead at (0, 1, 0) in effects.h; a Y-down world gives its light's direction explicitly.
// Lengths are in world units (AO range, light radii); directions need not be normalised.
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
  // The layout the image is in while the passes read it; it must allow sampled reads: SHADER_READ_ONLY_OPTIMAL,
  // READ_ONLY_OPTIMAL, GENERAL, or for depth DEPTH_READ_ONLY_OPTIMAL, DEPTH_STENCIL_READ_ONLY_OPTIMAL or
  // DEPTH_READ_ONLY_STENCIL_ATTACHMENT_OPTIMAL; any other is an error naming the field.
  // UNDEFINED (0) = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL.
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;
  // The image's VkImageCreateInfo::usage, as the engine created it. 0 = not stated (not checked); stated, it must
  // include VK_IMAGE_USAGE_SAMPLED_BIT.
  VkImageUsageFlags usage = 0;
  // The view's subresourceRange.aspectMask. 0 = not stated: COLOR, or DEPTH for GBufferDesc::depth. Stated, it
  // must be COLOR (DEPTH alone for the depth buffer): a depth view with the STENCIL aspect is an error.
  VkImageAspectFlags aspectMask = 0;
  // The view's format, as the engine created it. UNDEFINED = not stated (not checked); stated, it must suit the
  // field: for depth a depth format equal to GBufferDesc::depthFormat (UNDEFINED there = D32_SFLOAT); for the
  // others no depth/stencil and no UINT/SINT format; for motionVectors a signed float of two or more channels
  // (R16G16_SFLOAT, R32G32_SFLOAT or their 3- and 4-channel SFLOAT forms: motion is in pixels, so UNORM and SNORM
  // are refused); for reactiveMask one with a red channel, not block-compressed (R8_UNORM, R16_SFLOAT, RGBA8, ...).
  VkFormat format = VK_FORMAT_UNDEFINED;
  // The image's extent (VkImageCreateInfo::extent). 0 and 0 = not stated (not checked); stated, both must equal
  // GBufferDesc::width and height: every G-buffer image is the G-buffer's size.
  uint32_t width = 0;
  uint32_t height = 0;  // 0 = not stated; see width
};

struct GBufferDesc {
  uint32_t width = 0;   // required: size of every G-buffer image and of the pass outputs
  uint32_t height = 0;  // required

  // Required: hardware depth as written by the rasterizer with the projection below, through a view of the
  // DEPTH aspect alone (see Images above). Pixels at the clear value (1 Standard, 0 ReversedZ) are sky: no rays
  // are traced.
  GBufferImage depth{};
  DepthConvention depthConvention = DepthConvention::Standard;
  // Format of the depth image, which sets the quantum ray origins are offset by: D32_SFLOAT, X8_D24_UNORM_PACK32,
  // D16_UNORM, or a combined depth-stencil format (D32_SFLOAT_S8_UINT, D24_UNORM_S8_UINT, D16_UNORM_S8_UINT),
  // which needs depth.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT to say the view leaves the stencil out.
  // UNDEFINED = D32_SFLOAT.
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;

  // Required: the normal the passes shade with (use the geometric normal for conformance checks).
  GBufferImage normal{};
  NormalEncoding normalEncoding = NormalEncoding::WorldFloat;
  // Optional geometric (face) normal, same encoding: used to offset ray origins robustly. Not given = normal.
  // Without it, ray origins are offset along the shading normal, which at silhouettes and on normal-mapped or
  // smooth-shaded low-poly surfaces points into the geometry: rays start behind their own triangle and report
  // self-shadowing speckles (docs/quickstart.md). One extra attachment fixes it: the fragment shader's
  // normalize(cross(dFdx(worldPos), dFdy(worldPos))), faced to the viewer (rbEncodeOctahedral packs it in RG16).
  GBufferImage geometricNormal{};
  // Optional: perceptual roughness in .x and metalness in .y (reflections; see also roughnessInNormalW).
  GBufferImage roughnessMetalness{};
  bool roughnessInNormalW = false;  // true: roughness is in normal.w (WorldFloat encoding only)
  GBufferImage albedo{};            // optional: base colour in .rgb
  GBufferImage motionVectors{};     // optional: screen-space motion in pixels (current - previous) in .xy
  // Optional reactive mask, .r in [0, 1] of any float or unorm format (R8_UNORM is enough): where it exceeds 0.5 the
  // denoisers drop the pixel's history and start afresh, and the ray schedule treats the pixel as new (adaptive rays
  // plan it from no history, converged tiles trace its tile). For what the SDK cannot see change: particles, UI,
  // a screen-space effect drawn into the G-buffer, a teleport the engine knows of. Not given = no pixel is reactive.
  // Above 0.25 and at most 0.5 (a follow-up: a pixel restarted in one of the last frames) a pass with
  // RaySchedule::resetRays traces them there and the scalar denoiser adds them to the kept history as
  // DenoiseSettings::resetFrames frames; nothing else reads that level (HybridEffects writes it in its change masks).
  GBufferImage reactiveMask{};

  // Camera, column-major 4x4 (GLM layout) as used to rasterize the G-buffer, Vulkan clip space (depth 0..1,
  // +Y down in NDC unless the projection flips it). Any projection works, including reversed-Z and infinite
  // far, as long as it is invertible.
  float view[16] = {};
  float projection[16] = {};
  // World-space camera position in double precision. All zero = taken from the inverse of `view`.
  double cameraPosition[3] = {0.0, 0.0, 0.0};
};

}  // namespace rb

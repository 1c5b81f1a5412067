#include "pass_constants.h"

#include "vulkan_formats.h"

#include <cmath>
#include <string>

namespace rb {

namespace {

// Inverse of a column-major 4x4 matrix in double precision; false if singular.
bool invert4(const float m[16], double out[16]) {
  double a[16];
  for (int i = 0; i < 16; ++i) a[i] = m[i];
  double inv[16];
  inv[0] = a[5] * a[10] * a[15] - a[5] * a[11] * a[14] - a[9] * a[6] * a[15] + a[9] * a[7] * a[14] +
           a[13] * a[6] * a[11] - a[13] * a[7] * a[10];
  inv[4] = -a[4] * a[10] * a[15] + a[4] * a[11] * a[14] + a[8] * a[6] * a[15] - a[8] * a[7] * a[14] -
           a[12] * a[6] * a[11] + a[12] * a[7] * a[10];
  inv[8] = a[4] * a[9] * a[15] - a[4] * a[11] * a[13] - a[8] * a[5] * a[15] + a[8] * a[7] * a[13] +
           a[12] * a[5] * a[11] - a[12] * a[7] * a[9];
  inv[12] = -a[4] * a[9] * a[14] + a[4] * a[10] * a[13] + a[8] * a[5] * a[14] - a[8] * a[6] * a[13] -
            a[12] * a[5] * a[10] + a[12] * a[6] * a[9];
  inv[1] = -a[1] * a[10] * a[15] + a[1] * a[11] * a[14] + a[9] * a[2] * a[15] - a[9] * a[3] * a[14] -
           a[13] * a[2] * a[11] + a[13] * a[3] * a[10];
  inv[5] = a[0] * a[10] * a[15] - a[0] * a[11] * a[14] - a[8] * a[2] * a[15] + a[8] * a[3] * a[14] +
           a[12] * a[2] * a[11] - a[12] * a[3] * a[10];
  inv[9] = -a[0] * a[9] * a[15] + a[0] * a[11] * a[13] + a[8] * a[1] * a[15] - a[8] * a[3] * a[13] -
           a[12] * a[1] * a[11] + a[12] * a[3] * a[9];
  inv[13] = a[0] * a[9] * a[14] - a[0] * a[10] * a[13] - a[8] * a[1] * a[14] + a[8] * a[2] * a[13] +
            a[12] * a[1] * a[10] - a[12] * a[2] * a[9];
  inv[2] = a[1] * a[6] * a[15] - a[1] * a[7] * a[14] - a[5] * a[2] * a[15] + a[5] * a[3] * a[14] + a[13] * a[2] * a[7] -
           a[13] * a[3] * a[6];
  inv[6] = -a[0] * a[6] * a[15] + a[0] * a[7] * a[14] + a[4] * a[2] * a[15] - a[4] * a[3] * a[14] -
           a[12] * a[2] * a[7] + a[12] * a[3] * a[6];
  inv[10] = a[0] * a[5] * a[15] - a[0] * a[7] * a[13] - a[4] * a[1] * a[15] + a[4] * a[3] * a[13] +
            a[12] * a[1] * a[7] - a[12] * a[3] * a[5];
  inv[14] = -a[0] * a[5] * a[14] + a[0] * a[6] * a[13] + a[4] * a[1] * a[14] - a[4] * a[2] * a[13] -
            a[12] * a[1] * a[6] + a[12] * a[2] * a[5];
  inv[3] = -a[1] * a[6] * a[11] + a[1] * a[7] * a[10] + a[5] * a[2] * a[11] - a[5] * a[3] * a[10] - a[9] * a[2] * a[7] +
           a[9] * a[3] * a[6];
  inv[7] = a[0] * a[6] * a[11] - a[0] * a[7] * a[10] - a[4] * a[2] * a[11] + a[4] * a[3] * a[10] + a[8] * a[2] * a[7] -
           a[8] * a[3] * a[6];
  inv[11] = -a[0] * a[5] * a[11] + a[0] * a[7] * a[9] + a[4] * a[1] * a[11] - a[4] * a[3] * a[9] - a[8] * a[1] * a[7] +
            a[8] * a[3] * a[5];
  inv[15] = a[0] * a[5] * a[10] - a[0] * a[6] * a[9] - a[4] * a[1] * a[10] + a[4] * a[2] * a[9] + a[8] * a[1] * a[6] -
            a[8] * a[2] * a[5];
  double det = a[0] * inv[0] + a[1] * inv[4] + a[2] * inv[8] + a[3] * inv[12];
  if (!std::isfinite(det) || std::fabs(det) < 1e-300) return false;
  for (int i = 0; i < 16; ++i) out[i] = inv[i] / det;
  return true;
}

}  // namespace

VkImageLayout readLayout(const GBufferImage& image) {
  return image.layout == VK_IMAGE_LAYOUT_UNDEFINED ? VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL : image.layout;
}

void cameraPosition(const GBufferDesc& g, double out[3]) {
  if (g.cameraPosition[0] != 0.0 || g.cameraPosition[1] != 0.0 || g.cameraPosition[2] != 0.0) {
    for (int i = 0; i < 3; ++i) out[i] = g.cameraPosition[i];
    return;
  }
  double inv[16];
  if (!invert4(g.view, inv)) {
    out[0] = out[1] = out[2] = 0.0;
    return;
  }
  for (int i = 0; i < 3; ++i) out[i] = inv[12 + i];
}

std::string checkImage(const GBufferImage& image, const std::string& name, bool depth) {
  switch (image.layout) {
    case VK_IMAGE_LAYOUT_UNDEFINED:
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL:
    case VK_IMAGE_LAYOUT_READ_ONLY_OPTIMAL:
    case VK_IMAGE_LAYOUT_GENERAL: break;
    case VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_OPTIMAL:
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL:
    case VK_IMAGE_LAYOUT_DEPTH_READ_ONLY_STENCIL_ATTACHMENT_OPTIMAL:
      if (depth) break;
      [[fallthrough]];
    default:
      return name + ".layout " + std::to_string(int(image.layout)) +
             " does not allow sampled reads: transition the image to SHADER_READ_ONLY_OPTIMAL" +
             (depth ? " or DEPTH_READ_ONLY_OPTIMAL" : "") + " before record() and state that layout here";
  }
  if (image.usage != 0 && !(image.usage & VK_IMAGE_USAGE_SAMPLED_BIT)) {
    return name + ".usage lacks VK_IMAGE_USAGE_SAMPLED_BIT: the passes read it through a sampler; add the bit to "
                  "the image's VkImageCreateInfo::usage";
  }
  const VkImageAspectFlags wanted = depth ? VK_IMAGE_ASPECT_DEPTH_BIT : VK_IMAGE_ASPECT_COLOR_BIT;
  if (image.aspectMask != 0 && image.aspectMask != wanted) {
    if (depth && (image.aspectMask & VK_IMAGE_ASPECT_STENCIL_BIT)) {
      return name + ".aspectMask has the STENCIL aspect: a depth-stencil view cannot be sampled; create a view of "
                    "the depth image with subresourceRange.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT alone and pass "
                    "that";
    }
    return name + ".aspectMask " + std::to_string(image.aspectMask) + " is not " +
           (depth ? "VK_IMAGE_ASPECT_DEPTH_BIT" : "VK_IMAGE_ASPECT_COLOR_BIT") + ": pass a view of that aspect alone";
  }
  return {};
}

namespace {

bool isCombinedDepthStencil(VkFormat f) {
  return f == VK_FORMAT_D32_SFLOAT_S8_UINT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D16_UNORM_S8_UINT;
}

// What a G-buffer field holds, which decides the formats it may have.
enum class ImageRole : uint8_t { Depth, Color, Motion, Reactive };


// Why a stated motion-vector format cannot hold motion in pixels, or "" when it can: a signed float of two or
// more 16- or 32-bit channels.
std::string motionFormatProblem(const FormatTraits& t) {
  if (t.read == FormatRead::Float && t.hasSign && !t.bits64 && t.channels >= 2) return {};
  if (t.read == FormatRead::Compressed) return "is block-compressed";
  if (t.channels == 1) return "has one channel, and the passes read motion from .xy";
  if (t.read == FormatRead::Normalized || t.read == FormatRead::Scaled) {
    return "is normalized: motion is in pixels, so a [0, 1] or [-1, 1] range clamps it";
  }
  if (t.read == FormatRead::Float && !t.hasSign) return "has no sign bit, and motion is signed";
  return "is not a signed float format of two or more 16- or 32-bit channels";
}

// GBufferImage::format (where stated) against what the passes read from the field. "" when it holds.
std::string checkFormat(const GBufferImage& image, const std::string& name, ImageRole role) {
  if (image.format == VK_FORMAT_UNDEFINED) return {};
  const FormatTraits t = formatTraits(image.format);
  const std::string stated = name + ".format " + formatName(image.format);
  if (role == ImageRole::Depth) {
    if (t.hasDepth) return {};
    return stated + " is not a depth format: the passes read hardware depth from this field; pass a view of the " +
           "depth buffer's DEPTH aspect and state the depth image's format";
  }
  if (t.read == FormatRead::DepthStencil) {
    return stated + " is a depth/stencil format, and this field is a colour image: pass the view of the colour " +
           "image the engine wrote it to (only GBufferDesc::depth is a depth buffer)";
  }
  if (t.read == FormatRead::Integer) {
    return stated + " is an integer format, which the passes' float samplers cannot read: store it in a UNORM " +
           "or SFLOAT format";
  }
  if (role == ImageRole::Motion) {
    if (std::string problem = motionFormatProblem(t); !problem.empty()) {
      return stated + " " + problem + ": motion vectors are pixels (current - previous) in .xy; create the image " +
             "as VK_FORMAT_R16G16_SFLOAT (or R32G32_SFLOAT, or an SFLOAT format with more channels)";
    }
  }
  if (role == ImageRole::Reactive) {
    if (t.read == FormatRead::Compressed) {
      return stated + " is block-compressed: the reactive mask is a per-pixel .r the engine writes; use " +
             "VK_FORMAT_R8_UNORM (or any UNORM or SFLOAT colour format)";
    }
    if (t.read != FormatRead::Unknown && !t.hasRed) {
      return stated + " has no red channel, and the passes read the mask from .r (alpha-only formats read 0 " +
             "there): use VK_FORMAT_R8_UNORM";
    }
  }
  return {};
}

// GBufferImage::width/height (where stated) against the G-buffer's size. "" when they match.
std::string checkExtent(const GBufferImage& image, const std::string& name, const GBufferDesc& g) {
  if (image.width == 0 && image.height == 0) return {};
  if (image.width == g.width && image.height == g.height) return {};
  return name + ".width x .height " + std::to_string(image.width) + "x" + std::to_string(image.height) +
         " is not the G-buffer's size " + std::to_string(g.width) + "x" + std::to_string(g.height) +
         " (GBufferDesc::width x height): every G-buffer image must be the G-buffer's size, pixel for pixel; " +
         "render or copy it at that size (or leave both at 0: not stated)";
}

}  // namespace

Status validateGBufferImages(const GBufferDesc& g, const char* passName) {
  auto invalid = [&](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, std::string(passName) + ": " + m};
  };
  if (isCombinedDepthStencil(g.depthFormat) && g.depth.aspectMask == 0) {
    return invalid("GBufferDesc::depthFormat " + std::to_string(int(g.depthFormat)) +
                   " has a stencil aspect, and a view of both aspects cannot be sampled: create the depth view with "
                   "subresourceRange.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT and set GBufferDesc::depth.aspectMask "
                   "to VK_IMAGE_ASPECT_DEPTH_BIT to say so");
  }
  struct Field {
    const GBufferImage& image;
    const char* name;
    ImageRole role;
  };
  const Field fields[] = {{g.depth, "depth", ImageRole::Depth},
                          {g.normal, "normal", ImageRole::Color},
                          {g.geometricNormal, "geometricNormal", ImageRole::Color},
                          {g.roughnessMetalness, "roughnessMetalness", ImageRole::Color},
                          {g.albedo, "albedo", ImageRole::Color},
                          {g.motionVectors, "motionVectors", ImageRole::Motion},
                          {g.reactiveMask, "reactiveMask", ImageRole::Reactive}};
  for (const Field& f : fields) {
    if (!f.image.view) continue;
    const std::string name = std::string("GBufferDesc::") + f.name;
    for (const std::string& m : {checkImage(f.image, name, f.role == ImageRole::Depth),
                                 checkFormat(f.image, name, f.role), checkExtent(f.image, name, g)}) {
      if (!m.empty()) return invalid(m);
    }
  }
  // The depth quantum comes from depthFormat: a stated depth.format that differs would offset ray origins wrongly.
  const VkFormat depthFormat = g.depthFormat == VK_FORMAT_UNDEFINED ? VK_FORMAT_D32_SFLOAT : g.depthFormat;
  if (g.depth.view && g.depth.format != VK_FORMAT_UNDEFINED && g.depth.format != depthFormat) {
    return invalid("GBufferDesc::depth.format " + formatName(g.depth.format) +
                   " differs from GBufferDesc::depthFormat " + formatName(g.depthFormat) +
                   (g.depthFormat == VK_FORMAT_UNDEFINED ? " (= D32_SFLOAT)" : "") +
                   ", which sets how far ray origins are offset (one step of the stored depth): set depthFormat to the "
                   "depth image's format");
  }
  return {};
}

Status fillGBufferConstants(const GBufferDesc& g, const TlasInfo& tlas, uint64_t frame, const char* passName,
                            GBufferConstants& out) {
  auto invalid = [&](const std::string& m) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS, std::string(passName) + ": " + m};
  };
  if (g.width == 0 || g.height == 0) {
    return invalid("GBufferDesc size " + std::to_string(g.width) + "x" + std::to_string(g.height) +
                   " is empty; set width and height to the G-buffer's size");
  }
  if (!g.depth.view) return invalid("GBufferDesc::depth.view is VK_NULL_HANDLE; the depth buffer is required");
  if (!g.normal.view) return invalid("GBufferDesc::normal.view is VK_NULL_HANDLE; a normal image is required");
  if (Status st = validateGBufferImages(g, passName); !st) return st;
  if (!tlas.tlas) return invalid("the TLAS is VK_NULL_HANDLE; build one with recordTlasBuild() first");
  if (g.normalEncoding != NormalEncoding::WorldFloat && g.normalEncoding != NormalEncoding::Octahedral) {
    return invalid("GBufferDesc::normalEncoding has an unknown value");
  }
  if (g.roughnessInNormalW && g.normalEncoding != NormalEncoding::WorldFloat) {
    return invalid("GBufferDesc::roughnessInNormalW needs NormalEncoding::WorldFloat (octahedral uses .zw otherwise)");
  }
  for (float v : g.view) {
    if (!std::isfinite(v)) return invalid("GBufferDesc::view contains a non-finite value");
  }
  double invProj[16], invView[16];
  if (!invert4(g.projection, invProj)) {
    return invalid("GBufferDesc::projection is not invertible; pass the projection matrix used to rasterize");
  }
  if (!invert4(g.view, invView)) return invalid("GBufferDesc::view is not invertible");
  for (int i = 0; i < 16; ++i) out.inverseProjection[i] = static_cast<float>(invProj[i]);
  for (int c = 0; c < 3; ++c) {
    // Column c of the rotation part of inverse(view), normalised so a scaled view matrix still reconstructs
    // lengths in world units through the projection.
    for (int r = 0; r < 3; ++r) out.viewToWorld[c][r] = static_cast<float>(invView[c * 4 + r]);
    out.viewToWorld[c][3] = 0.0f;
  }
  // w at depth 1, formed in double: the shader adds the small term a * (depth - 1) to it without cancellation.
  out.wAtDepthOne = static_cast<float>(invProj[11] + invProj[15]);
  double cam[3];
  cameraPosition(g, cam);
  for (int i = 0; i < 3; ++i) out.cameraToTlas[i] = static_cast<float>(cam[i] - tlas.originOffset[i]);
  // The depth quantum: one step of the stored value (float depth: 0 = one ulp, computed in the shader).
  switch (g.depthFormat) {
    case VK_FORMAT_UNDEFINED:
    case VK_FORMAT_D32_SFLOAT:
    case VK_FORMAT_D32_SFLOAT_S8_UINT: out.depthQuantum = 0.0f; break;
    case VK_FORMAT_X8_D24_UNORM_PACK32:
    case VK_FORMAT_D24_UNORM_S8_UINT: out.depthQuantum = 1.0f / 16777215.0f; break;
    case VK_FORMAT_D16_UNORM:
    case VK_FORMAT_D16_UNORM_S8_UINT: out.depthQuantum = 1.0f / 65535.0f; break;
    default: return invalid("GBufferDesc::depthFormat is not a depth format");
  }
  out.size[0] = g.width;
  out.size[1] = g.height;
  uint32_t flags = 0;
  if (g.depthConvention == DepthConvention::ReversedZ) flags |= RB_GB_REVERSED_Z;
  if (g.normalEncoding == NormalEncoding::Octahedral) flags |= RB_GB_OCTAHEDRAL;
  if (g.geometricNormal.view) flags |= RB_GB_GEOMETRIC_NORMAL;
  if (g.roughnessInNormalW) flags |= RB_GB_ROUGHNESS_IN_NORMAL_W;
  if (g.roughnessMetalness.view) flags |= RB_GB_ROUGHNESS_IMAGE;
  if (g.albedo.view) flags |= RB_GB_ALBEDO_IMAGE;
  if (g.reactiveMask.view) flags |= RB_GB_REACTIVE;
  out.flags = flags;
  out.frameIndex = static_cast<uint32_t>(frame);
  return {};
}

}  // namespace rb

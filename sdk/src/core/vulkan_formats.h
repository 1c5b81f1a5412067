// What a VkFormat is, for the messages and checks that name one: its Vulkan name, and how a shader's float
// sampler reads its channels and how many there are (the G-buffer hand-over checks, validateGBufferImages).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <string>

namespace rb {

enum class FormatRead : uint8_t {
  Unknown = 0,   // not a format of the table (an extension's): the checks leave it alone where they can
  Float,         // SFLOAT, and the packed UFLOAT formats (which have no sign)
  Normalized,    // UNORM, SNORM, SRGB: read as [0, 1] or [-1, 1]
  Scaled,        // USCALED, SSCALED: integers read as floats
  Integer,       // UINT, SINT: a float sampler cannot read them
  DepthStencil,  // the depth and stencil formats
  Compressed,    // block-compressed (BC, ETC2, EAC, ASTC, PVRTC)
};

struct FormatTraits {
  FormatRead read = FormatRead::Unknown;
  uint32_t channels = 0;  // colour channels; 0 for depth, compressed and unknown formats
  bool hasRed = false;    // .r holds data (A8_UNORM does not; a sampler reads it as 0)
  bool hasSign = false;   // negative values survive: SFLOAT, SNORM, SSCALED, SINT
  bool bits64 = false;    // 64-bit channels, which a float sampler cannot read
  bool hasDepth = false;  // a depth format (S8_UINT alone has none)
};

// UNDEFINED and unknown formats give FormatRead::Unknown.
FormatTraits formatTraits(VkFormat format);

// "VK_FORMAT_R8_UINT" for every core format and the few extension ones above; any other as "VkFormat <number>".
std::string formatName(VkFormat format);

}  // namespace rb

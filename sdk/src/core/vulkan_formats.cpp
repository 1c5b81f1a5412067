// What a VkFormat is (vulkan_formats.h). The core colour formats come in runs of the same
// channels over the same sequence of numeric types, so one row per run names and classifies all of them.
#include "vulkan_formats.h"

#include <iterator>
#include <span>

namespace rb {

namespace {

struct NumericType {
  const char* suffix;
  FormatRead read;
  bool hasSign;
};
constexpr NumericType kUnorm{"UNORM", FormatRead::Normalized, false}, kSnorm{"SNORM", FormatRead::Normalized, true},
    kUscaled{"USCALED", FormatRead::Scaled, false}, kSscaled{"SSCALED", FormatRead::Scaled, true},
    kUint{"UINT", FormatRead::Integer, false}, kSint{"SINT", FormatRead::Integer, true},
    kSrgb{"SRGB", FormatRead::Normalized, false}, kSfloat{"SFLOAT", FormatRead::Float, true};
constexpr NumericType k8Bit[] = {kUnorm, kSnorm, kUscaled, kSscaled, kUint, kSint, kSrgb};
constexpr NumericType k10Bit[] = {kUnorm, kSnorm, kUscaled, kSscaled, kUint, kSint};
constexpr NumericType k16Bit[] = {kUnorm, kSnorm, kUscaled, kSscaled, kUint, kSint, kSfloat};
constexpr NumericType k32Bit[] = {kUint, kSint, kSfloat};

// VK_FORMAT_<layout>_<type><tail> for each type in order, numbered from `first`.
struct FormatRun {
  VkFormat first;
  const char* layout;
  uint32_t channels;
  std::span<const NumericType> types;
  const char* tail;
  bool bits64;
};
constexpr FormatRun kRuns[] = {
    {VK_FORMAT_R8_UNORM, "R8", 1, k8Bit, "", false},
    {VK_FORMAT_R8G8_UNORM, "R8G8", 2, k8Bit, "", false},
    {VK_FORMAT_R8G8B8_UNORM, "R8G8B8", 3, k8Bit, "", false},
    {VK_FORMAT_B8G8R8_UNORM, "B8G8R8", 3, k8Bit, "", false},
    {VK_FORMAT_R8G8B8A8_UNORM, "R8G8B8A8", 4, k8Bit, "", false},
    {VK_FORMAT_B8G8R8A8_UNORM, "B8G8R8A8", 4, k8Bit, "", false},
    {VK_FORMAT_A8B8G8R8_UNORM_PACK32, "A8B8G8R8", 4, k8Bit, "_PACK32", false},
    {VK_FORMAT_A2R10G10B10_UNORM_PACK32, "A2R10G10B10", 4, k10Bit, "_PACK32", false},
    {VK_FORMAT_A2B10G10R10_UNORM_PACK32, "A2B10G10R10", 4, k10Bit, "_PACK32", false},
    {VK_FORMAT_R16_UNORM, "R16", 1, k16Bit, "", false},
    {VK_FORMAT_R16G16_UNORM, "R16G16", 2, k16Bit, "", false},
    {VK_FORMAT_R16G16B16_UNORM, "R16G16B16", 3, k16Bit, "", false},
    {VK_FORMAT_R16G16B16A16_UNORM, "R16G16B16A16", 4, k16Bit, "", false},
    {VK_FORMAT_R32_UINT, "R32", 1, k32Bit, "", false},
    {VK_FORMAT_R32G32_UINT, "R32G32", 2, k32Bit, "", false},
    {VK_FORMAT_R32G32B32_UINT, "R32G32B32", 3, k32Bit, "", false},
    {VK_FORMAT_R32G32B32A32_UINT, "R32G32B32A32", 4, k32Bit, "", false},
    {VK_FORMAT_R64_UINT, "R64", 1, k32Bit, "", true},
    {VK_FORMAT_R64G64_UINT, "R64G64", 2, k32Bit, "", true},
    {VK_FORMAT_R64G64B64_UINT, "R64G64B64", 3, k32Bit, "", true},
    {VK_FORMAT_R64G64B64A64_UINT, "R64G64B64A64", 4, k32Bit, "", true},
};
// The runs follow each other without a gap, so a format between two firsts belongs to the earlier run.
constexpr bool runsAreContiguous() {
  for (size_t i = 0; i + 1 < std::size(kRuns); ++i)
    if (kRuns[i].first + int(kRuns[i].types.size()) != kRuns[i + 1].first) return false;
  return kRuns[std::size(kRuns) - 1].first + 3 == VK_FORMAT_B10G11R11_UFLOAT_PACK32;
}
static_assert(runsAreContiguous(), "kRuns must list the core formats R8_UNORM .. R64G64B64A64_SFLOAT in order");

// VK_FORMAT_A8_UNORM_KHR (VK_KHR_maintenance5), which older Vulkan headers lack: alpha alone, .r reads 0.
constexpr int kA8Unorm = 1000470001;

struct SingleFormat {
  int format;
  const char* name;  // without VK_FORMAT_
  FormatTraits traits;
};
constexpr FormatTraits kUnorm2{FormatRead::Normalized, 2, true}, kUnorm3{FormatRead::Normalized, 3, true},
    kUnorm4{FormatRead::Normalized, 4, true}, kUfloat3{FormatRead::Float, 3, true},
    kDepth{FormatRead::DepthStencil, 0, false, false, false, true};
constexpr SingleFormat kSingles[] = {
    {VK_FORMAT_R4G4_UNORM_PACK8, "R4G4_UNORM_PACK8", kUnorm2},
    {VK_FORMAT_R4G4B4A4_UNORM_PACK16, "R4G4B4A4_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_B4G4R4A4_UNORM_PACK16, "B4G4R4A4_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_R5G6B5_UNORM_PACK16, "R5G6B5_UNORM_PACK16", kUnorm3},
    {VK_FORMAT_B5G6R5_UNORM_PACK16, "B5G6R5_UNORM_PACK16", kUnorm3},
    {VK_FORMAT_R5G5B5A1_UNORM_PACK16, "R5G5B5A1_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_B5G5R5A1_UNORM_PACK16, "B5G5R5A1_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_A1R5G5B5_UNORM_PACK16, "A1R5G5B5_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_B10G11R11_UFLOAT_PACK32, "B10G11R11_UFLOAT_PACK32", kUfloat3},
    {VK_FORMAT_E5B9G9R9_UFLOAT_PACK32, "E5B9G9R9_UFLOAT_PACK32", kUfloat3},
    {VK_FORMAT_D16_UNORM, "D16_UNORM", kDepth},
    {VK_FORMAT_X8_D24_UNORM_PACK32, "X8_D24_UNORM_PACK32", kDepth},
    {VK_FORMAT_D32_SFLOAT, "D32_SFLOAT", kDepth},
    {VK_FORMAT_S8_UINT, "S8_UINT", {FormatRead::DepthStencil}},
    {VK_FORMAT_D16_UNORM_S8_UINT, "D16_UNORM_S8_UINT", kDepth},
    {VK_FORMAT_D24_UNORM_S8_UINT, "D24_UNORM_S8_UINT", kDepth},
    {VK_FORMAT_D32_SFLOAT_S8_UINT, "D32_SFLOAT_S8_UINT", kDepth},
    {VK_FORMAT_A4R4G4B4_UNORM_PACK16, "A4R4G4B4_UNORM_PACK16", kUnorm4},
    {VK_FORMAT_A4B4G4R4_UNORM_PACK16, "A4B4G4R4_UNORM_PACK16", kUnorm4},
    {kA8Unorm, "A8_UNORM_KHR", {FormatRead::Normalized, 1, false}},
};

bool isCompressed(VkFormat f) {
  return (f >= VK_FORMAT_BC1_RGB_UNORM_BLOCK && f <= VK_FORMAT_ASTC_12x12_SRGB_BLOCK) ||
         (f >= VK_FORMAT_PVRTC1_2BPP_UNORM_BLOCK_IMG && f <= VK_FORMAT_PVRTC2_4BPP_SRGB_BLOCK_IMG) ||
         (f >= VK_FORMAT_ASTC_4x4_SFLOAT_BLOCK && f <= VK_FORMAT_ASTC_12x12_SFLOAT_BLOCK);
}

// The run holding `f` and its index in it, or nullptr.
const FormatRun* findRun(VkFormat f, size_t& index) {
  for (const FormatRun& run : kRuns) {
    if (f >= run.first && size_t(f - run.first) < run.types.size()) {
      index = size_t(f - run.first);
      return &run;
    }
  }
  return nullptr;
}

const SingleFormat* findSingle(VkFormat f) {
  for (const SingleFormat& s : kSingles)
    if (s.format == int(f)) return &s;
  return nullptr;
}

}  // namespace

FormatTraits formatTraits(VkFormat format) {
  size_t index = 0;
  if (const FormatRun* run = findRun(format, index)) {
    const NumericType& type = run->types[index];
    return {type.read, run->channels, true, type.hasSign, run->bits64, false};
  }
  if (const SingleFormat* single = findSingle(format)) return single->traits;
  if (isCompressed(format)) return {FormatRead::Compressed};
  return {};
}

std::string formatName(VkFormat format) {
  size_t index = 0;
  if (const FormatRun* run = findRun(format, index))
    return std::string("VK_FORMAT_") + run->layout + "_" + run->types[index].suffix + run->tail;
  if (const SingleFormat* single = findSingle(format)) return std::string("VK_FORMAT_") + single->name;
  if (format == VK_FORMAT_UNDEFINED) return "VK_FORMAT_UNDEFINED";
  return "VkFormat " + std::to_string(int(format)) + (isCompressed(format) ? " (block-compressed)" : "");
}

}  // namespace rb

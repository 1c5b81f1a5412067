// Images the scenarios handle outside the SDK: engine-side sampled images uploaded from the host (G-buffers,
// textures), readbacks of pass outputs, and tonemapped PNGs of HDR results for the docs.
//
// Thread safety: what takes a BenchEnv submits to its queue, so it runs on the thread that drives the BenchEnv.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bench_env.h"

namespace rbbench {

// A device-local 2D image, sampled, uploaded and left in SHADER_READ_ONLY_OPTIMAL for compute and ray tracing
// shaders.
struct SampledImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

// Throws BenchFailure naming `what` on any failure.
SampledImage uploadSampledImage(BenchEnv& env, VkFormat format, VkImageAspectFlags aspect, uint32_t width,
                                uint32_t height, const void* data, size_t bytes, const char* what);
void destroySampledImage(BenchEnv& env, SampledImage& img);

// Copies a colour image of `texelBytes` per texel to the host, after the writes of every earlier command. The
// image is in `layout` (SHADER_READ_ONLY_OPTIMAL, as passes leave their outputs, or GENERAL) and is left in it.
std::vector<uint8_t> readImage(BenchEnv& env, VkImage image, VkImageLayout layout, uint32_t width, uint32_t height,
                               uint32_t texelBytes, const char* what);
// An R16G16B16A16_SFLOAT image as 4 floats per texel.
std::vector<float> readRgba16f(BenchEnv& env, VkImage image, VkImageLayout layout, uint32_t width, uint32_t height,
                               const char* what);

// Writes `rgba` (4 floats per pixel, linear HDR) as an 8-bit sRGB PNG, `exposure` times the value through
// Reinhard's x / (1 + x) per channel. Throws BenchFailure when the file cannot be written.
void writeTonemappedPng(const std::string& path, const std::vector<float>& rgba, uint32_t width, uint32_t height,
                        double exposure);

}  // namespace rbbench

// CPU images read back from the engine, and writers for PNG (stb) and EXR (OpenEXR).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "sample_engine/result.h"

namespace sample_engine {

// Tonemapped output: sRGB-encoded RGBA8, rows from the top.
struct ImageRGBA8 {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> pixels;  // width * height * 4

  glm::u8vec4 at(uint32_t x, uint32_t y) const {
    const uint8_t* p = &pixels[(static_cast<size_t>(y) * width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
  }
};

// Linear HDR radiance before tonemapping (lighting pass output), rows from the top.
struct ImageRGBA32F {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<float> pixels;  // width * height * 4

  glm::vec4 at(uint32_t x, uint32_t y) const {
    const float* p = &pixels[(static_cast<size_t>(y) * width + x) * 4];
    return {p[0], p[1], p[2], p[3]};
  }
};

// The writers encode in memory and then write the file through writeFile, so a failed write is an error.
Status writePng(const std::string& path, const ImageRGBA8& image);
// halfFloat = true writes RGBA half, otherwise RGBA float.
Status writeExr(const std::string& path, const ImageRGBA32F& image, bool halfFloat = true);
// Writes `bytes` to the file at `path` (created or replaced) and checks every step, the close included, so that a
// full disk or a failing device is an error ("cannot write <path>: No space left on device") rather than a short
// file. A regular file left part-written is removed.
Status writeFile(const std::string& path, std::string_view bytes);

// CPU reference of the tonemap pass (exposure, ACES fit, sRGB encode), to predict output colors.
glm::vec3 tonemapLinear(const glm::vec3& hdr, float exposure);  // result is linear in [0,1]
glm::u8vec3 tonemapToSrgb8(const glm::vec3& hdr, float exposure);

}  // namespace sample_engine

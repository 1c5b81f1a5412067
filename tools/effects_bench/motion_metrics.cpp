// Motion scenario metrics (see the header).
#include "motion_metrics.h"

#include <cmath>

namespace rbEffects {

double rmseOver(const EffectFrame& test, const EffectFrame& reference, const std::vector<uint8_t>& pixels) {
  const uint32_t c = test.channels;
  double sum = 0.0;
  uint64_t n = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    if (!pixels[i]) continue;
    for (uint32_t k = 0; k < c; ++k) {
      const double d = double(test.values[i * c + k]) - reference.values[i * c + k];
      sum += d * d;
    }
    n += c;
  }
  return n ? std::sqrt(sum / double(n)) : 0.0;
}

double meanAbsoluteChange(const EffectFrame& a, const EffectFrame& b, const std::vector<uint8_t>& pixels) {
  const uint32_t c = a.channels;
  double sum = 0.0;
  uint64_t n = 0;
  for (size_t i = 0; i < pixels.size(); ++i) {
    if (!pixels[i]) continue;
    for (uint32_t k = 0; k < c; ++k) sum += std::fabs(double(a.values[i * c + k]) - b.values[i * c + k]);
    n += c;
  }
  return n ? sum / double(n) : 0.0;
}

std::vector<uint8_t> changedPixels(const EffectFrame& before, const EffectFrame& now,
                                   const std::vector<uint8_t>& surface, float threshold) {
  const uint32_t c = now.channels;
  double scale = 1.0;
  if (c > 1) {  // RGB: relative to the frame's mean colour norm
    double sum = 0.0;
    uint64_t n = 0;
    for (size_t i = 0; i < surface.size(); ++i) {
      if (!surface[i]) continue;
      double s2 = 0.0;
      for (uint32_t k = 0; k < c; ++k) s2 += double(now.values[i * c + k]) * now.values[i * c + k];
      sum += std::sqrt(s2);
      ++n;
    }
    scale = n ? sum / double(n) : 0.0;
  }
  std::vector<uint8_t> out(surface.size(), 0);
  for (size_t i = 0; i < surface.size(); ++i) {
    if (!surface[i]) continue;
    double d2 = 0.0;
    for (uint32_t k = 0; k < c; ++k) {
      const double d = double(now.values[i * c + k]) - before.values[i * c + k];
      d2 += d * d;
    }
    out[i] = std::sqrt(d2) > threshold * scale ? 1 : 0;
  }
  return out;
}

std::vector<float> viewDepth(const std::vector<float>& depth, float zNear, float zFar, bool reversedZ) {
  std::vector<float> z(depth.size());
  for (size_t i = 0; i < depth.size(); ++i) {
    const double d = reversedZ ? 1.0 - depth[i] : depth[i];
    z[i] = d >= 1.0 ? 0.0f : float(zNear * zFar / (zFar - d * (zFar - zNear)));
  }
  return z;
}

std::vector<uint8_t> disoccludedPixels(const std::vector<float>& depthNow, const std::vector<float>& depthBefore,
                                       const std::vector<glm::vec2>& motion, const std::vector<uint8_t>& surfaceNow,
                                       uint32_t width, uint32_t height) {
  std::vector<uint8_t> out(surfaceNow.size(), 0);
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      if (!surfaceNow[i]) continue;
      glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
      if (!motion.empty()) p -= motion[i];
      if (p.x < 0.0f || p.y < 0.0f || p.x >= float(width) || p.y >= float(height)) {
        out[i] = 1;
        continue;
      }
      const float before = depthBefore[size_t(p.y) * width + size_t(p.x)];
      // The surface's own view depth changes little between frames; another surface's differs.
      out[i] = before <= 0.0f || std::fabs(before - depthNow[i]) > 0.05f * depthNow[i] ? 1 : 0;
    }
  }
  return out;
}

std::vector<uint8_t> both(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  std::vector<uint8_t> out(a.size());
  for (size_t i = 0; i < a.size(); ++i) out[i] = a[i] && b[i];
  return out;
}

uint64_t count(const std::vector<uint8_t>& pixels) {
  uint64_t n = 0;
  for (uint8_t p : pixels) n += p ? 1 : 0;
  return n;
}

}  // namespace rbEffects

// Error metrics, accumulation and PNG output of the effects bench (see the header).
#include "image_error.h"

#include <algorithm>
#include <cmath>

#include "sample_engine/image_io.h"

namespace rbEffects {

namespace se = sample_engine;

std::vector<uint8_t> surfaceMask(const std::vector<float>& depth) {
  std::vector<uint8_t> mask(depth.size());
  for (size_t i = 0; i < depth.size(); ++i) mask[i] = depth[i] < 1.0f ? 1 : 0;
  return mask;
}

uint64_t countSet(const std::vector<uint8_t>& mask) {
  return uint64_t(std::count(mask.begin(), mask.end(), uint8_t(1)));
}

ErrorStats compare(const std::vector<float>& test, const std::vector<float>& reference,
                   const std::vector<uint8_t>& mask, uint32_t channels) {
  ErrorStats e;
  if (test.size() != reference.size() || test.size() != mask.size() * channels) return {NAN, NAN};
  double sq = 0.0, sum = 0.0;
  uint64_t n = 0;
  for (size_t p = 0; p < mask.size(); ++p) {
    if (!mask[p]) continue;
    for (uint32_t c = 0; c < channels; ++c) {
      const double d = double(test[p * channels + c]) - double(reference[p * channels + c]);
      sq += d * d;
      sum += d;
      ++n;
    }
  }
  if (n == 0) return e;
  e.rmse = std::sqrt(sq / double(n));
  e.bias = sum / double(n);
  return e;
}

void Accumulator::add(const std::vector<float>& frame) {
  const int half = int(frames() % 2);
  std::vector<double>& s = sum_[half];
  if (s.empty()) s.assign(frame.size(), 0.0);
  for (size_t i = 0; i < frame.size() && i < s.size(); ++i) s[i] += frame[i];
  ++frames_[half];
}

std::vector<float> Accumulator::mean() const {
  const size_t n = sum_[0].size();
  std::vector<float> out(n, 0.0f);
  const double total = double(frames());
  for (size_t i = 0; i < n && total > 0; ++i)
    out[i] = float((sum_[0][i] + (sum_[1].empty() ? 0.0 : sum_[1][i])) / total);
  return out;
}

std::vector<float> Accumulator::halfMean(int half) const {
  const std::vector<double>& s = sum_[half];
  std::vector<float> out(s.size(), 0.0f);
  for (size_t i = 0; i < s.size() && frames_[half]; ++i) out[i] = float(s[i] / frames_[half]);
  return out;
}

std::vector<float> rgbOf(const std::vector<float>& rgba) {
  std::vector<float> rgb(rgba.size() / 4 * 3);
  for (size_t p = 0; p < rgba.size() / 4; ++p)
    for (int c = 0; c < 3; ++c) rgb[p * 3 + c] = rgba[p * 4 + c];
  return rgb;
}

namespace {

uint8_t srgb8(float linear) {
  const float v = std::clamp(linear, 0.0f, 1.0f);
  const float s = v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(s * 255.0f));
}

se::ImageRGBA8 image(uint32_t width, uint32_t height) {
  se::ImageRGBA8 img;
  img.width = width;
  img.height = height;
  img.pixels.assign(size_t(width) * height * 4, 255);
  return img;
}

}  // namespace

se::Status writeGreyPng(const std::string& path, const std::vector<float>& values, uint32_t width, uint32_t height) {
  if (values.size() != size_t(width) * height) return se::Status::failure(path + ": image size mismatch");
  se::ImageRGBA8 img = image(width, height);
  for (size_t i = 0; i < values.size(); ++i)
    img.pixels[i * 4] = img.pixels[i * 4 + 1] = img.pixels[i * 4 + 2] = srgb8(values[i]);
  return se::writePng(path, img);
}

se::Status writeTonemappedPng(const std::string& path, const std::vector<float>& rgb, uint32_t width, uint32_t height,
                              float exposure) {
  if (rgb.size() != size_t(width) * height * 3) return se::Status::failure(path + ": image size mismatch");
  se::ImageRGBA8 img = image(width, height);
  for (size_t i = 0; i < size_t(width) * height; ++i) {
    const glm::u8vec3 c = se::tonemapToSrgb8({rgb[i * 3], rgb[i * 3 + 1], rgb[i * 3 + 2]}, exposure);
    img.pixels[i * 4] = c.r;
    img.pixels[i * 4 + 1] = c.g;
    img.pixels[i * 4 + 2] = c.b;
  }
  return se::writePng(path, img);
}

se::Status writeMaskPng(const std::string& path, const std::vector<uint8_t>& mask, uint32_t width, uint32_t height) {
  std::vector<float> v(mask.size());
  for (size_t i = 0; i < mask.size(); ++i) v[i] = mask[i] ? 1.0f : 0.0f;
  return writeGreyPng(path, v, width, height);
}

}  // namespace rbEffects

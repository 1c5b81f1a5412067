#include "converged_pair.h"

#include <catch2/catch_test_macros.hpp>
#include <glm/glm.hpp>

#include <algorithm>

namespace rbtest {

void recordSideBySide(GpuFixture& fx, rb::AccelerationStructureService& service, BuiltScene& built,
                      rb::HybridFrame frame, rb::HybridEffects& skipping, rb::HybridEffects& plain,
                      bool shadingRecords) {
  fx.runAndSettle([&](VkCommandBuffer cmd) {
    rb::TlasBuildOptions options = kRebuildTlas;
    options.writeShadingRecords = shadingRecords;
    auto tlas = service.recordTlasBuild(cmd, built.instances, options);
    RB_REQUIRE_OK(tlas);
    built.tlas = tlas.value();
    frame.tlas = &built.tlas;
    RB_REQUIRE_OK(skipping.record(cmd, frame));
    RB_REQUIRE_OK(plain.record(cmd, frame));
  });
}

void addToMean(std::vector<float>& mean, const std::vector<float>& image, uint32_t frames) {
  if (mean.empty()) mean.assign(image.size(), 0.0f);
  REQUIRE(mean.size() == image.size());
  for (size_t k = 0; k < image.size(); ++k) mean[k] += image[k] / float(frames);
}

Retraced retracedPixels(const std::vector<float>& before, const std::vector<float>& since,
                        const std::vector<float>& reference, const std::vector<float>& skipping) {
  REQUIRE(before.size() == since.size());
  REQUIRE(reference.size() == since.size());
  REQUIRE(skipping.size() == since.size());
  Retraced r;
  for (size_t i = 0; i < since.size() / 4; ++i) {
    if (reference[i * 4 + 3] < 0.5f) continue;  // no reflection, or the sky
    const glm::vec3 b(before[i * 4], before[i * 4 + 1], before[i * 4 + 2]);
    const glm::vec3 s(since[i * 4], since[i * 4 + 1], since[i * 4 + 2]);
    if (glm::length(s - b) < 0.5f * std::max({glm::length(b), 0.2f * glm::length(s), 0.2f})) continue;
    ++r.changed;
    bool same = skipping[i * 4 + 3] > 0.5f;
    for (int k = 0; k < 3; ++k) same = same && skipping[i * 4 + k] == reference[i * 4 + k];
    r.caught += same;
    r.stale += skipping[i * 4 + 3] > 1.5f;
  }
  return r;
}

size_t staleMarks(const std::vector<float>& rgba) {
  size_t n = 0;
  for (size_t i = 0; i < rgba.size() / 4; ++i) n += rgba[i * 4 + 3] > 1.5f;
  return n;
}

}  // namespace rbtest

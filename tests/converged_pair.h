// What the converged-tile tests of the RGB signals (tests/converged_reflection_test.cpp,
// tests/converged_lights_test.cpp) share: two HybridEffects recorded side by side over one TLAS (the same rays), and
// the count of the pixels whose colour changed that the skipping one traced again.
#pragma once

#include <raybridge/raybridge.h>

#include <cstddef>
#include <vector>

#include "test_scene.h"
#include "test_support.h"

namespace rbtest {

// Records `skipping` and then `plain` in one frame, over one TLAS rebuilt from `built.instances` (with the shading
// records reflections read when `shadingRecords`), so that both trace the same rays; settles the frame.
void recordSideBySide(GpuFixture& fx, rb::AccelerationStructureService& service, BuiltScene& built,
                      rb::HybridFrame frame, rb::HybridEffects& skipping, rb::HybridEffects& plain,
                      bool shadingRecords);

// Adds image / frames to `mean` (sized to the image when empty).
void addToMean(std::vector<float>& mean, const std::vector<float>& image, uint32_t frames);

// RGBA images of one size. A pixel changed when the mean colour `since` a change differs from the mean `before` it by
// more than half of the larger of the two's scale (|before|, a fifth of |since|, 0.2): noise alone almost never does
// that over several frames. Of those, `caught` were traced this frame by the skipping effect as by the reference
// (the same rgb, a = 1, or 2 where a held tile's history was dropped), `stale` were marked stale (a = 2).
struct Retraced {
  size_t changed = 0, caught = 0, stale = 0;
};
Retraced retracedPixels(const std::vector<float>& before, const std::vector<float>& since,
                        const std::vector<float>& reference, const std::vector<float>& skipping);

// The pixels of an RGBA image marked stale (a = 2).
size_t staleMarks(const std::vector<float>& rgba);

}  // namespace rbtest

// Keyframe interpolation of one glTF animation sampler (LINEAR with slerp for rotations, STEP,
// CUBICSPLINE), in double precision.
#pragma once

#include <cstdint>
#include <vector>

#include "sample_engine/animation.h"

namespace sample_engine::detail {

using KeyLocation = ScenePose::KeyLocation;

// Finds the key interval of `t`: k0, k1 and the fraction between them (k0 == k1 outside the keys). `hint` is
// the interval found last frame: time usually moves forward by less than a key, so most calls are O(1).
KeyLocation locate(const std::vector<float>& times, double t, uint32_t hint);

// Evaluates sampler `smp` (`width` floats per value) at location `at` into out[0..width). Rotations (width 4,
// x y z w) are slerped along the shorter arc (LINEAR) or normalized after the spline (CUBICSPLINE).
void sample(const AnimationSampler& smp, uint32_t width, bool rotation, const KeyLocation& at, double* out);

}  // namespace sample_engine::detail

// glTF 2.0 animation sampler evaluation (spec 3.11 and Appendix C), in double precision.
// Internal to the pose reference. Thread-safe: pure functions.
#pragma once

#include <cstddef>
#include <vector>

namespace pose_reference {

enum class Interpolation { Linear, Step, CubicSpline };

// Evaluates one sampler at time `t`.
// `times`: the keyframe times (strictly increasing, at least one). `values`: `width` doubles per key for
// LINEAR and STEP; for CUBICSPLINE 3 * width per key in the spec's order (in-tangent, value, out-tangent).
// Before the first key / after the last key the first / last value holds (the spec's clamping).
// `rotation` (width 4, quaternions x,y,z,w): LINEAR uses slerp along the shorter arc; the result of every
// interpolation mode is normalized, as the spec asks of CUBICSPLINE rotations.
std::vector<double> sampleKeyframes(const std::vector<double>& times, const std::vector<double>& values, size_t width,
                                    Interpolation interpolation, bool rotation, double t);

}  // namespace pose_reference

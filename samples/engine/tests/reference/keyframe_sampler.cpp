// Keyframe interpolation: STEP, LINEAR (lerp, or slerp for rotations) and the CUBICSPLINE Hermite of Appendix
// C.
#include "keyframe_sampler.h"

#include <algorithm>
#include <cmath>

namespace pose_reference {
namespace {

void normalize4(std::vector<double>& q) {
  const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (len > 0.0)
    for (double& c : q) c /= len;
}

// Spherical interpolation; negating b when the quaternions are more than 90 degrees apart takes the shorter
// arc (q and -q are the same rotation).
std::vector<double> slerp(const double* a, const double* bIn, double u) {
  double b[4] = {bIn[0], bIn[1], bIn[2], bIn[3]};
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0.0) {
    for (double& c : b) c = -c;
    d = -d;
  }
  double wa = 1.0 - u, wb = u;
  if (d < 1.0 - 1e-12) {  // else the arc is too short for sin(theta) to be divided by: lerp is exact enough
    const double theta = std::acos(std::min(d, 1.0));
    const double s = std::sin(theta);
    wa = std::sin((1.0 - u) * theta) / s;
    wb = std::sin(u * theta) / s;
  }
  std::vector<double> r(4);
  for (int i = 0; i < 4; ++i) r[size_t(i)] = wa * a[i] + wb * b[i];
  return r;
}

}  // namespace

std::vector<double> sampleKeyframes(const std::vector<double>& times, const std::vector<double>& values, size_t width,
                                    Interpolation interpolation, bool rotation, double t) {
  const bool cubic = interpolation == Interpolation::CubicSpline;
  const size_t keyStride = cubic ? 3 * width : width;
  const size_t valueOffset = cubic ? width : 0;  // skip the in-tangent
  auto value = [&](size_t key) { return values.data() + key * keyStride + valueOffset; };

  std::vector<double> result(width);
  auto hold = [&](size_t key) {
    std::copy(value(key), value(key) + width, result.begin());
    if (rotation) normalize4(result);
    return result;
  };
  if (times.size() == 1 || t <= times.front()) return hold(0);
  if (t >= times.back()) return hold(times.size() - 1);

  // Segment k: times[k] <= t < times[k + 1].
  const size_t k = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  const double delta = times[k + 1] - times[k];
  const double u = (t - times[k]) / delta;
  switch (interpolation) {
    case Interpolation::Step: return hold(k);
    case Interpolation::Linear:
      if (rotation) {
        result = slerp(value(k), value(k + 1), u);
      } else {
        for (size_t i = 0; i < width; ++i) result[i] = (1.0 - u) * value(k)[i] + u * value(k + 1)[i];
      }
      break;
    case Interpolation::CubicSpline: {
      // Appendix C: p(u) = (2u^3 - 3u^2 + 1) v_k + (u^3 - 2u^2 + u) delta b_k + (-2u^3 + 3u^2) v_k+1
      //                   + (u^3 - u^2) delta a_k+1, with b = out-tangent, a = in-tangent.
      const double u2 = u * u, u3 = u2 * u;
      const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
      const double* outTangent = values.data() + k * keyStride + 2 * width;
      const double* inTangentNext = values.data() + (k + 1) * keyStride;
      for (size_t i = 0; i < width; ++i)
        result[i] = h00 * value(k)[i] + h10 * delta * outTangent[i] + h01 * value(k + 1)[i] +
                    h11 * delta * inTangentNext[i];
      break;
    }
  }
  if (rotation) normalize4(result);
  return result;
}

}  // namespace pose_reference

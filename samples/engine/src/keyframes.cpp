#include "keyframes.h"

#include <algorithm>
#include <cmath>

namespace sample_engine::detail {

KeyLocation locate(const std::vector<float>& times, double t, uint32_t hint) {
  const size_t n = times.size();
  KeyLocation l;
  if (n == 1 || t <= double(times[0])) return l;
  if (t >= double(times[n - 1])) {
    l.k0 = l.k1 = uint32_t(n - 1);
    return l;
  }
  size_t k1 = 0;  // first key with time > t
  if (hint >= 1 && hint < n && double(times[hint - 1]) <= t && t < double(times[hint])) {
    k1 = hint;
  } else if (hint >= 1 && hint + 1 < n && double(times[hint]) <= t && t < double(times[hint + 1])) {
    k1 = hint + 1;
  } else {
    k1 = size_t(std::upper_bound(times.begin(), times.end(), t, [](double a, float b) { return a < double(b); }) -
                times.begin());
  }
  l.k0 = uint32_t(k1 - 1);
  l.k1 = uint32_t(k1);
  const double td = double(times[k1]) - double(times[k1 - 1]);
  l.s = td > 0.0 ? (t - double(times[k1 - 1])) / td : 1.0;
  return l;
}

void sample(const AnimationSampler& smp, uint32_t width, bool rotation, const KeyLocation& at, double* out) {
  const size_t k0 = at.k0, k1 = at.k1;
  const double s = at.s;
  const bool cubic = smp.interpolation == AnimationInterpolation::CubicSpline;
  const size_t stride = cubic ? 3 * size_t(width) : width;
  const float* v0 = &smp.values[k0 * stride + (cubic ? width : 0)];
  const float* v1 = &smp.values[k1 * stride + (cubic ? width : 0)];
  if (k0 == k1 || smp.interpolation == AnimationInterpolation::Step) {
    for (uint32_t c = 0; c < width; ++c) out[c] = v0[c];
  } else if (!cubic) {
    if (rotation) {
      glm::dquat a(v0[3], v0[0], v0[1], v0[2]), b(v1[3], v1[0], v1[1], v1[2]);
      a = glm::normalize(a);
      b = glm::normalize(b);
      if (glm::dot(a, b) < 0.0) b = -b;  // shortest arc
      // Angle from the chord (accurate for nearly equal quaternions, unlike acos of the dot product).
      const double theta = 2.0 * std::atan2(glm::length(glm::dvec4(a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w)),
                                            glm::length(glm::dvec4(a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w)));
      glm::dquat r;
      if (theta < 1e-12) {
        r = glm::normalize(a * (1.0 - s) + b * s);
      } else {
        const double sinTheta = std::sin(theta);
        r = a * (std::sin((1.0 - s) * theta) / sinTheta) + b * (std::sin(s * theta) / sinTheta);
      }
      out[0] = r.x;
      out[1] = r.y;
      out[2] = r.z;
      out[3] = r.w;
    } else {
      for (uint32_t c = 0; c < width; ++c) out[c] = double(v0[c]) * (1.0 - s) + double(v1[c]) * s;
    }
  } else {
    // Hermite spline (glTF appendix C): out-tangent of k0 and in-tangent of k1, scaled by the key spacing.
    const double td = double(smp.times[k1]) - double(smp.times[k0]);
    const float* b0 = &smp.values[k0 * stride + 2 * size_t(width)];
    const float* a1 = &smp.values[k1 * stride];
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    for (uint32_t c = 0; c < width; ++c) out[c] = h00 * v0[c] + td * h10 * b0[c] + h01 * v1[c] + td * h11 * a1[c];
    if (rotation) {
      const double len = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
      if (len > 0.0)
        for (int c = 0; c < 4; ++c) out[c] /= len;
    }
  }
}

}  // namespace sample_engine::detail

// What the bench's generated scenes share: a portable seeded random generator and double-precision 3-vectors.
// Thread safety: plain values; a SplitMix64 is used by one thread at a time.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace rbbench {

inline constexpr double kPi = 3.14159265358979323846;

// SplitMix64: the same scene on every platform (std distributions are implementation-defined).
struct SplitMix64 {
  uint64_t state;
  double next() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return double(z >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
  }
  double in(double lo, double hi) { return lo + (hi - lo) * next(); }
};

using Vec3 = std::array<double, 3>;
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 normalized(const Vec3& v) {
  const double l = std::sqrt(dot(v, v));
  return {v[0] / l, v[1] / l, v[2] / l};
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace rbbench

#include "tlas_motion.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace rb {

namespace {

constexpr size_t kStride = TlasMotionMeasure::kFloatsPerInstance;

// Instance i's translation along axis a.
float originOf(std::span<const float> transforms, size_t i, int a) { return transforms[kStride * i + 4 * a + 3]; }

// Whether every float is finite: its exponent bits not all set. Written on the bits so that it vectorises
// (std::isfinite per float does not), as it runs over twelve floats per instance every frame.
uint32_t nonFiniteBit(float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return uint32_t((bits & 0x7f800000u) == 0x7f800000u);
}

bool allFinite(std::span<const float> transforms) {
  uint32_t nonFinite = 0;
  for (float v : transforms) nonFinite |= nonFiniteBit(v);
  return nonFinite == 0;
}

}  // namespace

void TlasMotionMeasure::reset(std::span<const float> transforms) {
  refitsSinceRebuild = 0;
  const size_t n = transforms.size() / kStride;
  groupOf_.assign(n, 0);
  groups_ = n ? 1 : 0;
  pad_ = 0.5;
  baseline_ = 0.0;
  ref_[0] = ref_[1] = ref_[2] = 0.0f;
  finite_ = allFinite(transforms);
  // A non-finite transform gives no grid and no baseline: growth() reads +inf until a finite list is measured.
  if (n == 0 || !finite_) return;

  // The grid spans the origins between the kOutlierFraction-th and (1 - kOutlierFraction)-th quantile per axis,
  // so one far instance (an anchor at the world origin of a streamed level) cannot stretch the cells until the
  // whole field is one group and no scatter is ever seen. Instances more than a cell outside are groups of
  // their own (below).
  // The quantiles come from at most kQuantileSamples origins taken at an even stride (deterministic, and a few
  // microseconds instead of a selection over a million instances at every rebuild).
  const size_t samples = std::min<size_t>(n, kQuantileSamples);
  const size_t q = size_t(double(samples) * kOutlierFraction);
  double lo[3], hi[3];
  std::vector<float> axis(samples);
  for (int a = 0; a < 3; ++a) {
    for (size_t k = 0; k < samples; ++k) axis[k] = originOf(transforms, k * n / samples, a);
    std::nth_element(axis.begin(), axis.begin() + std::ptrdiff_t(samples - 1 - q), axis.end());
    hi[a] = axis[samples - 1 - q];
    std::nth_element(axis.begin(), axis.begin() + std::ptrdiff_t(q), axis.begin() + std::ptrdiff_t(samples - 1 - q));
    lo[a] = axis[q];
  }
  for (int a = 0; a < 3; ++a) ref_[a] = float(lo[a]);  // an input float: exact
  // Cubic cells sized so that the box holds about n / kTlasClusterInstances of them. An axis thinner than a
  // cell (a city on a plane, a row of lamps) gets one cell, and the cells divide the other axes among them.
  double extent[3], longest = 0.0;
  for (int a = 0; a < 3; ++a) {
    extent[a] = hi[a] - lo[a];
    longest = std::max(longest, extent[a]);
  }
  double edge = 1.0;  // the inliers all in one point: one cell, and a unit cube per instance for the area
  uint64_t dims[3] = {1, 1, 1}, total = 1;
  if (longest > 0.0) {
    const double cellsWanted = std::max(1.0, double(n) / kTlasClusterInstances);
    bool spread[3] = {true, true, true};
    edge = longest;
    for (int round = 0; round < 3; ++round) {
      double product = 1.0;
      int axes = 0, thinnest = -1;
      for (int a = 0; a < 3; ++a) {
        if (!spread[a]) continue;
        product *= extent[a];
        ++axes;
        if (thinnest < 0 || extent[a] < extent[thinnest]) thinnest = a;
      }
      edge = std::pow(product / cellsWanted, 1.0 / axes);
      // Strictly: an axis without extent (every origin on one plane) makes the product and the edge 0 and must go.
      if (axes == 1 || extent[thinnest] > edge) break;
      spread[thinnest] = false;
    }
    edge = std::max(edge, longest * 1e-6);
    total = 1;
    for (int a = 0; a < 3; ++a) {
      dims[a] = uint64_t(std::clamp(std::ceil(extent[a] / edge), 1.0, double(n)));
      total *= dims[a];
    }
  }
  // Outside the quantiles by more than a cell: a group of its own. Nearer (the tails of an even field), the
  // border cells take it.
  auto isOutlier = [&](size_t i) {
    for (int a = 0; a < 3; ++a) {
      const double v = originOf(transforms, i, a);
      if (v < lo[a] - edge || v > hi[a] + edge) return true;
    }
    return false;
  };
  // Dense cell -> group table; the clamp above bounds it by n per axis, and `total` stays near cellsWanted
  // (each axis rounds up by at most one cell).
  std::vector<uint32_t> groupOfCell(size_t(std::min<uint64_t>(total, uint64_t(n) * 8)), UINT32_MAX);
  groups_ = 0;
  for (size_t i = 0; i < n; ++i) {
    if (isOutlier(i)) {
      groupOf_[i] = groups_++;
      continue;
    }
    uint64_t cell = 0;
    for (int a = 2; a >= 0; --a) {
      const double t = (double(originOf(transforms, i, a)) - lo[a]) / edge;
      cell = cell * dims[a] + std::min<uint64_t>(uint64_t(std::clamp(t, 0.0, double(dims[a] - 1))), dims[a] - 1);
    }
    uint32_t& g = groupOfCell[cell % groupOfCell.size()];
    if (g == UINT32_MAX) g = groups_++;
    groupOf_[i] = g;
  }
  pad_ = edge * 0.5;
  baseline_ = summedArea(transforms);  // finite: every input float is
}

double TlasMotionMeasure::growth(std::span<const float> transforms) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  // A list of another length is no refit chain (the caller rebuilds on the count anyway): no growth claimed.
  if (transforms.size() / kStride != groupOf_.size()) return 1.0;
  // min and max skip NaN, so a non-finite transform would vanish from the boxes: summedArea() says NaN
  // instead, and it reads as unbounded growth.
  if (!finite_) return inf;
  const double now = summedArea(transforms);
  if (std::isnan(now)) return inf;
  // A zero baseline (every instance scaled to nothing, on one line or in one point) grows from nothing.
  if (!(baseline_ > 0.0)) return now > 0.0 ? inf : 1.0;
  return std::isfinite(now) ? now / baseline_ : inf;
}

// NaN when an input float is not finite.
double TlasMotionMeasure::summedArea(std::span<const float> transforms) {
  // The boxes are float (half the memory of double: at a million instances they outgrow the caches), in
  // coordinates relative to ref_, a grid corner of reset(): an origin near the field minus ref_ is exact
  // (Sterbenz), so a box far from the world origin keeps its size to the bit instead of rounding to the inputs'
  // spacing out there (1 unit at 1e7), which would move the measure by percents when nothing moved.
  constexpr float inf = std::numeric_limits<float>::infinity();
  boxes_.resize(size_t(groups_) * 6);
  for (uint32_t g = 0; g < groups_; ++g) {
    for (int a = 0; a < 3; ++a) {
      boxes_[6 * g + a] = inf;
      boxes_[6 * g + 3 + a] = -inf;
    }
  }
  const float pad = float(pad_);
  // Any non-finite input float makes a bound below non-finite (pad is finite and positive): one test per bound
  // instead of another pass over the twelve floats of each instance.
  uint32_t nonFinite = 0;
  const float ref[3] = {ref_[0], ref_[1], ref_[2]};  // locals: the box stores below may not alias them
  for (size_t i = 0; i < groupOf_.size(); ++i) {
    const float* m = &transforms[kStride * i];
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      // The bounds of the cube [-pad, pad]^3 under the instance's linear part: pad times the row's absolute sum.
      const float half = pad * (std::abs(m[4 * a]) + std::abs(m[4 * a + 1]) + std::abs(m[4 * a + 2]));
      const float origin = m[4 * a + 3] - ref[a];
      lo[a] = origin - half;
      hi[a] = origin + half;
      nonFinite |= nonFiniteBit(lo[a]) | nonFiniteBit(hi[a]);
    }
    float* box = &boxes_[6 * size_t(groupOf_[i])];
    for (int a = 0; a < 3; ++a) {
      box[a] = std::min(box[a], lo[a]);
      box[3 + a] = std::max(box[3 + a], hi[a]);
    }
  }
  if (nonFinite) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0.0;
  for (uint32_t g = 0; g < groups_; ++g) {
    const float* box = &boxes_[6 * g];
    const double dx = double(box[3]) - box[0], dy = double(box[4]) - box[1], dz = double(box[5]) - box[2];
    sum += 2.0 * (dx * dy + dy * dz + dz * dx);
  }
  return sum;
}

}  // namespace rb

#include "tlas_motion.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rb {

namespace {

constexpr size_t kStride = TlasMotionMeasure::kFloatsPerInstance;

// Instance i's translation along axis a.
float originOf(std::span<const float> transforms, size_t i, int a) { return transforms[kStride * i + 4 * a + 3]; }

}  // namespace

void TlasMotionMeasure::reset(std::span<const float> transforms) {
  refitsSinceRebuild = 0;
  const size_t n = transforms.size() / kStride;
  groupOf_.assign(n, 0);
  groups_ = n ? 1 : 0;
  pad_ = 0.0f;
  baseline_ = 0.0;
  if (n == 0) return;
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = originOf(transforms, 0, a);
  for (size_t i = 1; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], originOf(transforms, i, a));
      hi[a] = std::max(hi[a], originOf(transforms, i, a));
    }
  }
  // Cubic cells sized so that the box holds about n / kTlasClusterInstances of them. An axis thinner than a
  // cell (a city on a plane, a row of lamps) gets one cell, and the cells divide the other axes among them.
  double extent[3], longest = 0.0;
  for (int a = 0; a < 3; ++a) {
    extent[a] = double(hi[a]) - double(lo[a]);
    longest = std::max(longest, extent[a]);
  }
  if (!(longest > 0.0) || !std::isfinite(longest)) {
    // Every origin in one point (or a non-finite transform): one group; its area is the padding's.
    pad_ = 0.5f;
    baseline_ = summedArea(transforms);
    return;
  }
  const double cellsWanted = std::max(1.0, double(n) / kTlasClusterInstances);
  bool spread[3] = {true, true, true};
  double edge = longest;
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
  uint64_t dims[3], total = 1;
  for (int a = 0; a < 3; ++a) {
    dims[a] = uint64_t(std::clamp(std::ceil(extent[a] / edge), 1.0, double(n)));
    total *= dims[a];
  }
  // Dense cell -> group table; the clamp above bounds it by n per axis, and `total` stays near cellsWanted
  // (each axis rounds up by at most one cell).
  std::vector<uint32_t> groupOfCell(size_t(std::min<uint64_t>(total, uint64_t(n) * 8)), UINT32_MAX);
  groups_ = 0;
  for (size_t i = 0; i < n; ++i) {
    uint64_t cell = 0;
    for (int a = 2; a >= 0; --a) {
      const double t = (double(originOf(transforms, i, a)) - lo[a]) / edge;
      cell = cell * dims[a] + std::min<uint64_t>(uint64_t(std::max(t, 0.0)), dims[a] - 1);
    }
    uint32_t& g = groupOfCell[cell % groupOfCell.size()];
    if (g == UINT32_MAX) g = groups_++;
    groupOf_[i] = g;
  }
  pad_ = float(edge * 0.5);
  baseline_ = summedArea(transforms);
}

double TlasMotionMeasure::growth(std::span<const float> transforms) {
  if (transforms.size() / kStride != groupOf_.size() || !(baseline_ > 0.0)) return 1.0;
  const double now = summedArea(transforms);
  return std::isfinite(now) ? now / baseline_ : std::numeric_limits<double>::infinity();
}

double TlasMotionMeasure::summedArea(std::span<const float> transforms) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  boxes_.resize(size_t(groups_) * 6);
  for (uint32_t g = 0; g < groups_; ++g) {
    for (int a = 0; a < 3; ++a) {
      boxes_[6 * g + a] = inf;
      boxes_[6 * g + 3 + a] = -inf;
    }
  }
  for (size_t i = 0; i < groupOf_.size(); ++i) {
    float* box = &boxes_[6 * size_t(groupOf_[i])];
    const float* m = &transforms[kStride * i];
    for (int a = 0; a < 3; ++a) {
      // The bounds of the cube [-pad, pad]^3 under the instance's linear part: pad times the row's absolute sum.
      const float half = pad_ * (std::abs(m[4 * a]) + std::abs(m[4 * a + 1]) + std::abs(m[4 * a + 2]));
      box[a] = std::min(box[a], m[4 * a + 3] - half);
      box[3 + a] = std::max(box[3 + a], m[4 * a + 3] + half);
    }
  }
  double sum = 0.0;
  for (uint32_t g = 0; g < groups_; ++g) {
    const float* box = &boxes_[6 * g];
    const double dx = double(box[3]) - box[0], dy = double(box[4]) - box[1], dz = double(box[5]) - box[2];
    sum += 2.0 * (dx * dy + dy * dz + dz * dx);
  }
  return sum;
}

}  // namespace rb

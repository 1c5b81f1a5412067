// Per-frame GPU time percentiles (see the header).
#include "frame_series.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace rbRender {

void FrameSeries::add(const std::string& metric, uint64_t frame, double ms) {
  Samples& s = metrics_[metric];
  if (s.any && frame <= s.lastFrame) return;
  s.any = true;
  s.lastFrame = frame;
  s.ms.push_back(ms);
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  // Nearest rank: the smallest value with at least p% of the values at or below it.
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * double(values.size()));
  const size_t index = size_t(std::max(rank, 1.0)) - 1;
  return values[std::min(index, values.size() - 1)];
}

nlohmann::json FrameSeries::summary() const {
  nlohmann::json out = nlohmann::json::object();
  size_t frames = 0;
  for (const auto& [name, s] : metrics_) {
    if (s.ms.size() <= kFrameSeriesWarmupFrames) continue;
    const std::vector<double> kept(s.ms.begin() + kFrameSeriesWarmupFrames, s.ms.end());
    frames = std::max(frames, kept.size());
    out[name] = {{"p50", percentile(kept, 50.0)},
                 {"p99", percentile(kept, 99.0)},
                 {"mean", std::accumulate(kept.begin(), kept.end(), 0.0) / double(kept.size())},
                 {"max", *std::max_element(kept.begin(), kept.end())},
                 {"samples", kept.size()}};
  }
  out["frames"] = frames;
  out["warmup_frames_left_out"] = kFrameSeriesWarmupFrames;
  return out;
}

}  // namespace rbRender

// Per-frame GPU times over a run of frames (a camera path, an animation), summarised as percentiles for
// stats.json: the fly-through numbers of docs/performance.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rbRender {

// The first frames build every BLAS and fill the denoisers' history: they are left out of the summary.
inline constexpr uint32_t kFrameSeriesWarmupFrames = 3;

class FrameSeries {
 public:
  // One frame's value of `metric` (ms). Frames are told apart by `frame`: a frame already added for this metric
  // is ignored, so the caller may offer the latest resolved timings after every submitted frame.
  void add(const std::string& metric, uint64_t frame, double ms);
  // {"frames": n, "warmup_frames_left_out": k, metric: {"p50", "p99", "mean", "max", "samples"}, ...}; metrics with
  // no frame past the warm-up are left out. Percentiles are nearest-rank over the frames after the warm-up.
  nlohmann::json summary() const;

 private:
  struct Samples {
    std::vector<double> ms;
    uint64_t lastFrame = 0;
    bool any = false;
  };
  std::map<std::string, Samples> metrics_;
};

// Nearest-rank percentile p (0..100) of `values` (sorted or not); 0 for an empty list.
double percentile(std::vector<double> values, double p);

}  // namespace rbRender

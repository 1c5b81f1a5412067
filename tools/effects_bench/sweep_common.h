// What the three effect sweeps share: the plan (settings, sizes, frame counts), medians of timed frames, the
// converged reference, image output and the self-checks.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "frame_driver.h"
#include "image_error.h"
#include "sweep_results.h"

namespace rbEffects {

struct SweepPlan {
  uint32_t width = 0, height = 0;
  uint32_t warmupFrames = 2, timedFrames = 3;
  // Traced: rays per pixel. Raster: shadow map size x PCF kernel, SSAO kernel, probe resolution (0 = sky).
  std::vector<uint32_t> shadowRays, aoRays, reflectionRays;
  std::vector<uint32_t> adaptiveRays;  // --scenario adaptive: the uniform ray counts compared
  std::vector<std::pair<uint32_t, uint32_t>> shadowMaps;
  std::vector<uint32_t> ssaoKernels, probeSizes;
  // Reference: total rays per pixel; traced in frames of at most kReferenceRaysPerFrame rays.
  uint32_t referenceShadows = 0, referenceAo = 0, referenceReflections = 0;
  float sunRadiusDegrees = 0.5f;
  float aoRange = 1.0f;
  float reflectionRoughness = 1.0f;
  std::string imagesDir;  // "" = no PNGs
};
inline constexpr uint32_t kReferenceRaysPerFrame = 64;  // the reflection pass's maximum

// Prints a progress line at once (the bench runs for minutes).
void progress(const char* format, ...) __attribute__((format(printf, 1, 2)));

double median(std::vector<double> values);
double medianOf(const std::vector<FrameSample>& samples, const std::function<double(const FrameSample&)>& f);
// Median of every engine pass, plus "frame" (FrameSample::frameMs).
nlohmann::json engineMedians(const std::vector<FrameSample>& samples);
// Median GPU ms and rays of one SDK pass.
PassResult passMedian(const std::vector<FrameSample>& samples, const char* name,
                      rb::PassStats rb::HybridStats::*member);

// Traces the converged reference: frames of `params` (the adapter set up by the caller), each with fresh
// noise (the SDK seeds its samplers per frame), the extracted values averaged on the CPU. Also returns the
// surface mask (from the captured depth) and fills `out` (frames, counted rays, halves' RMSE, seconds).
struct ReferenceImage {
  std::vector<float> values;
  std::vector<uint8_t> mask;
};
using Extract = std::function<sample_engine::Result<std::vector<float>>(const rbRender::CapturedFrame&)>;
sample_engine::Result<ReferenceImage> traceReference(FrameDriver& driver, const sample_engine::FrameParams& params,
                                                     uint32_t frames, uint32_t channels, const Extract& extract,
                                                     rb::PassStats rb::HybridStats::*counted, Reference& out);

// Writes `<imagesDir>/<effect>/<id>.png` with `write` and returns the path relative to imagesDir ("" when no
// images are written).
sample_engine::Result<std::string> writeImage(const SweepPlan& plan, const std::string& effect, const std::string& id,
                                              const std::function<sample_engine::Status(const std::string&)>& write);

// (a) more traced rays never make the raw error worse (max rays < 1 ray), (b) every traced row counted rays,
// (c) the reference's own noise is under half the error of the best raw traced row. Failures go into
// result.checkFailures.
void selfCheck(EffectResult& result);

}  // namespace rbEffects

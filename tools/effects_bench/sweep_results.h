// What one effect's sweep measured: its converged reference and one row per method and setting.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rbEffects {

// One SDK pass of a traced row (medians over the timed frames).
struct PassResult {
  std::string name;  // "shadow", "shadow_denoise", "ao", "ao_denoise", "reflection", "reflection_denoise"
  double gpuMs = 0.0;
  uint64_t rays = 0;  // counted by the shaders (PassStats::rays), not derived from the settings
  double raysPerSecond() const { return gpuMs > 0.0 ? double(rays) / (gpuMs * 1e-3) : 0.0; }
};

struct Row {
  // "traced_raw", "traced_denoised", "raster"; AO and reflections also "traced_half_raw", "traced_half_denoised"
  // (half-resolution tracing at the same ray counts, params.half_resolution = true)
  std::string method;
  std::string setting;  // human-readable, e.g. "8 rays", "map 2048, PCF 3", "probe 128"
  std::string id;       // file-name friendly, unique within the effect (the PNG's stem)
  nlohmann::json params;
  double effectMs = 0.0;           // GPU ms of the effect's own passes (what the plots put on x)
  std::string effectMsOf;          // which passes effectMs sums
  double frameMs = 0.0;            // GPU ms of the whole frame (engine passes, hook included)
  nlohmann::json engineMs;         // medians of each engine pass
  std::vector<PassResult> passes;  // SDK passes (traced rows only)
  double rmse = 0.0, bias = 0.0;
  std::string image;  // PNG, relative to --images ("" when not written)
};

struct Reference {
  uint32_t raysPerFrame = 0, frames = 0;
  uint64_t raysCounted = 0;  // sum of PassStats::rays over the reference frames
  double halvesRmse = 0.0;   // RMSE between the even-frame and odd-frame means
  // Estimated RMSE of the reference itself against the converged limit: halvesRmse / 2 (each half has twice
  // the variance of the whole, and the halves' difference twice that of one half).
  double noiseRmse() const { return halvesRmse * 0.5; }
  double seconds = 0.0;
  std::string image;
};

struct EffectResult {
  std::string effect;    // "shadows", "ao", "reflections"
  std::string compared;  // what the error is measured on
  std::string effectMsNote;
  uint64_t surfacePixels = 0;
  Reference reference;
  std::vector<Row> rows;
  std::vector<std::string> checkFailures;  // self-checks that failed (empty = all passed)
  nlohmann::json summary;                  // scenario-specific conclusions (null = none)
  double seconds = 0.0;
};

}  // namespace rbEffects

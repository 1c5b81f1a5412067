// The benchmark scenarios. Each prints its table(s) and returns its rows and summary as JSON.
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "bench_env.h"
#include "gltf_meshes.h"

namespace rbbench {

// BLAS build GPU time against triangle count (one BLAS per mesh), procedural sizes and glTF models.
nlohmann::json runBuildScenario(BenchEnv& env, const std::vector<GltfModel>& models);
// A mesh copied N times: N distinct BLASes against one shared BLAS (dedup) with N instances.
nlohmann::json runDuplicationScenario(BenchEnv& env);
// The same mesh as MeshRole::Static (PREFER_FAST_TRACE) and MeshRole::Dynamic (PREFER_FAST_BUILD).
nlohmann::json runFastBuildScenario(BenchEnv& env);
// BLAS bytes before and after compaction per mesh size and glTF model.
nlohmann::json runCompactionScenario(BenchEnv& env, const std::vector<GltfModel>& models);
// TLAS over many instances: recordTlasBuild host time and TLAS build GPU time.
nlohmann::json runTlasScenario(BenchEnv& env);
// TLAS refits while instances scatter: trace time over rebuilt, refitted and adaptive TLASes, and build times.
nlohmann::json runTlasMotionScenario(BenchEnv& env);
// Raw primary-ray rate on a finely tessellated scene (and on rays that miss everything).
nlohmann::json runTraceScenario(BenchEnv& env);
// The thesis's stress (many rays per pixel, all hit) and miss scenarios: the device's raw trace rate.
nlohmann::json runGigaRaysScenario(BenchEnv& env);
// Shadow pass GPU time with 0%, 10%, 50% and 100% of a leaf canopy's triangles alpha-tested (any-hit), against
// the all-opaque scene.
nlohmann::json runAlphaScenario(BenchEnv& env);
// The many-light pass on a floor of pillars under 1, 16, 256 and 4,096 lights: stochastic (1 and 4 rays per pixel)
// against the exact mode, raw and denoised (pass time, rays, relative RMSE).
nlohmann::json runLightsScenario(BenchEnv& env);
// Frames recorded and run while meshes, effects, presets, the resolution and the TLAS's instances change at random
// (seeded); the SDK's memory and handles at the start, after the warm-up and at the end, which must show no growth,
// no live handle after release and no validation error. Its result lists what failed under "failures".
nlohmann::json runSoakScenario(BenchEnv& env);
// The device memory of HybridEffects for every preset (with local lights) at four resolutions: by effect and category,
// and pass images per pixel (docs/integration.md, "Memory sweep"). Its result lists what failed under "failures": the
// effects' sum against the pass memory, pass images per pixel against the pixel count, what a destroyed HybridEffects
// leaves behind.
nlohmann::json runMemoryScenario(BenchEnv& env);

}  // namespace rbbench

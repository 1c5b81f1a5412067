// Output of the effects bench: the JSON document and the printed tables.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sweep_results.h"

namespace rbEffects {

// The raw trace rate of the device: raybridge-bench's gigarays scenario, stress row (all rays hit).
struct RawRate {
  std::string source;
  double graysPerSecond = 0.0;
};
// Reads scenarios.gigarays.summary.stressGRaysPerSecond; the error names the file and what is missing.
std::string readRawRate(const std::string& path, RawRate& out);

nlohmann::json toJson(const EffectResult& result, const std::optional<RawRate>& raw);
// One table per effect (rows, reference) and the traced passes' rays/s (fraction of the raw rate when known).
void printTables(const std::vector<EffectResult>& results, const std::optional<RawRate>& raw);

}  // namespace rbEffects

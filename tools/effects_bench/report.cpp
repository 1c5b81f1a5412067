// JSON and tables of the effects bench (see the header).
#include "report.h"

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace rbEffects {

std::string readRawRate(const std::string& path, RawRate& out) {
  std::ifstream in(path);
  if (!in) return "--raw-rate-json: cannot open '" + path + "'";
  nlohmann::json doc = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) return "--raw-rate-json: '" + path + "' is not valid JSON";
  const nlohmann::json::json_pointer ptr("/scenarios/gigarays/summary/stressGRaysPerSecond");
  if (!doc.contains(ptr) || !doc[ptr].is_number())
    return "--raw-rate-json: '" + path +
           "' has no scenarios.gigarays.summary.stressGRaysPerSecond (run "
           "raybridge-bench --scenario gigarays)";
  out.source = path;
  out.graysPerSecond = doc[ptr].get<double>();
  if (!(out.graysPerSecond > 0.0)) return "--raw-rate-json: the stress rate in '" + path + "' is not positive";
  return {};
}

namespace {

nlohmann::json passJson(const PassResult& p, const std::optional<RawRate>& raw) {
  nlohmann::json j = {{"gpu_ms", p.gpuMs}, {"rays", p.rays}, {"rays_per_second", p.raysPerSecond()}};
  if (raw && p.rays) j["fraction_of_raw_rate"] = p.raysPerSecond() / (raw->graysPerSecond * 1e9);
  return j;
}

}  // namespace

nlohmann::json toJson(const EffectResult& r, const std::optional<RawRate>& raw) {
  nlohmann::json rows = nlohmann::json::array();
  for (const Row& row : r.rows) {
    nlohmann::json passes = nlohmann::json::object();
    for (const PassResult& p : row.passes) passes[p.name] = passJson(p, raw);
    rows.push_back({{"method", row.method},
                    {"setting", row.setting},
                    {"id", row.id},
                    {"params", row.params},
                    {"effect_ms", row.effectMs},
                    {"effect_ms_of", row.effectMsOf},
                    {"frame_ms", row.frameMs},
                    {"engine_ms", row.engineMs},
                    {"passes", passes},
                    {"rmse", row.rmse},
                    {"bias", row.bias},
                    {"image", row.image}});
  }
  const Reference& ref = r.reference;
  nlohmann::json out = {{"compared", r.compared},
                        {"effect_ms_note", r.effectMsNote},
                        {"surface_pixels", r.surfacePixels},
                        {"reference",
                         {{"rays_per_pixel", ref.raysPerFrame * ref.frames},
                          {"rays_per_frame", ref.raysPerFrame},
                          {"frames", ref.frames},
                          {"rays_counted", ref.raysCounted},
                          {"halves_rmse", ref.halvesRmse},
                          {"noise_rmse_estimate", ref.noiseRmse()},
                          {"seconds", ref.seconds},
                          {"image", ref.image}}},
                        {"rows", rows},
                        {"checks", {{"passed", r.checkFailures.empty()}, {"failures", r.checkFailures}}},
                        {"seconds", r.seconds}};
  if (!r.summary.is_null()) out["summary"] = r.summary;
  return out;
}

void printTables(const std::vector<EffectResult>& results, const std::optional<RawRate>& raw) {
  for (const EffectResult& r : results) {
    std::printf("\n== %s: error on the %s; reference %u rays per pixel (%u frames), noise RMSE ~%.5f\n",
                r.effect.c_str(), r.compared.c_str(), r.reference.raysPerFrame * r.reference.frames, r.reference.frames,
                r.reference.noiseRmse());
    // The method column as wide as its longest name (the adaptive scenario's run to 27 characters).
    int methodWidth = 16;
    for (const Row& row : r.rows) methodWidth = std::max(methodWidth, int(row.method.size()));
    std::printf("%-*s %-18s %10s %10s %10s %10s  %s\n", methodWidth, "method", "setting", "effect ms", "frame ms",
                "RMSE", "bias", "effect ms of");
    for (const Row& row : r.rows)
      std::printf("%-*s %-18s %10.3f %10.3f %10.5f %+10.5f  %s\n", methodWidth, row.method.c_str(), row.setting.c_str(),
                  row.effectMs, row.frameMs, row.rmse, row.bias, row.effectMsOf.c_str());
  }
  std::printf("\n== traced passes: rays counted per frame and rays/s");
  if (raw) std::printf(" (raw rate: %.4f GRays/s from %s)", raw->graysPerSecond, raw->source.c_str());
  std::printf("\n%-12s %-14s %-10s %12s %10s %12s %10s\n", "effect", "pass", "setting", "rays", "gpu ms", "Mrays/s",
              raw ? "of raw" : "");
  for (const EffectResult& r : results) {
    for (const Row& row : r.rows) {
      // The denoised rows repeat the same trace pass.
      if (row.method != "traced_raw" && row.method != "traced_half_raw") continue;
      for (const PassResult& p : row.passes) {
        std::printf("%-12s %-14s %-10s %12llu %10.3f %12.2f", r.effect.c_str(), p.name.c_str(), row.setting.c_str(),
                    static_cast<unsigned long long>(p.rays), p.gpuMs, p.raysPerSecond() * 1e-6);
        if (raw) std::printf(" %10.4f", p.raysPerSecond() / (raw->graysPerSecond * 1e9));
        std::printf("\n");
      }
    }
  }
}

}  // namespace rbEffects

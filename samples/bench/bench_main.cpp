// raybridge-bench: the acceleration-structure service measured in the scenarios of a thesis on hybrid ray
// tracing. Prints a table per scenario, progress on stderr, and writes every number to JSON (--out).
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "bench_env.h"
#include "bench_options.h"
#include "gltf_meshes.h"
#include "report.h"
#include "scenarios.h"

using namespace rbbench;

namespace {

std::string utcNow() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::string versionString(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

nlohmann::json deviceJson(BenchEnv& env) {
  const rb::DeviceInfo& i = env.info();
  char vendor[16];
  std::snprintf(vendor, sizeof vendor, "0x%04x", i.vendorId);
  return {{"name", i.deviceName},
          {"driverName", i.driverName},
          {"driverInfo", i.driverInfo},
          {"vulkan", versionString(i.apiVersion)},
          {"vendorId", vendor},
          {"isCpu", i.isCpu},
          {"timestampPeriodNs", i.timestampPeriodNs},
          {"timestampValidBits", env.timestampValidBits()}};
}

int run(const BenchOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  BenchEnv env(options);
  const rb::DeviceInfo& info = env.info();
  std::printf("raybridge-bench on %s (%s %s, Vulkan %s)%s, trace resolution %ux%u%s\n", info.deviceName.c_str(),
              info.driverName.c_str(), info.driverInfo.c_str(), versionString(info.apiVersion).c_str(),
              info.isCpu ? " [CPU device: compare ratios, not absolute times]" : "", env.sizes().width,
              env.sizes().height,
              options.quick  ? " [--quick]"
              : options.full ? " [--full]"
                             : "");
  std::fflush(stdout);

  // "all" is every scenario but the soak and the memory sweep, which run only when named.
  auto wanted = [&](const std::string& name) {
    return options.scenario == name || (options.scenario == "all" && name != "soak" && name != "memory");
  };
  std::vector<GltfModel> models;
  std::vector<std::string> messages;
  if (wanted("build") || wanted("compaction")) {
    models = loadGltfModels(options.scenesDir, messages);
    for (const std::string& m : messages) std::printf("%s\n", m.c_str());
    if (!models.empty()) std::printf("glTF scenes: %zu models from %s\n", models.size(), options.scenesDir.c_str());
  }

  nlohmann::json doc;
  doc["tool"] = "raybridge-bench";
  doc["date"] = utcNow();
  doc["commandLine"] = options.commandLine;
  doc["device"] = deviceJson(env);
  doc["options"] = {{"scenario", options.scenario},   {"quick", options.quick},
                    {"full", options.full},           {"width", env.sizes().width},
                    {"height", env.sizes().height},   {"scenesDir", options.scenesDir},
                    {"imagesDir", options.imagesDir}, {"framesInFlight", env.ctx().framesInFlight()},
                    {"frames", options.frames},       {"seed", options.seed}};
  doc["gltfModels"] = nlohmann::json::array();
  for (const GltfModel& m : models) {
    doc["gltfModels"].push_back({{"name", m.name},
                                 {"meshes", m.meshes.size()},
                                 {"instances", m.instances.size()},
                                 {"uniqueTriangles", m.uniqueTriangles()}});
  }
  doc["messages"] = messages;
  doc["scenarios"] = nlohmann::json::object();
  doc["secondsPerScenario"] = nlohmann::json::object();

  struct Entry {
    const char* name;
    std::function<nlohmann::json()> fn;
  };
  const Entry entries[] = {
      {"build", [&] { return runBuildScenario(env, models); }},
      {"duplication", [&] { return runDuplicationScenario(env); }},
      {"fastbuild-vs-fasttrace", [&] { return runFastBuildScenario(env); }},
      {"compaction", [&] { return runCompactionScenario(env, models); }},
      {"tlas", [&] { return runTlasScenario(env); }},
      {"tlas-motion", [&] { return runTlasMotionScenario(env); }},
      {"trace", [&] { return runTraceScenario(env); }},
      {"gigarays", [&] { return runGigaRaysScenario(env); }},
      {"alpha", [&] { return runAlphaScenario(env); }},
      {"lights", [&] { return runLightsScenario(env); }},
      {"soak", [&] { return runSoakScenario(env); }},
      {"memory", [&] { return runMemoryScenario(env); }},
  };
  // A failing scenario is reported and the others still run (a GPU session is too costly to lose whole).
  std::vector<std::string> failures;
  for (const Entry& e : entries) {
    if (!wanted(e.name)) continue;
    const auto t0 = std::chrono::steady_clock::now();
    env.progress(std::string("scenario ") + e.name);
    try {
      doc["scenarios"][e.name] = e.fn();
      // A scenario that ran to the end but whose checks failed (the soak's leak checks) keeps its numbers.
      for (const auto& f : doc["scenarios"][e.name].value("failures", nlohmann::json::array())) {
        std::fprintf(stderr, "raybridge-bench: scenario %s failed: %s\n", e.name, f.get<std::string>().c_str());
        failures.push_back(std::string(e.name) + ": " + f.get<std::string>());
      }
    } catch (const BenchFailure& f) {
      std::fprintf(stderr, "raybridge-bench: scenario %s failed: %s\n", e.name, f.what());
      doc["scenarios"][e.name] = {{"error", f.what()}};
      failures.push_back(std::string(e.name) + ": " + f.what());
      check(env.device().waitIdle(), "vkDeviceWaitIdle after a failed scenario");
      env.settle();
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    doc["secondsPerScenario"][e.name] = s;
    env.progress(std::string("scenario ") + e.name + " done in " + std::to_string(s) + " s");
  }
  check(env.device().waitIdle(), "vkDeviceWaitIdle");

  const uint32_t errors = env.device().validationErrorCount();
  doc["failures"] = failures;
  doc["validation"] = {{"enabled", env.device().validationEnabled()},
                       {"errors", errors},
                       {"messages", env.device().validationErrors()}};
  doc["totalSeconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!options.outPath.empty()) {
    std::ofstream out(options.outPath);
    out << doc.dump(2) << "\n";
    if (!out) throw BenchFailure("could not write " + options.outPath);
    std::printf("\nwrote %s\n", options.outPath.c_str());
  }
  std::printf("total %.1f s\n", doc["totalSeconds"].get<double>());
  if (!failures.empty()) {
    std::fprintf(stderr, "raybridge-bench: %zu scenario(s) failed; first: %s\n", failures.size(),
                 failures.front().c_str());
    return 1;
  }
  if (env.device().validationEnabled() && errors > 0) {
    std::fprintf(stderr, "raybridge-bench: the validation layer reported %u error(s); first: %s\n", errors,
                 env.device().validationErrors().front().c_str());
    return 3;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  std::string error;
  if (!parseOptions(argc, argv, options, error)) {
    std::fprintf(stderr, "raybridge-bench: %s\n%s", error.c_str(), usage().c_str());
    return 2;
  }
  if (options.help) {
    std::printf("%s", usage().c_str());
    return 0;
  }
  try {
    return run(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "raybridge-bench: failed: %s\n", e.what());
    return 1;
  }
}

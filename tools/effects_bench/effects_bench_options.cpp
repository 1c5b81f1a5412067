// Command-line parsing of raybridge-effects-bench, through CLI11 (see the header and
// samples/common/cli_support.h).
#include "effects_bench_options.h"

#include <raybridge/hybrid_effects.h>

#include <vector>

#include "cli_support.h"

namespace rbEffects {

namespace {

// bit i = name i; local_lights: --scenario motion only (the other scenarios have no sweep for it)
const std::vector<std::string> kEffectNames = {"shadows", "ao", "reflections", "local_lights"};
static_assert(rb::kEffectShadows == 1 && rb::kEffectAo == 2 && rb::kEffectReflections == 4 &&
              rb::kEffectLocalLights == 8);
constexpr uint64_t kMaxReferenceRays = 1u << 20;

// "N" (every effect) or "shadows=N,ao=N,reflections=N" (any subset); "" or an error without the option name.
std::string parseReferenceRays(std::string_view text, Options* o) {
  if (text.find('=') == std::string_view::npos) {
    uint64_t all = 0;
    if (std::string e = rbCli::parseWholeNumber(text, 1, kMaxReferenceRays, all); !e.empty())
      return e + " (or EFFECT=N,...)";
    if (o) o->referenceRaysShadows = o->referenceRaysAo = o->referenceRaysReflections = uint32_t(all);
    return {};
  }
  while (!text.empty()) {
    const size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    const size_t eq = item.find('=');
    uint64_t n = 0;
    if (eq == std::string_view::npos || !rbCli::parseWholeNumber(item.substr(eq + 1), 1, kMaxReferenceRays, n).empty())
      return "bad item " + rbCli::quote(item) + " (want N or EFFECT=N,... with N in 1.." +
             std::to_string(kMaxReferenceRays) + ")";
    const std::string_view name = item.substr(0, eq);
    if (name == "shadows") {
      if (o) o->referenceRaysShadows = uint32_t(n);
    } else if (name == "ao") {
      if (o) o->referenceRaysAo = uint32_t(n);
    } else if (name == "reflections") {
      if (o) o->referenceRaysReflections = uint32_t(n);
    } else {
      return "unknown effect " + rbCli::quote(name) + " (shadows, ao, reflections)";
    }
  }
  return {};
}

void addOptions(CLI::App& app, Options& o) {
  rbCli::prepare(app);
  app.description(
      "For each effect: sweeps traced rays per pixel (raw and denoised) and the raster counterpart's\n"
      "resolution or kernel, times each setting with GPU timestamps (median of --frames frames) and measures\n"
      "its error (RMSE over surface pixels) against a converged reference traced by Raybridge.");
  app.footer("Defaults: 1920x1080 on a GPU, 320x180 on a CPU device; --quick: tiny size, few settings, and checks.");
  app.add_option("--scenario", o.scenario,
                 "what to measure: speed-vs-error (default); adaptive (uniform against adaptive rays for shadows "
                 "and ao, planned per pixel and per warp-sized tile, accumulated over frames); or motion (every "
                 "denoised effect, local_lights too, frame by frame while the camera and the scene move: error, "
                 "lag, flicker, disocclusion against a converged reference per frame)")
      ->type_name("NAME")
      ->check(rbCli::oneOf({"speed-vs-error", "adaptive", "motion"}));
  app.add_option("--characters", o.characters,
                 "motion: skinned characters walking in the walkers case (default 3; 0 = no walkers case)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(0, 64));
  app.add_option("--motion-rays", o.motionRays, "motion: rays per pixel of the denoised sequences (default 1 4 16)")
      ->type_name("N ...")
      ->check(rbCli::wholeNumber(1, 64));
  app.add_option("--motion-cases", o.motionCases,
                 "motion: the cases to run (default all: still pan turn walkers teleport lamp_jump door)")
      ->type_name("NAME ...")
      ->check(rbCli::oneOf(std::vector<std::string>(std::begin(kMotionCases), std::end(kMotionCases))));
  app.add_flag("--no-anti-lag", o.noAntiLag, "motion: denoisers without anti-lag (DenoiseSettings::disableAntiLag)");
  app.add_flag("--no-short-history-filter", o.noShortHistoryFilter,
               "motion: AO's denoiser without the short-history filter\n"
               "(AoEffectSettings::disableShortHistoryFilter)");
  app.add_flag("--no-reset-rays", o.noResetRays,
               "motion: soft shadows and AO trace their own rays where a change restarts the history\n"
               "(Shadow/AoEffectSettings::disableResetRays)");
  app.add_flag("--no-reflection-changes", o.noReflectionChanges,
               "motion: reflections do not restart where a ray hits a changed light's reach\n"
               "(ReflectionEffectSettings::disableRelitResets)");
  app.add_option("--reset-rays-factor", o.resetRaysFactor,
                 "motion: soft shadows and AO trace F x their rays where a change restarts the history\n"
                 "(RaySchedule::resetRays; default: rb::kDefaultResetRaysFactor)")
      ->type_name("F")
      ->check(rbCli::wholeNumber(2, 64));
  app.add_option("--reset-follow-up", o.resetFollowUp,
                 "motion: frames after a change that its pixels still trace the reset rays (0 = none;\n"
                 "HybridEffectsDesc::resetFollowUpFrames, default rb::kDefaultResetFollowUpFrames)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(0, rb::kMaxResetFollowUpFrames));
  app.add_flag(
      "--converged-tiles", o.convergedTiles,
      "motion: every effect skips its converged tiles (RaySchedule::convergedTiles), to measure their lag cost");
  app.add_flag("--no-change-resets", o.noChangeResets,
               "motion: no change resets (HybridEffectsDesc::disableChangeResets): the denoisers follow moved objects "
               "and lights by anti-lag alone");
  app.add_option("--scenes", o.scenes,
                 "motion: folder of the character glTF models (default ../shared/scenes beside the source tree)")
      ->type_name("DIR");
  app.add_option_function<std::string>(
         "--effects",
         [&o](const std::string& value) {
           rbCli::parseNameSet(value, kEffectNames, "an effect", o.effects);
           o.effectsGiven = true;
         },
         "effects to sweep, comma-separated (default shadows,ao,reflections; motion: also local_lights)")
      ->type_name("LIST")
      ->check(CLI::Validator(
          [](std::string& value) {
            uint32_t set = 0;
            std::string e = rbCli::parseNameSet(value, kEffectNames, "an effect", set);
            return !e.empty() ? e
                   : set == 0 ? std::string("no effect given (shadows, ao, reflections, local_lights)")
                              : std::string();
          },
          ""));
  app.add_option_function<uint32_t>(
         "--width", [&o](const uint32_t& v) { o.width = v; }, "image width, with --height (default: see below)")
      ->type_name("W")
      ->check(rbCli::wholeNumber(16, 16384));
  app.add_option_function<uint32_t>(
         "--height", [&o](const uint32_t& v) { o.height = v; }, "image height")
      ->type_name("H")
      ->check(rbCli::wholeNumber(16, 16384));
  app.add_option("--out", o.out, "JSON report (default: none)")->type_name("FILE.json");
  app.add_option("--images", o.images, "folder for the PNGs (FLIP input; default: none)")->type_name("DIR");
  app.add_option_function<std::string>(
         "--reference-rays", [&o](const std::string& value) { parseReferenceRays(value, &o); },
         "total rays per pixel of each effect's reference (default: chosen from the\n"
         "device and --quick)")
      ->type_name("N|shadows=N,ao=N,reflections=N")
      ->check(CLI::Validator([](std::string& value) { return parseReferenceRays(value, nullptr); }, ""));
  app.add_option("--raw-rate-json", o.rawRateJson, "raybridge-bench JSON with the gigarays scenario")
      ->type_name("BENCH.json");
  app.add_option_function<uint32_t>(
         "--frames", [&o](const uint32_t& v) { o.timedFrames = v; },
         "frames whose median is reported (default 7 on a GPU, 3 on a CPU)")
      ->type_name("N")
      ->check(rbCli::wholeNumber(1, 100000));
  app.add_option("--ao-range", o.aoRange, "world units: the traced AO range and the SSAO radius (default 1)")
      ->type_name("R")
      ->check(rbCli::realNumber(rbCli::above(0.0), rbCli::unbounded(), " (world units)"));
  app.add_option("--reflection-roughness", o.reflectionRoughness,
                 "traced reflections' threshold, 1 = every surface traces (default 1)")
      ->type_name("T")
      ->check(rbCli::realNumber(rbCli::above(0.0), rbCli::atMost(1.0)));
  app.add_flag("--quick", o.quick, "tiny size, few settings, and checks (a smoke run)");
  app.add_option("--device", o.device, "pick the Vulkan device whose name contains SUBSTR")->type_name("SUBSTR");
  app.add_flag("--validation", o.validation, "enable VK_LAYER_KHRONOS_validation (also RAYBRIDGE_VALIDATION=1)");
}

}  // namespace

const char* usage() {
  static const std::string help = [] {
    Options unused;
    CLI::App app{"", "raybridge-effects-bench"};
    addOptions(app, unused);
    return app.help();
  }();
  return help.c_str();
}

std::string parseOptions(int argc, char** argv, Options& o) {
  o.commandLine = rbCli::commandLine(argc, argv);
  CLI::App app{"", "raybridge-effects-bench"};
  addOptions(app, o);
  if (std::string e = rbCli::parse(app, argc, argv, o.help); !e.empty() || o.help) return e;
  if (o.width.has_value() != o.height.has_value()) return "--width and --height go together";
  if (o.scenario != "motion" && (o.effects & rb::kEffectLocalLights))
    return "--effects local_lights: only --scenario motion measures local lights; drop it or add --scenario motion";
  if (o.scenario == "motion" && !o.effectsGiven) o.effects = rb::kAllEffects;
  if (o.resetRaysFactor && o.noResetRays) return "--reset-rays-factor and --no-reset-rays: give one of them";
  if (o.resetFollowUp && o.noResetRays)
    return "--reset-follow-up: follow-ups trace the reset rays, which --no-reset-rays turns off; give one of them";
  return {};
}

}  // namespace rbEffects

// Shared machinery of the effect sweeps (see the header).
#include "sweep_common.h"

#include <algorithm>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <filesystem>

namespace rbEffects {

namespace se = sample_engine;

void progress(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::vprintf(format, args);
  va_end(args);
  std::printf("\n");
  std::fflush(stdout);
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double medianOf(const std::vector<FrameSample>& samples, const std::function<double(const FrameSample&)>& f) {
  std::vector<double> v;
  for (const FrameSample& s : samples) v.push_back(f(s));
  return median(v);
}

nlohmann::json engineMedians(const std::vector<FrameSample>& samples) {
  auto m = [&](double se::PassTimings::*field) {
    return medianOf(samples, [field](const FrameSample& s) { return s.engine.*field; });
  };
  return {{"shadow_map", m(&se::PassTimings::shadowMs)},
          {"probe", m(&se::PassTimings::probeMs)},
          {"prepass", m(&se::PassTimings::prepassMs)},
          {"ssao", m(&se::PassTimings::ssaoMs)},
          {"hook", m(&se::PassTimings::hookMs)},
          {"lighting", m(&se::PassTimings::lightingMs)},
          {"tonemap", m(&se::PassTimings::tonemapMs)},
          {"frame", medianOf(samples, [](const FrameSample& s) { return s.frameMs(); })}};
}

PassResult passMedian(const std::vector<FrameSample>& samples, const char* name,
                      rb::PassStats rb::HybridStats::*member) {
  PassResult p;
  p.name = name;
  p.gpuMs = medianOf(samples, [member](const FrameSample& s) { return (s.passes.*member).gpuMs; });
  p.rays = uint64_t(medianOf(samples, [member](const FrameSample& s) { return double((s.passes.*member).rays); }));
  return p;
}

se::Result<ReferenceImage> traceReference(FrameDriver& driver, const se::FrameParams& params, uint32_t frames,
                                          uint32_t channels, const Extract& extract,
                                          rb::PassStats rb::HybridStats::*counted, Reference& out) {
  using R = se::Result<ReferenceImage>;
  const auto start = std::chrono::steady_clock::now();
  // Two untimed frames first: BLAS builds, pass creation and pipeline compilation are not part of any sample.
  if (auto warm = driver.run(params, 2, 0); !warm) return R::failure(warm.error);
  Accumulator acc;
  ReferenceImage ref;
  out.frames = frames;
  out.raysCounted = 0;
  for (uint32_t f = 0; f < frames; ++f) {
    FrameSample sample;
    auto cap = driver.capture(params, &sample);
    if (!cap) return R::failure(cap.error);
    if (ref.mask.empty()) ref.mask = surfaceMask(cap.value.depth);
    auto values = extract(cap.value);
    if (!values) return R::failure(values.error);
    if (values.value.size() != ref.mask.size() * channels) return R::failure("reference: unexpected image size");
    acc.add(values.value);
    out.raysCounted += (sample.passes.*counted).rays;
    if (frames >= 8 && (f + 1) % std::max(1u, frames / 4) == 0) progress("  reference: %u/%u frames", f + 1, frames);
  }
  ref.values = acc.mean();
  out.halvesRmse = frames >= 2 ? compare(acc.halfMean(0), acc.halfMean(1), ref.mask, channels).rmse : 0.0;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return R::success(std::move(ref));
}

se::Result<std::string> writeImage(const SweepPlan& plan, const std::string& effect, const std::string& id,
                                   const std::function<se::Status(const std::string&)>& write) {
  using R = se::Result<std::string>;
  if (plan.imagesDir.empty()) return R::success("");
  const std::filesystem::path dir = std::filesystem::path(plan.imagesDir) / effect;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return R::failure("--images: cannot create '" + dir.string() + "': " + ec.message());
  const std::string relative = effect + "/" + id + ".png";
  if (se::Status s = write((dir / (id + ".png")).string()); !s) return R::failure(s.error);
  return R::success(relative);
}

void selfCheck(EffectResult& r) {
  const Row* fewest = nullptr;
  const Row* most = nullptr;
  for (const Row& row : r.rows) {
    if (row.method == "raster") continue;
    uint64_t rays = 0;
    for (const PassResult& p : row.passes) rays += p.rays;
    if (rays == 0) r.checkFailures.push_back("(b) traced row '" + row.method + " " + row.setting + "' counted no rays");
    if (row.method != "traced_raw") continue;
    const uint32_t n = row.params.value("rays_per_pixel", 0u);
    if (!fewest || n < fewest->params.value("rays_per_pixel", 0u)) fewest = &row;
    if (!most || n > most->params.value("rays_per_pixel", 0u)) most = &row;
  }
  char buf[256];
  if (fewest && most && fewest != most && !(most->rmse < fewest->rmse)) {
    std::snprintf(buf, sizeof buf, "(a) raw RMSE at %s (%.5f) is not below RMSE at %s (%.5f)", most->setting.c_str(),
                  most->rmse, fewest->setting.c_str(), fewest->rmse);
    r.checkFailures.push_back(buf);
  }
  if (most && !(r.reference.noiseRmse() < 0.5 * most->rmse)) {
    std::snprintf(buf, sizeof buf, "(c) reference noise %.5f (halves RMSE / 2) is not under half the RMSE of %s (%.5f)",
                  r.reference.noiseRmse(), most->setting.c_str(), most->rmse);
    r.checkFailures.push_back(buf);
  }
}

}  // namespace rbEffects

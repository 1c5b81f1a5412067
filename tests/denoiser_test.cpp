// The denoiser: 4-ray AO denoised beats raw 4-ray AO and is no worse than raw 16-ray AO against a converged
// reference; temporal accumulation with reprojection keeps improving while the camera moves.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

struct AoScene {
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  AoScene() { addToEmbree(embree, scene); }
};

SyntheticView viewAt(double shift) {
  SyntheticView v;
  v.eye = {-6.0 + shift, 3.5, 7.0};
  v.target = {0.0 + shift, 0.8, 0.0};
  v.fovYDegrees = 45.0;
  v.width = 96;
  v.height = 72;
  return v;
}

// Runs `frames` frames of AO (and the denoiser when `denoise`) over the views given, returns the last output.
std::vector<float> runFrames(GpuFixture& fx, const AoScene& s, const std::vector<CpuGBuffer>& views, uint32_t rays,
                             bool denoise, const rb::DenoiseSettings& dn = {}) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  BuiltScene built = buildScene(fx, *service.value(), s.scene);
  rb::AoSettings settings;
  settings.raysPerPixel = rays;
  settings.range = 2.0f;
  std::vector<float> out;
  for (const CpuGBuffer& cpu : views) {
    GpuGBuffer gbuffer(fx, cpu);
    rb::GBufferDesc desc = gbuffer.desc();
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto tlas = service.value()->recordTlasBuild(cmd, built.instances, gbuffer.cameraRelativeTlas());
      RB_REQUIRE_OK(tlas);
      RB_REQUIRE_OK(ao.value()->record(cmd, {.gbuffer = desc, .tlas = tlas.value(), .settings = settings}));
      if (denoise)
        RB_REQUIRE_OK(
            denoiser.value()->record(cmd, {.gbuffer = desc, .signal = ao.value()->outputs().aoView, .settings = dn}));
    });
    VkImage image = denoise ? denoiser.value()->outputs().denoised : ao.value()->outputs().ao;
    out = readR16f(fx, image, desc.width, desc.height);
  }
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
  return out;
}

double rmse(const std::vector<float>& a, const std::vector<float>& b, const CpuGBuffer& g) {
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!g.hit[i]) continue;
    sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    ++n;
  }
  return std::sqrt(sum / double(n));
}

}  // namespace

TEST_CASE("denoised 4-ray AO beats raw 4-ray AO and matches raw 16-ray AO", "[denoise][ao]") {
  GpuFixture fx;
  AoScene s;
  CpuGBuffer g = traceGBuffer(s.embree, viewAt(0.0));
  std::vector<float> reference = runFrames(fx, s, {g}, 2048, false);
  std::vector<float> raw4 = runFrames(fx, s, {g}, 4, false);
  std::vector<float> raw16 = runFrames(fx, s, {g}, 16, false);
  rb::DenoiseSettings spatialOnly;
  spatialOnly.disableTemporal = true;
  std::vector<float> denoised4 = runFrames(fx, s, {g}, 4, true, spatialOnly);
  double eRaw4 = rmse(raw4, reference, g), eRaw16 = rmse(raw16, reference, g),
         eDenoised = rmse(denoised4, reference, g);
  INFO("RMSE raw 4: " << eRaw4 << ", raw 16: " << eRaw16 << ", denoised 4 (one frame, spatial): " << eDenoised);
  CHECK(eDenoised < eRaw4);
  // Was eDenoised <= eRaw16 with the denoiser that blurred by 13x13 whatever its noise. The adaptive one moves a
  // pixel by at most one standard deviation of its noise (so it never made the effects bench's rows worse than
  // raw by much): measured on lavapipe, raw 4 0.1017, denoised 4 (one frame, unknown noise) 0.0950, raw 16 0.0324.
  CHECK(eDenoised < 0.97 * eRaw4);
  // The full denoiser (temporal + spatial) over four frames of a still camera does better still.
  std::vector<float> full = runFrames(fx, s, {g, g, g, g}, 4, true);
  double eFull = rmse(full, reference, g);
  INFO("full denoiser after 4 frames: " << eFull);
  CHECK(eFull < eDenoised);
}

TEST_CASE("temporal accumulation reprojects through camera motion", "[denoise][temporal]") {
  GpuFixture fx;
  AoScene s;
  // Eight frames while the camera pans sideways; the reference is the last frame's converged AO.
  std::vector<CpuGBuffer> views;
  for (int i = 0; i < 8; ++i) views.push_back(traceGBuffer(s.embree, viewAt(0.08 * i)));
  const CpuGBuffer& last = views.back();
  std::vector<float> reference = runFrames(fx, s, {last}, 2048, false);
  rb::DenoiseSettings temporalOnly;
  temporalOnly.disableSpatial = true;
  std::vector<float> accumulated = runFrames(fx, s, views, 4, true, temporalOnly);
  std::vector<float> oneFrame = runFrames(fx, s, {last}, 4, true, temporalOnly);  // nothing to accumulate yet
  double eAcc = rmse(accumulated, reference, last), eOne = rmse(oneFrame, reference, last);
  INFO("RMSE after 8 reprojected frames " << eAcc << ", after 1 frame " << eOne);
  // Eight frames of 4 rays behave like ~32 rays where the history survived: far below one frame's error.
  CHECK(eAcc < 0.6 * eOne);
  // A camera cut: a history that does not match is rejected, not smeared (the result equals one frame's).
  std::vector<CpuGBuffer> cut = {views.front(), traceGBuffer(s.embree, [] {
                                   SyntheticView v = viewAt(0.0);
                                   v.eye = {7.0, 3.0, -6.0};
                                   v.target = {0.0, 0.8, 0.0};
                                   return v;
                                 }())};
  std::vector<float> afterCut = runFrames(fx, s, cut, 4, true, temporalOnly);
  std::vector<float> cutReference = runFrames(fx, s, {cut.back()}, 2048, false);
  std::vector<float> cutOneFrame = runFrames(fx, s, {cut.back()}, 4, true, temporalOnly);
  double eCut = rmse(afterCut, cutReference, cut.back()), eCutOne = rmse(cutOneFrame, cutReference, cut.back());
  INFO("after a camera cut: " << eCut << " vs one fresh frame " << eCutOne);
  CHECK(eCut < 1.3 * eCutOne);
}

// The adaptive scalar denoiser on synthetic signals over a real G-buffer: a known truth per pixel, binary rays drawn
// from it on the CPU, so the error of raw and denoised is measured exactly.
namespace {

// Visibility-like truth: lit, a penumbra ramp, umbra, then a hard edge back to lit. Multiples of 1/1024, so a
// fraction of 1024 rays is one of them and every value is exact in half floats.
float shadowTruth(uint32_t x, uint32_t /*y*/) {
  float p = x < 30 ? 1.0f : x < 50 ? 1.0f - float(x - 30) / 20.0f : x < 70 ? 0.0f : 1.0f;
  return std::round(p * 1024.0f) / 1024.0f;
}

// AO-like truth: smooth, mostly open, darker towards the bottom and a dark blob.
float aoTruth(uint32_t x, uint32_t y) {
  double dx = double(x) - 60.0, dy = double(y) - 40.0;
  double p = 0.95 - 0.4 * double(y) / 72.0 - 0.5 * std::exp(-(dx * dx + dy * dy) / 120.0);
  return float(std::round(std::clamp(p, 0.0, 1.0) * 1024.0) / 1024.0);
}

// A fraction of `rays` binary rays per pixel, each hitting with the truth's probability.
std::vector<float> binaryRays(const std::function<float(uint32_t, uint32_t)>& truth, uint32_t w, uint32_t h,
                              uint32_t rays, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<float> out(size_t(w) * h);
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      std::binomial_distribution<uint32_t> draw(rays, truth(x, y));
      out[size_t(y) * w + x] = float(draw(rng)) / float(rays);
    }
  }
  return out;
}

std::vector<float> truthImage(const std::function<float(uint32_t, uint32_t)>& truth, uint32_t w, uint32_t h) {
  std::vector<float> out(size_t(w) * h);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) out[size_t(y) * w + x] = truth(x, y);
  return out;
}

// One frame of a fresh denoiser over `signal` (R32F, or RGBA32F for the RGB kinds); the output read back (R16F:
// one float per pixel, else four).
std::vector<float> denoiseOnce(GpuFixture& fx, const CpuGBuffer& cpu, const std::vector<float>& signal,
                               rb::DenoiseSignal kind, const rb::DenoiseSettings& settings) {
  const uint32_t w = cpu.view.width, h = cpu.view.height;
  const bool scalar = kind == rb::DenoiseSignal::Scalar;
  SampledImage input = uploadSampledImage(fx, scalar ? VK_FORMAT_R32_SFLOAT : VK_FORMAT_R32G32B32A32_SFLOAT,
                                          VK_IMAGE_ASPECT_COLOR_BIT, w, h, signal.data(), signal.size() * 4);
  std::vector<float> out;
  {
    GpuGBuffer gbuffer(fx, cpu);
    rb::DenoiserDesc dd;
    dd.signal = kind;
    auto denoiser = rb::Denoiser::create(fx.ctx(), dd);
    RB_REQUIRE_OK(denoiser);
    fx.runFrame([&](VkCommandBuffer cmd) {
      RB_REQUIRE_OK(
          denoiser.value()->record(cmd, {.gbuffer = gbuffer.desc(), .signal = input.view, .settings = settings}));
    });
    VkImage image = denoiser.value()->outputs().denoised;
    out = scalar ? readR16f(fx, image, w, h) : readRgba16f(fx, image, w, h);
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
  }
  destroySampledImage(fx, input);
  return out;
}

// The one-ray signal's error must fall at least this much. Measured on lavapipe (96x72, one frame): shadow 0.187 ->
// 0.143 (x0.76), AO 0.465 -> 0.339 (x0.73); the denoiser before this one left one-ray signals as they were (its
// binomial noise, c (1 - c) / 1 at c = 0 or 1, was 0).
constexpr double kOneRayGain = 0.85;
// A glossy reflection's error (roughness 0.5, noise 50% of the colour) must fall at least this much. Measured on
// lavapipe: 0.245 -> 0.071 (x0.29).
constexpr double kGlossyGain = 0.5;

rb::DenoiseSettings oneFrame(uint32_t rays) {
  rb::DenoiseSettings s;
  s.disableTemporal = true;  // one frame, no history: the spatial filter alone
  s.raysPerPixel = rays;
  return s;
}

}  // namespace

TEST_CASE("a converged scalar signal passes the denoiser bit for bit", "[denoise][adaptive]") {
  GpuFixture fx;
  AoScene s;
  CpuGBuffer g = traceGBuffer(s.embree, viewAt(0.0));
  const uint32_t w = g.view.width, h = g.view.height;
  // 1024 rays: the binomial noise is at most 0.5 / 32 = 0.016, under kDefaultDenoiseConvergedNoise; the hard edge
  // at x = 70 and the penumbra stay as they are, exactly.
  std::vector<float> in = binaryRays(shadowTruth, w, h, 1024, 7);
  std::vector<float> out = denoiseOnce(fx, g, in, rb::DenoiseSignal::Scalar, oneFrame(1024));
  size_t changed = 0;
  for (size_t i = 0; i < in.size(); ++i) changed += out[i] != in[i];
  CHECK(changed == 0);
  // With history too (the full default denoiser, first frame).
  rb::DenoiseSettings full;
  full.raysPerPixel = 1024;
  out = denoiseOnce(fx, g, in, rb::DenoiseSignal::Scalar, full);
  changed = 0;
  for (size_t i = 0; i < in.size(); ++i) changed += out[i] != in[i];
  CHECK(changed == 0);
  // A noisy signal is changed (the test would pass for a denoiser that does nothing otherwise).
  std::vector<float> noisy = binaryRays(shadowTruth, w, h, 4, 8);
  out = denoiseOnce(fx, g, noisy, rb::DenoiseSignal::Scalar, oneFrame(4));
  changed = 0;
  for (size_t i = 0; i < in.size(); ++i) changed += out[i] != noisy[i];
  CHECK(changed > in.size() / 20);
}

TEST_CASE("the denoiser filters a one-ray signal and never raises the error", "[denoise][adaptive]") {
  GpuFixture fx;
  AoScene s;
  CpuGBuffer g = traceGBuffer(s.embree, viewAt(0.0));
  const uint32_t w = g.view.width, h = g.view.height;
  struct Case {
    const char* name;
    std::function<float(uint32_t, uint32_t)> truth;
  };
  for (const Case& c : {Case{"shadow", shadowTruth}, Case{"ao", aoTruth}}) {
    const std::vector<float> truth = truthImage(c.truth, w, h);
    for (uint32_t rays : {1u, 2u, 4u, 8u, 16u, 32u}) {
      std::vector<float> raw = binaryRays(c.truth, w, h, rays, 100 + rays);
      std::vector<float> out = denoiseOnce(fx, g, raw, rb::DenoiseSignal::Scalar, oneFrame(rays));
      for (float v : out) REQUIRE(std::isfinite(v));
      const double eRaw = rmse(raw, truth, g), eOut = rmse(out, truth, g);
      std::printf("[denoise][adaptive] %s, %u rays, one frame: RMSE raw %.4f, denoised %.4f\n", c.name, rays, eRaw,
                  eOut);
      INFO(c.name << ", " << rays << " rays: RMSE raw " << eRaw << ", denoised " << eOut);
      CHECK(eOut <= eRaw);
      if (rays == 1) CHECK(eOut < kOneRayGain * eRaw);
    }
  }
}

TEST_CASE("a noise-free RGB signal passes the a-trous steps bit for bit, a noisy one is filtered",
          "[denoise][adaptive]") {
  // The a-trous steps skip a pixel whose taps all carry no noise (denoise_rgb_atrous.comp); the filter would move
  // a curved colour ramp's pixels by up to ~0.1% (the colour floor, 1 ulp here), so an exact pass shows that the
  // skip happened, and the noisy case that it does not happen where the filter has work to do.
  GpuFixture fx;
  AoScene s;
  const SyntheticView view = viewAt(0.0);
  const uint32_t w = view.width, h = view.height;
  const size_t n = s.scene.instances.size();
  // Quadratic ramps in steps of one half-float ulp (the output's format: passing means equal), restarting every 16
  // pixels: the neighbours differ by about the floor's tolerance, and unevenly, so the filter would move them.
  auto colour = [](uint32_t x, uint32_t y) {
    return glm::vec3(1.0f + float((x % 16) * (x % 16)) / 1024.0f, 0.5f + float((y % 16) * (y % 16)) / 2048.0f, 0.25f);
  };
  auto signal = [&](float noise) {
    std::mt19937 rng(5);
    std::normal_distribution<float> gauss(0.0f, noise);
    std::vector<float> out(size_t(w) * h * 4);
    for (uint32_t y = 0; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) {
        glm::vec3 c = colour(x, y);
        float* px = &out[(size_t(y) * w + x) * 4];
        for (int k = 0; k < 3; ++k) px[k] = noise > 0.0f ? std::max(c[k] + gauss(rng) * c[k], 0.0f) : c[k];
        px[3] = 1.0f;
      }
    }
    return out;
  };
  auto changedPixels = [&](const std::vector<float>& in, const std::vector<float>& out, const CpuGBuffer& g) {
    size_t changed = 0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      if (!g.hit[i]) continue;
      bool same = true;
      for (int k = 0; k < 3; ++k) same = same && out[i * 4 + k] == in[i * 4 + k];
      changed += !same;
    }
    return changed;
  };
  size_t surface = 0;
  const CpuGBuffer glossy = traceGBuffer(s.embree, view, std::vector<float>(n, 0.5f));
  for (size_t i = 0; i < size_t(w) * h; ++i) surface += glossy.hit[i];
  REQUIRE(surface > size_t(w) * h / 4);
  rb::DenoiseSettings oneFrameRgb;
  oneFrameRgb.disableTemporal = true;
  // A mirror (roughness 0): the temporal pass gives it no noise.
  const CpuGBuffer mirror = traceGBuffer(s.embree, view, std::vector<float>(n, 0.0f));
  const std::vector<float> clean = signal(0.0f);
  std::vector<float> out = denoiseOnce(fx, mirror, clean, rb::DenoiseSignal::Reflection, oneFrameRgb);
  CHECK(changedPixels(clean, out, mirror) == 0);
  // With the default settings too (the first frame: no history yet).
  out = denoiseOnce(fx, mirror, clean, rb::DenoiseSignal::Reflection, {});
  CHECK(changedPixels(clean, out, mirror) == 0);
  // A glossy reflection and an RGB signal with noise of 30% of the colour: most pixels are filtered.
  const std::vector<float> noisy = signal(0.3f);
  for (rb::DenoiseSignal kind : {rb::DenoiseSignal::Rgb, rb::DenoiseSignal::Reflection}) {
    out = denoiseOnce(fx, glossy, noisy, kind, oneFrameRgb);
    const size_t changed = changedPixels(noisy, out, glossy);
    INFO("signal " << uint32_t(kind) << ": " << changed << " of " << surface << " noisy pixels changed");
    CHECK(changed > surface / 2);
  }
}

TEST_CASE("reflections: mirrors keep their edges, glossy noise is filtered, uncovered pixels pass",
          "[denoise][adaptive]") {
  GpuFixture fx;
  AoScene s;
  const SyntheticView view = viewAt(0.0);
  const uint32_t w = view.width, h = view.height;
  const size_t n = s.scene.instances.size();
  // Colour stripes with sharp edges (what a mirror reflects), and a smooth colour (a rough reflection's mean).
  auto stripes = [](uint32_t x, uint32_t) {
    return (x / 6) % 2 ? glm::vec3(1.8f, 0.2f, 0.1f) : glm::vec3(0.1f, 0.3f, 1.2f);
  };
  auto smooth = [](uint32_t x, uint32_t y) {
    return glm::vec3(0.6f, 0.5f, 0.4f) * (1.0f + 0.3f * std::sin(0.1f * float(x) + 0.05f * float(y)));
  };
  const uint32_t uncoveredRows = 8;  // rougher than the pass's threshold: nothing traced, coverage 0
  auto signal = [&](const std::function<glm::vec3(uint32_t, uint32_t)>& colour, float noise) {
    std::mt19937 rng(11);
    std::normal_distribution<float> gauss(0.0f, noise);
    std::vector<float> out(size_t(w) * h * 4);
    for (uint32_t y = 0; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) {
        glm::vec3 c = colour(x, y);
        float* px = &out[(size_t(y) * w + x) * 4];
        for (int k = 0; k < 3; ++k) px[k] = std::max(c[k] + (noise > 0.0f ? gauss(rng) * c[k] : 0.0f), 0.0f);
        px[3] = y < uncoveredRows ? 0.0f : 1.0f;
      }
    }
    return out;
  };
  auto rgbError = [&](const std::vector<float>& a, const std::function<glm::vec3(uint32_t, uint32_t)>& truth,
                      const CpuGBuffer& g) {
    double sum = 0.0;
    size_t count = 0;
    for (uint32_t y = uncoveredRows; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) {
        size_t i = size_t(y) * w + x;
        if (!g.hit[i]) continue;
        glm::vec3 t = truth(x, y);
        for (int k = 0; k < 3; ++k) sum += (double(a[i * 4 + k]) - t[k]) * (double(a[i * 4 + k]) - t[k]);
        count += 3;
      }
    }
    return std::sqrt(sum / double(count));
  };
  rb::DenoiseSettings oneFrameRgb;
  oneFrameRgb.disableTemporal = true;

  SECTION("mirror") {
    CpuGBuffer g = traceGBuffer(s.embree, view, std::vector<float>(n, 0.0f));
    std::vector<float> in = signal(stripes, 0.0f);
    std::vector<float> out = denoiseOnce(fx, g, in, rb::DenoiseSignal::Reflection, oneFrameRgb);
    double worst = 0.0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      for (int k = 0; k < 4; ++k) REQUIRE(std::isfinite(out[i * 4 + k]));
      if (!g.hit[i] || i < size_t(uncoveredRows) * w) continue;
      for (int k = 0; k < 3; ++k)
        worst = std::max(worst, std::fabs(double(out[i * 4 + k]) - in[i * 4 + k]) / double(in[i * 4 + k]));
    }
    INFO("largest relative change of a mirror pixel: " << worst);
    CHECK(worst < 2e-3);  // half-float rounding only: the stripes' edges are kept
  }
  SECTION("glossy") {
    CpuGBuffer g = traceGBuffer(s.embree, view, std::vector<float>(n, 0.5f));
    std::vector<float> in = signal(smooth, 0.5f);
    std::vector<float> out = denoiseOnce(fx, g, in, rb::DenoiseSignal::Reflection, oneFrameRgb);
    for (float v : out) REQUIRE(std::isfinite(v));
    const double eRaw = rgbError(in, smooth, g), eOut = rgbError(out, smooth, g);
    std::printf("[denoise][adaptive] glossy reflection (roughness 0.5), one frame: RMSE raw %.4f, denoised %.4f\n",
                eRaw, eOut);
    INFO("RMSE raw " << eRaw << ", denoised " << eOut);
    CHECK(eOut < kGlossyGain * eRaw);
    // Coverage is kept: 0 where nothing was traced (the value passes as it is), 1 elsewhere. (The sky is never
    // covered: ReflectionPass traces no ray there.)
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      if (!g.hit[i]) continue;
      const bool covered = i >= size_t(uncoveredRows) * w;
      REQUIRE(out[i * 4 + 3] == (covered ? 1.0f : 0.0f));
      if (!covered) REQUIRE(std::fabs(out[i * 4] - in[i * 4]) <= 2e-3f * in[i * 4] + 1e-6f);
    }
  }
  SECTION("a reflection needs roughness in the G-buffer") {
    CpuGBuffer g = traceGBuffer(s.embree, view);
    GpuGBuffer gbuffer(fx, g);
    rb::GBufferDesc desc = gbuffer.desc();
    desc.roughnessInNormalW = false;
    rb::DenoiserDesc dd;
    dd.signal = rb::DenoiseSignal::Reflection;
    auto denoiser = rb::Denoiser::create(fx.ctx(), dd);
    RB_REQUIRE_OK(denoiser);
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::Status st = denoiser.value()->record(cmd, {.gbuffer = desc, .signal = desc.normal.view});
      REQUIRE(!st);
      CHECK(st.error().message.find("roughness") != std::string::npos);
    });
  }
}

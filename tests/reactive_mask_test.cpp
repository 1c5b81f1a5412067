// GBufferDesc::reactiveMask: the engine's per-pixel "this changed" for what the SDK cannot see. The denoiser drops
// the history of exactly the masked pixels, and the readers of its history agree with it.
#include <catch2/catch_test_macros.hpp>

#include <glm/gtc/packing.hpp>

#include <cstring>
#include <memory>
#include <utility>

#include "raybridge_shader_interface.glsl"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

constexpr uint32_t kW = 40, kH = 30;

bool masked(uint32_t x, uint32_t y) { return x >= 10 && x < 22 && y >= 8 && y < 17; }

// The conformance scene's G-buffer with an R8 reactive mask over masked() uploaded, an AO pass and a denoiser.
struct MaskedScene {
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  CpuGBuffer cpu;
  SampledImage mask{};
  SampledImage followUpMask{};  // the follow-up level (RB_REACTIVE_FOLLOW_UP_VALUE) over the same pixels
  std::unique_ptr<rb::AoPass> ao;
  std::unique_ptr<rb::Denoiser> denoiser;
  GpuFixture& fx;
  explicit MaskedScene(GpuFixture& f) : fx(f) {
    addToEmbree(embree, scene);
    cpu = traceGBuffer(embree, conformanceView(kW, kH));
    std::vector<uint8_t> maskBytes(size_t(kW) * kH, 0);
    for (uint32_t y = 0; y < kH; ++y)
      for (uint32_t x = 0; x < kW; ++x) maskBytes[size_t(y) * kW + x] = masked(x, y) ? 255 : 0;
    mask = uploadSampledImage(fx, VK_FORMAT_R8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, kW, kH, maskBytes.data(),
                              maskBytes.size());
    for (uint8_t& b : maskBytes) b = b ? uint8_t(RB_REACTIVE_FOLLOW_UP_VALUE * 255.0 + 0.5) : 0;
    followUpMask = uploadSampledImage(fx, VK_FORMAT_R8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, kW, kH, maskBytes.data(),
                                      maskBytes.size());
    auto a = rb::AoPass::create(fx.ctx());
    RB_REQUIRE_OK(a);
    ao = std::move(a.value());
    auto d = rb::Denoiser::create(fx.ctx());
    RB_REQUIRE_OK(d);
    denoiser = std::move(d.value());
  }
  ~MaskedScene() {
    destroySampledImage(fx, mask);
    destroySampledImage(fx, followUpMask);
  }
  // The masked and other surface pixels.
  std::pair<size_t, size_t> surfaceCounts() const {
    size_t m = 0, o = 0;
    for (uint32_t y = 0; y < kH; ++y)
      for (uint32_t x = 0; x < kW; ++x)
        if (cpu.hit[size_t(y) * kW + x]) (masked(x, y) ? m : o)++;
    return {m, o};
  }
};

}  // namespace

TEST_CASE("a reactive mask drops the history of exactly the masked pixels", "[denoise][reactive]") {
  GpuFixture fx;
  MaskedScene m(fx);
  const CpuGBuffer& cpu = m.cpu;

  auto frame = [&](bool withMask) {
    runPassFrame(
        fx, m.scene, cpu, false,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
          rb::GBufferDesc gbuffer = g;
          if (withMask) gbuffer.reactiveMask = {m.mask.view};
          RB_REQUIRE_OK(m.ao->record(cmd, {.gbuffer = gbuffer, .tlas = tlas}));
          RB_REQUIRE_OK(m.denoiser->record(cmd, {.gbuffer = gbuffer, .signal = m.ao->outputs().aoView}));
        },
        [](const rb::GBufferDesc&) {});
  };
  for (int i = 0; i < 4; ++i) frame(false);
  const std::vector<float> before = historyFrames(fx, *m.denoiser);
  frame(true);
  const std::vector<float> after = historyFrames(fx, *m.denoiser);

  size_t maskedSurface = 0, otherSurface = 0, wrong = 0;
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (!cpu.hit[i]) continue;
      const bool isMasked = masked(x, y);
      (isMasked ? maskedSurface : otherSurface)++;
      // A masked pixel starts afresh (one frame); every other surface pixel keeps its history and adds this frame.
      const float expected = isMasked ? 1.0f : before[i] + 1.0f;
      if (after[i] != expected) {
        if (wrong++ < 5)
          UNSCOPED_INFO("pixel " << x << "," << y << (isMasked ? " (masked)" : "") << ": " << after[i]
                                 << " frames, expected " << expected);
      }
    }
  INFO(maskedSurface << " masked and " << otherSurface << " other surface pixels");
  REQUIRE(maskedSurface > 20);
  REQUIRE(otherSurface > 100);
  for (size_t i = 0; i < before.size(); ++i)
    if (cpu.hit[i]) REQUIRE(before[i] == 4.0f);  // the history had grown before the mask
  CHECK(wrong == 0);
}

TEST_CASE("reset rays trace RaySchedule::resetRays in exactly the masked pixels, counted as that many frames",
          "[denoise][reactive][schedule]") {
  GpuFixture fx;
  MaskedScene m(fx);
  const CpuGBuffer& cpu = m.cpu;
  constexpr uint32_t kRays = 2, kResetRays = 8, kResetFrames = kResetRays / kRays;
  rb::PassStats stats;
  auto frame = [&](bool withMask, bool followUp = false) {
    runPassFrame(
        fx, m.scene, cpu, false,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
          rb::GBufferDesc gbuffer = g;
          if (withMask) gbuffer.reactiveMask = {m.mask.view};
          if (followUp) gbuffer.reactiveMask = {m.followUpMask.view};
          rb::AoSettings a;
          a.raysPerPixel = kRays;
          a.schedule.resetRays = kResetRays;
          RB_REQUIRE_OK(m.ao->record(cmd, {.gbuffer = gbuffer, .tlas = tlas, .settings = a}));
          rb::DenoiseSettings d;
          d.raysPerPixel = kRays;
          d.resetFrames = kResetFrames;
          RB_REQUIRE_OK(m.denoiser->record(cmd, {.gbuffer = gbuffer, .signal = m.ao->outputs().aoView, .settings = d}));
        },
        [](const rb::GBufferDesc&) {});
    stats = m.ao->stats();
  };
  for (int i = 0; i < 3; ++i) frame(false);
  const std::vector<float> before = historyFrames(fx, *m.denoiser);
  const auto [maskedSurface, otherSurface] = m.surfaceCounts();
  REQUIRE(maskedSurface > 20);
  REQUIRE(otherSurface > 100);
  // Without a mask nothing restarts: every surface pixel traces its own rays.
  CHECK(stats.rays == uint64_t(maskedSurface + otherSurface) * kRays);
  frame(true);
  // With it, exactly the masked surface pixels trace the reset rays (sky traces nothing either way).
  CHECK(stats.rays == uint64_t(otherSurface) * kRays + uint64_t(maskedSurface) * kResetRays);
  const std::vector<float> after = historyFrames(fx, *m.denoiser);
  size_t wrong = 0;
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (!cpu.hit[i]) continue;
      // A masked pixel restarts at resetRays / raysPerPixel frames; every other one adds this frame to its history.
      const float expected = masked(x, y) ? float(kResetFrames) : before[i] + 1.0f;
      if (after[i] != expected && wrong++ < 5)
        UNSCOPED_INFO("pixel " << x << "," << y << ": " << after[i] << " frames, expected " << expected);
    }
  CHECK(wrong == 0);
  // The next frame without a mask adds one frame to the restarted pixels' kResetFrames.
  frame(false);
  const std::vector<float> next = historyFrames(fx, *m.denoiser);
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (cpu.hit[i] && masked(x, y) && next[i] != float(kResetFrames + 1) && wrong++ < 5)
        UNSCOPED_INFO("pixel " << x << "," << y << ": " << next[i] << " frames the frame after");
    }
  CHECK(wrong == 0);
  // A follow-up (the mask at RB_REACTIVE_FOLLOW_UP_VALUE): the masked pixels trace the reset rays again and keep
  // their history, which grows by kResetFrames; the others add one frame.
  frame(false, true);
  CHECK(stats.rays == uint64_t(otherSurface) * kRays + uint64_t(maskedSurface) * kResetRays);
  const std::vector<float> followed = historyFrames(fx, *m.denoiser);
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const size_t i = size_t(y) * kW + x;
      if (!cpu.hit[i]) continue;
      const float expected = next[i] + (masked(x, y) ? float(kResetFrames) : 1.0f);
      if (followed[i] != expected && wrong++ < 5)
        UNSCOPED_INFO("pixel " << x << "," << y << ": " << followed[i] << " frames after a follow-up, expected "
                               << expected);
    }
  CHECK(wrong == 0);
}

TEST_CASE("a reactive mask in a layout that cannot be sampled is refused by name", "[denoise][reactive][errors]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(16, 12));
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        rb::GBufferDesc gbuffer = g;
        gbuffer.reactiveMask = {g.normal.view, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
        for (const rb::Status& st : {ao.value()->record(cmd, {.gbuffer = gbuffer, .tlas = tlas}),
                                     denoiser.value()->record(cmd, {.gbuffer = gbuffer, .signal = g.normal.view})}) {
          REQUIRE_FALSE(st);
          INFO(st.error().message);
          CHECK(st.error().message.find("reactiveMask") != std::string::npos);
        }
      },
      [](const rb::GBufferDesc&) {});
}

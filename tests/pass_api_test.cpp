// The shape every pass shares: create(Context&, const XDesc& = {}) with a size that creates the images at once,
// record(cmd, const XFrame&) refusing a malformed frame by name, and the history a Denoiser hands out.
#include <catch2/catch_test_macros.hpp>

#include <cstring>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

bool contains(const rb::Status& st, const std::string& text) {
  if (st) return false;
  const bool found = st.error().message.find(text) != std::string::npos;
  if (!found) UNSCOPED_INFO("message: " << st.error().message);
  return found;
}

template <typename Created>
bool refusedWith(const Created& created, const std::string& text) {
  if (created) return false;
  const bool found = created.error().message.find(text) != std::string::npos;
  if (!found) UNSCOPED_INFO("message: " << created.error().message);
  return found && created.error().code == rb::ErrorCode::InvalidArgument;
}

}  // namespace

TEST_CASE("a pass description's size creates the output images at create()", "[api]") {
  GpuFixture fx;
  rb::Context& ctx = fx.ctx();
  const VkDeviceSize before = ctx.memoryStats().bytes[size_t(rb::MemoryCategory::PassImages)];

  auto shadow = rb::ShadowPass::create(ctx, {.width = 20, .height = 12});
  RB_REQUIRE_OK(shadow);
  CHECK(shadow.value()->outputs().visibilityView != VK_NULL_HANDLE);
  CHECK(shadow.value()->outputs().width == 20);
  auto ao = rb::AoPass::create(ctx, {.width = 20, .height = 12});
  RB_REQUIRE_OK(ao);
  CHECK(ao.value()->outputs().aoView != VK_NULL_HANDLE);
  CHECK(ao.value()->outputs().height == 12);
  auto lights = rb::ManyLightPass::create(ctx, {.width = 20, .height = 12});
  RB_REQUIRE_OK(lights);
  CHECK(lights.value()->outputs().irradianceView != VK_NULL_HANDLE);
  auto reflection = rb::ReflectionPass::create(ctx, {.width = 20, .height = 12});
  RB_REQUIRE_OK(reflection);
  CHECK(reflection.value()->outputs().radianceView != VK_NULL_HANDLE);
  auto shading = rb::PrimaryShadingPass::create(ctx, {.width = 20, .height = 12});
  RB_REQUIRE_OK(shading);
  CHECK(shading.value()->outputs().radianceView != VK_NULL_HANDLE);
  CHECK(shading.value()->outputs().distanceView != VK_NULL_HANDLE);
  auto denoiser = rb::Denoiser::create(ctx, {.signal = rb::DenoiseSignal::Rgb, .width = 20, .height = 12});
  RB_REQUIRE_OK(denoiser);
  CHECK(denoiser.value()->outputs().denoisedView != VK_NULL_HANDLE);
  CHECK(ctx.memoryStats().bytes[size_t(rb::MemoryCategory::PassImages)] > before);

  // Zero-initialised: nothing until the first record().
  auto lazy = rb::AoPass::create(ctx);
  RB_REQUIRE_OK(lazy);
  CHECK(lazy.value()->outputs().aoView == VK_NULL_HANDLE);

  // One of the two: refused by name, whichever pass.
  CHECK(refusedWith(rb::ShadowPass::create(ctx, {.width = 20}), "ShadowPassDesc: width 20 and height 0"));
  CHECK(refusedWith(rb::AoPass::create(ctx, {.height = 7}), "AoPassDesc: width 0 and height 7"));
  CHECK(refusedWith(rb::ManyLightPass::create(ctx, {.width = 3}), "ManyLightPassDesc"));
  CHECK(refusedWith(rb::ReflectionPass::create(ctx, {.width = 3}), "ReflectionPassDesc"));
  CHECK(refusedWith(rb::PrimaryShadingPass::create(ctx, {.height = 3}), "PrimaryShadingPassDesc"));
  CHECK(refusedWith(rb::Denoiser::create(ctx, {.width = 3}), "DenoiserDesc"));
}

TEST_CASE("PrimaryRayPassDesc::opaqueOnly traces what the default pass traces, without a material table", "[api]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, *service.value(), scene);
  const uint32_t W = 48, H = 32;

  const rb::MemoryStats beforeDefault = fx.ctx().memoryStats();
  auto withAlpha = rb::PrimaryRayPass::create(fx.ctx());
  RB_REQUIRE_OK(withAlpha);
  const rb::MemoryStats beforeOpaque = fx.ctx().memoryStats();
  auto opaque = rb::PrimaryRayPass::create(fx.ctx(), {.opaqueOnly = true});
  RB_REQUIRE_OK(opaque);
  const rb::MemoryStats after = fx.ctx().memoryStats();
  // The default pass holds a fallback material table; the opaque-only one holds none of it.
  CHECK(after.total() - beforeOpaque.total() < beforeOpaque.total() - beforeDefault.total());
  CHECK(after.allocations - beforeOpaque.allocations < beforeOpaque.allocations - beforeDefault.allocations);

  auto materials = rb::MaterialTable::create(fx.ctx());
  RB_REQUIRE_OK(materials);
  rb::GpuImage dist[2] = {fx.makeImage(W, H, VK_FORMAT_R32_SFLOAT), fx.makeImage(W, H, VK_FORMAT_R32_SFLOAT)};
  rb::GpuImage ids[2] = {fx.makeImage(W, H, VK_FORMAT_R32G32_UINT), fx.makeImage(W, H, VK_FORMAT_R32G32_UINT)};
  const rb::TlasInfo tlas{.tlas = built.tlas.tlas};
  fx.runFrame([&](VkCommandBuffer cmd) {
    for (int i = 0; i < 2; ++i) {
      fx.toGeneral(cmd, dist[i]);
      fx.toGeneral(cmd, ids[i]);
    }
    rb::PrimaryRayPass* passes[2] = {withAlpha.value().get(), opaque.value().get()};
    for (int i = 0; i < 2; ++i) {
      RB_REQUIRE_OK(passes[i]->record(
          cmd, {.tlas = tlas, .camera = conformanceCamera(), .targets = {dist[i].view, ids[i].view, W, H}}));
    }
    CHECK(
        contains(opaque.value()->record(cmd, {.tlas = tlas,
                                              .camera = conformanceCamera(),
                                              .targets = {dist[1].view, ids[1].view, W, H},
                                              .settings = {.materials = materials.value().get()}}),
                 "PrimaryRaySettings::materials is set, but the pass was created with PrimaryRayPassDesc::opaqueOnly"));
  });
  std::vector<uint8_t> d0 = fx.readImage(dist[0], 4), d1 = fx.readImage(dist[1], 4);
  std::vector<uint8_t> i0 = fx.readImage(ids[0], 8), i1 = fx.readImage(ids[1], 8);
  CHECK(d0 == d1);
  CHECK(i0 == i1);
  size_t hits = 0;
  for (size_t p = 0; p < size_t(W) * H; ++p) {
    float t;
    std::memcpy(&t, d0.data() + 4 * p, 4);
    hits += t > 0.0f ? 1 : 0;
  }
  CHECK(hits > size_t(W) * H / 4);  // the comparison is over a scene the camera sees
  for (int i = 0; i < 2; ++i) {
    fx.destroyImage(dist[i]);
    fx.destroyImage(ids[i]);
  }
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
}

TEST_CASE("a malformed frame is refused by name", "[api]") {
  GpuFixture fx;
  auto lights = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(lights);
  auto list = rb::LightList::create(fx.ctx());
  RB_REQUIRE_OK(list);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  auto shadow = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  const rb::LightSource one[1] = {rb::LightSource{}};
  fx.runFrame([&](VkCommandBuffer cmd) {
    CHECK(contains(lights.value()->record(cmd, {.lightList = list.value().get(), .lights = one}),
                   "ManyLightFrame has both lightList and 1 lights; give one of them"));
    CHECK(contains(denoiser.value()->record(cmd, {}), "DenoiseFrame::signal is VK_NULL_HANDLE"));
    // A zero-initialised frame: the G-buffer is the first thing named.
    const rb::Status st = shadow.value()->record(cmd, {});
    CHECK_FALSE(st);
    CHECK(st.error().code == rb::ErrorCode::InvalidArgument);
  });
}

TEST_CASE("a Denoiser's history is what its latest record() left", "[api][denoise]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(40, 30));
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  CHECK(denoiser.value()->history().mean == VK_NULL_HANDLE);
  CHECK_FALSE(denoiser.value()->history().valid);

  rb::GBufferDesc traced{};
  for (int frame = 0; frame < 2; ++frame) {
    runPassFrame(
        fx, scene, cpu, false,
        [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
          RB_REQUIRE_OK(ao.value()->record(cmd, {.gbuffer = g, .tlas = tlas}));
          RB_REQUIRE_OK(denoiser.value()->record(cmd, {.gbuffer = g, .signal = ao.value()->outputs().aoView}));
          traced = g;
        },
        [](const rb::GBufferDesc&) {});
  }
  const rb::DenoiseHistory h = denoiser.value()->history();
  CHECK(h.mean != VK_NULL_HANDLE);
  CHECK(h.distance != VK_NULL_HANDLE);
  CHECK(h.noise != VK_NULL_HANDLE);  // a Scalar denoiser's
  CHECK(h.sampler != VK_NULL_HANDLE);
  CHECK(h.width == 40);
  CHECK(h.height == 30);
  CHECK(h.valid);
  for (int i = 0; i < 3; ++i) CHECK(h.cameraPosition[i] == traced.cameraPosition[i]);
  // The ping-pong: the next record() writes the other image, and history() follows it.
  const VkImageView first = h.mean;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(ao.value()->record(cmd, {.gbuffer = g, .tlas = tlas}));
        RB_REQUIRE_OK(denoiser.value()->record(cmd, {.gbuffer = g, .signal = ao.value()->outputs().aoView}));
      },
      [](const rb::GBufferDesc&) {});
  CHECK(denoiser.value()->history().mean != first);
  denoiser.value()->resetHistory();
  CHECK_FALSE(denoiser.value()->history().valid);
}

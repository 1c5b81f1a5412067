#include "effects_rig.h"

#include "test_support.h"

namespace rbtest {

EffectsRig::EffectsRig(GpuFixture& fx, uint32_t width, uint32_t height, float roughness) : fx_(fx) {
  const TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const std::vector<float> perInstance(scene.instances.size(), roughness);
  const CpuGBuffer cpu = traceGBuffer(embree, motionTestView(width, height), perInstance);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  service_ = std::move(service.value());
  built_ = buildScene(fx, *service_, scene);
  gbuffer_ = std::make_unique<GpuGBuffer>(fx, cpu);
}

EffectsRig::~EffectsRig() {
  (void)fx_.device().waitIdle();
  destroyScene(fx_, built_);
}

void EffectsRig::record(rb::HybridEffects& effects, std::span<const rb::LightSource> lights) {
  RB_REQUIRE_OK(recordEdited(effects, [&](rb::HybridFrame& f) { f.localLights = lights; }));
}

rb::Status EffectsRig::recordEdited(rb::HybridEffects& effects, const std::function<void(rb::HybridFrame&)>& edit) {
  rb::Status st;
  fx_.runFrame([&](VkCommandBuffer cmd) {
    rb::HybridFrame f;
    f.gbuffer = gbuffer_->desc();
    f.instances = built_.instances;
    f.light.angularRadiusDegrees = 1.0f;
    edit(f);
    st = effects.record(cmd, f);
  });
  return st;
}

std::vector<rb::LightSource> lampRow(size_t count) {
  std::vector<rb::LightSource> lights(count);
  for (size_t i = 0; i < count; ++i) {
    lights[i].light.type = rb::LightType::Point;
    lights[i].light.position[0] = count == 2 ? (i == 0 ? -1.0 : 1.5) : -1.5 + 0.5 * double(i);
    lights[i].light.position[1] = 1.5;
    lights[i].light.range = 6.0f;
    lights[i].intensity = 4.0f;
  }
  return lights;
}

}  // namespace rbtest

// Headless frame driving for the effects bench (see the header).
#include "frame_driver.h"

#include "sample_engine/procedural.h"

namespace rbEffects {

namespace se = sample_engine;

se::Result<std::unique_ptr<FrameDriver>> FrameDriver::create(const Config& config) {
  using R = se::Result<std::unique_ptr<FrameDriver>>;
  std::unique_ptr<FrameDriver> d(new FrameDriver());
  // The same device for raster and traced rows (Raybridge's extensions enabled), so both compare like for like.
  se::EngineConfig ec;
  ec.enableValidation = config.validation;
  ec.deviceNameFilter = config.device;
  ec.applicationName = "raybridge-effects-bench";
  rbAdapter::configureEngine(ec, d->features_);
  auto engine = se::Engine::create(ec);
  if (!engine) return R::failure("engine: " + engine.error);
  d->engine_ = std::move(engine.value);
  se::Engine& e = *d->engine_;
  if (se::Status s = e.loadScene(config.scene ? *config.scene : se::makeDefaultDemoScene()); !s)
    return R::failure("loadScene: " + s.error);
  if (config.width && config.height) {
    if (se::Status s = e.setRenderSize(config.width, config.height); !s) return R::failure(s.error);
  }
  d->base_.camera = e.scene().camera ? *e.scene().camera : se::defaultCameraFor(e.sceneBounds());
  if (e.scene().sun) d->base_.sun = *e.scene().sun;
  d->base_.sun.direction = glm::normalize(d->base_.sun.direction);

  auto adapter = rbAdapter::Adapter::create(e, {});
  if (!adapter) return R::failure("adapter: " + adapter.error);
  d->adapter_ = std::move(adapter.value);
  auto capture = rbRender::FrameCapture::create(e);
  if (!capture) return R::failure(capture.error);
  d->capture_ = std::move(capture.value);

  FrameDriver* self = d.get();
  e.setPrepassHook([self](const se::PrepassHookInfo& info, se::LightingInputs& inputs) {
    self->adapter_->recordFrame(info, inputs);
    if (!self->captureNext_) return;
    self->captureNext_ = false;
    const rb::HybridOutputs& fo = self->adapter_->effects().outputs();
    // An effect that is off names a 1x1 neutral image: nothing to capture.
    const rb::EffectSet on = self->adapter_->effects().desc().effects;
    auto of = [&](rb::EffectSet effect, const rb::EffectImage& e) { return (on & effect) ? e.image : VK_NULL_HANDLE; };
    const std::vector<rbRender::CaptureImage> images = {
        {"shadow_raw", of(rb::kEffectShadows, fo.shadowRaw), 1},
        {"shadow", of(rb::kEffectShadows, fo.shadow), 1},
        {"ao_raw", of(rb::kEffectAo, fo.aoRaw), 1},
        {"ao", of(rb::kEffectAo, fo.ao), 1},
        {"reflection_raw", of(rb::kEffectReflections, fo.reflectionRaw), 4},
        {"reflection", of(rb::kEffectReflections, fo.reflection), 4},
        {"lights_raw", of(rb::kEffectLocalLights, fo.localLightsRaw), 4},
        {"lights", of(rb::kEffectLocalLights, fo.localLights), 4}};
    if (se::Status s = self->capture_->record(info, info.normalRoughness, images); !s) self->captureError_ = s.error;
  });
  return R::success(std::move(d));
}

FrameDriver::~FrameDriver() {
  if (engine_) {
    (void)engine_->waitIdle();
    engine_->setPrepassHook({});
  }
  adapter_.reset();  // before the engine: it releases SDK objects on the engine's device
  capture_.reset();
}

se::Status FrameDriver::setRenderSize(uint32_t width, uint32_t height) { return engine_->setRenderSize(width, height); }

se::Status FrameDriver::finishFrame(FrameSample* sample) {
  if (se::Status s = engine_->waitIdle(); !s) return s;
  // The device is idle: the SDK may read every timestamp and ray counter recorded so far.
  adapter_->context().releaseAfterIdle();
  if (!adapter_->lastError().empty()) return se::Status::failure("Raybridge: " + adapter_->lastError());
  if (sample) {
    sample->engine = engine_->lastTimings();
    sample->passes = adapter_->effects().stats();
  }
  return se::Status::success();
}

se::Result<std::vector<FrameSample>> FrameDriver::run(const se::FrameParams& params, uint32_t warmup, uint32_t timed,
                                                      const std::function<void(uint32_t, se::FrameParams&)>& vary) {
  using R = se::Result<std::vector<FrameSample>>;
  for (uint32_t i = 0; i < warmup; ++i) {
    if (se::Status s = engine_->renderFrame(params); !s) return R::failure(s.error);
  }
  if (warmup) {
    if (se::Status s = finishFrame(nullptr); !s) return R::failure(s.error);
  }
  std::vector<FrameSample> samples(timed);
  for (uint32_t i = 0; i < timed; ++i) {
    se::FrameParams p = params;
    if (vary) vary(i, p);
    if (se::Status s = engine_->renderFrame(p); !s) return R::failure(s.error);
    if (se::Status s = finishFrame(&samples[i]); !s) return R::failure(s.error);
  }
  return R::success(std::move(samples));
}

se::Result<rbRender::CapturedFrame> FrameDriver::capture(const se::FrameParams& params, FrameSample* sample) {
  using R = se::Result<rbRender::CapturedFrame>;
  captureNext_ = true;
  captureError_.clear();
  if (se::Status s = engine_->renderFrame(params); !s) return R::failure(s.error);
  if (se::Status s = finishFrame(sample); !s) return R::failure(s.error);
  if (captureNext_) return R::failure("the capture frame did not run the pre-pass hook");
  if (!captureError_.empty()) return R::failure(captureError_);
  return R::success(capture_->read());
}

}  // namespace rbEffects

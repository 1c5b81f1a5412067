// The sample engine plus the Raybridge adapter on one device, driven headless one frame at a time: timed frames
// (GPU timestamps of the engine's passes and of the SDK's passes, read after each frame) and capture frames
// (the pre-pass depth and the adapter's effect images copied to the host, plus the engine's readbacks).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "frame_capture.h"
#include "raybridge_sample_engine_adapter.h"
#include "sample_engine/engine.h"

namespace rbEffects {

// One timed frame: the engine's pass timings and the adapter's pass statistics of that same frame.
struct FrameSample {
  sample_engine::PassTimings engine;
  rb::HybridStats passes;
  // Engine passes of a steady-state frame: the optional shadow-visibility output and the one-time probe
  // capture are left out (the first is a readback aid, the second is reported on its own).
  double frameMs() const {
    return engine.shadowMs + engine.prepassMs + engine.ssaoMs + engine.hookMs + engine.lightingMs + engine.tonemapMs;
  }
};

class FrameDriver {
 public:
  struct Config {
    uint32_t width = 0, height = 0;  // 0 = decided by the caller after create() (see setRenderSize)
    std::string device;
    bool validation = false;
    // The scene to load; empty = the default demo scene (makeDefaultDemoScene).
    std::optional<sample_engine::Scene> scene;
  };
  // Creates the engine on a device with Raybridge's features, loads the default demo scene, creates the adapter
  // (shadows at first) and installs the hook. Never throws.
  static sample_engine::Result<std::unique_ptr<FrameDriver>> create(const Config& config);
  ~FrameDriver();

  sample_engine::Engine& engine() { return *engine_; }
  rbAdapter::Adapter& adapter() { return *adapter_; }
  // The scene's camera and sun, engine defaults otherwise.
  const sample_engine::FrameParams& baseParams() const { return base_; }
  sample_engine::Status setRenderSize(uint32_t width, uint32_t height);

  // Renders `warmup` untimed frames, then `timed` frames, waiting after each so that its timestamps and pass
  // statistics are resolved. `vary` may change the parameters of each timed frame (e.g. to force a probe capture).
  sample_engine::Result<std::vector<FrameSample>> run(
      const sample_engine::FrameParams& params, uint32_t warmup, uint32_t timed,
      const std::function<void(uint32_t, sample_engine::FrameParams&)>& vary = {});
  // Renders one frame that also copies the depth and the adapter's effect images (named "shadow_raw",
  // "shadow", "ao_raw", "ao", "reflection_raw", "reflection", "lights_raw", "lights"; absent where the frame had
  // none) to the host. The engine's
  // readbacks (readbackHdr, readbackShadowVisibility, readbackSsao) refer to this frame afterwards.
  // `sample` receives the frame's statistics when given.
  sample_engine::Result<rbRender::CapturedFrame> capture(const sample_engine::FrameParams& params,
                                                         FrameSample* sample = nullptr);

 private:
  FrameDriver() = default;
  sample_engine::Status finishFrame(FrameSample* sample);

  rb::RequiredFeatures features_;  // must outlive Engine::create()
  std::unique_ptr<sample_engine::Engine> engine_;
  std::unique_ptr<rbAdapter::Adapter> adapter_;
  std::unique_ptr<rbRender::FrameCapture> capture_;
  sample_engine::FrameParams base_;
  bool captureNext_ = false;
  std::string captureError_;
};

}  // namespace rbEffects

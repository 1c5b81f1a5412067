// Failure injection (issue 12, item 5), the engine's side, through EngineConfig's test hooks for the frame loop's
// vkQueueSubmit2 and vkWaitForFences. VK_ERROR_DEVICE_LOST from the submit or from the fence wait is an error of
// renderFrame() that names it, not an abort or a hang; every later call says the device is lost without touching
// the GPU, and the engine is destroyed cleanly. A submit that fails without losing the device (out of memory) costs
// that frame only: the next frames render. The device is not really lost here, so the validation layer has nothing
// to report.
#include <atomic>
#include <string>

#include <catch2/catch_test_macros.hpp>

#include "engine_test_support.h"
#include "sample_engine/engine.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;

namespace {

// When set, the hook returns VK_ERROR_DEVICE_LOST; otherwise it forwards to the loader. Counted either way.
std::atomic<bool> loseSubmit{false}, loseWait{false};
std::atomic<bool> submitOutOfMemoryOnce{false};  // the next submit returns VK_ERROR_OUT_OF_HOST_MEMORY
std::atomic<uint32_t> submits{0}, waits{0};

VKAPI_ATTR VkResult VKAPI_CALL injectedSubmit(VkQueue queue, uint32_t count, const VkSubmitInfo2* submitInfos,
                                              VkFence fence) {
  ++submits;
  if (loseSubmit) return VK_ERROR_DEVICE_LOST;
  if (submitOutOfMemoryOnce.exchange(false)) return VK_ERROR_OUT_OF_HOST_MEMORY;
  return vkQueueSubmit2(queue, count, submitInfos, fence);
}

VKAPI_ATTR VkResult VKAPI_CALL injectedWait(VkDevice device, uint32_t count, const VkFence* fences, VkBool32 all,
                                            uint64_t timeout) {
  ++waits;
  if (loseWait) return VK_ERROR_DEVICE_LOST;
  return vkWaitForFences(device, count, fences, all, timeout);
}

std::unique_ptr<Engine> injectedEngine() {
  loseSubmit = loseWait = submitOutOfMemoryOnce = false;
  submits = waits = 0;
  EngineConfig config;
  config.queueSubmit2 = &injectedSubmit;
  config.waitForFences = &injectedWait;
  auto engine = test_support::makeEngine(config);
  REQUIRE(engine->loadScene(makeDefaultDemoScene()).ok());
  REQUIRE(engine->setRenderSize(64, 48).ok());
  return engine;
}

FrameParams paramsFor(const Engine& engine) {
  FrameParams p;
  p.camera = engine.scene().camera ? *engine.scene().camera : defaultCameraFor(engine.sceneBounds());
  p.shadow.mapSize = 1024;
  return p;
}

// After the loss: the next frame, the wait and the readback fail at once, saying so, without a submit.
void checkEverythingReportsTheLoss(Engine& engine, const FrameParams& params) {
  loseSubmit = loseWait = false;  // the device still works: the engine must not try it again all the same
  const uint32_t submitted = submits, waited = waits;
  const Status frame = engine.renderFrame(params);
  REQUIRE_FALSE(frame.ok());
  INFO(frame.error);
  CHECK(frame.error.find("renderFrame") != std::string::npos);
  CHECK(frame.error.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  const Status idle = engine.waitIdle();
  CHECK_FALSE(idle.ok());
  CHECK(idle.error.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  const auto ldr = engine.readbackLdr();
  CHECK_FALSE(ldr.ok());
  CHECK(ldr.error.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  CHECK(submits == submitted);
  CHECK(waits == waited);
  CHECK(engine.validationErrorCount() == 0);
}

}  // namespace

TEST_CASE("a device lost at the frame's submit is reported by renderFrame, and the engine still shuts down",
          "[inject][device-lost]") {
  auto engine = injectedEngine();
  const FrameParams params = paramsFor(*engine);
  REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(submits > 0);

  loseSubmit = true;
  const Status s = engine->renderFrame(params);
  REQUIRE_FALSE(s.ok());
  INFO(s.error);
  CHECK(s.error.find("vkQueueSubmit2") != std::string::npos);
  CHECK(s.error.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  CHECK(s.error.find("device lost") != std::string::npos);
  checkEverythingReportsTheLoss(*engine, params);
  engine.reset();  // waits for the device (idle: the failed frame was never submitted) and destroys everything
}

TEST_CASE("a device lost at the frame slot's fence wait is reported by renderFrame, and the engine still shuts down",
          "[inject][device-lost]") {
  auto engine = injectedEngine();
  const FrameParams params = paramsFor(*engine);
  // Both frame slots in flight; the third frame waits for the first slot's fence.
  REQUIRE(engine->renderFrame(params).ok());
  REQUIRE(engine->renderFrame(params).ok());

  loseWait = true;
  const uint32_t waited = waits;
  const Status s = engine->renderFrame(params);
  REQUIRE_FALSE(s.ok());
  INFO(s.error);
  CHECK(waits == waited + 1);
  CHECK(s.error.find("vkWaitForFences") != std::string::npos);
  CHECK(s.error.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  CHECK(s.error.find("device lost") != std::string::npos);
  checkEverythingReportsTheLoss(*engine, params);
  engine.reset();
}

TEST_CASE("a frame whose submit fails without losing the device is reported, and the next frames render", "[inject]") {
  auto engine = injectedEngine();
  const FrameParams params = paramsFor(*engine);
  REQUIRE(engine->renderFrame(params).ok());
  submitOutOfMemoryOnce = true;
  const Status s = engine->renderFrame(params);
  REQUIRE_FALSE(s.ok());
  INFO(s.error);
  CHECK(s.error.find("vkQueueSubmit2") != std::string::npos);
  CHECK(s.error.find("VK_ERROR_OUT_OF_HOST_MEMORY") != std::string::npos);
  // The failed frame's slot comes round again: its fence was reset but never submitted, so waiting for it would
  // never return.
  for (int frame = 0; frame < 3; ++frame) {
    const Status next = engine->renderFrame(params);
    INFO(next.error);
    REQUIRE(next.ok());
  }
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->readbackLdr().ok());
  CHECK(engine->validationErrorCount() == 0);
}

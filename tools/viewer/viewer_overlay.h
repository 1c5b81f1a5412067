// Dear ImGui in the viewer: ImGui's GLFW platform backend on the window, its Vulkan renderer backend on the
// engine's overlay hook (Engine::setOverlayHook), drawing into the tonemapped frame. Knows neither Raybridge
// nor the adapter; viewer_panel.h fills the UI.
//
//   auto overlay = ImGuiOverlay::create(glfwWindow).value;
//   engine.setOverlayHook(overlay->hook());
//   each frame: overlay->beginFrame(); ...ImGui widgets...; overlay->endFrame(); engine.renderFrame(params);
//   a frame without beginFrame()/endFrame() draws no UI (hidden overlay)
//   at the end: engine.setOverlayHook({}); engine.waitIdle(); overlay.reset();
//
// The Vulkan backend starts on the hook's first call, from what the hook passes (device, queue, render pass,
// frames in flight); the font atlas is uploaded in that frame's command buffer (no queue submit or wait of its
// own) and the upload buffer is freed once that frame has finished.
//
// Thread safety: one ImGui context per process, used from the thread that renders.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "sample_engine/engine.h"

struct GLFWwindow;

namespace rbViewer {

class ImGuiOverlay {
 public:
  // The ImGui context (no imgui.ini written) and the GLFW backend; the window's own callbacks keep working
  // (the backend chains them).
  static sample_engine::Result<std::unique_ptr<ImGuiOverlay>> create(GLFWwindow* window);
  // Requires the engine's GPU work to be done (Engine::waitIdle) and the hook removed.
  ~ImGuiOverlay();
  ImGuiOverlay(const ImGuiOverlay&) = delete;
  ImGuiOverlay& operator=(const ImGuiOverlay&) = delete;

  // Starts (ImGui::NewFrame) and finishes (ImGui::Render) the UI of the next rendered frame.
  void beginFrame();
  void endFrame();

  // Records the UI of the latest endFrame() into the frame; nothing when no UI was built since the last frame.
  sample_engine::OverlayHook hook();

  // The UI takes the mouse / keyboard this frame (the viewer's camera controls should ignore them).
  bool wantsMouse() const;
  bool wantsKeyboard() const;
  // The first error of the Vulkan backend ("" = none); the UI is not drawn after one.
  const std::string& lastError() const;

  struct Impl;

 private:
  explicit ImGuiOverlay(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbViewer

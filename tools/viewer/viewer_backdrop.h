// The viewer's backdrop: one image drawn over the whole tonemapped frame on the engine's overlay hook, under the
// ImGui overlay (the inspect views of viewer_inspect.h). Knows neither Raybridge nor ImGui. Its own pipeline and
// shaders (shaders/backdrop.*), because the Vulkan backend of Debian's Dear ImGui 1.86 draws no texture but its
// font atlas: it has no ImGui_ImplVulkan_AddTexture.
//
//   Backdrop backdrop;
//   engine.setOverlayHook([&](const OverlayHookInfo& info) { backdrop.record(info, imageOfThisFrame()); ui(info); });
//   at the end: engine.setOverlayHook({}); engine.waitIdle(); then destroy the backdrop.
//
// Per frame it only rewrites the descriptor set of the frame slot it records into (one set per frame in flight:
// the frame that last used a slot has finished when the hook runs for it), so it creates and destroys nothing
// while running and any view may be shown, one that changes every frame (a ping-ponged history) too.
//
// Thread safety: used from the thread that renders, like the engine's hooks.
#pragma once

#include <memory>
#include <string>

#include "sample_engine/engine.h"

namespace rbViewer {

// Which part of the image the backdrop shows.
enum class BackdropChannel : int32_t { Rgb = -1, Red = 0, Green = 1, Blue = 2, Alpha = 3 };

// One frame's backdrop. A default one draws nothing.
struct BackdropImage {
  // 2D colour view, SHADER_READ_ONLY_OPTIMAL with its writes visible to fragment shaders when the hook runs; it
  // must stay valid until this frame has finished. Sampled nearest, with normalized coordinates, so an image of
  // another size than the frame is stretched over it. VK_NULL_HANDLE = no backdrop.
  VkImageView view = VK_NULL_HANDLE;
  BackdropChannel channel = BackdropChannel::Rgb;  // Rgb = as it is, else that channel as grey; alpha is ignored
  float scale = 1.0f;        // multiplies the value (1 / the largest value maps that value to white)
  bool compressHdr = false;  // true = then v / (1 + v) per channel, for HDR images (as raybridge-render's lights.png)
};

class Backdrop {
 public:
  Backdrop();
  // Requires the GPU work of every frame it recorded to be done (Engine::waitIdle) and the hook removed.
  ~Backdrop();
  Backdrop(const Backdrop&) = delete;
  Backdrop& operator=(const Backdrop&) = delete;

  // Draws `image` over info's whole target in a render pass of its own (info.renderPass: the frame's colour is
  // overwritten), followed by a barrier that makes its writes visible to the next colour attachment user (the UI).
  // Records nothing for an image without a view. The Vulkan objects are made on the first draw.
  void record(const sample_engine::OverlayHookInfo& info, const BackdropImage& image);

  // The first error ("" = none); nothing is drawn after one.
  const std::string& lastError() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbViewer

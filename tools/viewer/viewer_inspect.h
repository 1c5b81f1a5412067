// The viewer's inspect views: one effect of rb::HybridEffects shown over the whole window instead of the lit frame,
// raw (the pass's output), denoised, as the length of its denoiser's history, or as the mask of the pixels a known
// change restarted. Says which image and how to show
// it (a BackdropImage, viewer_backdrop.h); the panel and --inspect choose, the overlay hook draws it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <raybridge/raybridge.h>

#include "viewer_backdrop.h"

namespace rbViewer {

enum class InspectEffect : uint32_t { Shadows, Ao, Reflections, LocalLights };
inline constexpr uint32_t kInspectEffectCount = 4;

enum class InspectView : uint32_t {
  LitFrame,  // the engine's frame: nothing inspected
  Raw,       // HybridOutputs::shadowRaw, aoRaw, reflectionRaw, localLightsRaw
  Denoised,  // HybridOutputs::shadow, ao, reflection, localLights (the raw image where no denoiser runs)
  // Frames the denoiser's history has accumulated (DenoiseHistory::mean's frames channel), 0 black to
  // maxHistoryFrames white in linear light: a pixel whose history was dropped this frame (anti-lag, disocclusion,
  // the reactive mask) holds 1 frame, dark grey (1/32 of white by default).
  HistoryLength,
  // The front end's change mask for the effect this frame (HybridEffects::changeMask): white where a known change (a
  // moved, deformed, appeared or vanished instance, a changed light, the engine's reactive mask) restarted the
  // history, black elsewhere; all black on a frame without a known change.
  ChangeMask,
};
inline constexpr uint32_t kInspectViewCount = 5;

struct Inspect {
  InspectEffect effect = InspectEffect::Shadows;
  InspectView view = InspectView::LitFrame;
};

// Names as --inspect spells them: shadows, ao, reflections, lights; lit, raw, denoised, history, changes.
const char* toString(InspectEffect effect);
const char* toString(InspectView view);
const char* label(InspectView view);  // as the panel shows it ("history length")
rb::EffectBits effectBit(InspectEffect effect);
// "EFFECT:VIEW" (ao:history), or just "lit"; nullopt for anything else.
std::optional<Inspect> parseInspect(std::string_view text);
std::string inspectNames();  // the accepted spellings, for --help and error messages

// What to draw this frame, read from the front end's latest record() (call it from the overlay hook, after the
// effects were recorded, to show this frame's images) and why it is not what was asked for ("" = it is).
struct InspectImage {
  BackdropImage image;  // no view = the lit frame
  std::string note;
};
// `hybrid`: the adapter records the effects (FrameSettings::enabled); in raster mode nothing is inspected.
InspectImage inspectImage(const rb::HybridEffects& fx, bool hybrid, const Inspect& inspect);

}  // namespace rbViewer

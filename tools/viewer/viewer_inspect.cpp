// The viewer's inspect views: see viewer_inspect.h.
#include "viewer_inspect.h"

namespace rbViewer {

namespace {

// What the front end holds for one effect.
struct EffectImages {
  const rb::EffectImage& raw;
  const rb::EffectImage& denoised;
  const rb::Denoiser* denoiser;  // nullptr where none runs
  bool rgb;                      // RGBA16F radiance / irradiance (HDR) rather than a scalar in .r
};

EffectImages imagesOf(const rb::HybridEffects& fx, InspectEffect effect) {
  const rb::HybridOutputs& o = fx.outputs();
  switch (effect) {
    case InspectEffect::Shadows: return {o.shadowRaw, o.shadow, fx.shadowDenoiser(), false};
    case InspectEffect::Ao: return {o.aoRaw, o.ao, fx.aoDenoiser(), false};
    case InspectEffect::Reflections: return {o.reflectionRaw, o.reflection, fx.reflectionDenoiser(), true};
    case InspectEffect::LocalLights: break;
  }
  return {o.localLightsRaw, o.localLights, fx.localLightDenoiser(), true};
}

BackdropImage showSignal(const rb::EffectImage& image, bool rgb) {
  BackdropImage b;
  b.view = image.view;
  b.channel = rgb ? BackdropChannel::Rgb : BackdropChannel::Red;
  b.compressHdr = rgb;
  return b;
}

}  // namespace

const char* toString(InspectEffect effect) {
  switch (effect) {
    case InspectEffect::Shadows: return "shadows";
    case InspectEffect::Ao: return "ao";
    case InspectEffect::Reflections: return "reflections";
    case InspectEffect::LocalLights: break;
  }
  return "lights";
}

const char* toString(InspectView view) {
  switch (view) {
    case InspectView::LitFrame: return "lit";
    case InspectView::Raw: return "raw";
    case InspectView::Denoised: return "denoised";
    case InspectView::HistoryLength: return "history";
    case InspectView::ChangeMask: break;
  }
  return "changes";
}

const char* label(InspectView view) {
  switch (view) {
    case InspectView::LitFrame: return "lit frame";
    case InspectView::HistoryLength: return "history length";
    case InspectView::ChangeMask: return "change mask";
    default: return toString(view);
  }
}

rb::EffectBits effectBit(InspectEffect effect) {
  switch (effect) {
    case InspectEffect::Shadows: return rb::kEffectShadows;
    case InspectEffect::Ao: return rb::kEffectAo;
    case InspectEffect::Reflections: return rb::kEffectReflections;
    case InspectEffect::LocalLights: break;
  }
  return rb::kEffectLocalLights;
}

std::optional<Inspect> parseInspect(std::string_view text) {
  if (text == toString(InspectView::LitFrame)) return Inspect{};
  const size_t colon = text.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  Inspect inspect;
  bool effectFound = false, viewFound = false;
  for (uint32_t i = 0; i < kInspectEffectCount; ++i)
    if (text.substr(0, colon) == toString(InspectEffect(i))) inspect.effect = InspectEffect(i), effectFound = true;
  for (uint32_t i = 0; i < kInspectViewCount; ++i)
    if (text.substr(colon + 1) == toString(InspectView(i))) inspect.view = InspectView(i), viewFound = true;
  if (!effectFound || !viewFound) return std::nullopt;
  return inspect;
}

std::string inspectNames() {
  std::string names = "EFFECT:VIEW, EFFECT one of ";
  for (uint32_t i = 0; i < kInspectEffectCount; ++i) names.append(i ? "|" : "").append(toString(InspectEffect(i)));
  names += ", VIEW one of ";
  for (uint32_t i = 0; i < kInspectViewCount; ++i) names.append(i ? "|" : "").append(toString(InspectView(i)));
  return names + ", or lit";
}

InspectImage inspectImage(const rb::HybridEffects& fx, bool hybrid, const Inspect& inspect) {
  InspectImage r;
  if (inspect.view == InspectView::LitFrame) return r;
  // Raster mode records no effect: the images would hold an older frame.
  if (!hybrid) return r.note = "raster mode: Raybridge's effects are not recorded", r;
  if (!(fx.desc().effects & effectBit(inspect.effect)))
    return r.note = std::string(toString(inspect.effect)) + " is off", r;
  const EffectImages images = imagesOf(fx, inspect.effect);
  switch (inspect.view) {
    case InspectView::LitFrame: break;
    case InspectView::Raw: r.image = showSignal(images.raw, images.rgb); break;
    case InspectView::Denoised:
      r.image = showSignal(images.denoised, images.rgb);
      if (!images.denoiser) r.note = "no denoiser runs: this is the raw image";
      break;
    case InspectView::HistoryLength: {
      if (!images.denoiser) return r.note = "no denoiser runs: no history", r;
      const rb::DenoiseHistory h = images.denoiser->history();
      if (!h.mean || !h.width) return r.note = "no history recorded yet", r;
      const uint32_t maxFrames = fx.desc().denoiser.maxHistoryFrames ? fx.desc().denoiser.maxHistoryFrames
                                                                     : rb::kDefaultMaxHistoryFrames;
      r.image.view = h.mean;
      // Scalar history: RG16F (mean, frames); RGB and reflection history: RGBA16F (mean colour, frames).
      r.image.channel = images.denoiser->signal() == rb::DenoiseSignal::Scalar ? BackdropChannel::Green
                                                                               : BackdropChannel::Alpha;
      r.image.scale = 1.0f / float(maxFrames);
      r.note = h.valid ? "black 0 frames, white " + std::to_string(maxFrames)
                       : "history not valid (reset, or temporal filtering off)";
      break;
    }
    case InspectView::ChangeMask: {
      if (!images.denoiser) return r.note = "no denoiser runs: no history to restart", r;
      if (fx.desc().disableChangeResets) return r.note = "change resets are off (HybridEffectsDesc)", r;
      const rb::EffectImage mask = fx.changeMask(effectBit(inspect.effect));
      // A frame without a known change writes no mask: nothing restarted but by anti-lag and disocclusion.
      if (!mask.view) return r.note = "no known change this frame", r;
      r.image.view = mask.view;
      r.image.channel = BackdropChannel::Red;
      r.note = "white: restarted by a known change";
      break;
    }
  }
  return r;
}

}  // namespace rbViewer

// Denoising for ray-traced signals: single-channel ones (shadow visibility, AO) and RGB HDR ones (the
// many-light irradiance of ManyLightPass), chosen by DenoiserDesc::signal. Temporal accumulation with
// reprojection (camera motion, or the engine's motion vectors when GBufferDesc::motionVectors is given),
// followed by an edge-aware a-trous spatial filter guided by depth and normals. Each signal needs its own
// Denoiser (it keeps that signal's history). The raw input is left untouched, so raw and denoised are both
// available.
//
// RGB signals (SVGF-style, Schied et al. 2017): the temporal pass reprojects bilinearly and keeps, beside the
// mean colour, the running variance of one frame's colour (from the 3x3 windows around the pixel while the
// history is shorter than 4 frames); the a-trous steps (3x3 taps, 5 by default) stop at colour differences larger
// than the remaining noise of the mean, so a converged or noise-free signal passes nearly unchanged, and filter
// in the signal's own domain (no albedo demodulation: ManyLightPass's irradiance has none). One temporal and
// DenoiseSettings::spatialIterations a-trous dispatches; 56 bytes of images per pixel (197 MiB at 2560x1440).
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipelines, history and
// output images and measurement objects are handed to the Context's deferred release (see context.h) and
// freed once those frames are done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/context.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>

#include <memory>

namespace rb {

// What a Denoiser filters.
enum class DenoiseSignal : uint32_t {
  Scalar = 0,  // default: R16/R32 .r (shadow visibility, AO); output R16_SFLOAT
  Rgb,         // RGBA16F/RGBA32F .rgb, HDR (e.g. ManyLightOutputs::irradiance); output R16G16B16A16_SFLOAT, a = 1
};

// Fixed for the denoiser's life (its history and images follow it). Zero-initialised = a scalar denoiser.
struct DenoiserDesc {
  DenoiseSignal signal = DenoiseSignal::Scalar;
};

struct DenoiseSettings {
  // false = accumulate over frames. Rgb: true still runs the temporal dispatch (it measures the noise), without
  // history.
  bool disableTemporal = false;
  bool disableSpatial = false;  // false = run the a-trous filter
  // 0 = 2 for Scalar (steps 1 and 2: a 13x13 footprint; 3 over-blurs 4-ray AO), 5 for Rgb (3x3 taps at steps 1 to
  // 16: its weights follow the measured noise, so the wide reach only blurs where the signal is still noisy).
  // At most 6.
  uint32_t spatialIterations = 0;
  uint32_t maxHistoryFrames = 0;  // 0 = 32: the running mean forgets more slowly than this
  float depthSigma = 0.0f;        // 0 = 0.005: plane-distance tolerance relative to view distance, per step
  float normalPower = 0.0f;       // 0 = 32: exponent of the normal similarity weight
  // Scalar signals: rays per pixel behind the signal, when it is a fraction of binary rays (shadow visibility,
  // binary AO): the spatial filter then knows the noise exactly and keeps every edge that is not noise.
  // 0 = unknown: the noise is estimated from the 3x3 neighbourhood, which also blurs thin noise-free features.
  // Rgb signals ignore it: their noise is the colour variance measured over the accumulated frames.
  uint32_t raysPerPixel = 0;
};

// Owned by the denoiser, left in SHADER_READ_ONLY_OPTIMAL after record().
struct DenoiseOutputs {
  // DenoiseSignal::Scalar: R16_SFLOAT (.r). DenoiseSignal::Rgb: R16G16B16A16_SFLOAT (.rgb, a = 1).
  VkImage denoised = VK_NULL_HANDLE;
  VkImageView denoisedView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

class Denoiser {
 public:
  static Result<std::unique_ptr<Denoiser>> create(Context& context, const DenoiserDesc& desc);
  static Result<std::unique_ptr<Denoiser>> create(Context& context);  // = DenoiseSignal::Scalar
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~Denoiser();

  // `signal`, in SHADER_READ_ONLY_OPTIMAL (the outputs of ShadowPass, AoPass and ManyLightPass are):
  //   Scalar: an R16/R32 float image view with the noisy value in .r.
  //   Rgb: an RGBA16F/RGBA32F image view with the noisy HDR value in .rgb (.a is ignored). A VkImageView does
  //        not tell its format, so this cannot be checked: a one-channel view would read as red only.
  // The G-buffer is the one the signal was traced from.
  Status record(VkCommandBuffer cmd, const GBufferDesc& gbuffer, VkImageView signal,
                const DenoiseSettings& settings = {});
  // Forget the history (after a camera cut or a scene change).
  void resetHistory();
  const DenoiseOutputs& outputs() const;
  DenoiseSignal signal() const;  // the DenoiserDesc::signal it was created with
  PassStats stats() const;       // GPU time (rays are 0: the denoiser traces none)

  struct Impl;

 private:
  explicit Denoiser(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb

// Denoising for ray-traced signals: single-channel ones (shadow visibility, AO), RGB HDR ones (the many-light
// irradiance of ManyLightPass) and reflections (ReflectionPass), chosen by DenoiserDesc::signal. Temporal
// accumulation with reprojection (camera motion, or the engine's motion vectors when GBufferDesc::motionVectors is
// given; the history read bilinearly from the texels that hold the same surface), followed by an edge-aware a-trous
// spatial filter guided by depth and normals. Under motion the history follows what changed: a pixel whose history
// is on another surface (disocclusion), whose motion vector is not finite, or whose engine reactive mask is set
// starts afresh, and anti-lag shortens the history where its 3x3 mean disagrees with this frame's by more than the
// noise explains (a moved object, shadow, reflection or light; DenoiseSettings::disableAntiLag). Each signal needs its
// own Denoiser (it keeps that signal's history). The raw input is left untouched, so raw and denoised are both
// available.
//
// Scalar signals: the filtering follows the noise measured in the data. The temporal pass estimates the variance
// left in each pixel's mean: binomial for a fraction of DenoiseSettings::raysPerPixel binary rays, at a
// probability taken from the pixel's rays and a 3x3 window of its neighbourhood (so a one-ray 0 or 1 still counts
// as noisy), else the window's variance; the least of the four windows with the pixel in a corner (an edge is not
// noise); divided by the frames accumulated. The a-trous steps (5x5 taps, 2 by default) weight value differences
// by the centre's noise, and carry the variance through. The last step moves the temporal mean towards the filtered
// value by at most as much as its noise explains (one standard deviation, falling off beyond, and less where the
// previous steps changed the neighbourhood by more than its noise: a pattern finer than the filter), and not at all
// where the noise is under DenoiseSettings::convergedNoise: converged or many-ray signals pass bit for bit. One
// temporal and spatialIterations a-trous dispatches (3 dispatches by default); 18 bytes of images per pixel of its own
// (63 MiB at 2560x1440) and 4 transient ones (8 with three or more steps) in a DenoiserScratch, its own or shared.
//
// RGB and reflection signals (SVGF-style, Schied et al. 2017): the temporal pass reprojects bilinearly and keeps,
// beside the mean colour, the running variance of one frame's colour (from the 3x3 windows around the pixel while the
// history is shorter than 4 frames); the a-trous steps (3x3 taps, 5 by default) stop at colour differences larger
// than the remaining noise of the mean, so a converged or noise-free signal passes nearly unchanged, and filter
// in the signal's own domain (no albedo demodulation: ManyLightPass's irradiance has none). One temporal and
// DenoiseSettings::spatialIterations a-trous dispatches; 32 bytes of images per pixel of its own (113 MiB at 2560x1440)
// and 16 transient ones in a DenoiserScratch, its own or shared.
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
  // RGBA16F/RGBA32F reflected radiance, .a = coverage (ReflectionOutputs::radiance): filtered as Rgb, guided by
  // the G-buffer's roughness (required): the filter's colour tolerance shrinks with it below roughness 0.1, so
  // a mirror (roughness 0, one deterministic ray) is not blurred. Pixels without coverage are neither filtered
  // nor taps. Output R16G16B16A16_SFLOAT, a = the coverage (0 or 1).
  Reflection,
};

// Fixed for the denoiser's life (its history and images follow it). Zero-initialised = a scalar denoiser.
struct DenoiserDesc {
  DenoiseSignal signal = DenoiseSignal::Scalar;
  // Create the images at width x height now (as prepare()), so that outputs() names the output and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

// Default of DenoiseSettings::convergedNoise: a scalar pixel whose noise has a standard deviation under 0.1 passes
// unfiltered (32 binary rays give at most 0.088: the filter's bias in narrow penumbrae costs more than such noise);
// up to twice that the filter's shift is ramped in.
inline constexpr float kDefaultDenoiseConvergedNoise = 0.1f;

// Default of DenoiseSettings::maxHistoryFrames: frames the temporal running mean averages at most.
inline constexpr uint32_t kDefaultMaxHistoryFrames = 32;
// The largest DenoiseSettings::maxHistoryFrames: the frame count is kept in a half float, exact to 2048; more is
// refused by name (a negative int converted to uint32_t lands there too).
inline constexpr uint32_t kMaxDenoiseHistoryFrames = 1024;

struct DenoiseSettings {
  // false = accumulate over frames. Rgb: true still runs the temporal dispatch (it measures the noise), without
  // history.
  bool disableTemporal = false;
  bool disableSpatial = false;  // false = run the a-trous filter
  // false = anti-lag: history whose 3x3 neighbourhood mean differs from this frame's by more than the noise explains
  // (scalar signals: 3 to 3.5 standard deviations, RGB: 3.5 to 4; kept in part between, dropped beyond) is shortened,
  // so a moved object, shadow, reflection or light is not faded in over maxHistoryFrames. true = pure accumulation.
  bool disableAntiLag = false;
  // 0 = 2 for Scalar (steps 1 and 2: a 13x13 footprint), 5 for Rgb and Reflection (3x3 taps at steps 1 to 16:
  // their weights follow the measured noise, so the wide reach only blurs where the signal is still noisy).
  // At most 6.
  uint32_t spatialIterations = 0;
  // 0 = kDefaultMaxHistoryFrames: the running mean forgets more slowly than this; at most kMaxDenoiseHistoryFrames.
  uint32_t maxHistoryFrames = 0;
  float depthSigma = 0.0f;   // 0 = 0.005: plane-distance tolerance relative to view distance, per step
  float normalPower = 0.0f;  // 0 = 32: exponent of the normal similarity weight
  // Scalar signals: rays per pixel behind the signal, when it is a fraction of binary rays (shadow visibility,
  // binary AO): the noise is then binomial, and an edge that all rays agree on is kept.
  // 0 = unknown: the noise is estimated from the 3x3 neighbourhood, which also blurs thin noise-free features.
  // Rgb signals ignore it: their noise is the colour variance measured over the accumulated frames.
  uint32_t raysPerPixel = 0;
  // Scalar signals: standard deviation of the noise under which a pixel passes unfiltered (its temporal mean, or
  // the raw value without history). 0 = kDefaultDenoiseConvergedNoise.
  float convergedNoise = 0.0f;
  // Scalar signals with raysPerPixel known, under 32: a pixel in the first 16 frames of its history (after a
  // reset, a teleported occluder, a disocclusion) is filtered harder, down to a quarter of convergedNoise, so that
  // its neighbours stand in for the frames it lacks; less so the more rays and frames it has
  // (shaders/denoise_noise.glsl, rbDnYouth). For smooth signals: AO's changed pixels after a teleport come within
  // 1.5x of a long history's error from the first frame after the teleport's (1.8x without), and AO of a single
  // frame at 1 to 16 rays loses 4-46% of its error. Not for shadows: their narrow penumbrae take the filter's bias
  // (single frames +10% to +100%). false = every pixel by convergedNoise alone. HybridEffects sets it for AO
  // (AoEffectSettings::disableShortHistoryFilter).
  bool shortHistoryFilter = false;
  // Scalar signals: how many frames a pixel's new value counts as where its history restarts because the G-buffer's
  // reactive mask is set there: the pass traced RaySchedule::resetRays rays in those pixels, so set resetRays /
  // raysPerPixel. The running mean then weighs each frame by its rays (a pixel restarted with 16 rays, then given 4
  // a frame, averages 16 + 4 + 4 rays, not three equal frames), and the noise the filter assumes is that of the
  // rays traced. A follow-up pixel (the mask above 0.25 and at most 0.5: GBufferDesc::reactiveMask) keeps its history
  // and adds this many frames to it. Whole frames (the history counts whole frames): resetRays / raysPerPixel rounded
  // down. 0 = 1 (the pass traced its usual rays); at most the history's frames (maxHistoryFrames resolved).
  // HybridEffects sets it with the reset rays it asks for.
  uint32_t resetFrames = 0;
};

// The transient images of denoisers that share them: the a-trous ping-pong images and the RGB guide, which each
// record() writes before it reads them and which nothing reads after it (issue 30: 16 bytes per pixel of each RGB
// denoiser, 4 of each scalar one). Denoisers recorded one after another into command buffers that run in submission
// order on one queue may share one: each record() orders its first write after the previous one's reads. HybridEffects
// shares one among its denoisers. Holds one image per kind at the size last asked for (a record() at another size
// replaces it: share one among denoisers of one size). Created empty; its images count to the Context's PassImages.
// Lifetime: as a Denoiser's (deferred release), and it must outlive the denoisers' records that name it.
// Thread safety: externally synchronised, together with every Denoiser that records with it.
class DenoiserScratch {
 public:
  static Result<std::unique_ptr<DenoiserScratch>> create(Context& context);
  ~DenoiserScratch();
  DenoiserScratch(const DenoiserScratch&) = delete;
  DenoiserScratch& operator=(const DenoiserScratch&) = delete;

  struct Impl;  // opaque

 private:
  friend struct internal::ContextAccess;
  explicit DenoiserScratch(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// What one record() filters. The G-buffer and signal have no defaults: a zero-initialised frame is refused by name.
struct DenoiseFrame {
  GBufferDesc gbuffer{};  // the one the signal was traced from
  // In SHADER_READ_ONLY_OPTIMAL (the outputs of ShadowPass, AoPass, ManyLightPass and ReflectionPass are):
  //   Scalar: an R16/R32 float image view with the noisy value in .r.
  //   Rgb: an RGBA16F/RGBA32F image view with the noisy HDR value in .rgb (.a is ignored). A VkImageView does
  //        not tell its format, so this cannot be checked: a one-channel view would read as red only.
  //   Reflection: as Rgb, .a = coverage (0 = no reflection there); the G-buffer must carry roughness
  //        (GBufferDesc::roughnessInNormalW or roughnessMetalness), that of the reflection rays.
  VkImageView signal = VK_NULL_HANDLE;
  DenoiseSettings settings{};
  // Transient images shared with other denoisers (DenoiserScratch); nullptr = the denoiser's own.
  DenoiserScratch* scratch = nullptr;
};

// Owned by the denoiser, left in SHADER_READ_ONLY_OPTIMAL after record().
struct DenoiseOutputs {
  // DenoiseSignal::Scalar: R16_SFLOAT (.r). Rgb: R16G16B16A16_SFLOAT (.rgb, a = 1). Reflection: as Rgb, a = coverage.
  VkImage denoised = VK_NULL_HANDLE;
  VkImageView denoisedView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

// The history a Denoiser's latest record() left: what the ray schedule of the pass that traces this signal reads
// (RaySchedule::history: adaptive rays and converged tiles), and what an engine may show in a debug view. Read-only:
// the images belong to the denoiser and are rewritten by its next record(). All in SHADER_READ_ONLY_OPTIMAL.
struct DenoiseHistory {
  // Scalar: RG16F (mean, frames accumulated). Rgb and Reflection: RGBA16F (mean colour, frames accumulated).
  VkImageView mean = VK_NULL_HANDLE;
  VkImage meanImage = VK_NULL_HANDLE;  // the image of `mean`, for a copy or a debug view's readback
  // Scalar: R16F (view distance of each pixel's surface). Rgb and Reflection: RG16F (view distance, standard deviation
  // of one frame's colour).
  VkImageView distance = VK_NULL_HANDLE;
  // Scalar only: RG16F, the latest temporal result (value, variance of its noise). VK_NULL_HANDLE otherwise.
  VkImageView noise = VK_NULL_HANDLE;
  VkSampler sampler = VK_NULL_HANDLE;  // nearest, clamped: the one the denoiser reads its history with
  uint32_t width = 0, height = 0;      // 0 before the first record() at the current size
  // false = the images hold no usable history (never written at this size, resetHistory(), temporal off).
  bool valid = false;
  // The camera of the frame that wrote it, as the temporal pass reprojects from: the world-space camera position and
  // projection * rotation-only view (column-major), both in double.
  double cameraPosition[3] = {};
  double viewProjection[16] = {};
};

class Denoiser {
 public:
  static Result<std::unique_ptr<Denoiser>> create(Context& context, const DenoiserDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~Denoiser();

  // Records the filtering of frame.signal into `cmd`. On an error (named field) nothing is recorded.
  Status record(VkCommandBuffer cmd, const DenoiseFrame& frame);
  // Creates the images at width x height now (the history starts empty), so that outputs() names the output
  // before the first record(); record() at the same size keeps them, at another size it recreates them. The output
  // image is the same whatever the DenoiseSettings, until the size changes. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  // Forget the history (after a camera cut or a scene change).
  void resetHistory();
  const DenoiseOutputs& outputs() const;
  DenoiseSignal signal() const;  // the DenoiserDesc::signal it was created with
  PassStats stats() const;       // GPU time (rays are 0: the denoiser traces none)
  // The history the latest record() left (see DenoiseHistory); mean is VK_NULL_HANDLE before the first record() or
  // after prepare() at another size.
  DenoiseHistory history() const;

  struct Impl;

 private:
  explicit Denoiser(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb

#include <raybridge/denoiser.h>

#include <cmath>
#include <cstring>
#include <string>

#include "compute_pipeline.h"
#include "context_impl.h"
#include "denoise_rgb_interface.glsl"
#include "denoiser_history.h"
#include "denoiser_scratch.h"
#include "gbuffer_sampler.h"
#include "image_barriers.h"
#include "initial_extent.h"
#include "pass_constants.h"
#include "pass_images.h"
#include "pass_metrics.h"
#include "raybridge_shaders.h"

namespace rb {

namespace {

// column-major a * b for 4x4 matrices in double.
void multiply(const double a[16], const double b[16], double out[16]) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      double s = 0.0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + r] * b[c * 4 + k];
      out[c * 4 + r] = s;
    }
  }
}

// A-trous iterations of an RGB signal when DenoiseSettings::spatialIterations is 0: 3x3 taps at steps 1 to 16
// (a 63x63 footprint), SVGF's reach for a few rays per pixel; the noise-aware weights keep it from
// over-blurring.
constexpr uint32_t kDefaultRgbIterations = 5;
// A-trous iterations of a scalar signal when DenoiseSettings::spatialIterations is 0: steps 1 and 2, a 13x13
// footprint.
constexpr uint32_t kDefaultScalarIterations = 2;

// The image barriers of one step of either record path, gathered and recorded as one vkCmdPipelineBarrier.
struct BarrierBatch {
  const DeviceFunctions& vk;
  VkCommandBuffer cmd;
  std::vector<VkImageMemoryBarrier> barriers;
  void add(const GpuImage& img, VkImageLayout from, VkImageLayout to, VkAccessFlags src, VkAccessFlags dst) {
    barriers.push_back(colorImageBarrier(img.image, from, to, src, dst));
  }
  void flush(VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage) {
    vk.vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 0, nullptr, 0, nullptr, static_cast<uint32_t>(barriers.size()),
                            barriers.data());
    barriers.clear();
  }
};

}  // namespace

struct Denoiser::Impl {
  Context& ctx;
  DenoiseSignal signal = DenoiseSignal::Scalar;
  ComputePipeline temporal, atrous;
  ComputePipeline atrousFinal;  // Scalar: the last a-trous step (writes the output)
  VkSampler sampler = VK_NULL_HANDLE;
  // The images a record() leaves for later readers (the next frame, the engine, the ray schedule), numbered as the
  // record paths number them (recordScalar, recordRgb), the transient ones (DenoiserScratch) left out. Scalar: 0,1:
  // history ping-pong (RG16F: mean, frames); 2,3: view distance ping-pong (R16F); 4: this frame's temporal result
  // (RG16F: value, noise variance); then the output (R16F, image 6). Rgb: 0-3 as recordRgb, then the output (5).
  PassImages images;
  // The transient images when the frame brings no shared DenoiserScratch (created on first use).
  std::unique_ptr<DenoiserScratch> ownScratch;
  PassMetrics metrics;
  DenoiseOutputs outputs;
  uint32_t parity = 0;  // which of each ping-pong pair this frame writes
  bool historyValid = false;
  // The images hold what a record() wrote, in the layouts it left them in (false from their creation until then:
  // adaptive rays read the history only when it is true).
  bool imagesWritten = false;
  double previousViewProjection[16] = {};
  double previousCamera[3] = {};
  explicit Impl(Context& c) : ctx(c) {}
  ~Impl() {  // frames in flight may still run its dispatches
    temporal.retire(ctx);
    atrous.retire(ctx);
    atrousFinal.retire(ctx);
    internal::contextImpl(ctx).retireHandle(sampler, &DeviceFunctions::vkDestroySampler);
    images.retire(ctx);
    ownScratch.reset();  // retires its images
    metrics.retire(ctx);
  }
};

namespace {

// The persistent images of either path (Impl::images). Their set never depends on the settings, so the output
// (Scalar: image 6, Rgb: image 5; persistent images 5 and 4) stays the same image from prepare() or the first
// record() until the size changes. The transient ones come from a DenoiserScratch. Scalar: see Impl::images;
// Rgb: see recordRgb. The view distances are half floats: the reprojection's same-surface test allows 2% and a half
// float holds a distance to 0.05% (to 65,504 m from the camera; farther reads as another surface: no history), and
// the RGB path keeps a standard deviation there, not a variance (whose HDR values overflow a half float; issue 30: 8
// and 16 bytes per pixel less).
std::vector<PassImages::Spec> imageSpecs(DenoiseSignal signal) {
  if (signal == DenoiseSignal::Scalar) {
    return {{VK_FORMAT_R16G16_SFLOAT, "denoiser history A"}, {VK_FORMAT_R16G16_SFLOAT, "denoiser history B"},
            {VK_FORMAT_R16_SFLOAT, "denoiser distance A"},   {VK_FORMAT_R16_SFLOAT, "denoiser distance B"},
            {VK_FORMAT_R16G16_SFLOAT, "denoiser temporal"},  {VK_FORMAT_R16_SFLOAT, "denoiser output"}};
  }
  return {{VK_FORMAT_R16G16B16A16_SFLOAT, "denoiser RGB history A"},
          {VK_FORMAT_R16G16B16A16_SFLOAT, "denoiser RGB history B"},
          {VK_FORMAT_R16G16_SFLOAT, "denoiser RGB surface A"},
          {VK_FORMAT_R16G16_SFLOAT, "denoiser RGB surface B"},
          {VK_FORMAT_R16G16B16A16_SFLOAT, "denoiser RGB spatial B"}};
}

// DenoiseSettings::maxHistoryFrames with its default; one frame without temporal filtering.
uint32_t historyFrames(const DenoiseSettings& s) {
  if (s.disableTemporal) return 1u;
  return s.maxHistoryFrames ? s.maxHistoryFrames : kDefaultMaxHistoryFrames;
}

constexpr uint32_t kScalarOutputImage = 6;
constexpr uint32_t kRgbOutputImage = 5;
// The output's place among the persistent images (Impl::images).
constexpr uint32_t kScalarOutputPersistent = 5;
constexpr uint32_t kRgbOutputPersistent = 4;

// A record path's images by number: the persistent ones (Impl::images) and the transient ones of the scratch, in the
// numbering of the comments of recordScalar and recordRgb.
struct ImageSlots {
  const GpuImage* slot[8] = {};
  uint32_t count = 0;
  const GpuImage& operator[](size_t i) const { return *slot[i]; }
  size_t size() const { return count; }
};

// The scratch a record uses: the frame's shared one, else the denoiser's own (created on first use; retired once a
// shared one is given, so no byte is held twice).
Result<DenoiserScratch::Impl*> scratchFor(Denoiser::Impl& s, DenoiserScratch* shared) {
  if (shared) {
    s.ownScratch.reset();
    return &internal::scratchImpl(*shared);
  }
  if (!s.ownScratch) {
    auto made = DenoiserScratch::create(s.ctx);
    if (!made) return made.error();
    s.ownScratch = std::move(made.value());
  }
  return &internal::scratchImpl(*s.ownScratch);
}

// Creates the images at width x height unless they exist at that size, and names the output in s.outputs. New
// images (a new size, or a set an earlier failure left incomplete) hold no history.
Status ensureImages(Denoiser::Impl& s, uint32_t width, uint32_t height) {
  const std::vector<PassImages::Spec> specs = imageSpecs(s.signal);
  const bool recreated = s.images.size() != specs.size() || s.images[0].width != width || s.images[0].height != height;
  if (recreated) s.imagesWritten = false;  // even when ensure() fails: it replaces what there was
  if (Status st = s.images.ensure(s.ctx, width, height, specs); !st) return st;
  if (recreated) s.historyValid = false;
  const GpuImage& out = s.images[s.signal == DenoiseSignal::Scalar ? kScalarOutputPersistent : kRgbOutputPersistent];
  s.outputs.denoised = out.image;
  s.outputs.denoisedView = out.view;
  s.outputs.width = width;
  s.outputs.height = height;
  return {};
}

}  // namespace

Denoiser::Denoiser(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Denoiser::~Denoiser() = default;

Result<std::unique_ptr<Denoiser>> Denoiser::create(Context& context, const DenoiserDesc& desc) {
  if (desc.signal != DenoiseSignal::Scalar && desc.signal != DenoiseSignal::Rgb &&
      desc.signal != DenoiseSignal::Reflection) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "Denoiser: DenoiserDesc::signal has an unknown value " + std::to_string(uint32_t(desc.signal)) +
                     "; use DenoiseSignal::Scalar, Rgb or Reflection"};
  }
  auto impl = std::make_unique<Impl>(context);
  impl->signal = desc.signal;
  const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
  auto sampled = [&](uint32_t b) {
    return VkDescriptorSetLayoutBinding{b, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, cs, nullptr};
  };
  auto storage = [&](uint32_t b) {
    return VkDescriptorSetLayoutBinding{b, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, cs, nullptr};
  };
  if (desc.signal != DenoiseSignal::Scalar) {
    Result<ComputePipeline> t = ComputePipeline::create(
        context, SpirvModule::of(spirv::denoise_rgb_temporal_comp),
        {sampled(RB_RGB_TEMPORAL_BINDING_DEPTH), sampled(RB_RGB_TEMPORAL_BINDING_MOTION),
         sampled(RB_RGB_TEMPORAL_BINDING_SIGNAL), sampled(RB_RGB_TEMPORAL_BINDING_HISTORY_IN),
         sampled(RB_RGB_TEMPORAL_BINDING_SURFACE_IN), storage(RB_RGB_TEMPORAL_BINDING_HISTORY_OUT),
         storage(RB_RGB_TEMPORAL_BINDING_SURFACE_OUT), storage(RB_RGB_TEMPORAL_BINDING_VALUE_OUT),
         storage(RB_RGB_TEMPORAL_BINDING_GUIDE_OUT), sampled(RB_RGB_TEMPORAL_BINDING_NORMAL),
         sampled(RB_RGB_TEMPORAL_BINDING_ROUGHNESS), sampled(RB_RGB_TEMPORAL_BINDING_REACTIVE)},
        sizeof(DenoiseConstants), "denoiser RGB temporal");
    if (!t) return t.error();
    impl->temporal = t.value();
    Result<ComputePipeline> a = ComputePipeline::create(context, SpirvModule::of(spirv::denoise_rgb_atrous_comp),
                                                        {sampled(RB_RGB_ATROUS_BINDING_GUIDE),
                                                         sampled(RB_RGB_ATROUS_BINDING_SIGNAL_IN),
                                                         storage(RB_RGB_ATROUS_BINDING_SIGNAL_OUT)},
                                                        sizeof(DenoiseConstants), "denoiser RGB a-trous");
    if (!a) return a.error();
    impl->atrous = a.value();
  } else {
    Result<ComputePipeline> t =
        ComputePipeline::create(context, SpirvModule::of(spirv::denoise_temporal_comp),
                                {sampled(RB_TEMPORAL_BINDING_DEPTH), sampled(RB_TEMPORAL_BINDING_MOTION),
                                 sampled(RB_TEMPORAL_BINDING_SIGNAL), sampled(RB_TEMPORAL_BINDING_HISTORY_IN),
                                 sampled(RB_TEMPORAL_BINDING_DISTANCE_IN), storage(RB_TEMPORAL_BINDING_HISTORY_OUT),
                                 storage(RB_TEMPORAL_BINDING_DISTANCE_OUT), storage(RB_TEMPORAL_BINDING_VALUE_OUT),
                                 storage(RB_TEMPORAL_BINDING_FINAL_OUT), sampled(RB_TEMPORAL_BINDING_REACTIVE)},
                                sizeof(DenoiseConstants), "denoiser temporal");
    if (!t) return t.error();
    impl->temporal = t.value();
    Result<ComputePipeline> a =
        ComputePipeline::create(context, SpirvModule::of(spirv::denoise_atrous_comp),
                                {sampled(RB_ATROUS_BINDING_DEPTH), sampled(RB_ATROUS_BINDING_NORMAL),
                                 sampled(RB_ATROUS_BINDING_SIGNAL_IN), storage(RB_ATROUS_BINDING_SIGNAL_OUT)},
                                sizeof(DenoiseConstants), "denoiser a-trous");
    if (!a) return a.error();
    impl->atrous = a.value();
    Result<ComputePipeline> f =
        ComputePipeline::create(context, SpirvModule::of(spirv::denoise_atrous_final_comp),
                                {sampled(RB_ATROUS_BINDING_DEPTH), sampled(RB_ATROUS_BINDING_NORMAL),
                                 sampled(RB_ATROUS_BINDING_SIGNAL_IN), storage(RB_ATROUS_BINDING_SIGNAL_OUT),
                                 sampled(RB_ATROUS_BINDING_TEMPORAL), sampled(RB_ATROUS_BINDING_HISTORY)},
                                sizeof(DenoiseConstants), "denoiser a-trous (final)");
    if (!f) return f.error();
    impl->atrousFinal = f.value();
  }
  Result<VkSampler> s = createNearestSampler(context);
  if (!s) return s.error();
  impl->sampler = s.value();
  if (Status st = impl->metrics.init(context, "denoiser", /*countsRays=*/false); !st) return st.error();
  std::unique_ptr<Denoiser> denoiser(new Denoiser(std::move(impl)));
  if (Status st = internal::prepareAtCreation(*denoiser, desc.width, desc.height, "DenoiserDesc"); !st) {
    return st.error();
  }
  return denoiser;
}

Status Denoiser::prepare(uint32_t width, uint32_t height) {
  if (width == 0 || height == 0) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 "Denoiser::prepare: size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is empty; pass the G-buffer's size"};
  }
  return ensureImages(*impl_, width, height);
}

void Denoiser::resetHistory() { impl_->historyValid = false; }
const DenoiseOutputs& Denoiser::outputs() const { return impl_->outputs; }
DenoiseSignal Denoiser::signal() const { return impl_->signal; }
PassStats Denoiser::stats() const { return impl_->metrics.latest(impl_->ctx); }

namespace {

// The RGB path (DenoiseSignal::Rgb), SVGF-style. The temporal pass always runs: it measures the noise the
// a-trous weights need (with disableTemporal it ignores the history). The a-trous steps then ping-pong between
// the two spatial images, the temporal result being the first of them; the last dispatch writes a = 1.
Status recordRgb(Denoiser::Impl& s, VkCommandBuffer cmd, const GBufferDesc& g, VkImageView signal,
                 const DenoiseSettings& settings, DenoiseConstants pc, uint32_t flags, DenoiserScratch* shared) {
  Context& ctx = s.ctx;
  // 0,1: colour history ping-pong (rgb mean, a frames); 2,3: surface ping-pong (view distance, standard deviation
  // of one frame's colour: RG16F, the deviation because a variance of HDR values overflows half floats); 4,5: the
  // temporal result and the a-trous ping-pong (rgb, a: the colour's standard deviation; a = 1 in the output); 6: the
  // guide (distance and normal, see denoise_rgb_common.glsl).
  if (Status st = ensureImages(s, g.width, g.height); !st) return st;
  Result<DenoiserScratch::Impl*> scratch = scratchFor(s, shared);
  if (!scratch) return scratch.error();
  Result<const GpuImage*> ping = scratch.value()->image(DenoiserScratch::Impl::kRgbPing, g.width, g.height);
  if (!ping) return ping.error();
  Result<const GpuImage*> guide = scratch.value()->image(DenoiserScratch::Impl::kRgbGuide, g.width, g.height);
  if (!guide) return guide.error();
  // 4 and 6 are the scratch's (transient: written here before they are read, read by nothing after).
  ImageSlots im;
  for (uint32_t i = 0; i < 4; ++i) im.slot[i] = &s.images[i];
  im.slot[4] = ping.value();
  im.slot[5] = &s.images[kRgbOutputPersistent];
  im.slot[6] = guide.value();
  im.count = 7;
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const uint32_t cur = s.parity, prev = 1 - s.parity;

  if (Status st = s.metrics.beginRecording(ctx, cmd); !st) return st;
  s.metrics.writeStart(ctx, cmd);
  BarrierBatch batch{vk, cmd};
  auto barrier = [&](const GpuImage& img, VkImageLayout from, VkImageLayout to, VkAccessFlags src, VkAccessFlags dst) {
    batch.add(img, from, to, src, dst);
  };
  auto flush = [&](VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage) { batch.flush(srcStage, dstStage); };
  const VkPipelineStageFlags cs = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | cs |
                                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  const VkImageLayout gen = VK_IMAGE_LAYOUT_GENERAL;
  const VkAccessFlags read = VK_ACCESS_SHADER_READ_BIT, write = VK_ACCESS_SHADER_WRITE_BIT;
  const bool historyUsable = !settings.disableTemporal && s.historyValid;
  if (!historyUsable) {
    // Nothing valid to read: give last frame's images a defined layout for the descriptor reads.
    for (uint32_t base : {0u, 2u}) barrier(im[base + prev], VK_IMAGE_LAYOUT_UNDEFINED, ro, 0, read);
  }
  for (uint32_t base : {0u, 2u}) barrier(im[base + cur], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  barrier(im[4], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  barrier(im[5], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  barrier(im[6], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  flush(readers, cs);

  const uint32_t iterations = settings.disableSpatial
                                  ? 0u
                                  : (settings.spatialIterations ? settings.spatialIterations : kDefaultRgbIterations);
  // The temporal result starts the a-trous ping-pong on the image from which `iterations` steps land on the output
  // (kRgbOutputImage, 5): image 4 for an odd count, 5 for an even one (0: the temporal result is the output).
  const uint32_t first = iterations % 2 == 0 ? kRgbOutputImage : 4u;
  const uint32_t other = first == 4u ? 5u : 4u;
  pc.flags = flags | (historyUsable ? RB_DN_HISTORY : 0u) | (iterations == 0 ? RB_DN_RGB_FINAL : 0u);
  pc.maxHistoryFrames = historyFrames(settings);
  {
    DescriptorWrites w;
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_DEPTH, g.depth.view, s.sampler, readLayout(g.depth));
    internal::writeReprojectionInputs(w, g, s.sampler, RB_RGB_TEMPORAL_BINDING_MOTION,
                                      RB_RGB_TEMPORAL_BINDING_REACTIVE);
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_SIGNAL, signal, s.sampler, ro);
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_HISTORY_IN, im[prev].view, s.sampler, ro);
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_SURFACE_IN, im[2 + prev].view, s.sampler, ro);
    w.storageImage(RB_RGB_TEMPORAL_BINDING_HISTORY_OUT, im[cur].view);
    w.storageImage(RB_RGB_TEMPORAL_BINDING_SURFACE_OUT, im[2 + cur].view);
    w.storageImage(RB_RGB_TEMPORAL_BINDING_VALUE_OUT, im[first].view);
    w.storageImage(RB_RGB_TEMPORAL_BINDING_GUIDE_OUT, im[6].view);
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_NORMAL, g.normal.view, s.sampler, readLayout(g.normal));
    // Read only for reflections (RB_DN_RGB_REFLECTION): the roughness image, else the normal (roughness in .w).
    const GBufferImage& roughness = roughnessImage(g);
    w.sampledImage(RB_RGB_TEMPORAL_BINDING_ROUGHNESS, roughness.view, s.sampler, readLayout(roughness));
    s.temporal.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
  }
  for (uint32_t base : {0u, 2u}) barrier(im[base + cur], gen, ro, write, read);
  barrier(im[first], gen, ro, write, read);
  barrier(im[6], gen, ro, write, read);
  flush(cs, readers);
  // A history written without temporal filtering holds one frame only: the next frame starts afresh anyway.
  s.historyValid = !settings.disableTemporal;
  s.imagesWritten = true;
  s.parity = prev;

  for (uint32_t i = 0; i < iterations; ++i) {
    const GpuImage& in = im[i % 2 == 0 ? first : other];
    const GpuImage& out = im[i % 2 == 0 ? other : first];
    if (i >= 1) {
      // Writing the image read one step earlier (the temporal result or an a-trous step).
      barrier(out, ro, gen, read, write);
      flush(cs, cs);
    }
    pc.flags = flags | (i + 1 == iterations ? RB_DN_RGB_FINAL : 0u);
    pc.atrousStep = 1u << i;
    DescriptorWrites w;
    w.sampledImage(RB_RGB_ATROUS_BINDING_GUIDE, im[6].view, s.sampler, ro);
    w.sampledImage(RB_RGB_ATROUS_BINDING_SIGNAL_IN, in.view, s.sampler, ro);
    w.storageImage(RB_RGB_ATROUS_BINDING_SIGNAL_OUT, out.view);
    s.atrous.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
    barrier(out, gen, ro, write, read);
    flush(cs, readers);
  }
  if (iterations == 0) {
    // The other spatial image was not written: keep its layout known.
    barrier(im[other], gen, ro, 0, read);
    flush(cs, readers);
  }
  s.metrics.writeEnd(ctx, cmd);
  return {};
}


// The scalar path (DenoiseSignal::Scalar). The temporal pass always runs: it measures the noise the a-trous
// weights and the final shift need (with disableTemporal it ignores the history). Its result (value, variance)
// stays in image 4 for the final step; the steps before it ping-pong between images 5 and 7 (7 exists only for
// three steps or more); the final step writes the R16 output, image 6.
Status recordScalar(Denoiser::Impl& s, VkCommandBuffer cmd, const GBufferDesc& g, VkImageView signal,
                    const DenoiseSettings& settings, DenoiseConstants pc, uint32_t flags, DenoiserScratch* shared) {
  Context& ctx = s.ctx;
  const uint32_t iterations = settings.disableSpatial ? 0u
                                                      : (settings.spatialIterations ? settings.spatialIterations
                                                                                    : kDefaultScalarIterations);
  if (Status st = ensureImages(s, g.width, g.height); !st) return st;
  Result<DenoiserScratch::Impl*> scratch = scratchFor(s, shared);
  if (!scratch) return scratch.error();
  // Images 0-6, then 7 (the second a-trous image) where there are three steps or more; 5 and 7 are the scratch's.
  ImageSlots im;
  for (uint32_t i = 0; i < 5; ++i) im.slot[i] = &s.images[i];
  Result<const GpuImage*> ping = scratch.value()->image(DenoiserScratch::Impl::kScalarPing, g.width, g.height);
  if (!ping) return ping.error();
  im.slot[5] = ping.value();
  im.slot[kScalarOutputImage] = &s.images[kScalarOutputPersistent];
  im.count = 7;
  if (iterations >= 3) {
    Result<const GpuImage*> pong = scratch.value()->image(DenoiserScratch::Impl::kScalarPong, g.width, g.height);
    if (!pong) return pong.error();
    im.slot[7] = pong.value();
    im.count = 8;
  } else if (!shared) {
    scratch.value()->release(DenoiserScratch::Impl::kScalarPong);  // its own: no byte that no step reads
  }
  const DeviceFunctions& vk = internal::deviceFunctions(ctx);
  const uint32_t cur = s.parity, prev = 1 - s.parity;

  if (Status st = s.metrics.beginRecording(ctx, cmd); !st) return st;
  s.metrics.writeStart(ctx, cmd);
  BarrierBatch batch{vk, cmd};
  const VkPipelineStageFlags cs = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  const VkPipelineStageFlags readers = VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | cs |
                                       VK_PIPELINE_STAGE_RAY_TRACING_SHADER_BIT_KHR;
  const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  const VkImageLayout gen = VK_IMAGE_LAYOUT_GENERAL;
  const VkAccessFlags read = VK_ACCESS_SHADER_READ_BIT, write = VK_ACCESS_SHADER_WRITE_BIT;
  const bool historyUsable = !settings.disableTemporal && s.historyValid;
  if (!historyUsable) {
    // Nothing valid to read: give last frame's images a defined layout for the descriptor reads.
    for (uint32_t base : {0u, 2u}) batch.add(im[base + prev], VK_IMAGE_LAYOUT_UNDEFINED, ro, 0, read);
  }
  // Every image written this frame starts undefined, in GENERAL; `writable` tracks the spatial ones.
  for (uint32_t base : {0u, 2u}) batch.add(im[base + cur], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  for (size_t i = 4; i < im.size(); ++i) batch.add(im[i], VK_IMAGE_LAYOUT_UNDEFINED, gen, read, write);
  batch.flush(readers, cs);
  bool writable[8] = {};
  for (size_t i = 5; i < im.size(); ++i) writable[i] = true;

  pc.flags = flags | (historyUsable ? RB_DN_HISTORY : 0u) | (iterations == 0 ? RB_DN_TEMPORAL_FINAL : 0u);
  pc.maxHistoryFrames = historyFrames(settings);
  {
    DescriptorWrites w;
    w.sampledImage(RB_TEMPORAL_BINDING_DEPTH, g.depth.view, s.sampler, readLayout(g.depth));
    internal::writeReprojectionInputs(w, g, s.sampler, RB_TEMPORAL_BINDING_MOTION, RB_TEMPORAL_BINDING_REACTIVE);
    w.sampledImage(RB_TEMPORAL_BINDING_SIGNAL, signal, s.sampler, ro);
    w.sampledImage(RB_TEMPORAL_BINDING_HISTORY_IN, im[prev].view, s.sampler, ro);
    w.sampledImage(RB_TEMPORAL_BINDING_DISTANCE_IN, im[2 + prev].view, s.sampler, ro);
    w.storageImage(RB_TEMPORAL_BINDING_HISTORY_OUT, im[cur].view);
    w.storageImage(RB_TEMPORAL_BINDING_DISTANCE_OUT, im[2 + cur].view);
    w.storageImage(RB_TEMPORAL_BINDING_VALUE_OUT, im[4].view);
    w.storageImage(RB_TEMPORAL_BINDING_FINAL_OUT, im[6].view);
    s.temporal.dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
  }
  for (uint32_t i : {cur, 2 + cur, 4u}) batch.add(im[i], gen, ro, write, read);
  // A history written without temporal filtering holds one frame only: the next frame starts afresh anyway.
  s.historyValid = !settings.disableTemporal;
  s.imagesWritten = true;
  s.parity = prev;

  pc.flags = flags;
  uint32_t input = 4;
  for (uint32_t i = 0; i < iterations; ++i) {
    const bool final = i + 1 == iterations;
    const uint32_t out = final ? kScalarOutputImage : (i % 2 == 0 ? 5u : 7u);
    if (!writable[out]) {
      // Reusing the spatial image read one step earlier.
      batch.add(im[out], ro, gen, read, write);
      writable[out] = true;
    }
    batch.flush(cs, i == 0 ? readers : cs);
    pc.atrousStep = 1u << i;
    DescriptorWrites w;
    w.sampledImage(RB_ATROUS_BINDING_DEPTH, g.depth.view, s.sampler, readLayout(g.depth));
    w.sampledImage(RB_ATROUS_BINDING_NORMAL, g.normal.view, s.sampler, readLayout(g.normal));
    w.sampledImage(RB_ATROUS_BINDING_SIGNAL_IN, im[input].view, s.sampler, ro);
    w.storageImage(RB_ATROUS_BINDING_SIGNAL_OUT, im[out].view);
    if (final) {
      w.sampledImage(RB_ATROUS_BINDING_TEMPORAL, im[4].view, s.sampler, ro);
      w.sampledImage(RB_ATROUS_BINDING_HISTORY, im[cur].view, s.sampler, ro);  // this frame's: .y the frames
    }
    (final ? s.atrousFinal : s.atrous).dispatch(ctx, cmd, w.writes, &pc, sizeof pc, g.width, g.height);
    batch.add(im[out], gen, ro, write, read);
    writable[out] = false;
    input = out;
  }
  // Every image ends in SHADER_READ_ONLY_OPTIMAL, written or not.
  for (size_t i = 5; i < im.size(); ++i)
    if (writable[i]) batch.add(im[i], gen, ro, write, read);
  batch.flush(cs, readers);
  s.metrics.writeEnd(ctx, cmd);
  return {};
}

// The constants every dispatch of a frame shares: the G-buffer's camera and layout (checked as the ray tracing
// passes check them), and the reprojection from the camera the history was written from (`previousCamera`,
// `previousViewProjection`). Also returns this frame's camera position and rotation-only view-projection, which
// record() keeps for the next frame.
Status prepareConstants(const GBufferDesc& g, uint64_t frame, const double previousCamera[3],
                        const double previousViewProjection[16], const char* who, DenoiseConstants& pc, uint32_t& flags,
                        double camera[3], double viewProjection[16]) {
  GBufferConstants pass{};
  TlasInfo noTlas;
  noTlas.tlas = reinterpret_cast<VkAccelerationStructureKHR>(uintptr_t(1));  // fillGBufferConstants wants one
  if (Status st = fillGBufferConstants(g, noTlas, frame, who, pass); !st) return st;
  std::memcpy(pc.inverseProjection, pass.inverseProjection, sizeof pc.inverseProjection);
  std::memcpy(pc.viewToWorld, pass.viewToWorld, sizeof pc.viewToWorld);
  pc.wAtDepthOne = pass.wAtDepthOne;
  flags = 0;
  if (g.depthConvention == DepthConvention::ReversedZ) flags |= RB_DN_REVERSED_Z;
  if (g.normalEncoding == NormalEncoding::Octahedral) flags |= RB_DN_OCTAHEDRAL;
  if (g.motionVectors.view) flags |= RB_DN_MOTION;
  if (g.reactiveMask.view) flags |= RB_DN_REACTIVE;
  pc.size[0] = g.width;
  pc.size[1] = g.height;
  // This frame's camera: projection * rotation-only view, kept for next frame's reprojection.
  cameraPosition(g, camera);
  double proj[16], viewRot[16] = {};
  for (int i = 0; i < 16; ++i) proj[i] = g.projection[i];
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) viewRot[c * 4 + r] = g.view[c * 4 + r];
  }
  viewRot[15] = 1.0;
  multiply(proj, viewRot, viewProjection);
  for (int i = 0; i < 16; ++i) pc.previousViewProjection[i] = static_cast<float>(previousViewProjection[i]);
  for (int i = 0; i < 3; ++i) pc.cameraDelta[i] = static_cast<float>(camera[i] - previousCamera[i]);
  return {};
}

}  // namespace

Status Denoiser::record(VkCommandBuffer cmd, const DenoiseFrame& frame) {
  const GBufferDesc& g = frame.gbuffer;
  const VkImageView signal = frame.signal;
  const DenoiseSettings& settings = frame.settings;
  Impl& s = *impl_;
  auto invalid = [](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, "Denoiser: " + m}; };
  if (!cmd) return invalid("cmd is VK_NULL_HANDLE");
  if (!signal) return invalid("DenoiseFrame::signal is VK_NULL_HANDLE; pass the noisy image's view");
  if (settings.spatialIterations > 6) return invalid("DenoiseSettings::spatialIterations exceeds 6");
  if (settings.maxHistoryFrames > kMaxDenoiseHistoryFrames) {
    return invalid("DenoiseSettings::maxHistoryFrames " + std::to_string(settings.maxHistoryFrames) + " exceeds " +
                   std::to_string(kMaxDenoiseHistoryFrames) +
                   " (a negative count converted to unsigned?); 0 = the default of " +
                   std::to_string(kDefaultMaxHistoryFrames));
  }
  if (settings.resetFrames > historyFrames(settings)) {
    return invalid("DenoiseSettings::resetFrames " + std::to_string(settings.resetFrames) + " exceeds the history's " +
                   std::to_string(historyFrames(settings)) +
                   " frames (a negative count converted to unsigned?); set RaySchedule::resetRays / raysPerPixel");
  }
  if (settings.disableTemporal && settings.disableSpatial) {
    return invalid("both temporal and spatial filtering are disabled; use the raw signal instead");
  }
  DenoiseConstants pc{};
  uint32_t flags = 0;
  double camera[3], viewProjection[16];
  if (Status st = prepareConstants(g, s.ctx.frameIndex(), s.previousCamera, s.previousViewProjection, "Denoiser", pc,
                                   flags, camera, viewProjection);
      !st) {
    return st;
  }
  pc.depthSigma = settings.depthSigma > 0.0f ? settings.depthSigma : 0.005f;
  pc.normalPower = settings.normalPower > 0.0f ? settings.normalPower : 32.0f;
  pc.signalRaysPerPixel = float(settings.raysPerPixel);
  pc.resetFrames = float(std::max(settings.resetFrames, 1u));
  pc.convergedNoise = settings.convergedNoise > 0.0f ? settings.convergedNoise : kDefaultDenoiseConvergedNoise;
  if (s.signal == DenoiseSignal::Reflection) {
    if (!g.roughnessInNormalW && !g.roughnessMetalness.view) {
      return invalid("a Reflection signal needs the G-buffer's roughness: set GBufferDesc::roughnessInNormalW or "
                     "roughnessMetalness");
    }
    flags |= RB_DN_RGB_REFLECTION | (roughnessInImage(g) ? RB_DN_RGB_ROUGHNESS_IMAGE : 0u);
  }
  if (internal::contextImpl(s.ctx).holdsKeptMarks(signal)) flags |= RB_DN_KEPT_MARKS;
  if (!settings.disableAntiLag) flags |= RB_DN_ANTI_LAG;
  if (settings.shortHistoryFilter) flags |= RB_DN_SHORT_HISTORY;
  if (s.signal != DenoiseSignal::Scalar) {
    Status st = recordRgb(s, cmd, g, signal, settings, pc, flags, frame.scratch);
    if (st) {
      std::memcpy(s.previousViewProjection, viewProjection, sizeof viewProjection);
      std::memcpy(s.previousCamera, camera, sizeof camera);
    }
    return st;
  }

  Status st = recordScalar(s, cmd, g, signal, settings, pc, flags, frame.scratch);
  if (st) {
    std::memcpy(s.previousViewProjection, viewProjection, sizeof viewProjection);
    std::memcpy(s.previousCamera, camera, sizeof camera);
  }
  return st;
}

DenoiseHistory Denoiser::history() const {
  const Impl& s = *impl_;
  DenoiseHistory h;
  // Scalar images: 0,1 the history ping-pong, 2,3 the distances; RGB: 0,1 the colour history, 2,3 the surface
  // (distance, variance). The latest record() wrote 1 - parity.
  if (!s.imagesWritten || s.images.size() < 5) return h;
  const uint32_t last = 1 - s.parity;
  h.mean = s.images[last].view;
  h.meanImage = s.images[last].image;
  h.distance = s.images[2 + last].view;
  h.noise = s.signal == DenoiseSignal::Scalar ? s.images[4].view : VK_NULL_HANDLE;
  h.sampler = s.sampler;
  h.width = s.images[0].width;
  h.height = s.images[0].height;
  h.valid = s.historyValid;
  std::memcpy(h.cameraPosition, s.previousCamera, sizeof h.cameraPosition);
  std::memcpy(h.viewProjection, s.previousViewProjection, sizeof h.viewProjection);
  return h;
}

namespace internal {

DenoiseHistory historyFor(const Denoiser& denoiser, const GBufferDesc& g) {
  DenoiseHistory h = denoiser.history();
  if (h.width != g.width || h.height != g.height) return {};
  return h;
}

Status historyReprojection(const DenoiseHistory& history, const GBufferDesc& g, uint64_t frame, const char* who,
                           DenoiseConstants& pc) {
  uint32_t flags = 0;
  double camera[3], viewProjection[16];
  if (Status st = prepareConstants(g, frame, history.cameraPosition, history.viewProjection, who, pc, flags, camera,
                                   viewProjection);
      !st) {
    return st;
  }
  pc.flags = flags | (history.valid ? RB_DN_HISTORY : 0u);
  return {};
}

}  // namespace internal

}  // namespace rb

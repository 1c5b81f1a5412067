// A G-buffer made by the Embree reference instead of a rasterizer: exact depth and geometric normals of a
// test scene, uploaded as the images an engine would hand to Raybridge. Lets the effect passes be checked
// against ground truth without any engine in the loop.
#pragma once

#include <raybridge/raybridge.h>

#include <glm/glm.hpp>

#include <functional>
#include <vector>

#include "embree_reference.h"
#include "test_scene.h"

namespace rbtest {

struct SyntheticView {
  glm::dvec3 eye{0.0};
  glm::dvec3 target{0.0, 0.0, -1.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  double fovYDegrees = 60.0;
  uint32_t width = 128, height = 96;
  bool reversedZ = false;
  float nearPlane = 0.05f;
  float farPlane = 500.0f;
};

// The conformance scene's camera (conformanceCamera()) as a synthetic view of the given size.
SyntheticView conformanceView(uint32_t width, uint32_t height, double fovYDegrees = 60.0);
// The motion tests' view of the conformance scene: from above and behind its boxes, so that a box's shadow from a
// light behind it (as seen) falls on visible ground.
SyntheticView motionTestView(uint32_t width, uint32_t height);

// CPU-side G-buffer: per pixel the exact hit (world position in double, geometric normal facing the eye).
struct CpuGBuffer {
  SyntheticView view;
  glm::mat4 viewMatrix{1.0f};  // camera-relative: rotation only (the translation lives in cameraPosition)
  glm::mat4 projection{1.0f};
  std::vector<float> depth;          // hardware depth values
  std::vector<glm::vec4> normal;     // world normal (xyz), w = 0
  std::vector<uint8_t> hit;          // 1 where the primary ray hit
  std::vector<glm::dvec3> position;  // world position of the hit
  std::vector<uint32_t> instance;    // instance id of the hit
};

// Traces the primary rays with Embree over `scene` (instances given in world space). `roughness`, indexed by
// instance, goes to the normal image's w (GBufferDesc::roughnessInNormalW); empty = 0 everywhere.
CpuGBuffer traceGBuffer(const EmbreeScene& embree, const SyntheticView& view, const std::vector<float>& roughness = {});

// A device-local 2D image with one mip and layer, sampled, uploaded from `data` (`bytes` bytes, tightly packed)
// and left in SHADER_READ_ONLY_OPTIMAL for ray tracing shaders: G-buffer images, material textures.
struct SampledImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
};
SampledImage uploadSampledImage(GpuFixture& fx, VkFormat format, VkImageAspectFlags aspect, uint32_t width,
                                uint32_t height, const void* data, size_t bytes);
void destroySampledImage(GpuFixture& fx, SampledImage& image);

// The G-buffer uploaded: D32 depth and RGBA32F normal images in SHADER_READ_ONLY_OPTIMAL.
class GpuGBuffer {
 public:
  GpuGBuffer(GpuFixture& fx, const CpuGBuffer& cpu);
  ~GpuGBuffer();
  // The contract as an engine would fill it; cameraPosition carries the eye in double.
  rb::GBufferDesc desc() const { return desc_; }
  rb::TlasBuildOptions cameraRelativeTlas(bool shadingRecords = false) const {
    rb::TlasBuildOptions o;
    for (int i = 0; i < 3; ++i) o.originOffset[i] = desc_.cameraPosition[i];
    o.writeShadingRecords = shadingRecords;
    return o;
  }

 private:
  GpuFixture& fx_;
  SampledImage depth_, normal_;
  rb::GBufferDesc desc_;
};

// One frame of effect passes on a synthetic G-buffer: builds `scene`, uploads `cpu`, builds a camera-relative
// TLAS (with shading records when asked), calls `record` inside the frame and `readback` after it (while the
// G-buffer and the scene still exist), then settles the frames in flight so the passes' statistics resolve.
using PassRecorder = std::function<void(VkCommandBuffer, const rb::GBufferDesc&, const rb::TlasInfo&)>;
using PassReadback = std::function<void(const rb::GBufferDesc&)>;
void runPassFrame(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu, bool shadingRecords,
                  const PassRecorder& record, const PassReadback& readback);

// Reads a pass output (in SHADER_READ_ONLY_OPTIMAL, left so) back: raw bytes, or R16F/R32F as floats.
std::vector<uint8_t> readPassImage(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height,
                                   uint32_t bytesPerPixel);
std::vector<float> readR16f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height);
// RGBA16F: 4 floats per pixel.
std::vector<float> readRgba16f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height);
std::vector<float> readR32f(GpuFixture& fx, VkImage image, uint32_t width, uint32_t height);
// Frames accumulated per pixel in the history a denoiser's latest record() left (its mean image's last channel:
// RG16F .g for Scalar, RGBA16F .a for Rgb and Reflection).
std::vector<float> historyFrames(GpuFixture& fx, const rb::Denoiser& denoiser);

}  // namespace rbtest

// Shared test fixture: a headless lavapipe (or GPU) device with the validation layer on and fatal, a Raybridge
// context on it, and helpers to upload meshes and read images back.
#pragma once

#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "context_impl.h"
#include "gpu_memory.h"
#include "procedural_meshes.h"

namespace rbtest {

// A mesh uploaded into "engine" buffers, with the MeshDesc that describes it.
struct UploadedMesh {
  rb::HeadlessBuffer vertices;
  rb::HeadlessBuffer indices;
  rb::MeshDesc desc;  // its host pointers point into `source`
  std::shared_ptr<const rbsamples::CpuMesh> source;
};

class GpuFixture {
 public:
  // requestAsyncComputeQueue: see HeadlessDeviceDesc (a second, compute-only queue when the device has one).
  explicit GpuFixture(uint32_t framesInFlight = 2, bool requestAsyncComputeQueue = false);
  // Fails the running test if the validation layer reported any error, or if a mesh from upload() was not
  // destroyed (the device would be destroyed with its buffers alive: LeakSanitizer's report in CI, and a
  // validation message that comes too late to fail the test).
  ~GpuFixture();

  rb::HeadlessDevice& device() { return *device_; }
  rb::Context& ctx() { return *ctx_; }
  const rb::DeviceFunctions& vk() { return rb::internal::deviceFunctions(*ctx_); }

  UploadedMesh upload(const rbsamples::CpuMesh& mesh, bool withHostCopies = true);
  void destroy(UploadedMesh& mesh);
  // Records with `record`, submits, waits, then advances the context by framesInFlight frames so every
  // deferred release and query of that work resolves.
  void runAndSettle(const std::function<void(VkCommandBuffer)>& record);
  // One frame: beginFrame, record, submit, wait.
  void runFrame(const std::function<void(VkCommandBuffer)>& record);

  rb::GpuImage makeImage(uint32_t w, uint32_t h, VkFormat format);
  // Transitions the image from UNDEFINED to GENERAL.
  void toGeneral(VkCommandBuffer cmd, const rb::GpuImage& image);
  // Copies a GENERAL-layout image to host memory (bytesPerPixel * w * h bytes).
  std::vector<uint8_t> readImage(const rb::GpuImage& image, uint32_t bytesPerPixel);
  void destroyImage(rb::GpuImage& image) { rb::destroyImage(*ctx_, image); }

 private:
  std::unique_ptr<rb::HeadlessDevice> device_;
  std::unique_ptr<rb::Context> ctx_;
  uint32_t liveUploads_ = 0;  // upload() minus destroy()
};

// Asserts a result is ok and prints its message otherwise.
#define RB_REQUIRE_OK(expr)                                               \
  do {                                                                    \
    auto&& rb_result_ = (expr);                                           \
    INFO((rb_result_.ok() ? std::string() : rb_result_.error().message)); \
    REQUIRE(rb_result_.ok());                                             \
  } while (0)

std::string sharedScenesDir();  // ../shared/scenes relative to the source tree

}  // namespace rbtest

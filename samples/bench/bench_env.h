// What every scenario needs: the headless device and Raybridge context, uploads into "engine" buffers, one-shot
// frames, trace targets, the sizes chosen for the device, progress lines. Failures throw BenchFailure; main()
// turns it into a message and a non-zero exit code.
#pragma once

#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_options.h"
#include "context_access.h"
#include "device_functions.h"
#include "gpu_memory.h"
#include "procedural_meshes.h"

namespace rbbench {

struct BenchFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Throws BenchFailure naming `what` when the result holds an error.
template <typename T>
T check(rb::Result<T> r, const std::string& what) {
  if (!r) throw BenchFailure(what + ": " + rb::toString(r.error().code) + ": " + r.error().message);
  return std::move(r).value();
}
void check(const rb::Status& s, const std::string& what);

// The TLAS of the benchmarks that trace a static instance list built once: a plain rebuild, without the
// ALLOW_UPDATE flag that the default (TlasBuildMode::Adaptive) builds with, as their published rates were measured.
inline constexpr rb::TlasBuildOptions kStaticTlas{.mode = rb::TlasBuildMode::Rebuild};

// A mesh uploaded into device-local buffers the way an engine would hold it.
struct UploadedMesh {
  rb::HeadlessBuffer vertices;
  rb::HeadlessBuffer indices;
  rb::MeshDesc desc;  // buffer addresses and counts; no host copies (the key is the buffer identity)
  uint64_t triangles = 0;
};

// Sizes and repeats picked from --quick/--full and the device kind.
struct BenchSizes {
  std::vector<uint64_t> buildTriangles;  // build and compaction sweeps
  uint32_t buildRepeats = 5;
  uint64_t duplicationTriangles = 0;        // triangles of the duplicated mesh
  std::vector<uint32_t> duplicationCopies;  // N
  uint64_t fastTriangles = 0;               // fastbuild-vs-fasttrace mesh
  uint32_t fastRepeats = 5;
  std::vector<uint32_t> tlasInstances;
  uint32_t tlasRepeats = 7;
  uint32_t motionInstances = 0;  // tlas-motion: instances flying apart
  uint32_t motionFrames = 0;     // tlas-motion: frames of flight
  uint64_t traceTriangles = 0;   // trace scenario ground
  uint32_t traceRepeats = 5;     // timed traces per measurement
  uint32_t width = 0, height = 0;
  bool gltfRepeatsOnce = false;
};

class BenchEnv {
 public:
  explicit BenchEnv(const BenchOptions& options);  // throws BenchFailure
  ~BenchEnv();

  rb::HeadlessDevice& device() { return *device_; }
  rb::Context& ctx() { return *ctx_; }
  const rb::DeviceFunctions& vk() const { return rb::internal::deviceFunctions(*ctx_); }
  const rb::DeviceInfo& info() const { return ctx_->deviceInfo(); }
  const BenchOptions& options() const { return options_; }
  const BenchSizes& sizes() const { return sizes_; }
  uint32_t timestampValidBits() const { return timestampValidBits_; }

  UploadedMesh upload(const rbsamples::CpuMesh& mesh, const std::string& name);
  void destroy(UploadedMesh& mesh);

  // One frame: beginFrame, record, submit, wait.
  void runFrame(const std::function<void(VkCommandBuffer)>& record);
  // Advances the context by framesInFlight frames after a wait, so queries and releases of that work resolve.
  void settle();

  // R32_SFLOAT hit distance + R32G32_UINT ids, transitioned to GENERAL on first use.
  struct TraceTargets {
    rb::GpuImage distance, ids;
    bool inGeneral = false;
  };
  TraceTargets makeTraceTargets(uint32_t width, uint32_t height);
  void destroyTraceTargets(TraceTargets& t);
  // Records the layout transition (first use) or a write-after-write barrier between traces.
  void recordTraceBarrier(VkCommandBuffer cmd, TraceTargets& t);
  // Fraction of pixels with a hit (distance > 0), read back from the distance image.
  double hitFraction(const TraceTargets& t);

  // "[bench] ..." on stderr.
  void progress(const std::string& line) const;

 private:
  BenchOptions options_;
  BenchSizes sizes_;
  std::unique_ptr<rb::HeadlessDevice> device_;
  std::unique_ptr<rb::Context> ctx_;
  uint32_t timestampValidBits_ = 64;
};

}  // namespace rbbench

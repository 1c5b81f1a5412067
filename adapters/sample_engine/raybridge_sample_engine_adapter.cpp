// Raybridge <-> sample engine: device setup, scene registration and the pre-pass hook (see the header).
#include "raybridge_sample_engine_adapter.h"

#include <cstddef>
#include <cstring>

namespace rbAdapter {

namespace se = sample_engine;

namespace {

// ORs the VkBool32 members of a core feature struct (they follow the sType/pNext header) into `dst`.
template <typename T>
void mergeBools(T& dst, const void* src, size_t firstOffset) {
  for (size_t o = firstOffset; o + sizeof(VkBool32) <= sizeof(T); o += sizeof(VkBool32)) {
    VkBool32 a, b;
    std::memcpy(&a, reinterpret_cast<const char*>(&dst) + o, sizeof a);
    std::memcpy(&b, static_cast<const char*>(src) + o, sizeof b);
    a = a || b;
    std::memcpy(reinterpret_cast<char*>(&dst) + o, &a, sizeof a);
  }
}

std::string rbError(const char* what, const rb::Error& e) {
  return std::string(what) + ": " + rb::toString(e.code) + ": " + e.message;
}

void copyMatrix(const glm::mat4& m, float out[16]) { std::memcpy(out, &m[0][0], 16 * sizeof(float)); }

}  // namespace

void configureEngine(se::EngineConfig& config, rb::RequiredFeatures& features) {
  for (const char* name : rb::requiredDeviceExtensions()) {
    bool present = false;
    for (const std::string& e : config.deviceExtensions) present = present || e == name;
    if (!present) config.deviceExtensions.emplace_back(name);
  }
  // The engine builds the core feature structs itself and takes the others as a chain: split Raybridge's.
  std::vector<VkBaseOutStructure*> others;
  for (auto* s = static_cast<VkBaseOutStructure*>(features.chainHead()); s; s = s->pNext) {
    switch (s->sType) {
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES:
        mergeBools(config.extraFeatures11, s, offsetof(VkPhysicalDeviceVulkan11Features, storageBuffer16BitAccess));
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES:
        mergeBools(config.extraFeatures12, s, offsetof(VkPhysicalDeviceVulkan12Features, samplerMirrorClampToEdge));
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES:
        mergeBools(config.extraFeatures13, s, offsetof(VkPhysicalDeviceVulkan13Features, robustImageAccess));
        break;
      default: others.push_back(s);
    }
  }
  if (others.empty()) return;
  for (size_t i = 0; i + 1 < others.size(); ++i) others[i]->pNext = others[i + 1];
  others.back()->pNext = static_cast<VkBaseOutStructure*>(const_cast<void*>(config.deviceFeaturesPNext));
  config.deviceFeaturesPNext = others.front();
}

struct Adapter::Impl {
  se::Engine& engine;
  AdapterConfig config;
  FrameSettings settings;
  std::unique_ptr<rb::Context> ctx;
  std::unique_ptr<rb::AccelerationStructureService> as;
  std::unique_ptr<rb::ShadowPass> shadows;  // only with kEffectShadows
  std::vector<rb::MeshHandle> meshes;       // parallel to engine.meshes(); null for empty meshes
  std::vector<rb::Instance> instances;
  rb::TlasInfo tlas;
  std::string error;

  explicit Impl(se::Engine& e) : engine(e) {}
  void fail(std::string message) {
    if (error.empty()) error = std::move(message);
  }
  rb::GBufferDesc describePrepass(const se::PrepassHookInfo& info) const;
};

Adapter::Adapter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Adapter::~Adapter() {
  // The SDK destroys its objects at once; the engine's frames in flight may still use them.
  (void)impl_->engine.waitIdle();
  impl_->shadows.reset();
  impl_->as.reset();
  impl_->ctx.reset();
}

se::Result<std::unique_ptr<Adapter>> Adapter::create(se::Engine& engine, const AdapterConfig& config) {
  using R = se::Result<std::unique_ptr<Adapter>>;
  auto impl = std::make_unique<Impl>(engine);
  impl->config = config;

  rb::ContextDesc desc;
  desc.instance = engine.instance();
  desc.physicalDevice = engine.physicalDevice();
  desc.device = engine.device();
  desc.getInstanceProcAddr = engine.getInstanceProcAddr();
  desc.framesInFlight = se::kFramesInFlight;
  desc.mainQueueFamily = engine.queueFamily();
  auto ctx = rb::Context::create(desc);
  if (!ctx) return R::failure(rbError("rb::Context::create", ctx.error()));
  impl->ctx = std::move(ctx.value());

  auto as = rb::AccelerationStructureService::create(*impl->ctx, config.accelerationStructures);
  if (!as) return R::failure(rbError("rb::AccelerationStructureService::create", as.error()));
  impl->as = std::move(as.value());

  if (config.effects & kEffectShadows) {
    auto shadows = rb::ShadowPass::create(*impl->ctx);
    if (!shadows) return R::failure(rbError("rb::ShadowPass::create", shadows.error()));
    impl->shadows = std::move(shadows.value());
  }

  std::unique_ptr<Adapter> adapter(new Adapter(std::move(impl)));
  if (se::Status s = adapter->syncScene(); !s) return R::failure(s.error);
  return R::success(std::move(adapter));
}

se::Status Adapter::syncScene() {
  Impl& a = *impl_;
  for (rb::MeshHandle h : a.meshes) {
    if (!h.isNull()) (void)a.as->releaseMesh(h);
  }
  a.meshes.clear();
  a.instances.clear();
  const std::span<const se::GpuMesh> meshes = a.engine.meshes();
  for (size_t i = 0; i < meshes.size(); ++i) {
    const se::GpuMesh& m = meshes[i];
    const uint32_t triangles = (m.indexCount ? m.indexCount : m.vertexCount) / 3;
    if (triangles == 0) {
      a.meshes.push_back({});
      continue;
    }
    if (m.positionAddress == 0) {
      return se::Status::failure("mesh " + std::to_string(i) +
                                 " has no device address: create the engine with "
                                 "EngineConfig::enableRayTracingInputs and rbAdapter::configureEngine()");
    }
    rb::MeshDesc d;
    d.vertexAddress = m.positionAddress;
    d.vertexBufferBytes = VkDeviceSize(m.vertexCount) * m.positionStride;
    d.vertexCount = m.vertexCount;
    d.vertexFormat = m.positionFormat;
    d.vertexStride = m.positionStride;
    d.indexType = m.indexCount ? rb::IndexType::Uint32 : rb::IndexType::None;
    d.indexAddress = m.indexAddress;
    d.indexBufferBytes = VkDeviceSize(m.indexCount) * sizeof(uint32_t);
    d.triangleCount = triangles;
    if (m.cpu) {
      d.hostVertices = m.cpu->positions.data();
      d.hostIndices = m.cpu->indices.empty() ? nullptr : m.cpu->indices.data();
      d.debugName = m.cpu->name.c_str();
    }
    auto handle = a.as->registerMesh(d);
    if (!handle) return se::Status::failure(rbError("registerMesh", handle.error()));
    a.meshes.push_back(handle.value());
  }
  for (const se::Instance& inst : a.engine.scene().instances) {
    if (inst.mesh >= a.meshes.size() || a.meshes[inst.mesh].isNull()) continue;
    rb::Instance out;
    out.mesh = a.meshes[inst.mesh];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) out.transform[r * 4 + c] = inst.transform[c][r];  // GLM is column-major
    }
    out.customIndex = inst.mesh;
    a.instances.push_back(out);
  }
  return se::Status::success();
}

rb::GBufferDesc Adapter::Impl::describePrepass(const se::PrepassHookInfo& info) const {
  rb::GBufferDesc g;
  g.width = info.extent.width;
  g.height = info.extent.height;
  g.depth = {info.depth.view, info.depth.layout};  // D32_SFLOAT, DEPTH_READ_ONLY_OPTIMAL
  g.depthFormat = info.depth.format;
  g.depthConvention = info.reversedZ ? rb::DepthConvention::ReversedZ : rb::DepthConvention::Standard;
  g.normalEncoding = rb::NormalEncoding::WorldFloat;
  g.geometricNormal = {info.geometricNormal.view, info.geometricNormal.layout};  // w = metallic, unused
  if (config.normals == GBufferNormals::Shading) {
    g.normal = {info.normalRoughness.view, info.normalRoughness.layout};
    g.roughnessInNormalW = true;
  } else {
    g.normal = g.geometricNormal;
  }
  copyMatrix(info.view, g.view);
  copyMatrix(info.proj, g.projection);
  for (int i = 0; i < 3; ++i) g.cameraPosition[i] = double(info.cameraPosition[i]);
  return g;
}

void Adapter::recordFrame(const se::PrepassHookInfo& info, se::LightingInputs& inputs) {
  Impl& a = *impl_;
  a.ctx->beginFrame();  // every frame, so deferred releases and statistics keep pace with the engine
  if (!a.settings.enabled || a.config.effects == 0) return;
  VkCommandBuffer cmd = info.commandBuffer;

  if (auto pending = a.as->recordPendingWork(cmd); !pending) return a.fail(rbError("recordPendingWork", pending.error()));
  rb::TlasBuildOptions options;
  for (int i = 0; i < 3; ++i) options.originOffset[i] = double(info.cameraPosition[i]);
  auto tlas = a.as->recordTlasBuild(cmd, a.instances, options);
  if (!tlas) return a.fail(rbError("recordTlasBuild", tlas.error()));
  a.tlas = tlas.value();

  const rb::GBufferDesc gbuffer = a.describePrepass(info);
  if (a.shadows) {
    rb::Light sun;
    sun.type = rb::LightType::Directional;
    for (int i = 0; i < 3; ++i) sun.direction[i] = info.sunDirection[i];
    sun.angularRadiusDegrees = a.settings.sunAngularRadiusDegrees;
    rb::ShadowSettings s;
    s.raysPerPixel = a.settings.shadowRaysPerPixel;
    if (rb::Status st = a.shadows->record(cmd, gbuffer, a.tlas, sun, s); !st) {
      return a.fail(rbError("ShadowPass::record", st.error()));
    }
    inputs.sunVisibility = a.shadows->outputs().visibilityView;  // SHADER_READ_ONLY_OPTIMAL
  }
  // Next effects: ambient occlusion -> inputs.ambientOcclusion, reflections -> inputs.reflection.
}

se::PrepassHook Adapter::prepassHook() {
  return [this](const se::PrepassHookInfo& info, se::LightingInputs& inputs) { recordFrame(info, inputs); };
}

FrameSettings& Adapter::settings() { return impl_->settings; }
const std::string& Adapter::lastError() const { return impl_->error; }
rb::Context& Adapter::context() { return *impl_->ctx; }
rb::AccelerationStructureService& Adapter::accelerationStructures() { return *impl_->as; }
const rb::ShadowPass* Adapter::shadowPass() const { return impl_->shadows.get(); }
const rb::TlasInfo& Adapter::lastTlas() const { return impl_->tlas; }
uint32_t Adapter::sceneInstances() const { return uint32_t(impl_->instances.size()); }

}  // namespace rbAdapter

// Raybridge <-> sample engine: device setup, scene registration, effects and the pre-pass hook (see the header).
#include "raybridge_sample_engine_adapter.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <span>

namespace rbAdapter {

namespace se = sample_engine;

namespace {

std::string rbError(const char* what, const rb::Error& e) {
  return std::string(what) + ": " + rb::toString(e.code) + ": " + e.message;
}

void copyMatrix(const glm::mat4& m, float out[16]) { std::memcpy(out, &m[0][0], 16 * sizeof(float)); }

float srgbToLinear(uint8_t v) {
  const float c = float(v) / 255.0f;
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// rb::Material has no emissive texture: an emissive texture is folded into the factor as its average texel
// (decoded from sRGB), so e.g. a mostly black emissive mask does not make the whole surface glow in reflections.
glm::vec3 averageSrgbDecoded(const se::TextureData& t) {
  const size_t pixels = size_t(t.width) * t.height;
  if (pixels == 0 || t.rgba8.size() < pixels * 4) return glm::vec3(1.0f);
  glm::dvec3 sum(0.0);
  for (size_t i = 0; i < pixels; ++i)
    for (int c = 0; c < 3; ++c) sum[c] += srgbToLinear(t.rgba8[i * 4 + size_t(c)]);
  return glm::vec3(sum / double(pixels));
}

// The engine's materials as reflection hits shade them, and the texture table they index: base-colour textures
// as the engine's sRGB views (sampling decodes to linear), metallic-roughness textures as its UNORM views
// (G = roughness, B = metallic), each (texture, view) once. All in SHADER_READ_ONLY_OPTIMAL until the next
// loadScene (Engine::textures()).
void convertMaterials(const se::Scene& scene, std::span<const se::GpuTexture> gpuTextures,
                      std::vector<rb::Material>& materials, std::vector<VkImageView>& views) {
  materials.clear();
  views.clear();
  std::vector<uint32_t> slot(gpuTextures.size() * 2, rb::kNoTexture);  // [2 * texture + (srgb ? 0 : 1)]
  auto textureSlot = [&](int index, bool srgb) -> uint32_t {
    if (index < 0 || size_t(index) >= gpuTextures.size()) return rb::kNoTexture;
    const VkImageView view = srgb ? gpuTextures[size_t(index)].srgbView : gpuTextures[size_t(index)].unormView;
    if (!view) return rb::kNoTexture;  // no texels: the engine samples white, as the factor alone does
    uint32_t& s = slot[size_t(index) * 2 + (srgb ? 0 : 1)];
    if (s == rb::kNoTexture) {
      s = uint32_t(views.size());
      views.push_back(view);
    }
    return s;
  };
  for (const se::Material& m : scene.materials) {
    rb::Material out;
    for (int c = 0; c < 4; ++c) out.baseColor[c] = m.baseColorFactor[c];
    out.metallic = std::clamp(m.metallicFactor, 0.0f, 1.0f);
    out.roughness = std::clamp(m.roughnessFactor, 0.0f, 1.0f);
    out.baseColorTexture = textureSlot(m.baseColorTexture, true);
    out.metallicRoughnessTexture = textureSlot(m.metallicRoughnessTexture, false);
    glm::vec3 emissive = m.emissiveFactor;
    if (m.emissiveTexture >= 0 && size_t(m.emissiveTexture) < scene.textures.size())
      emissive *= averageSrgbDecoded(scene.textures[size_t(m.emissiveTexture)]);
    for (int c = 0; c < 3; ++c) out.emissive[c] = emissive[c];
    materials.push_back(out);
  }
}

rb::PassStats statsOf(const auto* pass) { return pass ? pass->stats() : rb::PassStats{}; }

}  // namespace

void configureEngine(se::EngineConfig& config, rb::RequiredFeatures& features) {
  for (const char* name : rb::requiredDeviceExtensions()) {
    bool present = false;
    for (const std::string& e : config.deviceExtensions) present = present || e == name;
    if (!present) config.deviceExtensions.emplace_back(name);
  }
  // The engine builds the core feature structs itself and takes the others as a chain: the SDK's helpers
  // split its requirements exactly that way.
  features.mergeVulkan12Into(config.extraFeatures12);
  config.deviceFeaturesPNext = features.extensionChain(const_cast<void*>(config.deviceFeaturesPNext));
  // A compute-only queue (where the device has one) for asynchronous BLAS work of deforming meshes.
  config.requestAsyncComputeQueue = true;
}

std::string effectsToString(EffectSet effects) {
  std::vector<std::string_view> names;
  if (effects & kEffectShadows) names.push_back("shadows");
  if (effects & kEffectAo) names.push_back("ao");
  if (effects & kEffectReflections) names.push_back("reflections");
  std::string out;
  for (size_t i = 0; i < names.size(); ++i) out.append(i ? "," : "").append(names[i]);
  return out;
}

std::string parseEffects(std::string_view text, EffectSet& out) {
  EffectSet set = 0;
  size_t start = 0;
  while (start <= text.size() && !text.empty()) {
    const size_t comma = text.find(',', start);
    const std::string_view item = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (item == "shadows") set |= kEffectShadows;
    else if (item == "ao") set |= kEffectAo;
    else if (item == "reflections") set |= kEffectReflections;
    else
      return std::string("'").append(item).append("' in '").append(text).append(
          "' is not an effect (shadows, ao, reflections)");
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  out = set;
  return {};
}

PresetDesc presetDesc(Preset preset) {
  switch (preset) {
    case Preset::Low: return {kEffectShadows | kEffectAo, false, 1, 4};
    case Preset::Medium: return {kEffectShadows | kEffectAo, true, 4, 4};
    case Preset::High: return {kAllEffects, true, 4, 4};
    case Preset::Ultra: return {kAllEffects, true, 8, 16};
    case Preset::ShadowsOnly: return {kEffectShadows, true, 4, 0};
    case Preset::AoOnly: return {kEffectAo, false, 1, 4};
    case Preset::ReflectionsOnly: return {kEffectReflections, false, 1, 0};
  }
  return {};
}

const char* toString(Preset preset) {
  switch (preset) {
    case Preset::Low: return "low";
    case Preset::Medium: return "medium";
    case Preset::High: return "high";
    case Preset::Ultra: return "ultra";
    case Preset::ShadowsOnly: return "shadows";
    case Preset::AoOnly: return "ao";
    case Preset::ReflectionsOnly: return "reflections";
  }
  return "?";
}

std::optional<Preset> parsePreset(std::string_view name) {
  for (int p = 0; p <= int(Preset::ReflectionsOnly); ++p)
    if (name == toString(Preset(p))) return Preset(p);
  return std::nullopt;
}

struct Adapter::Impl {
  se::Engine& engine;
  AdapterConfig config;
  FrameSettings settings;
  // Declared before what is created from it, so it is destroyed last. Disabled passes are destroyed at once:
  // the SDK defers the release of their Vulkan objects until the frames in flight are done.
  std::unique_ptr<rb::Context> ctx;
  std::unique_ptr<rb::AccelerationStructureService> as;
  std::unique_ptr<rb::ShadowPass> shadows;         // only with kEffectShadows
  std::unique_ptr<rb::AoPass> ao;                  // only with kEffectAo
  std::unique_ptr<rb::ReflectionPass> reflection;  // only with kEffectReflections
  std::unique_ptr<rb::Denoiser> shadowDenoiser;    // only for denoised soft shadows
  std::unique_ptr<rb::Denoiser> aoDenoiser;        // only for denoised AO
  std::vector<rb::MeshHandle> meshes;    // parallel to engine.meshes(); null for empty meshes
  std::vector<rb::MeshHandle> deformed;  // parallel to engine.deformedInstances(): dynamic BLASes
  std::vector<rb::Instance> instances;
  std::vector<uint32_t> instanceSource;  // Scene::instances index of each entry of `instances`
  std::vector<rb::Material> materials;  // the engine's materials, converted
  std::vector<VkImageView> textureViews;  // what rb::Material texture indices index (engine-owned views)
  bool materialsDirty = true;           // not yet given to the reflection pass
  rb::TlasInfo tlas;
  FrameImages images;
  std::string error;

  explicit Impl(se::Engine& e) : engine(e) {}
  EffectSet effects() const {  // what exists, so a failed setEffects never leaves flags and passes apart
    return (shadows ? kEffectShadows : 0u) | (ao ? kEffectAo : 0u) | (reflection ? kEffectReflections : 0u);
  }
  void fail(std::string message) {
    if (error.empty()) error = std::move(message);
  }
  se::Status updateDenoisers();
  se::Status updateDynamicMeshes(const se::PrepassHookInfo& info);
  rb::GBufferDesc describePrepass(const se::PrepassHookInfo& info, bool shadingNormals) const;
};

Adapter::Adapter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Adapter::~Adapter() {
  // The passes would not need it (the SDK defers their release), but ~AccelerationStructureService and
  // ~Context destroy what is left at once, and the engine's frames in flight may still use it; the engine
  // offers no finer wait than idle. Impl's members then go in reverse order: passes, service, context.
  (void)impl_->engine.waitIdle();
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

  rb::AsServiceDesc asDesc = config.accelerationStructures;
  if (asDesc.dynamicMode != rb::DynamicBuildMode::InFrame && !asDesc.asyncQueue) {
    asDesc.asyncQueue = engine.asyncComputeQueue();  // VK_NULL_HANDLE on one-queue devices: the SDK falls back
    asDesc.asyncQueueFamily = engine.asyncComputeQueueFamily();
  }
  auto as = rb::AccelerationStructureService::create(*impl->ctx, asDesc);
  if (!as) return R::failure(rbError("rb::AccelerationStructureService::create", as.error()));
  impl->as = std::move(as.value());

  std::unique_ptr<Adapter> adapter(new Adapter(std::move(impl)));
  if (se::Status s = adapter->syncScene(); !s) return R::failure(s.error);
  if (se::Status s = adapter->setEffects(config.effects); !s) return R::failure(s.error);
  return R::success(std::move(adapter));
}

se::Status Adapter::setEffects(EffectSet effects) {
  Impl& a = *impl_;
  if (effects & ~kAllEffects) return se::Status::failure("setEffects: unknown effect bits " + std::to_string(effects & ~kAllEffects));
  // Disable first (the SDK releases their memory after the frames in flight), then create the new ones.
  if (!(effects & kEffectShadows)) a.shadows.reset(), a.shadowDenoiser.reset();
  if (!(effects & kEffectAo)) a.ao.reset(), a.aoDenoiser.reset();
  if (!(effects & kEffectReflections)) a.reflection.reset();
  if ((effects & kEffectShadows) && !a.shadows) {
    auto p = rb::ShadowPass::create(*a.ctx);
    if (!p) return se::Status::failure(rbError("rb::ShadowPass::create", p.error()));
    a.shadows = std::move(p.value());
  }
  if ((effects & kEffectAo) && !a.ao) {
    auto p = rb::AoPass::create(*a.ctx);
    if (!p) return se::Status::failure(rbError("rb::AoPass::create", p.error()));
    a.ao = std::move(p.value());
  }
  if ((effects & kEffectReflections) && !a.reflection) {
    auto p = rb::ReflectionPass::create(*a.ctx);
    if (!p) return se::Status::failure(rbError("rb::ReflectionPass::create", p.error()));
    a.reflection = std::move(p.value());
    a.materialsDirty = true;
  }
  return se::Status::success();
}

EffectSet Adapter::effects() const { return impl_->effects(); }

se::Status Adapter::applyPreset(Preset preset, float sunAngularRadiusDegrees) {
  const PresetDesc d = presetDesc(preset);
  if (se::Status s = setEffects(d.effects); !s) return s;
  FrameSettings& f = impl_->settings;
  if (d.effects & kEffectShadows) {
    f.sunAngularRadiusDegrees = d.softShadows ? sunAngularRadiusDegrees : 0.0f;
    f.shadowRaysPerPixel = d.shadowRaysPerPixel;
  }
  if (d.effects & kEffectAo) f.aoRaysPerPixel = d.aoRaysPerPixel;
  return se::Status::success();
}

namespace {

// The engine's buffers as a Raybridge mesh: positions R32G32B32_SFLOAT, uint32 indices (or none), attributes
// interleaved {vec3 normal; vec2 uv; vec4 tangent}.
rb::MeshDesc describeMesh(VkDeviceAddress positions, uint32_t positionStride, uint32_t vertexCount,
                          const se::GpuMesh& topology, VkDeviceAddress attributes, uint32_t attributeStride) {
  rb::MeshDesc d;
  d.vertexAddress = positions;
  d.vertexBufferBytes = VkDeviceSize(vertexCount) * positionStride;
  d.vertexCount = vertexCount;
  d.vertexFormat = topology.positionFormat;
  d.vertexStride = positionStride;
  d.indexType = topology.indexCount ? rb::IndexType::Uint32 : rb::IndexType::None;
  d.indexAddress = topology.indexAddress;
  d.indexBufferBytes = VkDeviceSize(topology.indexCount) * sizeof(uint32_t);
  d.triangleCount = (topology.indexCount ? topology.indexCount : vertexCount) / 3;
  if (attributes) {
    d.normalAddress = attributes;
    d.normalStride = attributeStride;
    d.texcoordAddress = attributes + 12;
    d.texcoordStride = attributeStride;
  }
  if (topology.cpu) d.debugName = topology.cpu->name.c_str();
  return d;
}

void toRowMajor3x4(const glm::mat4& m, float out[12]) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) out[r * 4 + c] = m[c][r];  // GLM is column-major
}

}  // namespace

se::Status Adapter::syncScene() {
  Impl& a = *impl_;
  for (rb::MeshHandle h : a.meshes) {
    if (!h.isNull()) (void)a.as->releaseMesh(h);
  }
  for (rb::MeshHandle h : a.deformed) (void)a.as->releaseMesh(h);
  a.meshes.clear();
  a.deformed.clear();
  a.instances.clear();
  a.instanceSource.clear();
  const se::Scene& scene = a.engine.scene();
  const std::span<const se::GpuMesh> meshes = a.engine.meshes();
  for (size_t i = 0; i < meshes.size(); ++i) {
    const se::GpuMesh& m = meshes[i];
    if ((m.indexCount ? m.indexCount : m.vertexCount) / 3 == 0) {
      a.meshes.push_back({});
      continue;
    }
    if (m.positionAddress == 0) {
      return se::Status::failure("mesh " + std::to_string(i) +
                                 " has no device address: create the engine with "
                                 "EngineConfig::enableRayTracingInputs and rbAdapter::configureEngine()");
    }
    rb::MeshDesc d = describeMesh(m.positionAddress, m.positionStride, m.vertexCount, m, m.attributeAddress,
                                  m.attributeStride);
    if (m.cpu) {  // content-hash dedup of identical static meshes
      d.hostVertices = m.cpu->positions.data();
      d.hostIndices = m.cpu->indices.empty() ? nullptr : m.cpu->indices.data();
    }
    auto handle = a.as->registerMesh(d);
    if (!handle) return se::Status::failure(rbError("registerMesh", handle.error()));
    a.meshes.push_back(handle.value());
  }
  // Deforming instances (skinned, morphed) trace their own deformed buffers, one dynamic BLAS each.
  std::vector<rb::MeshHandle> byInstance(scene.instances.size());
  for (const se::DeformedInstance& di : a.engine.deformedInstances()) {
    rb::MeshDesc d = describeMesh(di.positionAddress, 12, di.vertexCount, meshes[di.mesh], di.attributeAddress, 36);
    d.role = rb::MeshRole::Dynamic;
    auto handle = a.as->registerMesh(d);
    if (!handle) return se::Status::failure(rbError("registerMesh (deformed instance)", handle.error()));
    a.deformed.push_back(handle.value());
    byInstance[di.instance] = handle.value();
  }
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const se::Instance& inst = scene.instances[i];
    rb::Instance out;
    out.mesh = byInstance[i].isNull() && inst.mesh < a.meshes.size() ? a.meshes[inst.mesh] : byInstance[i];
    if (out.mesh.isNull()) continue;
    toRowMajor3x4(inst.transform, out.transform);
    out.customIndex = inst.mesh;
    out.material = meshes[inst.mesh].material;
    a.instances.push_back(out);
    a.instanceSource.push_back(uint32_t(i));
  }
  convertMaterials(scene, a.engine.textures(), a.materials, a.textureViews);
  if (a.materials.empty()) a.materials.emplace_back();
  for (rb::Instance& inst : a.instances) inst.material = std::min<uint32_t>(inst.material, uint32_t(a.materials.size() - 1));
  a.materialsDirty = true;
  return se::Status::success();
}

se::Status Adapter::Impl::updateDynamicMeshes(const se::PrepassHookInfo& info) {
  // This frame's node animation moves instances; deformation rewrote the deformed buffers.
  if (info.instanceTransforms.size() == engine.scene().instances.size())
    for (size_t k = 0; k < instances.size(); ++k) toRowMajor3x4(info.instanceTransforms[instanceSource[k]], instances[k].transform);
  if (deformed.empty() || !settings.updateDeformedMeshes) return se::Status::success();
  for (rb::MeshHandle h : deformed)
    if (rb::Status s = as->updateMesh(h); !s) return se::Status::failure(rbError("updateMesh", s.error()));
  if (rb::Status s = as->submitDynamicWork({info.deformSemaphore, info.deformValue}); !s)
    return se::Status::failure(rbError("submitDynamicWork", s.error()));
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  if (as->fillTlasWait(wait) && info.submitWaits) info.submitWaits->push_back(wait);
  if (as->fillVertexReuseWait(wait) && info.deformWaits) info.deformWaits->push_back(wait);
  return se::Status::success();
}

se::Status Adapter::Impl::updateDenoisers() {
  const bool wantShadow = shadows && settings.denoise && settings.sunAngularRadiusDegrees > 0.0f;
  const bool wantAo = ao && settings.denoise;
  if (!wantShadow) shadowDenoiser.reset();
  if (!wantAo) aoDenoiser.reset();
  for (auto [want, denoiser] : {std::pair{wantShadow, &shadowDenoiser}, {wantAo, &aoDenoiser}}) {
    if (!want || *denoiser) continue;
    auto d = rb::Denoiser::create(*ctx);
    if (!d) return se::Status::failure(rbError("rb::Denoiser::create", d.error()));
    *denoiser = std::move(d.value());
  }
  return se::Status::success();
}

rb::GBufferDesc Adapter::Impl::describePrepass(const se::PrepassHookInfo& info, bool shadingNormals) const {
  rb::GBufferDesc g;
  g.width = info.extent.width;
  g.height = info.extent.height;
  g.depth = {info.depth.view, info.depth.layout};  // D32_SFLOAT, DEPTH_READ_ONLY_OPTIMAL
  g.depthFormat = info.depth.format;
  g.depthConvention = info.reversedZ ? rb::DepthConvention::ReversedZ : rb::DepthConvention::Standard;
  g.normalEncoding = rb::NormalEncoding::WorldFloat;
  g.geometricNormal = {info.geometricNormal.view, info.geometricNormal.layout};  // w = metallic, unused
  if (shadingNormals) {
    g.normal = {info.normalRoughness.view, info.normalRoughness.layout};
    g.roughnessInNormalW = true;  // perceptual roughness in normalRoughness.w
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
  a.images = {};
  if (!a.settings.enabled || a.effects() == 0) return;
  VkCommandBuffer cmd = info.commandBuffer;
  if (se::Status s = a.updateDenoisers(); !s) return a.fail(s.error);
  if (a.reflection && a.materialsDirty) {
    if (rb::Status s = a.reflection->setMaterials(a.materials, a.textureViews); !s) return a.fail(rbError("setMaterials", s.error()));
    a.materialsDirty = false;
  }

  if (se::Status st = a.updateDynamicMeshes(info); !st) return a.fail(st.error);
  if (auto pending = a.as->recordPendingWork(cmd); !pending) return a.fail(rbError("recordPendingWork", pending.error()));
  rb::TlasBuildOptions options;
  for (int i = 0; i < 3; ++i) options.originOffset[i] = double(info.cameraPosition[i]);
  options.writeShadingRecords = a.reflection != nullptr;  // vertex data + material per instance, for hits
  auto tlas = a.as->recordTlasBuild(cmd, a.instances, options);
  if (!tlas) return a.fail(rbError("recordTlasBuild", tlas.error()));
  a.tlas = tlas.value();

  const FrameSettings& f = a.settings;
  const rb::GBufferDesc gbuffer = a.describePrepass(info, a.config.normals == GBufferNormals::Shading);
  if (a.shadows) {
    rb::Light sun;
    sun.type = rb::LightType::Directional;
    for (int i = 0; i < 3; ++i) sun.direction[i] = info.sunDirection[i];
    sun.angularRadiusDegrees = f.sunAngularRadiusDegrees;
    rb::ShadowSettings s;
    s.raysPerPixel = f.shadowRaysPerPixel;
    if (rb::Status st = a.shadows->record(cmd, gbuffer, a.tlas, sun, s); !st)
      return a.fail(rbError("ShadowPass::record", st.error()));
    const rb::ShadowOutputs& out = a.shadows->outputs();
    a.images.shadowRaw = a.images.shadow = out.visibility;
    inputs.sunVisibility = out.visibilityView;  // SHADER_READ_ONLY_OPTIMAL
    if (a.shadowDenoiser) {
      rb::DenoiseSettings d = f.denoiser;  // the visibility is a fraction of this many binary rays
      d.raysPerPixel = s.raysPerPixel ? s.raysPerPixel : 4u;
      if (rb::Status st = a.shadowDenoiser->record(cmd, gbuffer, out.visibilityView, d); !st)
        return a.fail(rbError("Denoiser::record (shadows)", st.error()));
      a.images.shadow = a.shadowDenoiser->outputs().denoised;
      inputs.sunVisibility = a.shadowDenoiser->outputs().denoisedView;
    }
  }
  if (a.ao) {
    rb::AoSettings s;
    s.raysPerPixel = f.aoRaysPerPixel;
    s.range = f.aoRange;
    s.estimator = f.aoEstimator;
    if (rb::Status st = a.ao->record(cmd, gbuffer, a.tlas, s); !st) return a.fail(rbError("AoPass::record", st.error()));
    const rb::AoOutputs& out = a.ao->outputs();
    a.images.aoRaw = a.images.ao = out.ao;
    inputs.ambientOcclusion = out.aoView;
    if (a.aoDenoiser) {
      rb::DenoiseSettings d = f.denoiser;
      // Binary AO is a fraction of binary rays; distance-weighted AO is not, so its noise is estimated.
      if (s.estimator == rb::AoEstimator::Binary) d.raysPerPixel = s.raysPerPixel ? s.raysPerPixel : 4u;
      if (rb::Status st = a.aoDenoiser->record(cmd, gbuffer, out.aoView, d); !st)
        return a.fail(rbError("Denoiser::record (AO)", st.error()));
      a.images.ao = a.aoDenoiser->outputs().denoised;
      inputs.ambientOcclusion = a.aoDenoiser->outputs().denoisedView;
    }
  }
  if (a.reflection) {
    // Roughness lives in normalRoughness.w, so reflections always read the shading G-buffer.
    const rb::GBufferDesc shading =
        a.config.normals == GBufferNormals::Shading ? gbuffer : a.describePrepass(info, true);
    rb::ReflectionSettings s;
    s.roughnessThreshold = f.reflectionRoughnessThreshold;
    s.raysPerPixel = f.reflectionRaysPerPixel;
    for (int i = 0; i < 3; ++i) {
      s.sunDirection[i] = info.sunDirection[i];
      s.sunRadiance[i] = f.sunRadiance[i];
      s.skyRadiance[i] = f.skyColor[i];
    }
    s.ambientIntensity = f.ambientIntensity > 0.0f ? f.ambientIntensity : 1e-6f;  // 0 would mean the default
    if (rb::Status st = a.reflection->record(cmd, shading, a.tlas, s); !st)
      return a.fail(rbError("ReflectionPass::record", st.error()));
    a.images.reflection = a.reflection->outputs().radiance;
    inputs.reflection = a.reflection->outputs().radianceView;
  }
}

void Adapter::releaseAfterIdle() { impl_->ctx->releaseAfterIdle(); }

void Adapter::resetHistory() {
  if (impl_->shadowDenoiser) impl_->shadowDenoiser->resetHistory();
  if (impl_->aoDenoiser) impl_->aoDenoiser->resetHistory();
}

se::PrepassHook Adapter::prepassHook() {
  return [this](const se::PrepassHookInfo& info, se::LightingInputs& inputs) { recordFrame(info, inputs); };
}

FrameSettings& Adapter::settings() { return impl_->settings; }
const std::string& Adapter::lastError() const { return impl_->error; }
rb::Context& Adapter::context() { return *impl_->ctx; }
rb::AccelerationStructureService& Adapter::accelerationStructures() { return *impl_->as; }
const rb::ShadowPass* Adapter::shadowPass() const { return impl_->shadows.get(); }
const rb::AoPass* Adapter::aoPass() const { return impl_->ao.get(); }
const rb::ReflectionPass* Adapter::reflectionPass() const { return impl_->reflection.get(); }
const rb::Denoiser* Adapter::shadowDenoiser() const { return impl_->shadowDenoiser.get(); }
const rb::Denoiser* Adapter::aoDenoiser() const { return impl_->aoDenoiser.get(); }
EffectStats Adapter::stats() const {
  const Impl& a = *impl_;
  return {statsOf(a.shadows.get()), statsOf(a.shadowDenoiser.get()), statsOf(a.ao.get()), statsOf(a.aoDenoiser.get()),
          statsOf(a.reflection.get())};
}
const FrameImages& Adapter::lastImages() const { return impl_->images; }
const rb::TlasInfo& Adapter::lastTlas() const { return impl_->tlas; }
uint32_t Adapter::sceneInstances() const { return uint32_t(impl_->instances.size()); }

}  // namespace rbAdapter

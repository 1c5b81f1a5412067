// Raybridge <-> sample engine: device setup, scene registration and the pre-pass hook (see the header).
#include "raybridge_sample_engine_adapter.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace rbAdapter {
namespace se = sample_engine;
namespace {

// glTF's MASK cutoff 0 cuts nothing; rb::Material's 0 means its default (0.5): the smallest cutoff that still
// cuts nothing stands for glTF's 0.
constexpr float kSmallestAlphaCutoff = 1e-6f;
// The UVs' offset in the engine's interleaved attributes {vec3 normal; vec2 uv; vec4 tangent} (engine.h).
constexpr VkDeviceSize kTexcoordOffset = 3 * sizeof(float);
static_assert(uint32_t(se::AlphaMode::Mask) == uint32_t(rb::AlphaMode::Mask) &&
              uint32_t(se::AlphaMode::Blend) == uint32_t(rb::AlphaMode::Blend));

std::string message(const char* what, const rb::Error& e) {
  return std::string(what) + ": " + rb::toString(e.code) + ": " + e.message;
}
se::Status failure(const char* what, const rb::Error& e) { return se::Status::failure(message(what, e)); }
void keepFirst(std::string& error, std::string message) {
  if (error.empty()) error = std::move(message);
}

// A pre-pass image as Raybridge's hand-over: its view, layout and format stated, at the viewport's size (every
// pre-pass image has it), so Raybridge checks them before it records anything.
rb::GBufferImage gbufferImage(const se::PassImage& image, VkExtent2D extent) {
  return {.view = image.view,
          .layout = image.layout,
          .format = image.format,
          .width = extent.width,
          .height = extent.height};
}

// The engine's materials as reflection hits shade them, and the texture table they index: base colour and
// emissive as the engine's sRGB views, metallic-roughness as its UNORM views (G = roughness, B = metallic).
void convertMaterials(const se::Scene& scene, std::span<const se::GpuTexture> gpu, std::vector<rb::Material>& out,
                      std::vector<VkImageView>& views) {
  out.clear(), views.clear();
  auto slot = [&](int index, bool srgb) -> uint32_t {
    if (index < 0 || size_t(index) >= gpu.size()) return rb::kNoTexture;
    const VkImageView view = srgb ? gpu[size_t(index)].srgbView : gpu[size_t(index)].unormView;
    if (!view) return rb::kNoTexture;  // no texels: the engine samples white, as the factor alone does
    if (std::find(views.begin(), views.end(), view) == views.end()) views.push_back(view);
    return uint32_t(std::find(views.begin(), views.end(), view) - views.begin());
  };
  for (const se::Material& m : scene.materials) {
    rb::Material r;
    std::memcpy(r.baseColor, &m.baseColorFactor[0], sizeof(r.baseColor));
    r.metallic = std::clamp(m.metallicFactor, 0.0f, 1.0f);
    r.roughness = std::clamp(m.roughnessFactor, 0.0f, 1.0f);
    r.baseColorTexture = slot(m.baseColorTexture, true);
    r.metallicRoughnessTexture = slot(m.metallicRoughnessTexture, false);
    r.emissiveTexture = slot(m.emissiveTexture, true);
    std::memcpy(r.emissive, &m.emissiveFactor[0], sizeof(r.emissive));
    // Cut-outs and blending (same enumerator order), with the UVs the engine samples (texture transforms baked).
    r.alphaMode = rb::AlphaMode(uint32_t(m.alphaMode));
    r.alphaCutoff = m.alphaMode == se::AlphaMode::Mask ? std::max(m.alphaCutoff, kSmallestAlphaCutoff) : 0.0f;
    out.push_back(r);
  }
  if (out.empty()) out.emplace_back();
}

// The engine's buffers as a Raybridge mesh: positions R32G32B32_SFLOAT, uint32 indices (or none), attributes
// interleaved {vec3 normal; vec2 uv; vec4 tangent}.
rb::MeshDesc describeMesh(VkDeviceAddress positions, uint32_t positionStride, uint32_t vertexCount,
                          const se::GpuMesh& topology, VkDeviceAddress attributes, uint32_t attributeStride) {
  rb::MeshDesc d;  // a dynamic mesh's deformed buffers have the same topology (indices) as its source mesh
  d.vertexAddress = positions, d.vertexBufferBytes = VkDeviceSize(vertexCount) * positionStride;
  d.vertexCount = vertexCount, d.vertexFormat = topology.positionFormat, d.vertexStride = positionStride;
  d.indexType = topology.indexCount ? rb::IndexType::Uint32 : rb::IndexType::None;
  d.indexAddress = topology.indexAddress, d.indexBufferBytes = VkDeviceSize(topology.indexCount) * sizeof(uint32_t);
  d.triangleCount = (topology.indexCount ? topology.indexCount : vertexCount) / 3;
  if (attributes) d.normalAddress = attributes, d.texcoordAddress = attributes + kTexcoordOffset;
  d.normalStride = d.texcoordStride = attributeStride;
  if (topology.cpu) d.debugName = topology.cpu->name.c_str();
  return d;
}

// Meshes whose material cuts out or blends run the SDK's any-hit shaders; the others keep the opaque fast path.
bool nonOpaque(const se::Scene& scene, const se::GpuMesh& mesh) {
  return mesh.material < scene.materials.size() && scene.materials[mesh.material].alphaMode != se::AlphaMode::Opaque;
}

// This frame's KHR_lights_punctual lights as the SDK's light list. The engine's direction is the way the light
// travels (node -Z); the SDK's directional light points towards the light. Angles: radians -> degrees.
void convertLights(std::span<const se::FrameLight> lights, std::vector<rb::LightSource>& out) {
  out.resize(lights.size());
  for (size_t i = 0; i < lights.size(); ++i) {
    const se::FrameLight& l = lights[i];
    rb::LightSource& r = out[i];
    r.light.type = l.type == se::PunctualLight::Type::Directional ? rb::LightType::Directional
                   : l.type == se::PunctualLight::Type::Spot      ? rb::LightType::Spot
                                                                  : rb::LightType::Point;
    const glm::vec3 d = r.light.type == rb::LightType::Directional ? -l.direction : l.direction;
    std::copy_n(&d[0], 3, r.light.direction);
    std::copy_n(&l.position[0], 3, r.light.position);
    r.light.range = l.range;
    r.light.spotOuterAngleDegrees = glm::degrees(l.outerConeAngle);
    r.spotInnerAngleDegrees = glm::degrees(l.innerConeAngle);
    std::copy_n(&l.color[0], 3, r.color);
    r.intensity = l.intensity;
  }
}

}  // namespace

void configureEngine(se::EngineConfig& config, rb::RequiredFeatures& features, rb::OptionalFeatures* optional) {
  // Shader execution reordering where the device has it: the engine fills the struct with what is supported.
  if (optional)
    config.optionalDeviceExtensions.push_back({rb::kInvocationReorderExtension, &optional->invocationReorder});
  for (const char* name : rb::requiredDeviceExtensions())
    if (std::ranges::find(config.deviceExtensions, name) == config.deviceExtensions.end())
      config.deviceExtensions.emplace_back(name);
  // The engine builds the core feature structs itself and takes the others as a chain, as the SDK splits them.
  features.mergeVulkan12Into(config.extraFeatures12);
  config.deviceFeaturesPNext = features.extensionChain(const_cast<void*>(config.deviceFeaturesPNext));
  config.requestAsyncComputeQueue = true;  // for asynchronous BLAS work of deforming meshes, where there is one
}

struct Adapter::Impl {
  se::Engine& engine;
  AdapterConfig config;
  FrameSettings settings;
  // Declared in creation order, so they are destroyed in reverse: front end, service, context.
  std::unique_ptr<rb::Context> ctx;
  std::unique_ptr<rb::AccelerationStructureService> as;
  std::unique_ptr<rb::HybridEffects> fx;
  // Ray-traced mode: the materials hits shade with, the pass, and the local lights' list (no G-buffer to cull).
  std::unique_ptr<rb::MaterialTable> materials;
  std::unique_ptr<rb::PrimaryShadingPass> shading;
  std::unique_ptr<rb::LightList> lightList;
  rb::TlasInfo tlas;                           // ray-traced mode's latest
  std::vector<rb::MeshHandle> meshes;          // parallel to engine.meshes(); null for empty meshes
  std::vector<rb::MeshHandle> deformed;        // parallel to engine.deformedInstances(): dynamic BLASes
  std::vector<rb::MeshBounds> deformedBounds;  // their pose boxes this frame: where the denoisers restart
  std::vector<rb::Instance> instances;
  std::vector<uint32_t> instanceSource;  // Scene::instances index of each entry of `instances`
  std::vector<rb::LightSource> lights;   // this frame's punctual lights (local lights effect)
  std::string error;

  explicit Impl(se::Engine& e) : engine(e) {}
};

Adapter::Adapter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Adapter::~Adapter() { (void)impl_->engine.waitIdle(); }

se::Result<std::unique_ptr<Adapter>> Adapter::create(se::Engine& engine, const AdapterConfig& config) {
  using R = se::Result<std::unique_ptr<Adapter>>;
  auto impl = std::make_unique<Impl>(engine);
  impl->config = config;
  rb::ContextDesc cd{engine.instance(),   engine.physicalDevice(),
                     engine.device(),     engine.getInstanceProcAddr(),
                     se::kFramesInFlight, nullptr,
                     engine.queueFamily()};
  // configureEngine's optional extension: the engine enabled it with every feature the device supports, so the
  // feature is on exactly where the device has it.
  cd.invocationReorderEnabled = std::ranges::find(engine.enabledDeviceExtensions(), rb::kInvocationReorderExtension) !=
                                    engine.enabledDeviceExtensions().end() &&
                                rb::supportsInvocationReorder(engine.instance(), engine.physicalDevice(),
                                                              engine.getInstanceProcAddr());
  auto ctx = rb::Context::create(cd);
  if (!ctx) return R::failure(message("rb::Context::create", ctx.error()));
  impl->ctx = std::move(ctx.value());
  rb::AsServiceDesc asDesc = config.accelerationStructures;
  if (asDesc.dynamicMode != rb::DynamicBuildMode::InFrame && !asDesc.asyncQueue)
    asDesc.asyncQueue = engine.asyncComputeQueue(), asDesc.asyncQueueFamily = engine.asyncComputeQueueFamily();
  auto as = rb::AccelerationStructureService::create(*impl->ctx, asDesc);
  if (!as) return R::failure(message("rb::AccelerationStructureService::create", as.error()));
  impl->as = std::move(as.value());
  rb::HybridEffectsDesc fxDesc = config.effects;
  if (config.preset != rb::Preset::None) fxDesc = rb::withPreset(fxDesc, config.preset);
  auto fx = rb::HybridEffects::create(*impl->ctx, impl->as.get(), fxDesc);
  if (!fx) return R::failure(message("rb::HybridEffects::create", fx.error()));
  impl->fx = std::move(fx.value());
  if (config.rayTraced) {
    if (impl->fx->desc().effects != 0)
      return R::failure("AdapterConfig::rayTraced: the effects " + std::to_string(impl->fx->desc().effects) +
                        " (rb::EffectSet) need the G-buffer ray-traced mode does not draw; leave them empty");
    auto table = rb::MaterialTable::create(*impl->ctx);
    if (!table) return R::failure(message("rb::MaterialTable::create", table.error()));
    impl->materials = std::move(table.value());
    auto pass = rb::PrimaryShadingPass::create(*impl->ctx);
    if (!pass) return R::failure(message("rb::PrimaryShadingPass::create", pass.error()));
    impl->shading = std::move(pass.value());
  }
  std::unique_ptr<Adapter> adapter(new Adapter(std::move(impl)));
  if (se::Status s = adapter->syncScene(); !s) return R::failure(s.error);
  return R::success(std::move(adapter));
}

se::Status Adapter::syncScene() {
  Impl& a = *impl_;
  for (auto* list : {&a.meshes, &a.deformed})
    for (rb::MeshHandle h : *list) (void)a.as->releaseMesh(h);  // null handles (empty meshes) fail harmlessly
  a.meshes.clear(), a.deformed.clear(), a.instances.clear(), a.instanceSource.clear();
  const se::Scene& scene = a.engine.scene();
  const std::span<const se::GpuMesh> meshes = a.engine.meshes();
  for (size_t i = 0; i < meshes.size(); ++i) {
    const se::GpuMesh& m = meshes[i];
    a.meshes.emplace_back();
    if ((m.indexCount ? m.indexCount : m.vertexCount) / 3 == 0) continue;
    if (m.positionAddress == 0)
      return se::Status::failure("mesh " + std::to_string(i) +
                                 " has no device address: create the engine with "
                                 "EngineConfig::enableRayTracingInputs and rbAdapter::configureEngine()");
    rb::MeshDesc d = describeMesh(m.positionAddress, m.positionStride, m.vertexCount, m, m.attributeAddress,
                                  m.attributeStride);
    d.nonOpaque = nonOpaque(scene, m);
    if (m.cpu) d.hostVertices = m.cpu->positions.data();  // content-hash dedup of identical static meshes
    if (m.cpu && !m.cpu->indices.empty()) d.hostIndices = m.cpu->indices.data();
    auto handle = a.as->registerMesh(d);
    if (!handle) return failure("registerMesh", handle.error());
    a.meshes.back() = handle.value();
  }
  // Deforming instances (skinned, morphed) trace their own deformed buffers, one dynamic BLAS each.
  std::vector<rb::MeshHandle> byInstance(scene.instances.size());
  for (const se::DeformedInstance& di : a.engine.deformedInstances()) {
    rb::MeshDesc d = describeMesh(di.positionAddress, 12, di.vertexCount, meshes[di.mesh], di.attributeAddress, 36);
    d.role = rb::MeshRole::Dynamic;
    d.nonOpaque = nonOpaque(scene, meshes[di.mesh]);
    auto handle = a.as->registerMesh(d);
    if (!handle) return failure("registerMesh (deforming instance)", handle.error());
    a.deformed.push_back(byInstance[di.instance] = handle.value());
  }
  std::vector<rb::Material> materials;  // and the texture views they index
  std::vector<VkImageView> views;
  convertMaterials(scene, a.engine.textures(), materials, views);
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const se::Instance& inst = scene.instances[i];
    rb::Instance out;
    out.mesh = byInstance[i].isNull() && inst.mesh < a.meshes.size() ? a.meshes[inst.mesh] : byInstance[i];
    if (out.mesh.isNull()) continue;
    out.setTransformColumnMajor(&inst.transform[0][0]);
    out.customIndex = inst.mesh;
    out.material = std::min<uint32_t>(meshes[inst.mesh].material, uint32_t(materials.size() - 1));
    a.instances.push_back(out);
    a.instanceSource.push_back(uint32_t(i));
  }
  if (rb::Status s = a.fx->setMaterials(materials, views); !s) return failure("HybridEffects::setMaterials", s.error());
  if (a.materials)
    if (rb::Status s = a.materials->setMaterials(materials, views); !s)
      return failure("MaterialTable::setMaterials", s.error());
  return se::Status::success();
}

void Adapter::recordFrame(const se::PrepassHookInfo& info, se::LightingInputs& inputs) {
  Impl& a = *impl_;
  a.ctx->beginFrame();  // every frame, so deferred releases and statistics keep pace with the engine
  if (!a.settings.enabled || (a.fx->desc().effects == 0 && !a.shading)) return;
  // This frame's node animation moves instances; deformation rewrote the deformed buffers.
  if (info.instanceTransforms.size() == a.engine.scene().instances.size())
    for (size_t k = 0; k < a.instances.size(); ++k)
      a.instances[k].setTransformColumnMajor(&info.instanceTransforms[a.instanceSource[k]][0][0]);
  const rb::AsyncBuildWait ready{info.deformSemaphore, info.deformValue};  // this frame's deformation
  if (!a.deformed.empty() && a.settings.updateDeformedMeshes) {
    a.deformedBounds.resize(a.deformed.size());
    for (size_t k = 0; k < a.deformed.size(); ++k) {
      const se::DeformedInstance& di = a.engine.deformedInstances()[k];
      std::memcpy(a.deformedBounds[k].min, &di.boundsMin[0], sizeof(float) * 3);
      std::memcpy(a.deformedBounds[k].max, &di.boundsMax[0], sizeof(float) * 3);
    }
    if (rb::Status s = a.as->updateDynamicMeshes(a.deformed, ready, info.submitWaits, info.deformWaits,
                                                 a.deformedBounds);
        !s)
      return keepFirst(a.error, message("updateDynamicMeshes", s.error()));
  }
  if (a.shading) return recordRayTraced(info);
  rb::HybridFrame f;
  rb::GBufferDesc& g = f.gbuffer;
  g.width = info.extent.width, g.height = info.extent.height;
  g.depth = gbufferImage(info.depth, info.extent), g.depthFormat = info.depth.format;  // DEPTH_READ_ONLY_OPTIMAL
  g.depthConvention = info.reversedZ ? rb::DepthConvention::ReversedZ : rb::DepthConvention::Standard;
  g.geometricNormal = gbufferImage(info.geometricNormal, info.extent);  // w = metallic, unused
  // Pixels, current - previous: the denoisers follow moving and skinned objects, not only the camera.
  g.motionVectors = gbufferImage(info.motionVectors, info.extent);
  std::memcpy(g.view, &info.view[0][0], sizeof(g.view));
  std::memcpy(g.projection, &info.proj[0][0], sizeof(g.projection));
  for (int i = 0; i < 3; ++i) g.cameraPosition[i] = info.cameraPositionD[i];  // camera-relative TLAS and rays
  rb::GBufferDesc shading = g;  // roughness lives in normalRoughness.w: reflections read the shading normals
  shading.normal = gbufferImage(info.normalRoughness, info.extent);
  shading.roughnessInNormalW = true;
  g.normal = a.config.geometricNormals ? g.geometricNormal : shading.normal;
  g.roughnessInNormalW = !a.config.geometricNormals;
  f.reflectionGBuffer = &shading;
  f.instances = a.instances;
  std::copy_n(&info.sunDirection[0], 3, f.light.direction);
  std::copy_n(&info.sunRadiance[0], 3, f.lighting.sunRadiance);
  std::copy_n(&info.skyColor[0], 3, f.lighting.skyRadiance);
  f.lighting.ambientIntensity = info.ambientIntensity;
  f.lighting.explicitValues = true;  // the engine's own values, zeros included
  if (a.fx->desc().effects & rb::kEffectLocalLights) convertLights(info.lights, a.lights), f.localLights = a.lights;
  if (rb::Status s = a.fx->record(info.commandBuffer, f); !s)
    return keepFirst(a.error, message("HybridEffects::record", s.error()));
  // SHADER_READ_ONLY_OPTIMAL, as LightingInputs requires. An effect that is off names a neutral image; the
  // engine's own term (its shadow map, its lights) stands in for it instead.
  const rb::HybridOutputs& out = a.fx->outputs();
  const rb::EffectSet on = a.fx->desc().effects;
  inputs.sunVisibility = (on & rb::kEffectShadows) ? out.shadow.view : VK_NULL_HANDLE;
  inputs.ambientOcclusion = (on & rb::kEffectAo) ? out.ao.view : VK_NULL_HANDLE;
  inputs.reflection = (on & rb::kEffectReflections) ? out.reflection.view : VK_NULL_HANDLE;
  // Replaces the engine's local lights and their shadow maps.
  inputs.localLightIrradiance = (on & rb::kEffectLocalLights) ? out.localLights.view : VK_NULL_HANDLE;
}

void Adapter::recordRayTraced(const se::PrepassHookInfo& info) {
  Impl& a = *impl_;
  if (!info.hdrColor.view)
    return keepFirst(a.error, "ray-traced mode: the frame has no HDR target to shade into; render it with "
                              "FrameParams::externalColor");
  if (auto pending = a.as->recordPendingWork(info.commandBuffer); !pending)
    return keepFirst(a.error, message("recordPendingWork", pending.error()));
  // Camera-relative TLAS around the float eye the camera below starts from, so the eye is exactly its origin.
  rb::TlasBuildOptions options;
  options.mode = a.fx->desc().tlasMode;
  for (int i = 0; i < 3; ++i) options.originOffset[i] = double(info.cameraPosition[i]);
  options.writeShadingRecords = true;  // hits shade with the materials
  auto tlas = a.as->recordTlasBuild(info.commandBuffer, a.instances, options);
  if (!tlas) return keepFirst(a.error, message("recordTlasBuild", tlas.error()));
  a.tlas = tlas.value();
  rb::PrimaryShadingSettings s;
  if (!info.lights.empty() && !a.lightList) {  // made by the first frame with lights
    auto lights = rb::LightList::create(*a.ctx);
    if (!lights) return keepFirst(a.error, message("rb::LightList::create", lights.error()));
    a.lightList = std::move(lights.value());
  }
  if (a.lightList) {
    convertLights(info.lights, a.lights);
    if (rb::Status st = a.lightList->record(info.commandBuffer, a.tlas, a.lights); !st)
      return keepFirst(a.error, message("LightList::record", st.error()));
    s.lights = a.lightList.get();
  }
  // The engine's camera: eye, its view direction and up (rotation-only view), and the field of view of its
  // projection (proj[1][1] = -1 / tan(fovY / 2), Y flipped). The target is as far as the eye is from the origin
  // (at least 1), so its direction keeps float precision far from the origin.
  const glm::mat3 toWorld(info.invView);
  const glm::vec3 forward = -toWorld[2], up = toWorld[1];
  const float reach = std::max(1.0f, glm::length(info.cameraPosition));
  rb::PrimaryRayCamera camera;
  for (int i = 0; i < 3; ++i) {
    camera.eye[i] = info.cameraPosition[i];
    camera.target[i] = info.cameraPosition[i] + forward[i] * reach;
    camera.upHint[i] = up[i];
  }
  camera.verticalFovDegrees = glm::degrees(2.0f * std::atan(1.0f / std::abs(info.proj[1][1])));
  std::copy_n(&info.sunDirection[0], 3, s.lighting.sunDirection);
  std::copy_n(&info.sunRadiance[0], 3, s.lighting.sunRadiance);
  std::copy_n(&info.skyColor[0], 3, s.lighting.skyRadiance);
  s.lighting.ambientIntensity = info.ambientIntensity;
  s.lighting.explicitValues = true;  // the engine's own values, zeros included
  s.materials = a.materials.get();
  rb::PrimaryShadingTargets targets;
  targets.width = info.extent.width, targets.height = info.extent.height;
  targets.radiance = info.hdrColor.view;  // GENERAL, as the engine hands it over and wants it back
  if (rb::Status st = a.shading->record(info.commandBuffer,
                                        {.tlas = a.tlas, .camera = camera, .targets = targets, .settings = s});
      !st)
    return keepFirst(a.error, message("PrimaryShadingPass::record", st.error()));
}

se::PrepassHook Adapter::prepassHook() {
  return [this](const se::PrepassHookInfo& info, se::LightingInputs& inputs) { recordFrame(info, inputs); };
}

FrameSettings& Adapter::settings() { return impl_->settings; }
const std::string& Adapter::lastError() const { return impl_->error; }
rb::HybridEffects& Adapter::effects() { return *impl_->fx; }
const rb::HybridEffects& Adapter::effects() const { return *impl_->fx; }
const rb::PrimaryShadingPass* Adapter::primaryShading() const { return impl_->shading.get(); }
const rb::TlasInfo& Adapter::lastTlas() const { return impl_->shading ? impl_->tlas : impl_->fx->lastTlas(); }
rb::Context& Adapter::context() { return *impl_->ctx; }
rb::AccelerationStructureService& Adapter::accelerationStructures() { return *impl_->as; }

}  // namespace rbAdapter

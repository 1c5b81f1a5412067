// soak: frames recorded and run, with framesInFlight frames on the GPU at once (FrameRing), while at random (seeded,
// SplitMix64, so a run is reproducible on every platform) the engine side registers, releases and resizes meshes
// (static ones that deduplicate, deforming cloth refit and rebuilt every frame, and deforming meshes shared through
// one MeshDesc::contentKey) under a BLAS budget that makes registrations evict cached BLASes or be refused, adds and
// removes TLAS instances, builds the TLAS itself (rebuild or refit, every instance upload and build preference) or
// lets HybridEffects build it, toggles effects and their settings, applies presets, changes the resolution, the
// light, the local lights and the materials. Every released handle is checked to be stale at once (isBuilt,
// updateMesh and a second releaseMesh must all answer StaleHandle).
//
// Memory is measured in one state, S, defined so that the same S at two points of the run holds the same resources
// unless something leaked (quiesce()):
//   - every registration the soak made is released (and its handle checked stale); no TLAS instance is left;
//   - no effect is enabled (HybridEffects::setDesc with an empty effect set: no pass, denoiser or material table);
//   - the BLAS cache is normalised: every static variant and shared deforming mesh is registered once more (a dedup
//     hit where its BLAS is cached, a build where the budget evicted it), built, and released in a fixed order, so
//     the service caches exactly one BLAS per distinct geometry (the budget holds them all when nothing else lives);
//   - 2 * framesInFlight + 2 frames then record pending work and an empty TLAS with fixed options (in-place
//     instances, shading records, rebuild, fast trace): every frame slot's TLAS buffers are in one configuration, a
//     compaction decided before S has happened, and what was retired has been released;
//   - the device is idle and Context::releaseAfterIdle() has run.
// Besides that cache, S holds the pools that grow to a high-water mark (per-slot TLAS buffers sized for the largest
// instance list and every build flag, readbacks of the refit measure): the prime drives each to the most the run can
// ask for (every mesh at its largest, the most instances, every TLAS option in every frame slot) before the warm-up
// ends. The storage blocks hold what is in use (an empty block is freed) and the build scratch is released by the
// frames without builds that end S's sequence (rb::kScratchWindowCalls).
// So memoryGrowthBytes = total bytes at the end's S minus those at the warm-up's S is 0 unless the SDK leaked, and
// so is the growth of the BLAS storage in use (AsStats::storageUsedBytes), which sees a leaked BLAS that a storage
// block's size hides. After the end's S the service and the effects are destroyed: the Context must then hold what
// it held before the soak (teardownBytes = 0).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <unordered_map>

#include "frame_ring.h"
#include "report.h"
#include "scenarios.h"
#include "scene_math.h"
#include "soak_scene.h"

namespace rbbench {

namespace {

constexpr uint32_t kMaxSharedPerKey = 3;  // registrations of one contentKey alive at once
constexpr uint64_t kSharedKeyBase = 0x50a40000ull;

// Counts of what the soak did (the JSON's "operations").
struct SoakCounts {
  uint64_t registerStatic = 0, releaseStatic = 0, registerDynamic = 0, releaseDynamic = 0, registerShared = 0,
           releaseShared = 0, resizeDynamic = 0, forceRebuild = 0, dynamicUpdates = 0, animationToggles = 0;
  uint64_t instanceAdds = 0, instanceRemovals = 0;
  uint64_t effectToggles = 0, presets = 0, settingChanges = 0, resolutionChanges = 0, lightChanges = 0,
           localLightChanges = 0, materialChanges = 0, historyResets = 0;
  uint64_t tlasOptionChanges = 0, tlasByEngine = 0, tlasByEffects = 0, tlasRefits = 0, tlasRebuilds = 0,
           tlasSkippedInstances = 0, framesWithoutEffects = 0;
  uint64_t staleChecks = 0, overBudget = 0;

  nlohmann::json toJson() const {
    return {{"registerStatic", registerStatic},
            {"releaseStatic", releaseStatic},
            {"registerDynamic", registerDynamic},
            {"releaseDynamic", releaseDynamic},
            {"registerShared", registerShared},
            {"releaseShared", releaseShared},
            {"resizeDynamic", resizeDynamic},
            {"forceRebuild", forceRebuild},
            {"dynamicUpdates", dynamicUpdates},
            {"animationToggles", animationToggles},
            {"instanceAdds", instanceAdds},
            {"instanceRemovals", instanceRemovals},
            {"effectToggles", effectToggles},
            {"presets", presets},
            {"settingChanges", settingChanges},
            {"resolutionChanges", resolutionChanges},
            {"lightChanges", lightChanges},
            {"localLightChanges", localLightChanges},
            {"materialChanges", materialChanges},
            {"historyResets", historyResets},
            {"tlasOptionChanges", tlasOptionChanges},
            {"tlasBuiltByEngine", tlasByEngine},
            {"tlasBuiltByEffects", tlasByEffects},
            {"tlasRefits", tlasRefits},
            {"tlasRebuilds", tlasRebuilds},
            {"tlasSkippedInstances", tlasSkippedInstances},
            {"framesWithoutEffects", framesWithoutEffects},
            {"staleHandleChecks", staleChecks},
            {"refusedOverBudget", overBudget}};
  }
};

// One registration the soak holds.
struct LiveMesh {
  enum class Kind : uint8_t { Static, Dynamic, Shared };
  uint64_t id = 0;
  rb::MeshHandle handle;
  Kind kind = Kind::Static;
  uint32_t variant = 0;  // static variant, or cloth variant of a Dynamic mesh
  uint32_t target = 0;   // deform target (Dynamic: its slot; Shared: dynamicSlots + key)
  float phase = 0.0f;
  bool animating = true;
  bool needsPose = true;  // its vertex buffer must be written this frame (new, or resized)
};

// One TLAS instance, placed over the ground.
struct Placed {
  uint64_t mesh = 0;  // LiveMesh::id
  double base[3] = {0, 0, 0};
  float scale = 0.5f, spin = 0.0f, speed = 0.0f;
};

// How the engine builds the TLAS while the policy holds (TLAS refits need the same options frame after frame).
struct TlasPolicy {
  bool byEngine = true;  // false: HybridEffects builds it over the frame's instances
  rb::TlasBuildOptions options;
  bool alwaysShadingRecords = false;
  bool cameraRelative = true;
};

struct MemorySample {
  rb::MemoryStats context;  // every category the SDK holds
  rb::MemoryStats effects;  // HybridEffects::memoryStats(): the pass categories
  rb::AsStats service;
  nlohmann::json toJson() const {
    nlohmann::json bytes = nlohmann::json::object();
    for (size_t c = 0; c < size_t(rb::MemoryCategory::Count); ++c)
      bytes[rb::toString(rb::MemoryCategory(c))] = context.bytes[c];
    return {{"bytes", bytes},
            {"totalBytes", context.total()},
            {"allocations", context.allocations},
            {"effectsBytes", effects.total()},
            {"meshHandles", service.meshHandles},
            {"blasCount", service.blasCount},
            {"blasQueued", service.blasQueued},
            {"blasBytes", service.blasBytes},
            {"storageBlocks", service.storageBlocks},
            {"storageBlockBytes", service.storageBlockBytes},
            {"storageUsedBytes", service.storageUsedBytes},
            {"scratchBytes", service.scratchBytes},
            {"tlasBytes", service.tlasBytes}};
  }
};

class SoakRun {
 public:
  explicit SoakRun(BenchEnv& env)
      : env_(env),
        sizes_(pickSoakSizes(env.options(), env.info().isCpu)),
        frames_(env.options().frames ? env.options().frames
                                     : (env.options().quick ? kQuickSoakFrames : kDefaultSoakFrames)),
        seed_(env.options().seed),
        rng_{env.options().seed} {}
  // After a failure part-way (BenchFailure), the members go with frames still in flight: the service's and the
  // Context's contract is a GPU that is done.
  ~SoakRun() {
    try {
      if (ring_) ring_->waitAll();
    } catch (const BenchFailure&) {
    }
    (void)env_.device().waitIdle();
  }
  SoakRun(const SoakRun&) = delete;
  SoakRun& operator=(const SoakRun&) = delete;

  nlohmann::json run();

 private:
  // ---- randomness ----
  bool chance(double p) { return rng_.next() < p; }
  uint32_t pick(size_t n) { return uint32_t(std::min<double>(rng_.next() * double(n), double(n - 1))); }

  // ---- meshes ----
  // Each returns false (and counts it) when the BLAS budget refuses the mesh; other errors throw.
  std::optional<rb::MeshHandle> tryRegister(const rb::MeshDesc& desc);
  bool registerStatic(uint32_t variant);
  bool registerDynamic(uint32_t slot, uint32_t variant);
  bool registerShared(uint32_t key);
  void release(size_t liveIndex);
  void expectStale(const LiveMesh& m);
  void resizeDynamic(LiveMesh& m, uint32_t variant);
  void place(uint64_t meshId);
  std::vector<size_t> liveOf(LiveMesh::Kind kind) const;
  uint32_t freeDynamicSlot();
  uint32_t sharedCount(uint32_t key) const;

  // ---- effects and the frame's inputs ----
  void setDesc(const rb::HybridEffectsDesc& desc, const char* what);
  void toggleEffect();
  void applyPreset();
  void changeSetting();
  void changeLight();
  void changeLocalLights();
  void changeTlasPolicy();

  // ---- frames ----
  void randomOperations();
  void recordFrame(VkCommandBuffer cmd, float t);
  VkDeviceSize measureBudget(const rb::AsServiceDesc& desc);
  void prime();
  void frame();
  MemorySample quiesce();
  MemorySample sample() const;
  void checkpoint(uint64_t frame);

  BenchEnv& env_;
  SoakSizes sizes_;
  uint32_t frames_;
  uint64_t seed_;
  SplitMix64 rng_;
  std::unique_ptr<SoakScene> scene_;
  std::unique_ptr<FrameRing> ring_;
  std::unique_ptr<rb::AccelerationStructureService> service_;
  std::unique_ptr<rb::HybridEffects> fx_;

  std::vector<LiveMesh> live_;
  std::vector<Placed> placed_;
  std::vector<bool> slotUsed_;  // deform targets of the Dynamic meshes
  uint64_t nextId_ = 1;
  uint32_t resolution_ = 0;
  uint32_t materialSet_ = 0;
  rb::Light light_;
  std::vector<rb::LightSource> localLights_;
  TlasPolicy tlas_;
  bool placing_ = true;        // new registrations get an instance (not while quiesce() normalises the cache)
  uint32_t lastQueued_ = 0;    // builds recordPendingWork left queued in the latest engine-built frame
  VkDeviceSize budget_ = 0;    // AsServiceDesc::blasBudgetBytes
  uint64_t frameCounter_ = 0;  // frames recorded by the soak, drain frames included
  std::chrono::steady_clock::time_point start_;

  SoakCounts counts_;
  uint64_t handlesAliveAfterRelease_ = 0;
  std::string firstAliveHandle_;
  nlohmann::json timeline_ = nlohmann::json::array();
  uint64_t instanceSum_ = 0, liveSum_ = 0, recorded_ = 0;  // sums over the frames recordFrame() recorded
  VkDeviceSize peakBytes_ = 0;                             // the most the Context held at the timeline's samples
};

std::vector<size_t> SoakRun::liveOf(LiveMesh::Kind kind) const {
  std::vector<size_t> out;
  for (size_t i = 0; i < live_.size(); ++i)
    if (live_[i].kind == kind) out.push_back(i);
  return out;
}

uint32_t SoakRun::freeDynamicSlot() {
  std::vector<uint32_t> free;
  for (uint32_t s = 0; s < sizes_.dynamicSlots; ++s)
    if (!slotUsed_[s]) free.push_back(s);
  return free.empty() ? UINT32_MAX : free[pick(free.size())];
}

uint32_t SoakRun::sharedCount(uint32_t key) const {
  uint32_t n = 0;
  for (const LiveMesh& m : live_) n += m.kind == LiveMesh::Kind::Shared && m.target == sizes_.dynamicSlots + key;
  return n;
}

void SoakRun::place(uint64_t meshId) {
  if (!placing_ || placed_.size() >= sizes_.maxInstances) return;
  Placed p;
  p.mesh = meshId;
  const double* lo = scene_->placementMin();
  const double* hi = scene_->placementMax();
  for (int i = 0; i < 3; ++i) p.base[i] = rng_.in(lo[i], hi[i]);
  p.scale = float(rng_.in(0.25, 0.7));
  p.spin = float(rng_.in(0.0, 2.0 * kPi));
  p.speed = chance(0.3) ? 0.0f : float(rng_.in(-1.0, 1.0));  // some never move: refits of an unchanged list
  placed_.push_back(p);
  ++counts_.instanceAdds;
}

std::optional<rb::MeshHandle> SoakRun::tryRegister(const rb::MeshDesc& desc) {
  rb::Result<rb::MeshHandle> h = service_->registerMesh(desc);
  if (h) return h.value();
  if (h.error().code != rb::ErrorCode::OutOfBudget) {
    throw BenchFailure(std::string("registerMesh(") + desc.debugName + "): " + rb::toString(h.error().code) + ": " +
                       h.error().message);
  }
  ++counts_.overBudget;  // the live meshes fill the budget: the engine would stream this one in later
  return std::nullopt;
}

bool SoakRun::registerStatic(uint32_t variant) {
  const SoakStaticVariant& v = scene_->staticVariants()[variant];
  rb::MeshDesc d = v.desc;
  d.debugName = v.name.c_str();
  LiveMesh m;
  m.id = nextId_++;
  const std::optional<rb::MeshHandle> h = tryRegister(d);
  if (!h) return false;
  m.handle = *h;
  m.kind = LiveMesh::Kind::Static;
  m.variant = variant;
  live_.push_back(m);
  ++counts_.registerStatic;
  place(m.id);
  return true;
}

bool SoakRun::registerDynamic(uint32_t slot, uint32_t variant) {
  rb::MeshDesc d = scene_->dynamicDesc(slot, scene_->clothVariants()[variant]);
  d.debugName = "soak cloth";
  LiveMesh m;
  m.id = nextId_++;
  const std::optional<rb::MeshHandle> h = tryRegister(d);
  if (!h) return false;
  m.handle = *h;
  m.kind = LiveMesh::Kind::Dynamic;
  m.variant = variant;
  m.target = slot;
  m.phase = float(rng_.in(0.0, 6.0));
  slotUsed_[slot] = true;
  live_.push_back(m);
  ++counts_.registerDynamic;
  place(m.id);
  return true;
}

bool SoakRun::registerShared(uint32_t key) {
  rb::MeshDesc d = scene_->dynamicDesc(sizes_.dynamicSlots + key, scene_->crowdVariant());
  d.contentKey = kSharedKeyBase + key;
  d.debugName = "soak crowd";
  LiveMesh m;
  m.id = nextId_++;
  const std::optional<rb::MeshHandle> h = tryRegister(d);
  if (!h) return false;
  m.handle = *h;
  m.kind = LiveMesh::Kind::Shared;
  m.target = sizes_.dynamicSlots + key;
  m.phase = float(key);
  live_.push_back(m);
  ++counts_.registerShared;
  place(m.id);
  return true;
}

void SoakRun::expectStale(const LiveMesh& m) {
  ++counts_.staleChecks;
  auto isStale = [](const rb::Error& e) { return e.code == rb::ErrorCode::StaleHandle; };
  const rb::Result<bool> built = service_->isBuilt(m.handle);
  bool stale = !built && isStale(built.error());
  if (m.kind != LiveMesh::Kind::Static) {
    const rb::Status update = service_->updateMesh(m.handle);
    stale = stale && !update && isStale(update.error());
  }
  const rb::Status again = service_->releaseMesh(m.handle);
  stale = stale && !again && isStale(again.error());
  if (!stale) {
    if (handlesAliveAfterRelease_++ == 0) {
      firstAliveHandle_ = "mesh handle {index " + std::to_string(m.handle.index) + ", generation " +
                          std::to_string(m.handle.generation) + "} still answered after releaseMesh";
    }
  }
}

void SoakRun::release(size_t liveIndex) {
  const LiveMesh m = live_[liveIndex];
  check(service_->releaseMesh(m.handle), "releaseMesh");
  expectStale(m);
  live_.erase(live_.begin() + ptrdiff_t(liveIndex));
  placed_.erase(std::remove_if(placed_.begin(), placed_.end(), [&](const Placed& p) { return p.mesh == m.id; }),
                placed_.end());
  switch (m.kind) {
    case LiveMesh::Kind::Static: ++counts_.releaseStatic; break;
    case LiveMesh::Kind::Dynamic:
      slotUsed_[m.target] = false;
      ++counts_.releaseDynamic;
      break;
    case LiveMesh::Kind::Shared: ++counts_.releaseShared; break;
  }
}

void SoakRun::resizeDynamic(LiveMesh& m, uint32_t variant) {
  rb::MeshDesc d = scene_->dynamicDesc(m.target, scene_->clothVariants()[variant]);
  d.debugName = "soak cloth";
  rb::MeshUpdate u;
  u.desc = &d;
  u.forceRebuild = true;  // new vertex and triangle counts
  const rb::Status st = service_->updateMesh(m.handle, u);
  if (!st && st.error().code == rb::ErrorCode::OutOfBudget) {
    ++counts_.overBudget;  // the larger cloth does not fit: it keeps its size
    return;
  }
  check(st, "updateMesh (resize)");
  m.variant = variant;
  m.needsPose = true;
  ++counts_.resizeDynamic;
}

void SoakRun::setDesc(const rb::HybridEffectsDesc& desc, const char* what) {
  check(fx_->setDesc(desc), std::string("HybridEffects::setDesc (") + what + ")");
}

void SoakRun::toggleEffect() {
  static constexpr rb::EffectBits kBits[] = {rb::kEffectShadows, rb::kEffectAo, rb::kEffectReflections,
                                             rb::kEffectLocalLights};
  rb::HybridEffectsDesc d = fx_->desc();
  d.effects ^= kBits[pick(4)];
  setDesc(d, "toggle");
  ++counts_.effectToggles;
}

void SoakRun::applyPreset() {
  const rb::Preset preset = rb::Preset(pick(rb::kPresetCount));
  check(fx_->applyPreset(preset), std::string("HybridEffects::applyPreset(") + rb::toString(preset) + ")");
  if (chance(0.5)) {
    rb::HybridEffectsDesc d = fx_->desc();
    d.effects |= rb::kEffectLocalLights;
    setDesc(d, "preset with local lights");
  }
  ++counts_.presets;
}

void SoakRun::changeSetting() {
  rb::HybridEffectsDesc d = fx_->desc();
  static constexpr uint32_t kRays[] = {0, 1, 2, 4};
  switch (pick(13)) {
    case 0: d.shadows.raysPerPixel = kRays[pick(4)]; break;
    case 1: d.shadows.softAngularRadiusDegrees = std::array<float, 3>{0.0f, 0.5f, 2.0f}[pick(3)]; break;
    case 2:
      d.shadows.disableDenoiser = !d.shadows.disableDenoiser;
      // Converged tiles (the soft-shadow presets') read the denoiser's history: off with it, as an engine must.
      if (d.shadows.disableDenoiser) d.shadows.schedule.convergedTiles.enabled = false;
      break;
    case 3: d.shadows.schedule.tileClassifier = !d.shadows.schedule.tileClassifier; break;
    case 4: d.ao.raysPerPixel = kRays[pick(4)]; break;
    case 5:
      d.ao.estimator = d.ao.estimator == rb::AoEstimator::Binary ? rb::AoEstimator::DistanceWeighted
                                                                 : rb::AoEstimator::Binary;
      break;
    case 6: d.ao.disableDenoiser = !d.ao.disableDenoiser; break;
    case 7:
      d.reflections.raysPerPixel = kRays[pick(3)];
      d.reflections.roughnessThreshold = chance(0.5) ? 0.0f : 0.5f;
      break;
    case 8: d.reflections.disableDenoiser = !d.reflections.disableDenoiser; break;
    case 9:
      d.localLights.mode = d.localLights.mode == rb::ManyLightMode::Stochastic ? rb::ManyLightMode::Exact
                                                                               : rb::ManyLightMode::Stochastic;
      break;
    case 10:
      d.localLights.disableDenoiser = !d.localLights.disableDenoiser;
      d.localLights.raysPerPixel = kRays[pick(3)];
      break;
    case 11:
      d.denoiser.spatialIterations = std::array<uint32_t, 3>{0, 1, 3}[pick(3)];
      d.denoiser.disableTemporal = chance(0.2);
      break;
    default: d.worldSpaceTlas = !d.worldSpaceTlas; break;
  }
  setDesc(d, "setting");
  ++counts_.settingChanges;
}

void SoakRun::changeLight() {
  rb::Light l;
  const FoliageView& v = scene_->view();
  const double* lo = scene_->placementMin();
  const double* hi = scene_->placementMax();
  const double r = rng_.next();
  if (r < 0.5) {
    l.type = rb::LightType::Directional;
    for (int i = 0; i < 3; ++i) l.direction[i] = float(v.toSun[i] + rng_.in(-0.15, 0.15));
    l.angularRadiusDegrees = std::array<float, 4>{0.0f, 0.0f, 0.5f, 2.0f}[pick(4)];
  } else {
    l.type = r < 0.8 ? rb::LightType::Point : rb::LightType::Spot;
    l.position[0] = rng_.in(lo[0], hi[0]);
    l.position[1] = rng_.in(2.0, 4.0);
    l.position[2] = rng_.in(lo[2], hi[2]);
    l.radius = chance(0.5) ? 0.0f : 0.15f;
    l.range = chance(0.5) ? 0.0f : 8.0f;
    l.direction[1] = -1.0f;
    l.spotOuterAngleDegrees = 40.0f;
  }
  light_ = l;
  ++counts_.lightChanges;
}

void SoakRun::changeLocalLights() {
  localLights_.clear();
  const uint32_t n = pick(13);
  const double* lo = scene_->placementMin();
  const double* hi = scene_->placementMax();
  for (uint32_t i = 0; i < n; ++i) {
    rb::LightSource s;
    s.light.type = chance(0.75) ? rb::LightType::Point : rb::LightType::Spot;
    s.light.position[0] = rng_.in(lo[0], hi[0]);
    s.light.position[1] = rng_.in(0.5, 2.0);
    s.light.position[2] = rng_.in(lo[2], hi[2]);
    s.light.radius = chance(0.5) ? 0.0f : 0.1f;
    s.light.range = 4.0f;
    s.light.direction[1] = -1.0f;
    for (float& c : s.color) c = float(rng_.in(0.3, 1.0));
    s.intensity = float(rng_.in(2.0, 8.0));
    localLights_.push_back(s);
  }
  ++counts_.localLightChanges;
}

void SoakRun::changeTlasPolicy() {
  TlasPolicy p;
  p.byEngine = chance(0.6);
  const rb::TlasBuildMode modes[3] = {rb::TlasBuildMode::Adaptive, rb::TlasBuildMode::Rebuild,
                                      rb::TlasBuildMode::UpdateIfPossible};
  p.options.mode = modes[pick(3)];
  p.options.instanceUpload = rb::TlasInstanceUpload(pick(3));
  p.options.preference = chance(0.5) ? rb::TlasBuildPreference::FastTrace : rb::TlasBuildPreference::FastBuild;
  p.alwaysShadingRecords = chance(0.3);
  p.cameraRelative = chance(0.7);
  tlas_ = p;
  ++counts_.tlasOptionChanges;
}

void SoakRun::randomOperations() {
  // Meshes.
  if (chance(0.15) && liveOf(LiveMesh::Kind::Static).size() < sizes_.maxStaticMeshes)
    registerStatic(pick(scene_->staticVariants().size()));
  if (chance(0.12)) {
    const std::vector<size_t> s = liveOf(LiveMesh::Kind::Static);
    if (!s.empty()) release(s[pick(s.size())]);
  }
  if (chance(0.05)) {
    const uint32_t slot = freeDynamicSlot();
    if (slot != UINT32_MAX) registerDynamic(slot, pick(scene_->clothVariants().size()));
  }
  if (chance(0.04)) {
    const std::vector<size_t> d = liveOf(LiveMesh::Kind::Dynamic);
    if (!d.empty()) release(d[pick(d.size())]);
  }
  if (chance(0.03)) {
    const uint32_t key = pick(sizes_.crowdKeys);
    if (sharedCount(key) < kMaxSharedPerKey) registerShared(key);
  }
  if (chance(0.03)) {
    const std::vector<size_t> s = liveOf(LiveMesh::Kind::Shared);
    if (!s.empty()) release(s[pick(s.size())]);
  }
  if (chance(0.03)) {
    const std::vector<size_t> d = liveOf(LiveMesh::Kind::Dynamic);
    if (!d.empty()) {
      LiveMesh& m = live_[d[pick(d.size())]];
      const uint32_t n = uint32_t(scene_->clothVariants().size());
      resizeDynamic(m, (m.variant + 1 + pick(n - 1)) % n);
    }
  }
  if (chance(0.02)) {
    const std::vector<size_t> d = liveOf(LiveMesh::Kind::Dynamic);
    if (!d.empty()) {
      rb::MeshUpdate u;
      u.forceRebuild = true;
      LiveMesh& m = live_[d[pick(d.size())]];
      check(service_->updateMesh(m.handle, u), "updateMesh (forceRebuild)");
      m.needsPose = true;
      ++counts_.forceRebuild;
    }
  }
  if (chance(0.02)) {
    const std::vector<size_t> d = liveOf(LiveMesh::Kind::Dynamic);
    if (!d.empty()) {
      LiveMesh& m = live_[d[pick(d.size())]];
      m.animating = !m.animating;
      ++counts_.animationToggles;
    }
  }
  // Instances.
  if (chance(0.15) && !live_.empty()) place(live_[pick(live_.size())].id);
  if (chance(0.12) && !placed_.empty()) {
    placed_.erase(placed_.begin() + ptrdiff_t(pick(placed_.size())));
    ++counts_.instanceRemovals;
  }
  if (chance(0.03)) changeTlasPolicy();
  // Effects and the frame's inputs.
  if (chance(0.02 * sizes_.effectChurn)) toggleEffect();
  if (chance(0.008 * sizes_.effectChurn)) applyPreset();
  if (chance(0.015 * sizes_.effectChurn)) changeSetting();
  if (chance(0.01)) {
    const uint32_t n = uint32_t(scene_->gbuffers().size());
    resolution_ = (resolution_ + 1 + pick(n - 1)) % n;
    ++counts_.resolutionChanges;
  }
  if (chance(0.02 * sizes_.effectChurn)) changeLight();
  if (chance(0.01)) changeLocalLights();
  if (chance(0.004)) {
    materialSet_ ^= 1u;
    check(fx_->setMaterials(scene_->materials(materialSet_), scene_->textures()), "HybridEffects::setMaterials");
    ++counts_.materialChanges;
  }
  if (chance(0.004)) {
    fx_->resetHistory();
    ++counts_.historyResets;
  }
}

void SoakRun::recordFrame(VkCommandBuffer cmd, float t) {
  // Deforming meshes: new poses into their vertex buffers, then updateMesh (refit or rebuild in this frame's work).
  std::vector<DeformRequest> deform;
  std::vector<bool> targetWritten(sizes_.dynamicSlots + sizes_.crowdKeys, false);
  for (LiveMesh& m : live_) {
    if (m.kind == LiveMesh::Kind::Static) continue;
    const bool pose = m.needsPose || m.animating;
    if (!pose) continue;
    if (!targetWritten[m.target]) {
      targetWritten[m.target] = true;
      const SoakClothVariant& v = m.kind == LiveMesh::Kind::Dynamic ? scene_->clothVariants()[m.variant]
                                                                    : scene_->crowdVariant();
      deform.push_back({m.target, &v, m.phase});
    }
    m.needsPose = false;
  }
  scene_->recordDeform(cmd, ring_->slot(), deform, t);
  for (LiveMesh& m : live_) {
    if (m.kind == LiveMesh::Kind::Static || !targetWritten[m.target]) continue;
    check(service_->updateMesh(m.handle), "updateMesh");
    ++counts_.dynamicUpdates;
  }

  // The instance list: every placed instance of a live mesh, moving.
  std::unordered_map<uint64_t, const LiveMesh*> byId;
  for (const LiveMesh& m : live_) byId[m.id] = &m;
  std::vector<rb::Instance> instances;
  instances.reserve(placed_.size());
  for (const Placed& p : placed_) {
    const LiveMesh* m = byId.at(p.mesh);
    rb::Instance in;
    in.mesh = m->handle;
    const float a = p.spin + p.speed * t, c = std::cos(a) * p.scale, s = std::sin(a) * p.scale;
    const float bob = p.speed != 0.0f ? 0.05f * std::sin(t + p.spin) : 0.0f;
    const float transform[12] = {c,  0, s, float(p.base[0]), 0, p.scale, 0, float(p.base[1]) + bob,
                                 -s, 0, c, float(p.base[2])};
    std::copy(std::begin(transform), std::end(transform), in.transform);
    in.customIndex = uint32_t(m->id & 0xFFFFFF);
    in.material = m->kind == LiveMesh::Kind::Static ? scene_->staticVariants()[m->variant].material : 2u;
    instances.push_back(in);
  }
  instanceSum_ += instances.size();
  liveSum_ += live_.size();
  ++recorded_;

  const SoakGBuffer& g = scene_->gbuffers()[resolution_];
  rb::HybridFrame frame;
  frame.gbuffer = g.desc;
  frame.light = light_;
  frame.localLights = localLights_;
  const rb::EffectSet effects = fx_->desc().effects;
  rb::TlasInfo tlas;
  if (tlas_.byEngine || effects == 0) {
    // The engine's own TLAS (it would trace or draw with it even without effects).
    lastQueued_ = check(service_->recordPendingWork(cmd), "recordPendingWork");
    rb::TlasBuildOptions o = tlas_.options;
    o.writeShadingRecords = tlas_.alwaysShadingRecords || (effects & rb::kEffectReflections) ||
                            service_->nonOpaqueMeshCount() > 0;
    if (tlas_.cameraRelative)
      std::copy(std::begin(g.desc.cameraPosition), std::end(g.desc.cameraPosition), o.originOffset);
    tlas = check(service_->recordTlasBuild(cmd, instances, o), "recordTlasBuild");
    frame.tlas = &tlas;
    ++counts_.tlasByEngine;
    counts_.tlasSkippedInstances += tlas.skippedInstances;
    ++(tlas.updated ? counts_.tlasRefits : counts_.tlasRebuilds);
  } else {
    frame.instances = instances;
    ++counts_.tlasByEffects;
  }
  check(fx_->record(cmd, frame), "HybridEffects::record");
  if (!frame.tlas) {
    counts_.tlasSkippedInstances += fx_->lastTlas().skippedInstances;
    ++counts_.tlasRebuilds;
  }
  if (effects == 0) ++counts_.framesWithoutEffects;
}

void SoakRun::frame() {
  VkCommandBuffer cmd = ring_->begin();
  recordFrame(cmd, float(frameCounter_++) / 30.0f);
  ring_->submit();
}

VkDeviceSize SoakRun::measureBudget(const rb::AsServiceDesc& desc) {
  // A service of its own, unbudgeted: the storage of every static variant and shared mesh (what the cache holds
  // in the measured state), then of one largest cloth.
  // Uncompacted: a registration reserves its BLAS's built size against the budget (compaction shrinks it later),
  // so the cache's variants must fit at their built sizes (on lavapipe compaction saves nothing; on the H200 the
  // compacted sizes made a budget that refused the cache's own variants with nothing else alive).
  rb::AsServiceDesc probeDesc = desc;
  probeDesc.disableCompaction = true;
  auto probe = check(rb::AccelerationStructureService::create(env_.ctx(), probeDesc), "creating the probe service");
  std::vector<rb::MeshHandle> handles;
  std::vector<DeformRequest> poses;
  for (const SoakStaticVariant& v : scene_->staticVariants()) {
    rb::MeshDesc d = v.desc;
    d.debugName = v.name.c_str();
    handles.push_back(check(probe->registerMesh(d), "probe registerMesh(" + v.name + ")"));
  }
  for (uint32_t k = 0; k < sizes_.crowdKeys; ++k) {
    rb::MeshDesc d = scene_->dynamicDesc(sizes_.dynamicSlots + k, scene_->crowdVariant());
    d.contentKey = kSharedKeyBase + k;
    handles.push_back(check(probe->registerMesh(d), "probe registerMesh(crowd)"));
    poses.push_back({sizes_.dynamicSlots + k, &scene_->crowdVariant(), float(k)});
  }
  // The peak of the storage in use (also the settled value, without compaction).
  auto buildAll = [&] {
    VkDeviceSize peak = 0;
    for (int f = 0; f < 1000; ++f) {
      uint32_t left = 0;
      env_.runFrame([&](VkCommandBuffer cmd) {
        scene_->recordDeform(cmd, 0, poses, 0.0f);
        left = check(probe->recordPendingWork(cmd), "probe recordPendingWork");
      });
      peak = std::max(peak, probe->stats().storageUsedBytes);
      if (left == 0) break;
    }
    env_.settle();
    return std::max(peak, probe->stats().storageUsedBytes);
  };
  const VkDeviceSize cached = buildAll();
  handles.push_back(
      check(probe->registerMesh(scene_->dynamicDesc(0, scene_->clothVariants().back())), "probe registerMesh(cloth)"));
  poses.push_back({0, &scene_->clothVariants().back(), 0.0f});
  const VkDeviceSize cloth = buildAll() - cached;
  for (rb::MeshHandle h : handles) check(probe->releaseMesh(h), "probe releaseMesh");
  check(env_.device().waitIdle(), "vkDeviceWaitIdle (probe)");
  probe.reset();
  env_.ctx().releaseAfterIdle();
  // Every cached geometry and half the deforming slots at their largest: with more cloth alive, registrations
  // evict cached BLASes (least recently released first) or are refused.
  return cached + cloth * std::max<uint32_t>(1, sizes_.dynamicSlots / 2);
}

void SoakRun::prime() {
  // Every variant registered (one twice: a dedup hit), the deforming meshes at the largest cloth as far as the
  // budget goes, the most instances, every effect at the largest resolution, and each TLAS option in every frame
  // slot: the pools reach what the random frames can ask for at most (see the comment at the top).
  for (uint32_t v = 0; v < scene_->staticVariants().size(); ++v) registerStatic(v);
  registerStatic(0);
  for (uint32_t k = 0; k < sizes_.crowdKeys; ++k) {
    for (uint32_t i = 0; i < kMaxSharedPerKey; ++i) registerShared(k);
  }
  const uint32_t largest = uint32_t(scene_->clothVariants().size() - 1);
  for (uint32_t s = 0; s < sizes_.dynamicSlots; ++s) registerDynamic(s, largest);
  while (placed_.size() < sizes_.maxInstances) place(live_[pick(live_.size())].id);
  uint64_t mostPixels = 0;
  for (uint32_t r = 0; r < scene_->gbuffers().size(); ++r) {
    const rb::GBufferDesc& d = scene_->gbuffers()[r].desc;
    if (uint64_t(d.width) * d.height > mostPixels) mostPixels = uint64_t(d.width) * d.height, resolution_ = r;
  }
  rb::HybridEffectsDesc all = fx_->desc();
  all.effects = rb::kAllEffects;
  setDesc(all, "prime");
  changeLocalLights();
  for (rb::TlasBuildMode mode :
       {rb::TlasBuildMode::Rebuild, rb::TlasBuildMode::UpdateIfPossible, rb::TlasBuildMode::Adaptive}) {
    for (rb::TlasBuildPreference pref : {rb::TlasBuildPreference::FastTrace, rb::TlasBuildPreference::FastBuild}) {
      for (rb::TlasInstanceUpload upload :
           {rb::TlasInstanceUpload::ReadInPlace, rb::TlasInstanceUpload::CopyToDevice}) {
        tlas_ = TlasPolicy{};
        tlas_.options.mode = mode;
        tlas_.options.preference = pref;
        tlas_.options.instanceUpload = upload;
        tlas_.alwaysShadingRecords = true;
        for (uint32_t f = 0; f < env_.ctx().framesInFlight(); ++f) frame();
      }
    }
  }
  // Then the random frames start from the High preset with local lights, the TLAS built by HybridEffects.
  check(fx_->applyPreset(rb::Preset::High), "applyPreset(High)");
  rb::HybridEffectsDesc high = fx_->desc();
  high.effects |= rb::kEffectLocalLights;
  setDesc(high, "start");
  tlas_ = TlasPolicy{};
  tlas_.byEngine = false;
}

MemorySample SoakRun::sample() const { return {env_.ctx().memoryStats(), fx_->memoryStats(), service_->stats()}; }

MemorySample SoakRun::quiesce() {
  while (!live_.empty()) release(live_.size() - 1);
  placed_.clear();
  rb::HybridEffectsDesc none = fx_->desc();
  none.effects = 0;
  setDesc(none, "quiesce");
  tlas_ = TlasPolicy{};  // the engine builds an empty TLAS: in place, shading records, rebuild, fast trace
  tlas_.alwaysShadingRecords = true;
  const uint32_t settle = 2 * env_.ctx().framesInFlight() + 2;
  // The cache made the same at every measurement: each static variant and shared mesh registered once (a dedup hit
  // where its BLAS is cached, a build where the budget evicted it), built, then released in a fixed order.
  placing_ = false;
  for (uint32_t v = 0; v < scene_->staticVariants().size(); ++v) {
    if (!registerStatic(v)) throw BenchFailure("the BLAS budget refused a static variant with nothing else alive");
  }
  for (uint32_t k = 0; k < sizes_.crowdKeys; ++k) {
    if (!registerShared(k)) throw BenchFailure("the BLAS budget refused a shared mesh with nothing else alive");
  }
  for (uint32_t f = 0;; ++f) {
    frame();
    if (lastQueued_ == 0) break;
    if (f > 1000) throw BenchFailure("builds stayed queued for 1000 frames");
  }
  for (uint32_t f = 0; f < settle; ++f) frame();  // compaction (GPU) decided, copied and the originals released
  while (!live_.empty()) release(0);
  placing_ = true;
  // Retired objects released, every frame slot's TLAS buffers back in the one configuration above, and the build
  // scratch let go (released at the end of a window of recording calls that built nothing).
  for (uint32_t f = 0; f < std::max(settle, 2 * rb::kScratchWindowCalls); ++f) frame();
  ring_->waitAll();
  check(env_.device().waitIdle(), "vkDeviceWaitIdle (quiesce)");
  env_.ctx().releaseAfterIdle();
  return sample();
}

void SoakRun::checkpoint(uint64_t frame) {
  const rb::MemoryStats m = env_.ctx().memoryStats();
  peakBytes_ = std::max(peakBytes_, m.total());
  const rb::AsStats s = service_->stats();
  timeline_.push_back({{"frame", frame},
                       {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count()},
                       {"totalBytes", m.total()},
                       {"allocations", m.allocations},
                       {"meshHandles", s.meshHandles},
                       {"blasCount", s.blasCount},
                       {"instances", placed_.size()},
                       {"effects", fx_->desc().effects},
                       {"resolution", scene_->gbuffers()[resolution_].desc.width}});
}

nlohmann::json SoakRun::run() {
  start_ = std::chrono::steady_clock::now();
  const auto start = start_;
  const uint32_t errorsBefore = env_.device().validationErrorCount();
  const rb::MemoryStats before = env_.ctx().memoryStats();  // what the Context held before the soak
  env_.progress("soak: preparing the scene (seed " + std::to_string(seed_) + ", " + std::to_string(frames_) +
                " frames)");
  scene_ = std::make_unique<SoakScene>(env_, sizes_);
  ring_ = std::make_unique<FrameRing>(env_);
  slotUsed_.assign(sizes_.dynamicSlots, false);
  rb::AsServiceDesc sd;
  // A small scratch budget: batches split, and the largest meshes build with transient scratch.
  sd.scratchBudgetBytes = env_.info().isCpu ? (256u << 10) : (4u << 20);
  // Builds spread over frames: some instances wait (TlasInfo::skippedInstances) for their BLAS.
  sd.maxBuildTrianglesPerCall = env_.info().isCpu ? 3000 : 60000;
  // A BLAS budget that cached BLASes and the deforming meshes compete for: registrations evict (destroying
  // BLASes the soak no longer holds) and are sometimes refused.
  budget_ = measureBudget(sd);
  sd.blasBudgetBytes = budget_;
  service_ = check(rb::AccelerationStructureService::create(env_.ctx(), sd), "creating the AS service");
  fx_ = check(rb::HybridEffects::create(env_.ctx(), service_.get()), "creating HybridEffects");
  check(fx_->setMaterials(scene_->materials(0), scene_->textures()), "HybridEffects::setMaterials");
  changeLight();
  const MemorySample atStart = sample();

  const uint32_t warmup = std::max<uint32_t>(frames_ / 10, 8 * env_.ctx().framesInFlight() + 4);
  const uint32_t every = std::max<uint32_t>(1, frames_ / 50);
  MemorySample atWarmup{};
  double warmupSeconds = 0.0;
  prime();
  const uint64_t primed = frameCounter_;
  for (uint64_t f = primed; f < frames_; ++f) {
    if (f == warmup) {
      const auto t0 = std::chrono::steady_clock::now();
      const rb::HybridEffectsDesc resume = fx_->desc();
      const TlasPolicy resumeTlas = tlas_;
      atWarmup = quiesce();
      setDesc(resume, "resume");
      tlas_ = resumeTlas;
      warmupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      env_.progress("soak: warm-up done at frame " + std::to_string(f) + ", " +
                    std::to_string(atWarmup.context.total()) + " bytes in the measured state");
    }
    VkCommandBuffer cmd = ring_->begin();
    randomOperations();
    recordFrame(cmd, float(frameCounter_++) / 30.0f);
    ring_->submit();
    if (f % every == 0) checkpoint(f);
    if ((f + 1) % std::max<uint32_t>(1, frames_ / 10) == 0) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      env_.progress("soak: frame " + std::to_string(f + 1) + " of " + std::to_string(frames_) + ", " +
                    std::to_string(live_.size()) + " meshes, " + std::to_string(placed_.size()) + " instances, " +
                    std::to_string(env_.ctx().memoryStats().total()) + " bytes, " + std::to_string(int(s)) + " s");
    }
  }
  const MemorySample atEnd = quiesce();
  const double soakSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Teardown: with the service and the effects gone the Context holds what it held before.
  fx_.reset();
  ring_->waitAll();
  check(env_.device().waitIdle(), "vkDeviceWaitIdle (teardown)");
  service_.reset();
  env_.ctx().releaseAfterIdle();
  const rb::MemoryStats after = env_.ctx().memoryStats();
  const int64_t teardownBytes = int64_t(after.total()) - int64_t(before.total());
  const int64_t teardownAllocations = int64_t(after.allocations) - int64_t(before.allocations);
  nlohmann::json variants = nlohmann::json::array();
  for (const SoakStaticVariant& v : scene_->staticVariants()) variants.push_back(v.name);
  ring_.reset();
  scene_.reset();
  const uint32_t validationErrors = env_.device().validationErrorCount() - errorsBefore;

  const int64_t growth = int64_t(atEnd.context.total()) - int64_t(atWarmup.context.total());
  const int64_t allocationGrowth = int64_t(atEnd.context.allocations) - int64_t(atWarmup.context.allocations);
  nlohmann::json growthByCategory = nlohmann::json::object();
  for (size_t c = 0; c < size_t(rb::MemoryCategory::Count); ++c) {
    growthByCategory[rb::toString(rb::MemoryCategory(c))] = int64_t(atEnd.context.bytes[c]) -
                                                            int64_t(atWarmup.context.bytes[c]);
  }
  const uint32_t liveHandlesAfterRelease = atEnd.service.meshHandles;
  // Suballocations inside the storage blocks: a leaked BLAS keeps its bytes of a block that the block's size hides.
  const int64_t storageUsedGrowth = int64_t(atEnd.service.storageUsedBytes) -
                                    int64_t(atWarmup.service.storageUsedBytes);
  const int64_t blasGrowth = int64_t(atEnd.service.blasCount) - int64_t(atWarmup.service.blasCount);

  nlohmann::json failures = nlohmann::json::array();
  if (growth != 0 || allocationGrowth != 0) {
    failures.push_back("the SDK's memory grew by " + std::to_string(growth) + " bytes and " +
                       std::to_string(allocationGrowth) +
                       " allocations between the warm-up and the end, in the same "
                       "state (by category: " +
                       growthByCategory.dump() + ")");
  }
  if (storageUsedGrowth != 0 || blasGrowth != 0) {
    failures.push_back("the BLAS storage in use grew by " + std::to_string(storageUsedGrowth) + " bytes and " +
                       std::to_string(blasGrowth) + " BLASes between the warm-up and the end, in the same state");
  }
  if (liveHandlesAfterRelease != 0) {
    failures.push_back(std::to_string(liveHandlesAfterRelease) +
                       " mesh handles stayed alive after every mesh was released (AsStats::meshHandles)");
  }
  if (handlesAliveAfterRelease_ != 0) {
    failures.push_back(std::to_string(handlesAliveAfterRelease_) +
                       " released handles were not stale; first: " + firstAliveHandle_);
  }
  if (teardownBytes != 0 || teardownAllocations != 0) {
    failures.push_back("after destroying the service and the effects the Context holds " +
                       std::to_string(teardownBytes) + " bytes and " + std::to_string(teardownAllocations) +
                       " allocations more than before the soak");
  }
  if (validationErrors > 0) {
    failures.push_back(std::to_string(validationErrors) +
                       " validation errors; first: " + env_.device().validationErrors().at(errorsBefore));
  }

  nlohmann::json resolutions = nlohmann::json::array();
  for (auto [w, h] : sizes_.resolutions) resolutions.push_back(std::to_string(w) + "x" + std::to_string(h));
  nlohmann::json summary = {{"frames", frames_},
                            {"seconds", soakSeconds},
                            {"framesPerSecond", double(frames_) / soakSeconds},
                            {"memoryGrowthBytes", growth},
                            {"allocationGrowth", allocationGrowth},
                            {"storageUsedGrowthBytes", storageUsedGrowth},
                            {"blasCountGrowth", blasGrowth},
                            {"liveHandlesAfterRelease", liveHandlesAfterRelease},
                            {"handlesAliveAfterRelease", handlesAliveAfterRelease_},
                            {"teardownBytes", teardownBytes},
                            {"validationErrors", validationErrors},
                            {"validationEnabled", env_.device().validationEnabled()},
                            {"passed", failures.empty()}};
  nlohmann::json out = {{"seed", seed_},
                        {"frames", frames_},
                        {"primeFrames", primed},
                        {"warmupFrames", warmup},
                        {"framesInFlight", env_.ctx().framesInFlight()},
                        {"blasBudgetBytes", budget_},
                        {"evictions", atEnd.service.evictions},
                        {"dedupHits", atEnd.service.dedupHits},
                        {"resolutions", resolutions},
                        {"sizes",
                         {{"dynamicSlots", sizes_.dynamicSlots},
                          {"crowdKeys", sizes_.crowdKeys},
                          {"maxStaticMeshes", sizes_.maxStaticMeshes},
                          {"maxInstances", sizes_.maxInstances}}},
                        {"operations", counts_.toJson()},
                        {"staticVariants", variants},
                        {"meanLiveMeshes", double(liveSum_) / double(std::max<uint64_t>(recorded_, 1))},
                        {"meanInstances", double(instanceSum_) / double(std::max<uint64_t>(recorded_, 1))},
                        {"peakSampledBytes", peakBytes_},
                        {"warmupMeasurementSeconds", warmupSeconds},
                        {"memory",
                         {{"start", atStart.toJson()},
                          {"warmup", atWarmup.toJson()},
                          {"end", atEnd.toJson()},
                          {"growthByCategory", growthByCategory}}},
                        {"timeline", timeline_},
                        {"summary", summary},
                        {"failures", failures}};
  return out;
}

}  // namespace

nlohmann::json runSoakScenario(BenchEnv& env) {
  SoakRun soak(env);
  nlohmann::json out = soak.run();

  Table table("soak: the SDK's memory (bytes) at the start, after the warm-up and at the end (seed " +
                  std::to_string(out["seed"].get<uint64_t>()) + ", " + std::to_string(out["frames"].get<uint32_t>()) +
                  " frames)",
              {{"when", "when"},
               {"blas storage", "blas_storage"},
               {"scratch", "scratch"},
               {"tlas", "tlas"},
               {"shader tables", "shader_tables"},
               {"pass images", "pass_images"},
               {"pass buffers", "pass_buffers"},
               {"total", "total"},
               {"allocs", "allocations"},
               {"handles", "meshHandles"},
               {"BLASes", "blasCount"}});
  for (const char* when : {"start", "warmup", "end"}) {
    const nlohmann::json& m = out["memory"][when];
    nlohmann::json row = m["bytes"];
    row["when"] = when;
    row["total"] = m["totalBytes"];
    row["allocations"] = m["allocations"];
    row["meshHandles"] = m["meshHandles"];
    row["blasCount"] = m["blasCount"];
    table.add(row);
  }
  table.print();
  printSummary(out["summary"]);
  return out;
}

}  // namespace rbbench

// Animation in the engine's frame: the hook's semaphore and waits, raster passes drawing the deformed buffers,
// the async compute queue, error messages, ScenePose's checks, and a measurement with many characters.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include <catch2/catch_test_macros.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "animation_test_support.h"
#include "sample_engine/procedural.h"

using namespace sample_engine;
using namespace animation_test;
using test_support::makeEngine;

TEST_CASE("the pre-pass hook sees the deformation semaphore and can add waits", "[animation][hook]") {
  const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
  auto engine = makeEngine();

  SECTION("a static scene has no deforming instance, semaphore or deformWaits") {
    REQUIRE(engine->loadScene(makeDefaultDemoScene()).ok());
    REQUIRE(engine->setRenderSize(kSize, kSize).ok());
    CHECK(engine->deformedInstances().empty());
    int calls = 0;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      ++calls;
      CHECK(info.deformSemaphore == VK_NULL_HANDLE);
      CHECK(info.deformWaits == nullptr);
      CHECK(info.submitWaits != nullptr);
      CHECK(info.deformedInstances.empty());
      CHECK(info.instanceTransforms.size() == engine->scene().instances.size());
    });
    render(*engine, {});
    CHECK(calls == 1);
  }

  SECTION("an animated scene: the semaphore reaches the frame number; waits on it are accepted") {
    REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
    REQUIRE(engine->setRenderSize(kSize, kSize).ok());
    std::vector<uint64_t> values;
    VkSemaphore semaphore = VK_NULL_HANDLE;
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      REQUIRE(info.deformSemaphore != VK_NULL_HANDLE);
      semaphore = info.deformSemaphore;
      REQUIRE(info.deformWaits != nullptr);
      REQUIRE(info.submitWaits != nullptr);
      CHECK(info.deformValue == info.frameNumber);
      CHECK(info.deformedInstances.size() == 1);
      values.push_back(info.deformValue);
      // What an async add-on does: the next deformation and this frame's submission wait on work it signals
      // (here the engine's own semaphore, at values already reached or reached before the wait).
      VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
      wait.semaphore = info.deformSemaphore;
      wait.value = info.deformValue;
      wait.stageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
      info.deformWaits->push_back(wait);
      info.submitWaits->push_back(wait);
    });
    for (double t : {0.1, 0.2, 0.3}) {
      FrameParams params;
      params.time = t;
      render(*engine, params);
    }
    REQUIRE(engine->waitIdle().ok());
    REQUIRE(values.size() == 3);
    CHECK(values[1] == values[0] + 1);
    uint64_t reached = 0;
    REQUIRE(vkGetSemaphoreCounterValue(engine->device(), semaphore, &reached) == VK_SUCCESS);
    CHECK(reached == values.back());
  }

  SECTION("waitIdle drops the waits a hook left, so their semaphore may be destroyed before the next frame") {
    // An add-on (an adapter with async BLAS work) leaves a wait on its own semaphore for the next deformation,
    // then is destroyed after waitIdle: the next frame must not wait on the destroyed semaphore.
    REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
    REQUIRE(engine->setRenderSize(kSize, kSize).ok());
    VkSemaphoreTypeCreateInfo type{VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO};
    type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
    VkSemaphoreCreateInfo ci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    ci.pNext = &type;
    VkSemaphore own = VK_NULL_HANDLE;
    REQUIRE(vkCreateSemaphore(engine->device(), &ci, nullptr, &own) == VK_SUCCESS);
    engine->setPrepassHook([&](const PrepassHookInfo& info, LightingInputs&) {
      VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
      wait.semaphore = own;
      wait.value = 0;  // reached from the start
      wait.stageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
      info.deformWaits->push_back(wait);
    });
    render(*engine, FrameParams{});
    engine->setPrepassHook({});
    REQUIRE(engine->waitIdle().ok());
    vkDestroySemaphore(engine->device(), own, nullptr);
    FrameParams later;
    later.time = 0.5;
    render(*engine, later);  // would wait on the destroyed semaphore
    REQUIRE(engine->waitIdle().ok());
  }
  engine->setPrepassHook({});
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

namespace {

// Per pixel: true where geometry covers it (the HDR pixel is not the sky colour).
std::vector<bool> coverage(Engine& engine, const FrameParams& params) {
  Status s = engine.renderFrame(params);
  INFO(s.error);
  REQUIRE(s.ok());
  auto hdr = engine.readbackHdr();
  INFO(hdr.error);
  REQUIRE(hdr.ok());
  std::vector<bool> covered(size_t(hdr.value.width) * hdr.value.height);
  for (uint32_t y = 0; y < hdr.value.height; ++y)
    for (uint32_t x = 0; x < hdr.value.width; ++x)
      covered[size_t(y) * hdr.value.width + x] = glm::length(glm::vec3(hdr.value.at(x, y)) - params.skyColor) > 1e-3f;
  return covered;
}

size_t differing(const std::vector<bool>& a, const std::vector<bool>& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

}  // namespace

TEST_CASE("raster passes draw the deformed buffers with this frame's transforms", "[animation][render]") {
  // The posed strip must cover the same pixels as a static mesh made of the reference's posed world positions.
  constexpr uint32_t kImage = 96;
  const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
  const double time = 0.75;
  const auto posed = reference(path, 0, time);
  REQUIRE(posed.size() == 1);
  Scene expected;
  MeshData mesh;
  for (const glm::dvec3& p : posed[0].worldPositions) mesh.positions.push_back(glm::vec3(p));
  mesh.indices = posed[0].indices;
  expected.meshes.push_back(mesh);
  expected.instances.push_back(Instance{});

  FrameParams params;
  params.camera = defaultCameraFor(expected.bounds());
  params.shadow.mapSize = 1024;
  params.time = time;
  auto engine = makeEngine();
  REQUIRE(engine->setRenderSize(kImage, kImage).ok());
  REQUIRE(engine->loadScene(expected).ok());
  const std::vector<bool> want = coverage(*engine, params);
  REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
  const std::vector<bool> got = coverage(*engine, params);
  params.restPose = true;
  const std::vector<bool> rest = coverage(*engine, params);

  size_t covered = 0;
  for (bool c : want) covered += c;
  INFO("covered " << covered << ", differing from the reference " << differing(got, want) << ", rest pose differs by "
                  << differing(rest, want));
  REQUIRE(covered > kImage * kImage / 20);
  CHECK(differing(got, want) <= covered / 50);  // edge pixels only
  CHECK(differing(rest, want) > covered / 5);   // the pose matters
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("an async compute queue is a compute family without graphics, or none", "[animation][queues]") {
  EngineConfig config;
  config.requestAsyncComputeQueue = true;
  auto engine = makeEngine(config);
  if (engine->asyncComputeQueue() == VK_NULL_HANDLE) {
    CHECK(engine->asyncComputeQueueFamily() == UINT32_MAX);  // e.g. lavapipe: one graphics+compute family
  } else {
    uint32_t n = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(engine->physicalDevice(), &n, nullptr);
    std::vector<VkQueueFamilyProperties> families(n);
    vkGetPhysicalDeviceQueueFamilyProperties(engine->physicalDevice(), &n, families.data());
    REQUIRE(engine->asyncComputeQueueFamily() < n);
    const VkQueueFlags flags = families[engine->asyncComputeQueueFamily()].queueFlags;
    CHECK((flags & VK_QUEUE_COMPUTE_BIT) != 0);
    CHECK((flags & VK_QUEUE_GRAPHICS_BIT) == 0);
    // Deformed buffers are shared with it; an animated frame stays valid.
    const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
    REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
    REQUIRE(engine->setRenderSize(kSize, kSize).ok());
    FrameParams params;
    params.time = 0.75;
    render(*engine, params);
    CHECK(compareWithReference(*engine, reference(path, 0, 0.75)) == 1);
  }
  EngineConfig plain;
  CHECK(makeEngine(plain)->asyncComputeQueue() == VK_NULL_HANDLE);
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("bad animation input fails with messages naming the value", "[animation][errors]") {
  SECTION("a joint index beyond the skin's joints") {
    SceneLoadResult r = loadGltf(
        writeFixture("sample_engine_bad_joint.gltf", pose_reference::writeSkinnedStripBadJoint));
    INFO(r.error);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error.find("vertex 7") != std::string::npos);
    CHECK(r.error.find("JOINTS_0 index 3") != std::string::npos);
    CHECK(r.error.find("3 joints") != std::string::npos);
    CHECK(r.error.find("primitive 0") != std::string::npos);
    CHECK(r.error.find("skin 0") != std::string::npos);
  }
  SECTION("a skinned vertex whose weights sum to zero") {
    SceneLoadResult r = loadGltf(
        writeFixture("sample_engine_zero_weights.gltf", pose_reference::writeSkinnedStripZeroWeights));
    INFO(r.error);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error.find("vertex 5") != std::string::npos);
    CHECK(r.error.find("must sum to 1") != std::string::npos);
  }
  SECTION("renderFrame: bad times and animation indices") {
    auto engine = makeEngine();
    REQUIRE(engine
                ->loadScene(
                    loadGltfScene(writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip)))
                .ok());
    REQUIRE(engine->setRenderSize(kSize, kSize).ok());
    const std::pair<double, const char*> badTimes[] = {{-1.0, "-1"},
                                                       {std::numeric_limits<double>::quiet_NaN(), "nan"},
                                                       {std::numeric_limits<double>::infinity(), "inf"}};
    for (const auto& [time, text] : badTimes) {
      FrameParams params;
      params.time = time;
      Status s = engine->renderFrame(params);
      INFO(s.error);
      CHECK_FALSE(s.ok());
      CHECK(s.error.find(std::string("time = ") + text) != std::string::npos);
    }
    FrameParams params;
    params.animations = {{0, 0.0}, {4, 0.0}};
    Status s = engine->renderFrame(params);
    INFO(s.error);
    CHECK_FALSE(s.ok());
    CHECK(s.error.find("animations[1].animation = 4") != std::string::npos);
    CHECK(s.error.find("0 'bend'") != std::string::npos);
    CHECK(engine->readbackDeformedPositions(1).error.find("out of range") != std::string::npos);
    REQUIRE(engine->waitIdle().ok());
    CHECK(engine->validationErrorCount() == 0);
  }
}

TEST_CASE("ScenePose checks the hierarchy and shares joint matrices of one skinned node", "[animation][pose]") {
  Scene scene;
  scene.meshes.push_back(makeBox({1, 1, 1}));
  MeshData& mesh = scene.meshes[0];
  mesh.joints0.assign(mesh.positions.size(), glm::u16vec4(0, 1, 0, 0));
  mesh.weights0.assign(mesh.positions.size(), glm::vec4(0.5f, 0.5f, 0.0f, 0.0f));
  scene.nodes.resize(3);
  scene.nodes[1].parent = 0;
  scene.nodes[1].translation = {0, 2, 0};
  scene.nodes[2].parent = 0;
  scene.skins.push_back(Skin{"skin", {0, 1}, {}});
  scene.instances = {Instance{0, glm::mat4(1.0f), 2, 0}, Instance{0, glm::mat4(1.0f), 2, 0}};
  ScenePose pose;
  REQUIRE(pose.reset(scene).ok());
  REQUIRE(pose.evaluate(scene, 0.0, {}, false).ok());
  CHECK(pose.jointOffset(0) == pose.jointOffset(1));
  CHECK(pose.packedJointMatrices().size() == 2);
  CHECK(pose.jointMatrices(1)[1][3] == glm::vec4(0, 2, 0, 1));
  CHECK(pose.morphWeights(0).empty());

  SECTION("a parent cycle") {
    scene.nodes[0].parent = 1;
    Status s = pose.reset(scene);
    INFO(s.error);
    CHECK(s.error.find("cycle") != std::string::npos);
  }
  SECTION("a joint index beyond the skin, in a scene built by hand, fails loadScene naming it") {
    mesh.joints0[3] = glm::u16vec4(0, 2, 0, 0);
    Status s = pose.reset(scene);
    INFO(s.error);
    CHECK(s.error.find("vertex 3: joint index 2 is out of range (the skin has 2 joints)") != std::string::npos);
    auto engine = makeEngine();
    Status load = engine->loadScene(scene);
    CHECK(load.error.find("joint index 2") != std::string::npos);
    CHECK(engine->deformedInstances().empty());
    CHECK(engine->validationErrorCount() == 0);
  }
  SECTION("an instance skin without joints on its mesh") {
    mesh.joints0.clear();
    mesh.weights0.clear();
    CHECK(pose.reset(scene).error.find("no joints0/weights0") != std::string::npos);
  }
}

// A measurement, not run by default ("[.perf]"): K characters (CesiumMan, Fox, BrainStem in turn, each its own
// appendScene copy at its own time offset) on the demo floor; prints the CPU cost of renderFrame and the GPU
// passes. RAYBRIDGE_PERF_CHARACTERS (default 200), RAYBRIDGE_PERF_WIDTH / _HEIGHT (default 2560 x 1440),
// RAYBRIDGE_PERF_FRAMES (default 30), RAYBRIDGE_PERF_VALIDATION (default 1). Checks one copy of each model
// against the reference.
TEST_CASE("many animated characters: timings", "[.perf][animation]") {
  auto env = [](const char* name, uint32_t fallback) {
    const char* v = std::getenv(name);
    return v && *v ? uint32_t(std::strtoul(v, nullptr, 10)) : fallback;
  };
  const uint32_t characters = env("RAYBRIDGE_PERF_CHARACTERS", 200), frames = env("RAYBRIDGE_PERF_FRAMES", 30);
  const uint32_t width = env("RAYBRIDGE_PERF_WIDTH", 2560), height = env("RAYBRIDGE_PERF_HEIGHT", 1440);
  std::vector<std::string> paths;
  for (const char* name : {"CesiumMan", "Fox", "BrainStem"}) {
    const auto p = test_support::sharedScenesDir() / name / (std::string(name) + ".gltf");
    if (std::filesystem::exists(p)) paths.push_back(p.string());
  }
  if (paths.empty()) SKIP("no shared character model in " + test_support::sharedScenesDir().string());
  std::vector<Scene> models;
  std::vector<float> scales;
  for (const std::string& p : paths) {
    models.push_back(loadGltfScene(p));
    scales.push_back(1.5f / std::max(models.back().bounds().radius(), 1e-3f));  // about 3 m tall
  }
  Scene scene = makeDefaultDemoScene();
  std::vector<AnimationPlayback> playbacks;
  std::vector<uint32_t> firstInstance, firstNode;
  const uint32_t columns = uint32_t(std::ceil(std::sqrt(double(characters))));
  for (uint32_t k = 0; k < characters; ++k) {
    const size_t m = k % models.size();
    const glm::vec3 at(-12.0f + 24.0f * float(k % columns) / float(columns), 0.0f,
                       -12.0f + 24.0f * float(k / columns) / float(columns));
    const glm::mat4 placement = glm::translate(glm::mat4(1.0f), at) * glm::scale(glm::mat4(1.0f), glm::vec3(scales[m]));
    firstInstance.push_back(uint32_t(scene.instances.size()));
    firstNode.push_back(uint32_t(scene.nodes.size()) + 1);
    playbacks.push_back({appendScene(scene, models[m], placement), 0.37 * double(k)});
  }
  EngineConfig config;
  config.requestAsyncComputeQueue = true;
  // RAYBRIDGE_PERF_VALIDATION=0: without the validation layer, whose per-command cost dominates the CPU time.
  const bool validation = env("RAYBRIDGE_PERF_VALIDATION", 1) != 0;
  config.enableValidation = validation;
  auto created = Engine::create(config);
  INFO(created.error);
  REQUIRE(created.ok());
  std::unique_ptr<Engine> engine = std::move(created.value);
  REQUIRE(engine->loadScene(scene).ok());
  REQUIRE(engine->setRenderSize(width, height).ok());
  FrameParams params;
  params.camera = Camera{.eye = {0.0f, 9.0f, 22.0f}, .target = {0.0f, 1.0f, 0.0f}, .fovYDegrees = 50.0f};
  params.animations = playbacks;
  double cpuMs = 0.0, deformMs = 0.0, shadowMs = 0.0, prepassMs = 0.0, lightingMs = 0.0;
  uint32_t timed = 0;
  for (uint32_t f = 0; f < frames; ++f) {
    params.time = double(f) / 30.0;
    REQUIRE(engine->waitIdle().ok());  // so that the time below is the CPU's alone (no frame-slot wait)
    const auto t0 = std::chrono::steady_clock::now();
    Status s = engine->renderFrame(params);
    const auto t1 = std::chrono::steady_clock::now();
    INFO(s.error);
    REQUIRE(s.ok());
    const PassTimings t = engine->lastTimings();
    if (f >= 3 && t.valid) {  // steady state
      cpuMs += std::chrono::duration<double, std::milli>(t1 - t0).count();
      deformMs += t.deformMs, shadowMs += t.shadowMs, prepassMs += t.prepassMs, lightingMs += t.lightingMs;
      ++timed;
    }
  }
  REQUIRE(engine->waitIdle().ok());
  // The animation evaluation alone.
  ScenePose pose;
  REQUIRE(pose.reset(engine->scene()).ok());
  const auto e0 = std::chrono::steady_clock::now();
  for (uint32_t f = 0; f < frames; ++f) REQUIRE(pose.evaluate(engine->scene(), f / 30.0, playbacks, false).ok());
  const double evaluateMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - e0).count() /
                            std::max(frames, 1u);
  size_t vertices = 0;
  for (const DeformedInstance& d : engine->deformedInstances()) vertices += d.vertexCount;
  std::printf("%u characters, %zu deformed instances, %zu deformed vertices, %ux%u on %s (async compute family %d, "
              "validation %s)\n"
              "per frame (mean of %u): ScenePose::evaluate %.3f ms (%zu joint matrices), renderFrame CPU %.3f ms, "
              "GPU deform %.3f ms, shadow %.3f, prepass %.3f, lighting %.3f\n",
              characters, engine->deformedInstances().size(), vertices, width, height,
              engine->deviceInfo().name.c_str(), int(engine->asyncComputeQueueFamily()), validation ? "on" : "off",
              timed, evaluateMs, pose.packedJointMatrices().size(), cpuMs / std::max(timed, 1u),
              deformMs / std::max(timed, 1u), shadowMs / std::max(timed, 1u), prepassMs / std::max(timed, 1u),
              lightingMs / std::max(timed, 1u));
  // The last frame's poses of one copy of each model.
  for (size_t m = 0; m < models.size() && m < characters; ++m) {
    INFO("character " << m << " (" << paths[m] << ")");
    const double t = params.time + playbacks[m].timeOffset;
    const glm::mat4 placement = glm::translate(glm::mat4(1.0f),
                                               glm::vec3(-12.0f + 24.0f * float(m) / float(columns), 0.0f, -12.0f)) *
                                glm::scale(glm::mat4(1.0f), glm::vec3(scales[m]));
    CHECK(compareWithReference(*engine, reference(paths[m], 0, t), firstInstance[m], int(firstNode[m]),
                               glm::dmat4(placement)) > 0);
  }
  CHECK(engine->validationErrorCount() == 0);
}

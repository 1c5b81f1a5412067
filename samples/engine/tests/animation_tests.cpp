// Animation against the independent double-precision reference poser (tests/reference): the engine's GPU
// skinning / morphing (deformed buffers) and CPU node animation (instance transforms), on generated fixtures and
// the shared sample models.
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

namespace {

void checkModelAgainstReference(const std::string& path, std::initializer_list<double> times) {
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
  REQUIRE(engine->setRenderSize(kSize, kSize).ok());
  REQUIRE_FALSE(engine->deformedInstances().empty());
  std::vector<pose_reference::PosedPrimitive> previous;
  for (double t : times) {
    INFO("time " << t);
    const auto ref = reference(path, 0, t);
    if (!previous.empty()) CHECK(poseDifference(previous, ref) > 100 * kRelativeTolerance * diagonal(ref));
    FrameParams params;
    params.time = t;
    render(*engine, params);
    CHECK(compareWithReference(*engine, ref) == engine->deformedInstances().size());
    previous = ref;
  }
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->lastTimings().deformMs > 0.0);
  CHECK(engine->validationErrorCount() == 0);
}

void checkSharedModel(const char* name) {
  const auto path = test_support::sharedScenesDir() / name / (std::string(name) + ".gltf");
  if (!std::filesystem::exists(path)) SKIP("shared glTF model not present: " + path.string());
  checkModelAgainstReference(path.string(), {0.4, 1.3});
}

}  // namespace

TEST_CASE("skinned strip (8 influences): deformed vertices and transforms match the reference",
          "[animation][skinning]") {
  const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
  const Scene scene = loadGltfScene(path);
  REQUIRE(scene.animations.size() == 1);
  CHECK(scene.animations[0].name == "bend");
  CHECK(scene.animations[0].duration == 2.0f);
  REQUIRE(scene.instances.size() == 1);
  CHECK(scene.instances[0].node == 1);
  CHECK(scene.instances[0].skin == 0);
  CHECK(scene.meshes[0].influences() == 8);
  // 0.75 s: the LINEAR rotation (shortest arc), 1.8 s: the CUBICSPLINE scale.
  checkModelAgainstReference(path, {0.75, 1.8});
}

TEST_CASE("morph cube: LINEAR and CUBICSPLINE weights, sparse deltas, match the reference", "[animation][morph]") {
  const std::string path = writeFixture("sample_engine_morph_cube.gltf", pose_reference::writeMorphCube);
  const Scene scene = loadGltfScene(path);
  REQUIRE(scene.meshes.size() == 1);
  REQUIRE(scene.meshes[0].morphTargets.size() == 2);
  CHECK(scene.meshes[0].morphWeights == std::vector<float>{0.25f, 0.0f});
  REQUIRE(scene.instances.size() == 2);  // one mesh, two nodes: two deformed instances
  auto engine = makeEngine();
  REQUIRE(engine->loadScene(scene).ok());
  REQUIRE(engine->setRenderSize(kSize, kSize).ok());
  REQUIRE(engine->deformedInstances().size() == 2);
  CHECK(engine->deformedInstances()[0].positionBuffer != engine->deformedInstances()[1].positionBuffer);

  SECTION("rest pose: the node's weights, else the mesh's") {
    FrameParams params;
    params.restPose = true;
    render(*engine, params);
    CHECK(compareWithReference(*engine, reference(path, -1, 0.0)) == 2);
  }
  for (double t : {0.5, 1.5}) {
    DYNAMIC_SECTION("time " << t) {
      FrameParams params;
      params.time = t;
      render(*engine, params);
      CHECK(compareWithReference(*engine, reference(path, 0, t)) == 2);
    }
  }
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("two appendScene copies at different time offsets get their own buffers and poses", "[animation][append]") {
  const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
  const Scene strip = loadGltfScene(path);
  Scene scene = makeDefaultDemoScene();
  const uint32_t staticInstances = uint32_t(scene.instances.size());
  const glm::mat4 placementA = glm::translate(glm::mat4(1.0f), glm::vec3(-2.0f, 0.0f, 0.0f));
  const glm::mat4 placementB = glm::translate(glm::mat4(1.0f), glm::vec3(2.0f, 0.0f, 1.0f)) *
                               glm::rotate(glm::mat4(1.0f), 0.5f, glm::vec3(0, 1, 0));
  const uint32_t nodesA = uint32_t(scene.nodes.size()) + 1;  // after the "placement" root
  const uint32_t a = appendScene(scene, strip, placementA);
  const uint32_t nodesB = uint32_t(scene.nodes.size()) + 1;
  const uint32_t b = appendScene(scene, strip, placementB);
  CHECK(a == 0);
  CHECK(b == 1);
  REQUIRE(scene.instances.size() == staticInstances + 2);
  CHECK(scene.animationIndex("bend") == 0u);  // the first of equal names
  CHECK(scene.animationIndex("1") == 1u);
  CHECK_FALSE(scene.animationIndex("2").has_value());
  CHECK_FALSE(scene.animationIndex("walk").has_value());

  auto engine = makeEngine();
  REQUIRE(engine->loadScene(scene).ok());
  REQUIRE(engine->setRenderSize(kSize, kSize).ok());
  REQUIRE(engine->deformedInstances().size() == 2);
  const DeformedInstance& da = engine->deformedInstances()[0];
  const DeformedInstance& db = engine->deformedInstances()[1];
  CHECK(da.instance == staticInstances);
  CHECK(db.instance == staticInstances + 1);
  CHECK(da.positionBuffer != db.positionBuffer);
  CHECK(da.attributeBuffer != db.attributeBuffer);
  CHECK(da.positionAddress != db.positionAddress);

  FrameParams params;
  params.time = 0.5;
  params.animations = {{a, 0.25}, {b, 0.7}};  // copy A at 0.75 s (rotation), copy B at 1.2 s (STEP translation)
  render(*engine, params);
  CHECK(compareWithReference(*engine, reference(path, 0, 0.75), staticInstances, int(nodesA), glm::dmat4(placementA)) ==
        1);
  CHECK(compareWithReference(*engine, reference(path, 0, 1.2), staticInstances + 1, int(nodesB),
                             glm::dmat4(placementB)) == 1);
  // The static demo instances keep their transforms.
  for (uint32_t i = 0; i < staticInstances; ++i) CHECK(engine->instanceTransforms()[i] == scene.instances[i].transform);
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("shared model CesiumMan is skinned like the reference", "[animation][skinning][samples]") {
  checkSharedModel("CesiumMan");
}
TEST_CASE("shared model Fox is skinned like the reference", "[animation][skinning][samples]") {
  checkSharedModel("Fox");
}
TEST_CASE("shared model BrainStem is skinned like the reference", "[animation][skinning][samples]") {
  checkSharedModel("BrainStem");
}

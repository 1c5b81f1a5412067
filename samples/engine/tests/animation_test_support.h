// Helpers of the animation tests: generated fixtures, the reference poser, and comparing the engine's deformed
// buffers and instance transforms with it.
#pragma once

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>

#include "engine_test_support.h"
#include "gltf_fixtures.h"
#include "gltf_pose_reference.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"

namespace animation_test {

using namespace sample_engine;

constexpr uint32_t kSize = 64;               // lavapipe is slow; the pixels are not what these tests look at
constexpr double kRelativeTolerance = 1e-5;  // of the model's bounding-box diagonal

// Writes a generated fixture into the temp directory and returns its path.
inline std::string writeFixture(const char* name, std::string (*writer)(const std::string&)) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  const std::string e = writer(path);
  INFO(e);
  REQUIRE(e.empty());
  return path;
}

inline Scene loadGltfScene(const std::string& path) {
  SceneLoadResult r = loadGltf(path);
  INFO(r.error);
  REQUIRE(r.ok());
  return std::move(r.scene);
}

inline std::vector<pose_reference::PosedPrimitive> reference(const std::string& path, int animation, double time) {
  std::string error;
  auto posed = pose_reference::poseGltf(path, animation, time, &error);
  INFO(error);
  REQUIRE(posed.has_value());
  return std::move(*posed);
}

inline double diagonal(const std::vector<pose_reference::PosedPrimitive>& prims) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const auto& p : prims)
    for (const glm::dvec3& v : p.localPositions) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
  return glm::length(hi - lo);
}

inline void render(Engine& engine, FrameParams params) {
  params.camera = defaultCameraFor(engine.sceneBounds());
  params.shadow.mapSize = 1024;
  Status s = engine.renderFrame(params);
  INFO(s.error);
  REQUIRE(s.ok());
}

// Compares every deforming instance's deformed positions and every instance's transform with the reference
// primitives at the same place in the order (matched by node and primitive order within the node). `placement`
// is what appendScene put above the reference's roots; `firstInstance` skips instances of other copies.
// Returns how many deformed instances were compared.
inline size_t compareWithReference(Engine& engine, const std::vector<pose_reference::PosedPrimitive>& ref,
                                   uint32_t firstInstance = 0, int nodeOffset = 0,
                                   const glm::dmat4& placement = glm::dmat4(1.0)) {
  const Scene& scene = engine.scene();
  const double tolerance = kRelativeTolerance * diagonal(ref);
  std::map<int, std::vector<const pose_reference::PosedPrimitive*>> refByNode;
  for (const auto& p : ref) refByNode[p.node].push_back(&p);
  std::map<int, size_t> seen;  // per reference node: instances matched so far
  std::map<uint32_t, uint32_t> deformedOf;
  for (uint32_t d = 0; d < engine.deformedInstances().size(); ++d)
    deformedOf[engine.deformedInstances()[d].instance] = d;
  size_t compared = 0;
  for (uint32_t i = firstInstance; i < firstInstance + ref.size(); ++i) {
    const Instance& inst = scene.instances.at(i);
    const int node = inst.node - nodeOffset;
    const auto& list = refByNode[node];
    REQUIRE(seen[node] < list.size());
    const pose_reference::PosedPrimitive& p = *list[seen[node]++];
    INFO("instance " << i << ", node " << node << ", primitive " << p.primitive);

    const glm::dmat4 expectedWorld = placement * p.nodeWorld;
    const glm::mat4 world = engine.instanceTransforms()[i];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        CHECK(std::abs(double(world[c][r]) - expectedWorld[c][r]) <= 1e-5 * (1.0 + std::abs(expectedWorld[c][r])));

    if (!deformedOf.count(i)) continue;
    auto positions = engine.readbackDeformedPositions(deformedOf[i]);
    INFO(positions.error);
    REQUIRE(positions.ok());
    REQUIRE(positions.value.size() == p.localPositions.size());
    double maxError = 0.0;
    for (size_t v = 0; v < p.localPositions.size(); ++v)
      maxError = std::max(maxError, glm::length(glm::dvec3(positions.value[v]) - p.localPositions[v]));
    INFO("max deformed-position error " << maxError << ", tolerance " << tolerance);
    CHECK(maxError <= tolerance);
    // The pose box the engine reports holds every deformed vertex, and is not much larger than they are.
    const DeformedInstance& di = engine.deformedInstances()[deformedOf[i]];
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    size_t outside = 0;
    for (const glm::vec3& q : positions.value) {
      lo = glm::min(lo, q), hi = glm::max(hi, q);
      outside += glm::any(glm::lessThan(q, di.boundsMin)) || glm::any(glm::greaterThan(q, di.boundsMax));
    }
    INFO("pose box x " << di.boundsMin.x << " .. " << di.boundsMax.x << ", y " << di.boundsMin.y << " .. "
                       << di.boundsMax.y << ", z " << di.boundsMin.z << " .. " << di.boundsMax.z << "; vertices x "
                       << lo.x << " .. " << hi.x << ", y " << lo.y << " .. " << hi.y << ", z " << lo.z << " .. "
                       << hi.z);
    CHECK(outside == 0);
    CHECK(glm::length(di.boundsMax - di.boundsMin) <= 3.0f * glm::length(hi - lo) + 1e-4f);
    ++compared;
  }
  return compared;
}

// Largest distance between two poses of the reference: a comparison is only meaningful if the poses differ.
inline double poseDifference(const std::vector<pose_reference::PosedPrimitive>& a,
                             const std::vector<pose_reference::PosedPrimitive>& b) {
  double d = 0.0;
  for (size_t p = 0; p < a.size(); ++p)
    for (size_t v = 0; v < a[p].localPositions.size(); ++v)
      d = std::max(d, glm::length(a[p].localPositions[v] - b[p].localPositions[v]));
  return d;
}

}  // namespace animation_test

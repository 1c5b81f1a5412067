// The pre-pass's motion vectors against the reference poser: for every pixel, where its surface point was on screen
// last frame, with the mesh skinned to another pose and the camera moved in between.
#include <cmath>
#include <limits>

#include <catch2/catch_test_macros.hpp>

#include "animation_test_support.h"

using namespace sample_engine;
using namespace animation_test;
using test_support::makeEngine;

namespace {

constexpr uint32_t kImage = 96;

struct TriangleHit {
  bool hit = false;
  size_t triangle = 0;
  double u = 0.0, v = 0.0;  // barycentrics of vertices 1 and 2
};

// The closest triangle along the ray (Moller-Trumbore, double precision).
TriangleHit intersect(const glm::dvec3& origin, const glm::dvec3& dir, const std::vector<glm::dvec3>& p,
                      const std::vector<uint32_t>& indices) {
  TriangleHit best;
  double bestT = std::numeric_limits<double>::max();
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::dvec3 a = p[indices[t]], b = p[indices[t + 1]], c = p[indices[t + 2]];
    const glm::dvec3 e1 = b - a, e2 = c - a, q = glm::cross(dir, e2);
    const double det = glm::dot(e1, q);
    if (std::abs(det) < 1e-14) continue;
    const glm::dvec3 s = origin - a;
    const double u = glm::dot(s, q) / det;
    const glm::dvec3 r = glm::cross(s, e1);
    const double v = glm::dot(dir, r) / det;
    const double dist = glm::dot(e2, r) / det;
    if (u < 0.0 || v < 0.0 || u + v > 1.0 || dist <= 0.0 || dist >= bestT) continue;
    bestT = dist;
    best = {true, t / 3, u, v};
  }
  return best;
}

// The engine's camera-relative matrices (frame_recorder.cpp): rotation-only view, projection with Y flipped.
glm::dmat4 cameraRelativeViewProj(const Camera& camera) {
  glm::mat4 view = viewMatrix(camera);
  view[3] = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  return glm::dmat4(projectionMatrix(camera, 1.0f)) * glm::dmat4(view);
}

glm::dvec2 pixelOf(const glm::dmat4& viewProj, const glm::dvec3& relative) {
  const glm::dvec4 clip = viewProj * glm::dvec4(relative, 1.0);
  return (glm::dvec2(clip) / clip.w * 0.5 + 0.5) * double(kImage);
}

}  // namespace

TEST_CASE("pre-pass motion vectors follow a skinned mesh and the camera to 0.1 px", "[animation][motion]") {
  const std::string path = writeFixture("sample_engine_skinned_strip.gltf", pose_reference::writeSkinnedStrip);
  auto engine = makeEngine();
  REQUIRE(engine->setRenderSize(kImage, kImage).ok());
  REQUIRE(engine->loadScene(loadGltfScene(path)).ok());
  const double t0 = 0.5, t1 = 0.75;
  FrameParams params;
  params.camera = defaultCameraFor(engine->sceneBounds());
  params.shadow.mapSize = 256;
  params.time = t0;
  const Camera camera0 = params.camera;
  REQUIRE(engine->renderFrame(params).ok());
  auto first = engine->readbackMotionVectors();
  INFO(first.error);
  REQUIRE(first.ok());
  size_t moving = 0;
  for (const glm::vec2& m : first.value) moving += m != glm::vec2(0.0f);
  CHECK(moving == 0);  // the scene's first frame has no previous one

  // Another pose, and the camera moved and turned a little.
  params.time = t1;
  params.camera.eye += glm::vec3(0.04f, -0.03f, 0.05f) * glm::length(camera0.eye - camera0.target);
  params.camera.target += glm::vec3(0.02f, 0.0f, -0.01f);
  const Camera camera1 = params.camera;
  REQUIRE(engine->renderFrame(params).ok());
  auto motion = engine->readbackMotionVectors();
  INFO(motion.error);
  REQUIRE(motion.ok());
  REQUIRE(motion.value.size() == size_t(kImage) * kImage);

  const auto posed0 = reference(path, 0, t0), posed1 = reference(path, 0, t1);
  REQUIRE(posed0.size() == 1);
  REQUIRE(posed1.size() == 1);
  const glm::dvec3 eye0(camera0.eye), eye1(camera1.eye);
  std::vector<glm::dvec3> relative1;  // this frame's posed mesh relative to this frame's eye
  for (const glm::dvec3& p : posed1[0].worldPositions) relative1.push_back(p - eye1);
  const std::vector<uint32_t>& indices = posed1[0].indices;
  const glm::dmat4 viewProj0 = cameraRelativeViewProj(camera0), viewProj1 = cameraRelativeViewProj(camera1);
  const glm::dmat4 inverse1 = glm::inverse(viewProj1);

  std::vector<TriangleHit> hits(size_t(kImage) * kImage);
  for (uint32_t y = 0; y < kImage; ++y)
    for (uint32_t x = 0; x < kImage; ++x) {
      const glm::dvec2 ndc = (glm::dvec2(x, y) + 0.5) / double(kImage) * 2.0 - 1.0;
      const glm::dvec4 far = inverse1 * glm::dvec4(ndc, 1.0, 1.0);
      hits[size_t(y) * kImage + x] = intersect(glm::dvec3(0.0), glm::normalize(glm::dvec3(far) / far.w), relative1,
                                               indices);
    }
  double worst = 0.0, largest = 0.0;
  size_t compared = 0, covered = 0;
  for (uint32_t y = 1; y + 1 < kImage; ++y)
    for (uint32_t x = 1; x + 1 < kImage; ++x) {
      const size_t i = size_t(y) * kImage + x;
      covered += hits[i].hit;
      // Interior pixels: rasterization and the ray agree on coverage there (a silhouette pixel may go either way).
      if (!hits[i].hit || !hits[i - 1].hit || !hits[i + 1].hit || !hits[i - kImage].hit || !hits[i + kImage].hit)
        continue;
      const TriangleHit& h = hits[i];
      const auto vertex0 = [&](int k) { return posed0[0].worldPositions[indices[h.triangle * 3 + size_t(k)]]; };
      const glm::dvec3 previous = (1.0 - h.u - h.v) * vertex0(0) + h.u * vertex0(1) + h.v * vertex0(2);
      const glm::dvec2 expected = glm::dvec2(x + 0.5, y + 0.5) - pixelOf(viewProj0, previous - eye0);
      const glm::dvec2 got(motion.value[i]);
      worst = std::max(worst, glm::length(got - expected));
      largest = std::max(largest, glm::length(expected));
      ++compared;
    }
  INFO("covered " << covered << ", compared " << compared << ", largest expected motion " << largest
                  << " px, worst error " << worst << " px");
  REQUIRE(compared > covered / 2);
  REQUIRE(compared > 100);
  CHECK(largest > 2.0);  // the case moves: a zero field would fail
  CHECK(worst <= 0.1);

  // The same frame again: nothing moved, and a still vertex gives exactly zero motion.
  REQUIRE(engine->renderFrame(params).ok());
  auto still = engine->readbackMotionVectors();
  REQUIRE(still.ok());
  moving = 0;
  for (const glm::vec2& m : still.value) moving += m != glm::vec2(0.0f);
  CHECK(moving == 0);
  REQUIRE(engine->waitIdle().ok());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("motion vectors need a pre-pass: an external-colour frame has none to read back", "[motion][errors]") {
  auto engine = makeEngine();
  REQUIRE(engine->setRenderSize(16, 16).ok());
  CHECK_FALSE(engine->readbackMotionVectors().ok());  // nothing rendered yet
  FrameParams params;
  params.externalColor = true;
  engine->setPrepassHook([](const PrepassHookInfo&, LightingInputs&) {});
  REQUIRE(engine->renderFrame(params).ok());
  auto r = engine->readbackMotionVectors();
  CHECK_FALSE(r.ok());
  CHECK(r.error.find("FrameParams::externalColor") != std::string::npos);
}

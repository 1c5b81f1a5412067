// Self-tests of the reference poser against analytic expectations derived from the fixtures' definitions
// (gltf_fixture_constants.h), plus sanity checks on sample models when they are present.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <filesystem>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "accessor_reader.h"
#include "gltf_fixture_constants.h"
#include "gltf_fixtures.h"
#include "gltf_pose_reference.h"

namespace fs = std::filesystem;
using namespace pose_reference;
using namespace pose_reference::fixture;

namespace {

// Fixture data is stored as float: expectations computed in double match to about 1e-6 at these magnitudes.
constexpr double kTolerance = 2e-5;

std::string writeFixture(const char* name, std::string (*writer)(const std::string&)) {
  const fs::path dir = fs::temp_directory_path() / "pose_reference_tests";
  fs::create_directories(dir);
  const std::string path = (dir / name).string();
  const std::string error = writer(path);
  INFO(error);
  REQUIRE(error.empty());
  return path;
}

std::vector<PosedPrimitive> pose(const std::string& path, int animation, double time) {
  std::string error;
  std::optional<std::vector<PosedPrimitive>> result = poseGltf(path, animation, time, &error);
  INFO("time " << time << ": " << error);
  REQUIRE(result.has_value());
  return *result;
}

std::string poseError(const std::string& path, int animation, double time) {
  std::string error;
  REQUIRE_FALSE(poseGltf(path, animation, time, &error).has_value());
  return error;
}

bool near(const glm::dvec3& a, const glm::dvec3& b, double tolerance = kTolerance) {
  return glm::length(a - b) <= tolerance;
}
#define CHECK_NEAR(a, b)                                                                                              \
  do {                                                                                                                \
    const glm::dvec3 a_ = (a), b_ = (b);                                                                              \
    INFO(#a " = (" << a_.x << ", " << a_.y << ", " << a_.z << "), expected (" << b_.x << ", " << b_.y << ", " << b_.z \
                   << ")");                                                                                           \
    CHECK(near(a_, b_));                                                                                              \
  } while (0)

// ---- Strip expectations, from rigid motions of the joints (no matrix chain of the poser is reused) ----

// The world-space rotation joint1 applies: `degrees` about its local Z, which the root turns by its yaw; the
// pivot is joint1's bind position. joint2 is its child and moves with it.
glm::dvec3 rotateAboutJoint1(const glm::dvec3& p, double degrees) {
  const glm::dvec3 axis = stripRootRotation() * glm::dvec3(0, 0, 1);
  const glm::dvec3 pivot = stripJointBindWorld(1);
  return pivot + glm::angleAxis(glm::radians(degrees), axis) * (p - pivot);
}

// Expected posed position of strip vertex (row, column): joint0 never moves; joint1 rotates by `degrees`;
// joint2 rotates with it, then is offset by the STEP translation (x in its parent's frame, i.e. root-rotated
// and scaled) and scaled uniformly about its own position by `scale`.
glm::dvec3 expectedStrip(int row, int column, double degrees, double stepOffsetX, double scale) {
  const glm::dvec3 p = stripBindPosition(row, column);
  const glm::dvec3 w = stripJointTotals(row);
  const glm::dvec3 pivot2 = stripJointBindWorld(2);
  const glm::dvec3 offset = kStripRootScale * (stripRootRotation() * glm::dvec3(stepOffsetX, 0, 0));
  const glm::dvec3 joint2 = rotateAboutJoint1(pivot2 + offset + scale * (p - pivot2), degrees);
  return w[0] * p + w[1] * rotateAboutJoint1(p, degrees) + w[2] * joint2;
}

void checkStrip(const std::string& path, double time, double degrees, double stepOffsetX, double scale) {
  const std::vector<PosedPrimitive> posed = pose(path, 0, time);
  REQUIRE(posed.size() == 1);
  INFO("time " << time);
  for (int row = 0; row < kStripRows; ++row)
    for (int column = 0; column < 2; ++column) {
      INFO("row " << row << " column " << column);
      CHECK_NEAR(posed[0].worldPositions[size_t(stripVertexIndex(row, column))],
                 expectedStrip(row, column, degrees, stepOffsetX, scale));
    }
}

glm::dmat4 trs(const glm::dvec3& t, const glm::dquat& r) {
  return glm::translate(glm::dmat4(1.0), t) * glm::mat4_cast(r);
}

}  // namespace

TEST_CASE("fixtures are valid glTF that tinygltf loads, with what they claim", "[pose_reference]") {
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  tinygltf::Model strip;
  REQUIRE(loader.LoadASCIIFromFile(&strip, &err, &warn, writeFixture("strip.gltf", writeSkinnedStrip)));
  CHECK(err.empty());
  REQUIRE(strip.animations.size() == 1);
  CHECK(strip.animations[0].name == "bend");
  std::vector<std::string> interpolations;
  for (const auto& s : strip.animations[0].samplers) interpolations.push_back(s.interpolation);
  CHECK(interpolations == std::vector<std::string>{"LINEAR", "STEP", "CUBICSPLINE"});
  REQUIRE(strip.skins.size() == 1);
  CHECK(strip.skins[0].joints.size() == size_t(kStripJointCount));

  // Every vertex's 8 weights sum to 1, and middle vertices use all 8 slots.
  const auto& attrs = strip.meshes[0].primitives[0].attributes;
  std::string e;
  const std::optional<AccessorValues> w0 = readAccessor(strip, attrs.at("WEIGHTS_0"), &e);
  const std::optional<AccessorValues> w1 = readAccessor(strip, attrs.at("WEIGHTS_1"), &e);
  REQUIRE((w0 && w1));
  REQUIRE(w0->count == size_t(kStripVertexCount));
  int fullyWeighted = 0;
  for (size_t v = 0; v < w0->count; ++v) {
    double sum = 0;
    int nonZero = 0;
    for (int i = 0; i < 4; ++i) {
      sum += w0->at(v, i) + w1->at(v, i);
      nonZero += (w0->at(v, i) > 0) + (w1->at(v, i) > 0);
    }
    CHECK(std::abs(sum - 1.0) < 1e-6);
    fullyWeighted += nonZero == 8;
  }
  CHECK(fullyWeighted >= kStripVertexCount / 2);
  // Inverse bind matrices are not identity.
  const std::optional<AccessorValues> ibm = readAccessor(strip, strip.skins[0].inverseBindMatrices, &e);
  REQUIRE(ibm);
  CHECK(std::abs(ibm->at(0, 0) - 1.0) > 0.1);

  tinygltf::Model cube;
  REQUIRE(loader.LoadASCIIFromFile(&cube, &err, &warn, writeFixture("cube.gltf", writeMorphCube)));
  REQUIRE(cube.meshes.size() == 1);
  CHECK(cube.meshes[0].primitives[0].targets.size() == size_t(kCubeTargetCount));
  CHECK(cube.meshes[0].weights == std::vector<double>(kCubeMeshWeights.begin(), kCubeMeshWeights.end()));
  CHECK(cube.accessors[size_t(cube.meshes[0].primitives[0].targets[1].at("POSITION"))].sparse.isSparse);
  CHECK(animationNames(writeFixture("cube.gltf", writeMorphCube)) == std::vector<std::string>{"morph"});
  CHECK(animationNames("/nonexistent/missing.gltf").empty());
}

TEST_CASE("skinned strip: bind pose where every joint is at its bind transform", "[pose_reference]") {
  const std::string path = writeFixture("strip.gltf", writeSkinnedStrip);
  const glm::dmat4 meshNodeWorld = stripRootMatrix() * trs(stripMeshNodeTranslation(), stripMeshNodeRotation());
  // Rest pose, and the two animation times at which all three channels give the bind values.
  for (auto [animation, time] : {std::pair{-1, 0.0}, std::pair{0, 0.0}, std::pair{0, 1.5}}) {
    INFO("animation " << animation << " time " << time);
    const std::vector<PosedPrimitive> posed = pose(path, animation, time);
    REQUIRE(posed.size() == 1);
    const PosedPrimitive& p = posed[0];
    CHECK(p.node == kStripMeshNode);
    CHECK((p.mesh == 0 && p.primitive == 0));
    CHECK(p.indices.size() == size_t(6 * (kStripRows - 1)));
    for (int c = 0; c < 4; ++c) CHECK(near(glm::dvec3(p.nodeWorld[c]), glm::dvec3(meshNodeWorld[c]), 1e-12));
    for (int row = 0; row < kStripRows; ++row)
      for (int column = 0; column < 2; ++column) {
        const size_t v = size_t(stripVertexIndex(row, column));
        CHECK_NEAR(p.worldPositions[v], stripBindPosition(row, column));
        CHECK_NEAR(glm::dvec3(meshNodeWorld * glm::dvec4(p.localPositions[v], 1.0)), p.worldPositions[v]);
        CHECK_NEAR(p.worldNormals[v], stripRootRotation() * glm::dvec3(0, 0, 1));
      }
  }
}

TEST_CASE("skinned strip: LINEAR rotation slerps along the shorter arc", "[pose_reference]") {
  const std::string path = writeFixture("strip.gltf", writeSkinnedStrip);
  checkStrip(path, 0.25, 30.0, 0.0, 1.0);  // halfway 0 -> 60 degrees
  checkStrip(path, 0.5, 60.0, 0.0, 1.0);   // a key
  checkStrip(path, 0.75, 30.0, 0.0, 1.0);  // 60 -> "0 stored as -identity": 30, not 210
  checkStrip(path, 0.99, 1.2, 0.0, 1.0);   // slerp is linear in angle: 60 * (1 - 0.98)

  // Normals of vertices that joint0 does not influence turn with joint1 (rigidly).
  const PosedPrimitive p = pose(path, 0, 0.25)[0];
  const glm::dvec3 bindNormal = stripRootRotation() * glm::dvec3(0, 0, 1);
  const glm::dvec3 turned = glm::angleAxis(glm::radians(30.0), stripRootRotation() * glm::dvec3(0, 0, 1)) * bindNormal;
  for (int row = 0; row < kStripRows; ++row)
    if (stripJointTotals(row)[0] == 0.0) CHECK_NEAR(p.worldNormals[size_t(stripVertexIndex(row, 0))], turned);
}

TEST_CASE("skinned strip: STEP translation holds its value until the next key", "[pose_reference]") {
  const std::string path = writeFixture("strip.gltf", writeSkinnedStrip);
  for (double t : {1.0, 1.2, 1.49}) checkStrip(path, t, 0.0, kStripStepOffsetX, 1.0);
  const std::vector<PosedPrimitive> a = pose(path, 0, 1.1), b = pose(path, 0, 1.4);
  CHECK(a[0].worldPositions == b[0].worldPositions);  // held exactly: nothing else moves in [1, 1.5)
  checkStrip(path, 1.5, 0.0, 0.0, 1.0);               // the third key restores the bind translation
}

TEST_CASE("skinned strip: CUBICSPLINE scale hits its keys and differs from linear between them", "[pose_reference]") {
  const std::string path = writeFixture("strip.gltf", writeSkinnedStrip);
  checkStrip(path, kStripScaleTimes[1], 0.0, 0.0, kStripScaleValues[1]);
  // Hermite at u = 0.5 of [1.5, 1.75] (delta 0.25): 0.5 * 1 + 0.125 * (0.25 * out0) + 0.5 * 1.5 - 0.125 * 0.
  const double hermite = 0.5 * kStripScaleValues[0] + 0.125 * 0.25 * kStripScaleOutTangent0 +
                         0.5 * kStripScaleValues[1];
  REQUIRE(hermite != 0.5 * (kStripScaleValues[0] + kStripScaleValues[1]));
  checkStrip(path, 1.625, 0.0, 0.0, hermite);
  // u = 0.6 of [1.75, 2], zero tangents: h00 = 2u^3 - 3u^2 + 1.
  const double u = 0.6, h00 = 2 * u * u * u - 3 * u * u + 1;
  checkStrip(path, 1.9, 0.0, 0.0, h00 * kStripScaleValues[1] + (1 - h00) * kStripScaleValues[2]);
}

TEST_CASE("animation time loops over the duration", "[pose_reference]") {
  const std::string path = writeFixture("strip.gltf", writeSkinnedStrip);
  for (double t : {0.25, 0.75, 1.2, 1.625}) {
    INFO("time " << t);
    const PosedPrimitive a = pose(path, 0, t)[0], b = pose(path, 0, t + kStripDuration)[0],
                         c = pose(path, 0, t + 5 * kStripDuration)[0];
    for (size_t v = 0; v < a.worldPositions.size(); ++v) {
      CHECK_NEAR(a.worldPositions[v], b.worldPositions[v]);
      CHECK_NEAR(a.worldPositions[v], c.worldPositions[v]);
    }
  }
  // fmod convention: the end of the animation is its start.
  CHECK(pose(path, 0, kStripDuration)[0].worldPositions == pose(path, 0, 0.0)[0].worldPositions);
}

TEST_CASE("morph cube: base + sum of weights * deltas, with the spec's weight precedence", "[pose_reference]") {
  const std::string path = writeFixture("cube.gltf", writeMorphCube);
  struct Case {
    int animation;
    double time;
    glm::dvec2 weights[2];  // node 0, node 1
  };
  const double l0 = kCubeLinearWeights[1][0], l1 = kCubeLinearWeights[1][1];
  const Case cases[] = {
      {-1, 0.0, {{kCubeMeshWeights[0], kCubeMeshWeights[1]}, {kCubeSplineNodeWeights[0], kCubeSplineNodeWeights[1]}}},
      {0, 0.0, {{0, 0}, {0, 0}}},
      {0, 0.5, {{0.5 * l0, 0.5 * l1}, {0, 0}}},  // LINEAR halfway; the spline's first key holds
      {0, 1.0, {{l0, l1}, {0, 0}}},              // keys of both samplers
      {0, 1.5, {{l0, l1}, {0.625, 0.25}}},       // LINEAR held; CUBICSPLINE (linear: 0.5, 0.5)
      {0, 2.5, {{0.5 * l0, 0.5 * l1}, {0, 0}}},  // looped
  };
  for (const Case& c : cases) {
    INFO("animation " << c.animation << " time " << c.time);
    const std::vector<PosedPrimitive> posed = pose(path, c.animation, c.time);
    REQUIRE(posed.size() == 2);
    for (int node = 0; node < 2; ++node) {
      INFO("node " << node);
      const PosedPrimitive& p = posed[size_t(node)];
      CHECK(p.node == node);
      REQUIRE(p.localPositions.size() == size_t(kCubeVertexCount));
      CHECK(p.indices.size() == 36);
      const glm::dmat4 world = trs(cubeNodeTranslation(node), cubeNodeRotation(node));
      for (int v = 0; v < kCubeVertexCount; ++v) {
        INFO("vertex " << v);
        const glm::dvec2 w = c.weights[node];
        const glm::dvec3 local = cubePosition(v) + w[0] * cubePositionDelta(0, v) + w[1] * cubePositionDelta(1, v);
        CHECK_NEAR(p.localPositions[size_t(v)], local);
        CHECK_NEAR(p.worldPositions[size_t(v)], glm::dvec3(world * glm::dvec4(local, 1.0)));
        const glm::dvec3 normal = cubeFaceNormal(v / 4) + w[0] * cubeNormalDelta(0, v) + w[1] * cubeNormalDelta(1, v);
        CHECK_NEAR(p.worldNormals[size_t(v)], glm::normalize(glm::dmat3(world) * normal));
      }
    }
  }
}

TEST_CASE("bad input is reported, naming the value", "[pose_reference]") {
  const std::string strip = writeFixture("strip.gltf", writeSkinnedStrip);
  CHECK(poseError(strip, 1, 0.0).find("animation 1 is out of range: the file has 1") != std::string::npos);
  CHECK(poseError(strip, -2, 0.0).find("animation -2") != std::string::npos);
  CHECK(poseError(strip, 0, -1.0).find("time -1") != std::string::npos);
  CHECK(poseError(strip, 0, std::nan("")).find("must be finite") != std::string::npos);
  CHECK(poseError("/nonexistent/missing.gltf", -1, 0.0).find("cannot load /nonexistent/missing.gltf") !=
        std::string::npos);

  const std::string badJoint = poseError(writeFixture("bad_joint.gltf", writeSkinnedStripBadJoint), 0, 0.0);
  INFO(badJoint);
  CHECK(badJoint.find("vertex " + std::to_string(kStripBadJointVertex) + " JOINTS_0[0] = joint index " +
                      std::to_string(kStripJointCount) + ", which is >= the skin's joint count " +
                      std::to_string(kStripJointCount)) != std::string::npos);
  const std::string zero = poseError(writeFixture("zero_weights.gltf", writeSkinnedStripZeroWeights), -1, 0.0);
  INFO(zero);
  CHECK(zero.find("vertex " + std::to_string(kStripZeroWeightVertex) + " has all skinning weights zero") !=
        std::string::npos);
}

// ---- Sample models, when ../shared/scenes is present ----

namespace {

void checkSampleModel(const char* name) {
  const std::string path = std::string(POSE_REFERENCE_SCENES_DIR) + "/" + name + "/" + name + ".gltf";
  if (!fs::exists(path)) SKIP(path << " is absent");
  const std::vector<PosedPrimitive> rest = pose(path, -1, 0.0), a = pose(path, 0, 0.0), b = pose(path, 0, 1.0);
  REQUIRE(!rest.empty());
  REQUIRE((a.size() == rest.size() && b.size() == rest.size()));
  // Bounds: the rest pose's extent, grown generously: a posed character stays near its bind pose.
  glm::dvec3 lo(1e300), hi(-1e300);
  for (const PosedPrimitive& p : rest)
    for (const glm::dvec3& v : p.worldPositions) lo = glm::min(lo, v), hi = glm::max(hi, v);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double radius = glm::length(hi - lo);
  REQUIRE(radius > 0.0);
  double moved = 0.0;
  for (size_t i = 0; i < rest.size(); ++i) {
    REQUIRE(a[i].worldPositions.size() == b[i].worldPositions.size());
    for (size_t v = 0; v < a[i].worldPositions.size(); ++v) {
      for (const glm::dvec3& p : {a[i].worldPositions[v], b[i].worldPositions[v]}) {
        REQUIRE((std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)));
        CHECK(glm::length(p - centre) < 2.0 * radius);
      }
      moved = std::max(moved, glm::length(a[i].worldPositions[v] - b[i].worldPositions[v]));
    }
    for (const glm::dvec3& n : a[i].worldNormals) CHECK(std::abs(glm::length(n) - 1.0) < 1e-9);
  }
  CHECK(moved > 0.01 * radius);  // the animation moves something between 0 s and 1 s

  // These models' rest node transforms are their bind pose: the rest pose is the stored POSITION placed by
  // the mesh node's world transform (measured: within 1e-5 of the size for all four models).
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  REQUIRE(loader.LoadASCIIFromFile(&model, &err, &warn, path));
  double restError = 0.0;
  for (const PosedPrimitive& p : rest) {
    const auto& attributes = model.meshes[size_t(p.mesh)].primitives[size_t(p.primitive)].attributes;
    const std::optional<AccessorValues> bind = readAccessor(model, attributes.at("POSITION"), &err);
    REQUIRE(bind);
    for (size_t v = 0; v < bind->count; ++v) {
      const glm::dvec4 stored(bind->at(v, 0), bind->at(v, 1), bind->at(v, 2), 1.0);
      restError = std::max(restError, glm::length(glm::dvec3(p.nodeWorld * stored) - p.worldPositions[v]));
    }
  }
  CHECK(restError < 1e-4 * radius);
}

}  // namespace

TEST_CASE("sample model CesiumMan poses sanely", "[pose_reference][samples]") { checkSampleModel("CesiumMan"); }
TEST_CASE("sample model Fox poses sanely", "[pose_reference][samples]") { checkSampleModel("Fox"); }
TEST_CASE("sample model BrainStem poses sanely", "[pose_reference][samples]") { checkSampleModel("BrainStem"); }
TEST_CASE("sample model RiggedFigure poses sanely", "[pose_reference][samples]") { checkSampleModel("RiggedFigure"); }

// Writers of the generated fixtures; the numbers come from gltf_fixture_constants.h.
#include "gltf_fixtures.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "gltf_document_builder.h"
#include "gltf_fixture_constants.h"

namespace pose_reference {
namespace {

using namespace fixture;
using nlohmann::json;

constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

json vec(const glm::dvec3& v) { return json::array({v.x, v.y, v.z}); }
json quat(const glm::dquat& q) { return json::array({q.x, q.y, q.z, q.w}); }  // glTF order x, y, z, w
// push_back per value: GCC 12 reports a false -Wstringop-overflow for vector::insert of initializer lists.
template <typename T, typename... Values>
void append(std::vector<T>& out, Values... values) {
  (out.push_back(T(values)), ...);
}
void push(std::vector<float>& out, const glm::dvec3& v) { append(out, v.x, v.y, v.z); }

enum class StripDefect { None, JointOutOfRange, ZeroWeights };

std::string writeStrip(const std::string& path, StripDefect defect, const char* function) {
  GltfDocumentBuilder b;
  json& doc = b.document();

  std::vector<float> positions, normals, uvs;
  std::vector<uint8_t> joints0;
  std::vector<uint16_t> joints1, weights1;
  std::vector<float> weights0;
  const glm::dvec3 normal = stripRootRotation() * glm::dvec3(0, 0, 1);
  for (int row = 0; row < kStripRows; ++row)
    for (int column = 0; column < 2; ++column) {
      push(positions, stripBindPosition(row, column));
      push(normals, normal);
      append(uvs, column, float(row) / float(kStripRows - 1));
      // Eight slots over the three joints: floats {j0, j1, j2, j0}, normalized shorts {j1, j2, j0, j1}. Each
      // joint's total is split unevenly over its slots; the float slots absorb the shorts' quantization, so
      // the per-joint totals (what the tests derive positions from) stay exact to float precision.
      const glm::dvec3 total = stripJointTotals(row);
      auto quantize = [](double w) { return uint16_t(std::lround(w * 65535.0)); };
      const uint16_t s4 = quantize(0.25 * total[1]), s5 = quantize(0.3 * total[2]), s6 = quantize(0.2 * total[0]),
                     s7 = quantize(0.15 * total[1]);
      const double rest0 = total[0] - s6 / 65535.0;
      float w[4] = {float(0.6 * rest0), float(total[1] - (s4 + s7) / 65535.0), float(total[2] - s5 / 65535.0),
                    float(0.4 * rest0)};
      uint16_t s[4] = {s4, s5, s6, s7};
      const int vertex = stripVertexIndex(row, column);
      if (defect == StripDefect::ZeroWeights && vertex == kStripZeroWeightVertex)
        for (int i = 0; i < 4; ++i) w[i] = 0.0f, s[i] = 0;
      weights0.insert(weights0.end(), w, w + 4);
      weights1.insert(weights1.end(), s, s + 4);
      const uint8_t firstJoint = defect == StripDefect::JointOutOfRange && vertex == kStripBadJointVertex
                                     ? uint8_t(kStripJointCount)
                                     : 0;
      append(joints0, firstJoint, 1, 2, 0);
      append(joints1, 1, 2, 0, 1);
    }
  std::vector<uint16_t> indices;
  for (int row = 0; row + 1 < kStripRows; ++row) {
    const uint16_t v0 = uint16_t(stripVertexIndex(row, 0)), v1 = uint16_t(v0 + 1), v2 = uint16_t(v0 + 2),
                   v3 = uint16_t(v0 + 3);
    append(indices, v0, v1, v3, v0, v3, v2);  // counter-clockwise seen from +Z (the normal)
  }

  json attributes = {{"POSITION", b.addFloats(positions, 3, kArrayBuffer, true)},
                     {"NORMAL", b.addFloats(normals, 3, kArrayBuffer)},
                     {"TEXCOORD_0", b.addFloats(uvs, 2, kArrayBuffer)},
                     {"JOINTS_0", b.addIntegers(joints0, 4, kUnsignedByte, kArrayBuffer, false)},
                     {"WEIGHTS_0", b.addFloats(weights0, 4, kArrayBuffer)},
                     {"JOINTS_1", b.addIntegers(joints1, 4, kUnsignedShort, kArrayBuffer, false)},
                     {"WEIGHTS_1", b.addIntegers(weights1, 4, kUnsignedShort, kArrayBuffer, true)}};
  const int indexAccessor = b.addIntegers(indices, 1, kUnsignedShort, kElementArrayBuffer, false);
  doc["meshes"] = json::array(
      {{{"name", "strip"},
        {"primitives", json::array({{{"attributes", attributes}, {"indices", indexAccessor}, {"mode", 4}}})}}});

  // Inverse bind matrices: inverses of the joints' bind world transforms, root included (not identity).
  std::vector<float> inverseBind;
  for (int j = 0; j < kStripJointCount; ++j) {
    const glm::dmat4 bindWorld = stripRootMatrix() *
                                 glm::translate(glm::dmat4(1.0), glm::dvec3(0, j * kStripBoneLength, 0));
    const glm::dmat4 inv = glm::inverse(bindWorld);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) inverseBind.push_back(float(inv[c][r]));
  }
  doc["skins"] = json::array({{{"joints", json::array({2, 3, 4})},
                               {"skeleton", 2},
                               {"inverseBindMatrices", b.addFloats(inverseBind, 16, 0)}}});

  const json boneOffset = vec({0, kStripBoneLength, 0});
  doc["nodes"] = json::array({{{"name", "root"},
                               {"children", json::array({1, 2})},
                               {"translation", vec(stripRootTranslation())},
                               {"rotation", quat(stripRootRotation())},
                               {"scale", vec(glm::dvec3(kStripRootScale))}},
                              {{"name", "strip"},
                               {"mesh", 0},
                               {"skin", 0},
                               {"translation", vec(stripMeshNodeTranslation())},
                               {"rotation", quat(stripMeshNodeRotation())}},
                              {{"name", "joint0"}, {"children", json::array({3})}},
                              {{"name", "joint1"}, {"children", json::array({4})}, {"translation", boneOffset}},
                              {{"name", "joint2"}, {"translation", boneOffset}}});
  doc["scenes"] = json::array({{{"nodes", json::array({kStripRootNode})}}});
  doc["scene"] = 0;

  auto times = [&](const auto& keys) {
    std::vector<float> t(keys.begin(), keys.end());
    return b.addFloats(t, 1, 0, true);
  };
  std::vector<float> rotations;
  for (size_t k = 0; k < kStripRotationTimes.size(); ++k) {
    const double half = glm::radians(kStripRotationDegrees[k]) / 2;
    const bool last = k + 1 == kStripRotationTimes.size();  // stored negated: same rotation, opposite hemisphere
    const double sign = last ? -1.0 : 1.0;
    append(rotations, 0.0, 0.0, sign * std::sin(half), sign * std::cos(half));
  }
  std::vector<float> translations;
  for (size_t k = 0; k < kStripTranslationTimes.size(); ++k)
    push(translations, {k == 1 ? kStripStepOffsetX : 0.0, kStripBoneLength, 0.0});
  std::vector<float> scales;  // per key: in-tangent, value, out-tangent
  for (size_t k = 0; k < kStripScaleTimes.size(); ++k) {
    push(scales, glm::dvec3(0.0));
    push(scales, glm::dvec3(kStripScaleValues[k]));
    push(scales, glm::dvec3(k == 0 ? kStripScaleOutTangent0 : 0.0));
  }
  doc["animations"] = json::array(
      {{{"name", "bend"},
        {"samplers", json::array({{{"input", times(kStripRotationTimes)},
                                   {"output", b.addFloats(rotations, 4, 0)},
                                   {"interpolation", "LINEAR"}},
                                  {{"input", times(kStripTranslationTimes)},
                                   {"output", b.addFloats(translations, 3, 0)},
                                   {"interpolation", "STEP"}},
                                  {{"input", times(kStripScaleTimes)},
                                   {"output", b.addFloats(scales, 3, 0)},
                                   {"interpolation", "CUBICSPLINE"}}})},
        {"channels", json::array({{{"sampler", 0}, {"target", {{"node", 3}, {"path", "rotation"}}}},
                                  {{"sampler", 1}, {"target", {{"node", 4}, {"path", "translation"}}}},
                                  {{"sampler", 2}, {"target", {{"node", 4}, {"path", "scale"}}}}})}}});

  const std::string e = b.write(path);
  return e.empty() ? e : std::string(function) + ": " + e;
}

}  // namespace

std::string writeSkinnedStrip(const std::string& path) {
  return writeStrip(path, StripDefect::None, "writeSkinnedStrip");
}
std::string writeSkinnedStripBadJoint(const std::string& path) {
  return writeStrip(path, StripDefect::JointOutOfRange, "writeSkinnedStripBadJoint");
}
std::string writeSkinnedStripZeroWeights(const std::string& path) {
  return writeStrip(path, StripDefect::ZeroWeights, "writeSkinnedStripZeroWeights");
}

std::string writeMorphCube(const std::string& path) {
  GltfDocumentBuilder b;
  json& doc = b.document();

  std::vector<float> positions, normals, uvs, delta0, normalDelta0, normalDelta1;
  const float corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int v = 0; v < kCubeVertexCount; ++v) {
    push(positions, cubePosition(v));
    push(normals, cubeFaceNormal(v / 4));
    append(uvs, corner[v % 4][0], corner[v % 4][1]);
    push(delta0, cubePositionDelta(0, v));
    push(normalDelta0, cubeNormalDelta(0, v));
    push(normalDelta1, cubeNormalDelta(1, v));
  }
  std::vector<uint32_t> indices;
  for (uint32_t f = 0; f < 6; ++f) append(indices, 4 * f, 4 * f + 1, 4 * f + 2, 4 * f, 4 * f + 2, 4 * f + 3);

  // Target 1's POSITION is sparse with no bufferView (zeros, then the +X face's four deltas): the common way
  // exporters store morph targets that move few vertices.
  std::vector<uint8_t> sparseIndices;
  std::vector<float> sparseValues;
  glm::dvec3 lo(0.0), hi(0.0);
  for (int v = 0; v < kCubeVertexCount; ++v)
    if (glm::dvec3 d = cubePositionDelta(1, v); d != glm::dvec3(0.0)) {
      sparseIndices.push_back(uint8_t(v));
      push(sparseValues, d);
      lo = glm::min(lo, d), hi = glm::max(hi, d);
    }
  const int sparseAccessor = b.addAccessor(-1, kFloat, kCubeVertexCount, "VEC3", false, {lo.x, lo.y, lo.z},
                                           {hi.x, hi.y, hi.z});
  doc["accessors"][size_t(sparseAccessor)]["sparse"] = {
      {"count", sparseIndices.size()},
      {"indices",
       {{"bufferView", b.addBufferView(sparseIndices.data(), sparseIndices.size(), 0)},
        {"componentType", kUnsignedByte}}},
      {"values", {{"bufferView", b.addBufferView(sparseValues.data(), sparseValues.size() * sizeof(float), 0)}}}};

  json primitive = {{"attributes",
                     {{"POSITION", b.addFloats(positions, 3, kArrayBuffer, true)},
                      {"NORMAL", b.addFloats(normals, 3, kArrayBuffer)},
                      {"TEXCOORD_0", b.addFloats(uvs, 2, kArrayBuffer)}}},
                    {"indices", b.addIntegers(indices, 1, kUnsignedInt, kElementArrayBuffer, false)},
                    {"mode", 4},
                    {"targets", json::array({{{"POSITION", b.addFloats(delta0, 3, kArrayBuffer, true)},
                                              {"NORMAL", b.addFloats(normalDelta0, 3, kArrayBuffer)}},
                                             {{"POSITION", sparseAccessor},
                                              {"NORMAL", b.addFloats(normalDelta1, 3, kArrayBuffer)}}})}};
  doc["meshes"] = json::array(
      {{{"name", "morph_cube"}, {"primitives", json::array({primitive})}, {"weights", kCubeMeshWeights}}});
  doc["nodes"] = json::array({{{"name", "cube"},
                               {"mesh", 0},
                               {"translation", vec(cubeNodeTranslation(0))},
                               {"rotation", quat(cubeNodeRotation(0))}},
                              {{"name", "cube_spline"},
                               {"mesh", 0},
                               {"translation", vec(cubeNodeTranslation(1))},
                               {"weights", kCubeSplineNodeWeights}}});
  doc["scenes"] = json::array({{{"nodes", json::array({0, 1})}}});
  doc["scene"] = 0;

  auto floats = [](const auto& values) { return std::vector<float>(values.begin(), values.end()); };
  std::vector<float> linearWeights, splineWeights;
  for (const auto& key : kCubeLinearWeights) linearWeights.insert(linearWeights.end(), key.begin(), key.end());
  for (const auto& key : kCubeSplineKeys)
    for (const auto& part : key) splineWeights.insert(splineWeights.end(), part.begin(), part.end());
  doc["animations"] = json::array(
      {{{"name", "morph"},
        {"samplers", json::array({{{"input", b.addFloats(floats(kCubeLinearTimes), 1, 0, true)},
                                   {"output", b.addFloats(linearWeights, 1, 0)},
                                   {"interpolation", "LINEAR"}},
                                  {{"input", b.addFloats(floats(kCubeSplineTimes), 1, 0, true)},
                                   {"output", b.addFloats(splineWeights, 1, 0)},
                                   {"interpolation", "CUBICSPLINE"}}})},
        {"channels", json::array({{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}},
                                  {{"sampler", 1}, {"target", {{"node", 1}, {"path", "weights"}}}}})}}});

  const std::string e = b.write(path);
  return e.empty() ? e : "writeMorphCube: " + e;
}

}  // namespace pose_reference

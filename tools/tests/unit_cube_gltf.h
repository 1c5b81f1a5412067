// What the render tests that write their own glTF box scenes share: one unit cube (-0.5..0.5, outward normals,
// counter-clockwise seen from outside) as a glTF mesh with one grey material, which nodes then scale and place.
// Not thread-safe (it writes into the one builder given).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "gltf_document_builder.h"

namespace rbRenderTest {

struct UnitCube {
  std::vector<float> positions, normals;  // xyz per vertex, 24 vertices
  std::vector<uint16_t> indices;          // 12 triangles
};

inline UnitCube makeUnitCube() {
  UnitCube c;
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {-1.0f, 1.0f}) {
      glm::vec3 n(0.0f), u(0.0f), v(0.0f);
      n[axis] = sign;
      u[(axis + 1) % 3] = 1.0f;
      v[(axis + 2) % 3] = 1.0f;
      if (sign < 0) std::swap(u, v);  // counter-clockwise seen from outside
      const uint16_t first = uint16_t(c.positions.size() / 3);
      for (glm::vec2 k : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
        const glm::vec3 p = 0.5f * (n + k.x * u + k.y * v);
        c.positions.insert(c.positions.end(), {p.x, p.y, p.z});
        c.normals.insert(c.normals.end(), {n.x, n.y, n.z});
      }
      for (int k : {0, 1, 2, 0, 2, 3}) c.indices.push_back(uint16_t(first + k));
    }
  }
  return c;
}

// Sets the document's meshes to the unit cube (mesh 0) and its materials to one grey one (material 0).
inline void addUnitCubeMesh(pose_reference::GltfDocumentBuilder& b) {
  constexpr int kUnsignedShort = 5123, kArrayBuffer = 34962, kElementArrayBuffer = 34963;
  const UnitCube cube = makeUnitCube();
  const nlohmann::json attributes = {{"POSITION", b.addFloats(cube.positions, 3, kArrayBuffer, true)},
                                     {"NORMAL", b.addFloats(cube.normals, 3, kArrayBuffer)}};
  const int indexAccessor = b.addIntegers(cube.indices, 1, kUnsignedShort, kElementArrayBuffer, false);
  nlohmann::json& doc = b.document();
  doc["materials"] = nlohmann::json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", {0.7, 0.7, 0.7, 1.0}}}}}});
  doc["meshes"] = nlohmann::json::array(
      {{{"primitives",
         nlohmann::json::array({{{"attributes", attributes}, {"indices", indexAccessor}, {"material", 0}}})}}});
}

}  // namespace rbRenderTest

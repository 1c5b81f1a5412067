// glTF loader completeness: strips and fans, sparse accessors, KHR_mesh_quantization, KHR_texture_transform,
// KHR_materials_emissive_strength, the default scene and non-finite geometry. The files are generated here.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>

#include "engine_test_support.h"
#include "gltf_document_builder.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/image_io.h"

using namespace sample_engine;
using nlohmann::json;
using pose_reference::GltfDocumentBuilder;

namespace {

constexpr int kByte = 5120, kUnsignedByte = 5121, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
constexpr int kPoints = 0, kLines = 1, kTriangles = 4, kStrip = 5, kFan = 6;

std::string tempPath(const std::string& name) { return (std::filesystem::temp_directory_path() / name).string(); }

// One mesh of `primitives` on node 0, the only node of scene 0; writes the file and returns its path.
std::string writeSingleMesh(GltfDocumentBuilder& b, const std::string& name, const json& primitives,
                            const std::string& meshName = "m") {
  json& doc = b.document();
  doc["meshes"] = json::array({{{"name", meshName}, {"primitives", primitives}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", {0}}}});
  doc["scene"] = 0;
  const std::string path = tempPath(name);
  const std::string e = b.write(path);
  INFO(e);
  REQUIRE(e.empty());
  return path;
}

SceneLoadResult load(const std::string& path) {
  SceneLoadResult r = loadGltf(path);
  INFO(r.error);
  REQUIRE(r.ok());
  return r;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

// The triangles of a mesh as position triples, each rotated to start at its smallest corner (same winding).
using Triangle = std::array<glm::vec3, 3>;
std::vector<Triangle> triangles(const MeshData& m) {
  auto less = [](const glm::vec3& a, const glm::vec3& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  };
  std::vector<Triangle> out;
  for (uint32_t t = 0; t < m.triangleCount(); ++t) {
    Triangle tri;
    for (uint32_t k = 0; k < 3; ++k) tri[k] = m.positions[m.indices.empty() ? t * 3 + k : m.indices[t * 3 + k]];
    const size_t first = size_t(std::min_element(tri.begin(), tri.end(), less) - tri.begin());
    std::rotate(tri.begin(), tri.begin() + long(first), tri.end());
    out.push_back(tri);
  }
  return out;
}

json primitive(int position, int indices, int mode) {
  json p = {{"attributes", {{"POSITION", position}}}, {"mode", mode}};
  if (indices >= 0) p["indices"] = indices;
  return p;
}

std::vector<float> flatten(const std::vector<glm::vec3>& v) {
  std::vector<float> f;
  for (const glm::vec3& p : v) f.insert(f.end(), {p.x, p.y, p.z});
  return f;
}

std::string writeTopology(const std::string& name, const std::vector<glm::vec3>& positions,
                          const std::vector<uint32_t>& indices, int mode) {
  GltfDocumentBuilder b;
  const int pos = b.addFloats(flatten(positions), 3, kArrayBuffer, true);
  const int idx = indices.empty() ? -1 : b.addIntegers(indices, 1, kUnsignedInt, kElementArrayBuffer, false);
  return writeSingleMesh(b, name, json::array({primitive(pos, idx, mode)}));
}

ImageRGBA32F renderWithCamera(Engine& engine, const Scene& scene, const Camera& camera) {
  Status s = engine.loadScene(scene);
  INFO(s.error);
  REQUIRE(s.ok());
  FrameParams p;
  p.camera = camera;
  p.shadow.mapSize = 256;
  s = engine.renderFrame(p);
  INFO(s.error);
  REQUIRE(s.ok());
  auto hdr = engine.readbackHdr();
  INFO(hdr.error);
  REQUIRE(hdr.ok());
  return std::move(hdr.value);
}

Camera frontCamera() {
  Camera c;
  c.eye = glm::vec3(0.5f, 0.25f, 3.0f);
  c.target = glm::vec3(0.5f, 0.25f, 0.0f);
  c.fovYDegrees = 60.0f;
  return c;
}

}  // namespace

TEST_CASE("glTF strips and fans load and render like the equivalent triangle lists", "[gltf]") {
  // A strip of 4 triangles over 6 vertices, and the same strip indexed with a degenerate join of two strips.
  const std::vector<glm::vec3> strip = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  const std::vector<uint32_t> stripList = {0, 1, 2, 1, 3, 2, 2, 3, 4, 3, 5, 4};  // glTF 3.7.2.1 winding
  const std::vector<uint32_t> joinedStrips = {0, 1, 2, 3, 3, 2, 2, 3, 4, 5};
  // A fan around vertex 0, and the same fan indexed over reversed vertices.
  const std::vector<glm::vec3> fan = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  const std::vector<uint32_t> fanList = {1, 2, 0, 2, 3, 0, 3, 4, 0};
  const std::vector<glm::vec3> fanReversed(fan.rbegin(), fan.rend());
  const std::vector<uint32_t> fanReversedIndices = {4, 3, 2, 1, 0};

  struct Case {
    const char* name;
    std::string path, listPath;
  };
  const Case cases[] = {
      {"strip", writeTopology("rb_strip.gltf", strip, {}, kStrip),
       writeTopology("rb_strip_list.gltf", strip, stripList, kTriangles)},
      {"indexed strip", writeTopology("rb_strip_indexed.gltf", strip, joinedStrips, kStrip),
       writeTopology("rb_strip_list.gltf", strip, stripList, kTriangles)},
      {"fan", writeTopology("rb_fan.gltf", fan, {}, kFan), writeTopology("rb_fan_list.gltf", fan, fanList, kTriangles)},
      {"indexed fan", writeTopology("rb_fan_indexed.gltf", fanReversed, fanReversedIndices, kFan),
       writeTopology("rb_fan_list.gltf", fan, fanList, kTriangles)},
  };
  auto engine = test_support::makeEngine();
  REQUIRE(engine->setRenderSize(64, 48).ok());
  for (const Case& c : cases) {
    INFO(c.name);
    const SceneLoadResult converted = load(c.path), list = load(c.listPath);
    REQUIRE(converted.scene.meshes.size() == 1);
    const std::vector<Triangle> a = triangles(converted.scene.meshes[0]), b = triangles(list.scene.meshes[0]);
    CHECK(a.size() == b.size());
    CHECK(a == b);
    const ImageRGBA32F imageA = renderWithCamera(*engine, converted.scene, frontCamera());
    const ImageRGBA32F imageB = renderWithCamera(*engine, list.scene, frontCamera());
    CHECK(imageA.pixels == imageB.pixels);
    // Something was drawn: the centre is not the sky.
    CHECK(imageA.at(32, 24) != imageA.at(0, 0));
  }
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("glTF points and lines are rejected naming mesh, primitive and mode", "[gltf]") {
  GltfDocumentBuilder b;
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3, kArrayBuffer, true);
  const std::string path = writeSingleMesh(b, "rb_points_lines.gltf",
                                           json::array({primitive(pos, -1, kPoints), primitive(pos, -1, kLines)}),
                                           "wire");
  const SceneLoadResult r = loadGltf(path);
  REQUIRE_FALSE(r.ok());
  INFO(r.error);
  CHECK(r.error.find("no renderable triangles") != std::string::npos);
  CHECK(r.error.find("mesh 'wire' primitive 0: skipped, mode 0 (POINTS)") != std::string::npos);
  CHECK(r.error.find("mesh 'wire' primitive 1: skipped, mode 1 (LINES)") != std::string::npos);
}

TEST_CASE("glTF sparse accessors override positions and indices", "[gltf]") {
  GltfDocumentBuilder b;
  json& doc = b.document();
  const std::vector<float> base = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 5, 5, 5, 6, 5};
  const int pos = b.addFloats(base, 3, kArrayBuffer, true);
  const std::vector<uint16_t> overridden = {1, 4};
  const std::vector<float> values = {2, 0, 0, 7, 7, 7};
  const int idxView = b.addBufferView(overridden.data(), overridden.size() * 2, 0);
  const int valView = b.addBufferView(values.data(), values.size() * 4, 0);
  doc["accessors"][size_t(pos)]["sparse"] = {{"count", 2},
                                             {"indices", {{"bufferView", idxView}, {"componentType", kUnsignedShort}}},
                                             {"values", {{"bufferView", valView}}}};
  doc["accessors"][size_t(pos)]["max"] = {7, 7, 7};
  // Indices 0,1,2,0,0,0 with the last three replaced by 3,4,5 through a sparse substitution.
  const int idx = b.addIntegers(std::vector<uint32_t>{0, 1, 2, 0, 0, 0}, 1, kUnsignedInt, kElementArrayBuffer, false);
  const std::vector<uint8_t> idxOverridden = {3, 4, 5};
  const std::vector<uint32_t> idxValues = {3, 4, 5};
  const int iv = b.addBufferView(idxOverridden.data(), 3, 0), vv = b.addBufferView(idxValues.data(), 12, 0);
  doc["accessors"][size_t(idx)]["sparse"] = {{"count", 3},
                                             {"indices", {{"bufferView", iv}, {"componentType", kUnsignedByte}}},
                                             {"values", {{"bufferView", vv}}}};
  const SceneLoadResult r = load(writeSingleMesh(b, "rb_sparse.gltf", json::array({primitive(pos, idx, kTriangles)})));
  const MeshData& m = r.scene.meshes.at(0);
  REQUIRE(m.positions.size() == 6);
  CHECK(m.positions[0] == glm::vec3(0, 0, 0));
  CHECK(m.positions[1] == glm::vec3(2, 0, 0));
  CHECK(m.positions[2] == glm::vec3(0, 1, 0));
  CHECK(m.positions[3] == glm::vec3(5, 5, 5));
  CHECK(m.positions[4] == glm::vec3(7, 7, 7));
  CHECK(m.positions[5] == glm::vec3(5, 6, 5));
  CHECK(m.indices == std::vector<uint32_t>{0, 1, 2, 3, 4, 5});
}

TEST_CASE("glTF KHR_mesh_quantization attributes dequantize per the spec", "[gltf]") {
  GltfDocumentBuilder b;
  json& doc = b.document();
  doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  // Positions: SHORT, not normalized, padded to 8-byte elements (vertex attributes are 4-byte aligned).
  const std::vector<int16_t> positions = {100, -200, 3, 0, -32768, 0, 32767, 0, 0, 1, 0, 0};
  const int pv = b.addBufferView(positions.data(), positions.size() * 2, kArrayBuffer);
  doc["bufferViews"][size_t(pv)]["byteStride"] = 8;
  const int pos = b.addAccessor(pv, kShort, 3, "VEC3", false, {-32768, -200, 0}, {100, 1, 3});
  // Normals: normalized BYTE, padded to 4 bytes; -128 clamps to -1.
  const std::vector<int8_t> normals = {0, 127, 0, 0, 0, 0, -128, 0, 64, 0, -64, 0};
  const int nv = b.addBufferView(normals.data(), normals.size(), kArrayBuffer);
  doc["bufferViews"][size_t(nv)]["byteStride"] = 4;
  const int nor = b.addAccessor(nv, kByte, 3, "VEC3", true);
  // Tangents: normalized SHORT.
  const std::vector<int16_t> tangents = {32767, 0, 0, 32767, 0, -32767, 0, -32767, 16384, 0, 0, 32767};
  const int tan = b.addIntegers(tangents, 4, kShort, kArrayBuffer, true);
  // UVs: normalized UNSIGNED_SHORT in set 0, plain UNSIGNED_BYTE (padded) in set 1.
  const std::vector<uint16_t> uv0 = {0, 65535, 65535, 0, 32768, 1};
  const int t0 = b.addIntegers(uv0, 2, kUnsignedShort, kArrayBuffer, true);
  const std::vector<uint8_t> uv1 = {3, 4, 0, 0, 255, 0, 0, 0, 1, 2, 0, 0};
  const int u1v = b.addBufferView(uv1.data(), uv1.size(), kArrayBuffer);
  doc["bufferViews"][size_t(u1v)]["byteStride"] = 4;
  const int t1 = b.addAccessor(u1v, kUnsignedByte, 3, "VEC2", false);
  json p = primitive(pos, -1, kTriangles);
  p["attributes"]["NORMAL"] = nor;
  p["attributes"]["TANGENT"] = tan;
  p["attributes"]["TEXCOORD_0"] = t0;
  p["attributes"]["TEXCOORD_1"] = t1;
  const SceneLoadResult r = load(writeSingleMesh(b, "rb_quantized.gltf", json::array({p})));
  const MeshData& m = r.scene.meshes.at(0);
  REQUIRE(m.positions.size() == 3);
  CHECK(m.positions[0] == glm::vec3(100, -200, 3));
  CHECK(m.positions[1] == glm::vec3(-32768, 0, 32767));
  CHECK(m.positions[2] == glm::vec3(0, 1, 0));
  REQUIRE(m.normals.size() == 3);
  CHECK(m.normals[0] == glm::vec3(0, 1, 0));
  CHECK(m.normals[1] == glm::vec3(0, 0, -1));
  CHECK(m.normals[2] == glm::vec3(64 / 127.0f, 0, -64 / 127.0f));
  REQUIRE(m.tangents.size() == 3);
  CHECK(m.tangents[0] == glm::vec4(1, 0, 0, 1));
  CHECK(m.tangents[1] == glm::vec4(0, -1, 0, -1));
  CHECK(m.tangents[2] == glm::vec4(16384 / 32767.0f, 0, 0, 1));
  REQUIRE(m.uvs.size() == 3);
  CHECK(m.uvs[0] == glm::vec2(0, 1));
  CHECK(m.uvs[1] == glm::vec2(1, 0));
  CHECK(m.uvs[2] == glm::vec2(32768 / 65535.0f, 1 / 65535.0f));
  REQUIRE(m.uvs1.size() == 3);
  CHECK(m.uvs1[0] == glm::vec2(3, 4));
  CHECK(m.uvs1[1] == glm::vec2(255, 0));
  CHECK(m.uvs1[2] == glm::vec2(1, 2));
}

TEST_CASE("glTF files requiring an unsupported extension fail naming it", "[gltf]") {
  GltfDocumentBuilder b;
  b.document()["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  b.document()["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3, kArrayBuffer, true);
  const SceneLoadResult r = loadGltf(
      writeSingleMesh(b, "rb_draco.gltf", json::array({primitive(pos, -1, kTriangles)})));
  REQUIRE_FALSE(r.ok());
  CHECK(r.error.find("KHR_draco_mesh_compression") != std::string::npos);
}

TEST_CASE("glTF KHR_texture_transform is baked into the UVs", "[gltf]") {
  // A 2x2 checker: red at texels (0,0) and (1,1), green at (1,0) and (0,1).
  ImageRGBA8 checker;
  checker.width = checker.height = 2;
  checker.pixels = {255, 0, 0, 255, 0, 255, 0, 255, 0, 255, 0, 255, 255, 0, 0, 255};
  const std::string png = tempPath("rb_checker.png");
  REQUIRE(writePng(png, checker).ok());

  auto write = [&](const std::string& name, const json& transform, bool emissiveTextureWithoutTransform) {
    GltfDocumentBuilder b;
    json& doc = b.document();
    doc["extensionsUsed"] = {"KHR_texture_transform"};
    doc["images"] = json::array({{{"uri", "rb_checker.png"}}});
    doc["samplers"] = json::array({{{"magFilter", 9728}, {"minFilter", 9728}}});  // NEAREST
    doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
    json base = {{"index", 0}};
    if (!transform.is_null()) base["extensions"] = {{"KHR_texture_transform", transform}};
    json material = {{"name", "checker"},
                     {"pbrMetallicRoughness", {{"baseColorTexture", base}, {"metallicFactor", 0.0}}}};
    if (emissiveTextureWithoutTransform) material["emissiveTexture"] = {{"index", 0}};
    doc["materials"] = json::array({material});
    // A quad facing +Z covering [-1,1]^2 whose UVs all sit in texel (0,0); TEXCOORD_1 in texel (1,1).
    const int pos = b.addFloats({-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0}, 3, kArrayBuffer, true);
    const int uv0 = b.addFloats({0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f}, 2, kArrayBuffer);
    const int uv1 = b.addFloats({0.75f, 0.75f, 0.75f, 0.75f, 0.75f, 0.75f, 0.75f, 0.75f}, 2, kArrayBuffer);
    const int idx = b.addIntegers(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, 1, kUnsignedShort, kElementArrayBuffer,
                                  false);
    json p = primitive(pos, idx, kTriangles);
    p["attributes"]["TEXCOORD_0"] = uv0;
    p["attributes"]["TEXCOORD_1"] = uv1;
    p["material"] = 0;
    return writeSingleMesh(b, name, json::array({p}));
  };
  const SceneLoadResult plain = load(write("rb_tt_plain.gltf", nullptr, false));
  const SceneLoadResult shifted = load(write("rb_tt_offset.gltf", {{"offset", {0.5, 0.0}}}, false));
  const SceneLoadResult rotated = load(write(
      "rb_tt_rotated.gltf", {{"offset", {0.0, 1.0}}, {"rotation", 1.5707963267948966}, {"scale", {2.0, 1.0}}}, false));
  const SceneLoadResult set1 = load(write("rb_tt_set1.gltf", {{"texCoord", 1}}, false));
  const SceneLoadResult mixed = load(write("rb_tt_mixed.gltf", {{"offset", {0.5, 0.0}}}, true));
  CHECK(plain.scene.meshes.at(0).uvs[0] == glm::vec2(0.25f, 0.25f));
  CHECK(shifted.scene.meshes.at(0).uvs[0] == glm::vec2(0.75f, 0.25f));
  CHECK(shifted.scene.materials.at(0).baseColorUv.offset == glm::vec2(0.5f, 0.0f));
  // offset + R * (scale * uv): scale -> (0.5, 0.25), R(90 deg) -> (0.25, -0.5), + (0, 1) -> (0.25, 0.5).
  const glm::vec2 r = rotated.scene.meshes.at(0).uvs[0];
  CHECK(std::abs(r.x - 0.25f) < 1e-6f);
  CHECK(std::abs(r.y - 0.5f) < 1e-6f);
  CHECK(set1.scene.meshes.at(0).uvs[0] == glm::vec2(0.75f, 0.75f));
  CHECK(set1.scene.meshes.at(0).uvs1[0] == glm::vec2(0.75f, 0.75f));
  // Textures with different mappings: the base colour's is used, with a warning.
  CHECK(mixed.scene.meshes.at(0).uvs[0] == glm::vec2(0.75f, 0.25f));
  CHECK(joined(mixed.warnings).find("different UV mappings") != std::string::npos);

  // Rendered: the offset moves the sample from a red texel to a green one.
  auto engine = test_support::makeEngine();
  REQUIRE(engine->setRenderSize(32, 32).ok());
  Camera camera;
  camera.eye = glm::vec3(0, 0, 2);
  camera.target = glm::vec3(0);
  const glm::vec4 a = renderWithCamera(*engine, plain.scene, camera).at(16, 16);
  const glm::vec4 c = renderWithCamera(*engine, shifted.scene, camera).at(16, 16);
  INFO("plain " << a.r << " " << a.g << ", shifted " << c.r << " " << c.g);
  CHECK(a.r > 4.0f * a.g);
  CHECK(c.g > 4.0f * c.r);
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("glTF KHR_materials_emissive_strength multiplies the emissive factor", "[gltf]") {
  GltfDocumentBuilder b;
  b.document()["extensionsUsed"] = {"KHR_materials_emissive_strength"};
  b.document()["materials"] = json::array(
      {{{"name", "bright"},
        {"emissiveFactor", {0.5, 0.25, 1.0}},
        {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}}},
       {{"name", "plain"}, {"emissiveFactor", {0.5, 0.25, 1.0}}}});
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3, kArrayBuffer, true);
  json p = primitive(pos, -1, kTriangles);
  p["material"] = 0;
  const SceneLoadResult r = load(writeSingleMesh(b, "rb_emissive_strength.gltf", json::array({p})));
  CHECK(r.scene.materials.at(0).emissiveFactor == glm::vec3(2.0f, 1.0f, 4.0f));
  CHECK(r.scene.materials.at(1).emissiveFactor == glm::vec3(0.5f, 0.25f, 1.0f));
}

TEST_CASE("glTF occlusion texture and its strength are loaded", "[gltf]") {
  GltfDocumentBuilder b;
  ImageRGBA8 white;
  white.width = white.height = 1;
  white.pixels = {128, 255, 255, 255};
  REQUIRE(writePng(tempPath("rb_orm.png"), white).ok());
  json& doc = b.document();
  doc["images"] = json::array({{{"uri", "rb_orm.png"}}});
  doc["textures"] = json::array({{{"source", 0}}});
  doc["materials"] = json::array({{{"pbrMetallicRoughness", {{"metallicRoughnessTexture", {{"index", 0}}}}},
                                   {"occlusionTexture", {{"index", 0}, {"strength", 0.5}, {"texCoord", 0}}}}});
  const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3, kArrayBuffer, true);
  json p = primitive(pos, -1, kTriangles);
  p["material"] = 0;
  const SceneLoadResult r = load(writeSingleMesh(b, "rb_occlusion.gltf", json::array({p})));
  const Material& m = r.scene.materials.at(0);
  CHECK(m.occlusionTexture == 0);
  CHECK(m.occlusionStrength == 0.5f);
  CHECK(m.occlusionUv.texCoord == 0);
  // Drawn with the packed-ORM path (validation on).
  auto engine = test_support::makeEngine();
  REQUIRE(engine->setRenderSize(16, 16).ok());
  renderWithCamera(*engine, r.scene, frontCamera());
  CHECK(engine->validationErrorCount() == 0);
}

TEST_CASE("glTF default scene selection", "[gltf]") {
  // Node 0 (mesh 0) is scene 0's, node 1 (mesh 1) scene 1's; node 2 is node 1's child.
  auto write = [](const std::string& name, const json& scene, bool withScenes) {
    GltfDocumentBuilder b;
    json& doc = b.document();
    const int pos = b.addFloats({0, 0, 0, 1, 0, 0, 0, 1, 0}, 3, kArrayBuffer, true);
    doc["meshes"] = json::array({{{"name", "a"}, {"primitives", {primitive(pos, -1, kTriangles)}}},
                                 {{"name", "b"}, {"primitives", {primitive(pos, -1, kTriangles)}}}});
    doc["nodes"] = json::array({{{"mesh", 0}}, {{"mesh", 1}, {"children", {2}}}, {{"mesh", 0}}});
    if (withScenes) doc["scenes"] = json::array({{{"nodes", {0}}}, {{"nodes", {1}}}});
    if (!scene.is_null()) doc["scene"] = scene;
    const std::string path = tempPath(name);
    REQUIRE(b.write(path).empty());
    return path;
  };
  auto nodes = [](const SceneLoadResult& r) {
    std::vector<int> n;
    for (const Instance& i : r.scene.instances) n.push_back(i.node);
    return n;
  };
  CHECK(nodes(load(write("rb_scene1.gltf", 1, true))) == std::vector<int>{1, 2});
  CHECK(nodes(load(write("rb_scene_none.gltf", nullptr, true))) == std::vector<int>{0});
  CHECK(nodes(load(write("rb_scene_roots.gltf", nullptr, false))) == std::vector<int>{0, 1, 2});
  const SceneLoadResult bad = loadGltf(write("rb_scene_bad.gltf", 5, true));
  CHECK_FALSE(bad.ok());
}

TEST_CASE("glTF non-finite positions and normals skip their triangles with one warning", "[gltf]") {
  GltfDocumentBuilder b;
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  // Primitive 0: three triangles; vertex 4 is infinite and vertex 5 NaN (both in triangle 1).
  const std::vector<float> positions = {0, 0, 0,   1, 0, 0, 0, 1, 0, 5, 0, 0, inf, 0,
                                        0, 5, nan, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1};
  const int pos = b.addFloats(positions, 3, kArrayBuffer);
  b.document()["accessors"][size_t(pos)]["min"] = {0, 0, 0};
  b.document()["accessors"][size_t(pos)]["max"] = {5, 1, 1};
  // Primitive 1: two triangles, a NaN normal in the second.
  const int pos2 = b.addFloats({2, 0, 0, 3, 0, 0, 2, 1, 0, 2, 0, 1, 3, 0, 1, 2, 1, 1}, 3, kArrayBuffer, true);
  const int nor2 = b.addFloats({0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, nan, 0, 1, 0, 0, 1}, 3, kArrayBuffer);
  json p1 = primitive(pos2, -1, kTriangles);
  p1["attributes"]["NORMAL"] = nor2;
  const SceneLoadResult r = load(
      writeSingleMesh(b, "rb_nonfinite.gltf", json::array({primitive(pos, -1, kTriangles), p1}), "broken"));
  INFO(joined(r.warnings));
  REQUIRE(r.warnings.size() == 2);
  CHECK(r.warnings[0].find("mesh 'broken' primitive 0") != std::string::npos);
  CHECK(r.warnings[0].find("POSITION accessor " + std::to_string(pos)) != std::string::npos);
  CHECK(r.warnings[1].find("mesh 'broken' primitive 1") != std::string::npos);
  CHECK(r.warnings[1].find("NORMAL accessor " + std::to_string(nor2)) != std::string::npos);
  REQUIRE(r.scene.meshes.size() == 2);
  CHECK(r.scene.meshes[0].triangleCount() == 2);
  CHECK(r.scene.meshes[1].triangleCount() == 1);
  const Bounds bounds = r.scene.bounds();
  CHECK(bounds.min == glm::vec3(0, 0, 0));
  CHECK(bounds.max == glm::vec3(5, 1, 1));  // vertex 3 of the skipped triangle is finite

  auto engine = test_support::makeEngine();
  REQUIRE(engine->setRenderSize(32, 32).ok());
  Status s = engine->loadScene(r.scene);
  INFO(s.error);
  REQUIRE(s.ok());
  const Bounds engineBounds = engine->sceneBounds();
  CHECK(std::isfinite(engineBounds.radius()));
  const ImageRGBA32F image = renderWithCamera(*engine, r.scene, defaultCameraFor(engineBounds));
  size_t drawn = 0;
  for (uint32_t y = 0; y < image.height; ++y)
    for (uint32_t x = 0; x < image.width; ++x) drawn += image.at(x, y) != image.at(0, 0);
  CHECK(drawn > 0);
  CHECK(engine->validationErrorCount() == 0);
}

// loadGltfFromMemory: .gltf and .glb bytes load like the files, the GltfExternalFiles policies for external
// URIs, and regression tests of what tests/fuzz/gltf_loader_fuzz found (each feeds the committed input,
// tests/fuzz/corpus/gltf_loader/crash-*, as bytes).
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>

#include "base64.h"
#include "sample_engine/gltf_loader.h"

using namespace sample_engine;

namespace {

// One triangle (positions 0,0,0 / 1,0,0 / 0,1,0, indices 0,1,2 as uint16 + 2 bytes of padding): 44 bytes.
std::vector<uint8_t> triangleBuffer() {
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint16_t indices[4] = {0, 1, 2, 0};
  std::vector<uint8_t> bytes(sizeof positions + sizeof indices);
  std::memcpy(bytes.data(), positions, sizeof positions);
  std::memcpy(bytes.data() + sizeof positions, indices, sizeof indices);
  return bytes;
}

// The triangle's glTF JSON with buffer 0 at `uri` ("" = no uri: a .glb's BIN chunk).
std::string triangleJson(const std::string& uri) {
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",)"
         R"("min":[0,0,0],"max":[1,1,0]},{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],)"
         R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],)"
         R"("buffers":[{"byteLength":44)" +
         (uri.empty() ? std::string() : R"(,"uri":")" + uri + "\"") + "}]}";
}

using test_support::base64;

std::vector<uint8_t> bytesOf(const std::string& text) { return std::vector<uint8_t>(text.begin(), text.end()); }

void append32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// A .glb: the JSON chunk (padded with spaces) and the BIN chunk (padded with zeros).
std::vector<uint8_t> glb(std::string json, std::vector<uint8_t> bin) {
  json.resize((json.size() + 3) / 4 * 4, ' ');
  bin.resize((bin.size() + 3) / 4 * 4, 0);
  std::vector<uint8_t> out{'g', 'l', 'T', 'F'};
  append32(out, 2);
  append32(out, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  append32(out, uint32_t(json.size()));
  append32(out, 0x4E4F534A);  // JSON
  out.insert(out.end(), json.begin(), json.end());
  append32(out, uint32_t(bin.size()));
  append32(out, 0x004E4942);  // BIN
  out.insert(out.end(), bin.begin(), bin.end());
  return out;
}

SceneLoadResult fromMemory(const std::vector<uint8_t>& bytes, bool binary, const std::string& baseDir = "",
                           GltfExternalFiles files = GltfExternalFiles::Anywhere) {
  GltfMemoryDesc desc;
  desc.bytes = bytes;
  desc.binary = binary;
  desc.baseDir = baseDir;
  desc.externalFiles = files;
  desc.name = "test";
  return loadGltfFromMemory(desc);
}

bool mentions(const SceneLoadResult& r, const std::string& what) { return r.error.find(what) != std::string::npos; }

}  // namespace

TEST_CASE("glTF from memory: .gltf and .glb bytes load like their files", "[gltf][memory]") {
  const std::vector<uint8_t> buffer = triangleBuffer();
  const std::vector<uint8_t> ascii = bytesOf(triangleJson("data:application/octet-stream;base64," + base64(buffer)));
  const std::vector<uint8_t> binary = glb(triangleJson(""), buffer);
  for (const auto& [bytes, isGlb] : {std::pair{ascii, false}, std::pair{binary, true}}) {
    SceneLoadResult r = fromMemory(bytes, isGlb);
    INFO(r.error);
    REQUIRE(r.ok());
    REQUIRE(r.scene.meshes.size() == 1);
    CHECK(r.scene.meshes[0].triangleCount() == 1);
    CHECK(r.scene.meshes[0].positions[1] == glm::vec3(1, 0, 0));

    const auto path = std::filesystem::temp_directory_path() / (isGlb ? "memory_test.glb" : "memory_test.gltf");
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    SceneLoadResult file = loadGltf(path.string());
    INFO(file.error);
    REQUIRE(file.ok());
    CHECK(file.scene.meshes[0].positions == r.scene.meshes[0].positions);
    CHECK(file.scene.meshes[0].indices == r.scene.meshes[0].indices);
    std::filesystem::remove(path);
  }

  SceneLoadResult empty = fromMemory({}, false);
  CHECK(empty.error == "glTF 'test' is empty");
  SceneLoadResult garbage = fromMemory(bytesOf("glTF?"), true);
  CHECK_FALSE(garbage.ok());
  CHECK(mentions(garbage, "failed to parse glTF 'test'"));
}

TEST_CASE("glTF from memory: external URIs are read as GltfExternalFiles says", "[gltf][memory]") {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "raybridge_gltf_external";
  fs::remove_all(root);
  fs::create_directories(root / "base" / "sub");
  const std::vector<uint8_t> buffer = triangleBuffer();
  for (const fs::path& p : {root / "base" / "tri.bin", root / "base" / "sub" / "tri.bin", root / "outside.bin"})
    std::ofstream(p, std::ios::binary)
        .write(reinterpret_cast<const char*>(buffer.data()), std::streamsize(buffer.size()));
  const std::string base = (root / "base").string();

  auto load = [&](const std::string& uri, GltfExternalFiles files) {
    return fromMemory(bytesOf(triangleJson(uri)), false, base, files);
  };
  for (const char* inside : {"tri.bin", "sub/tri.bin", "sub/../tri.bin", "./sub/tri.bin"}) {
    INFO(inside);
    for (GltfExternalFiles files : {GltfExternalFiles::Anywhere, GltfExternalFiles::InsideBaseDir}) {
      SceneLoadResult r = load(inside, files);
      INFO(r.error);
      CHECK(r.ok());
    }
    SceneLoadResult none = load(inside, GltfExternalFiles::None);
    CHECK(mentions(none, std::string("the URI '") + inside + "' names an external file"));
    CHECK(mentions(none, "GltfExternalFiles::None"));
  }
  const std::string absolute = (root / "outside.bin").string();
  for (const std::string& outside : {std::string("../outside.bin"), std::string("sub/../../outside.bin"), absolute}) {
    INFO(outside);
    SceneLoadResult refused = load(outside, GltfExternalFiles::InsideBaseDir);
    CHECK(mentions(refused, "the URI '" + outside + "' names a file outside the base folder '" + base + "'"));
    CHECK(mentions(refused, "GltfExternalFiles::InsideBaseDir"));
  }
  SceneLoadResult anywhere = load("../outside.bin", GltfExternalFiles::Anywhere);
  INFO(anywhere.error);
  CHECK(anywhere.ok());
  fs::remove_all(root);
}

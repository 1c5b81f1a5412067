// The glTF malformed-input matrix (issue 12): each row takes a small valid asset (a skinned, textured, animated unit
// quad with a camera and a point light, as .gltf with an embedded buffer or as .glb), applies one kind of damage and
// asserts the outcome: a named error (the message names the member, index or value), or, where loadGltf()
// documents the case as tolerated, a scene with warnings that name what was skipped. Every row that loads is
// uploaded and rendered with the validation layer on. All files are generated here; none is stored.
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <catch2/catch_test_macros.hpp>
#include <nlohmann/json.hpp>

#include "base64.h"
#include "engine_test_support.h"
#include "sample_engine/engine.h"
#include "sample_engine/gltf_loader.h"
#include "sample_engine/image_io.h"

using namespace sample_engine;
using nlohmann::json;

namespace {

constexpr int kUnsignedByte = 5121, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125, kFloat = 5126;
const float kNaN = std::numeric_limits<float>::quiet_NaN(), kInf = std::numeric_limits<float>::infinity();

// The base asset's data: accessor i reads all of buffer view i.
enum Data : int { kPositions, kNormals, kUvs, kJoints, kWeights, kIndices, kTimes, kTranslations, kInverseBinds };

using test_support::base64;

std::filesystem::path scratchDir() {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / "raybridge_gltf_malformed";
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void writeFile(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// A 2x2 RGBA PNG from the engine's own encoder.
const std::vector<uint8_t>& pngBytes() {
  static const std::vector<uint8_t> bytes = [] {
    ImageRGBA8 checker;
    checker.width = checker.height = 2;
    checker.pixels = {255, 0, 0, 255, 0, 255, 0, 255, 0, 255, 0, 255, 255, 0, 0, 255};
    const auto path = scratchDir() / "checker.png";
    REQUIRE(writePng(path.string(), checker).ok());
    std::ifstream file(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  }();
  return bytes;
}

struct Input {
  std::vector<uint8_t> bytes;
  bool binary = false;
  std::string baseDir;  // "" = the working directory
};

void put32(std::vector<uint8_t>& bytes, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + size_t(i)] = uint8_t(v >> (8 * i));
}
uint32_t get32(const std::vector<uint8_t>& bytes, size_t at) {
  return uint32_t(bytes[at]) | uint32_t(bytes[at + 1]) << 8 | uint32_t(bytes[at + 2]) << 16 |
         uint32_t(bytes[at + 3]) << 24;
}

void append32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// A .glb: the JSON chunk (padded with spaces) and, when `withBin`, the BIN chunk (padded with zeros).
std::vector<uint8_t> glbBytes(std::string text, std::vector<uint8_t> bin, bool withBin = true) {
  text.resize((text.size() + 3) / 4 * 4, ' ');
  bin.resize((bin.size() + 3) / 4 * 4, 0);
  std::vector<uint8_t> out{'g', 'l', 'T', 'F'};
  append32(out, 2);
  append32(out, uint32_t(12 + 8 + text.size() + (withBin ? 8 + bin.size() : 0)));
  append32(out, uint32_t(text.size()));
  append32(out, 0x4E4F534A);  // JSON
  out.insert(out.end(), text.begin(), text.end());
  if (withBin) {
    append32(out, uint32_t(bin.size()));
    append32(out, 0x004E4942);  // BIN
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}
size_t binChunkHeader(const std::vector<uint8_t>& glb) { return 20 + get32(glb, 12); }

// The base asset: its JSON and buffer 0.
struct Asset {
  json doc;
  std::vector<uint8_t> bin;

  size_t offset(int view) const { return doc["bufferViews"][size_t(view)]["byteOffset"].get<size_t>(); }
  void setFloat(int view, size_t index, float v) { std::memcpy(bin.data() + offset(view) + index * 4, &v, 4); }
  int addView(const void* data, size_t bytes) {
    bin.resize((bin.size() + 3) / 4 * 4, 0);
    const size_t at = bin.size();
    bin.resize(at + bytes);
    if (bytes) std::memcpy(bin.data() + at, data, bytes);
    doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", bytes}});
    return int(doc["bufferViews"].size()) - 1;
  }
  json& accessor(int a) { return doc["accessors"][size_t(a)]; }
  json& primitive() { return doc["meshes"][0]["primitives"][0]; }
  json& node(int n) { return doc["nodes"][size_t(n)]; }

  // Buffer 0's byteLength, and its uri as a base64 data: URI, unless the row set them.
  json embedded() const {
    json d = doc;
    if (!d["buffers"][0].contains("byteLength")) d["buffers"][0]["byteLength"] = bin.size();
    if (!d["buffers"][0].contains("uri"))
      d["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(bin);
    return d;
  }
  Input gltf() const {
    const std::string text = embedded().dump();
    return {std::vector<uint8_t>(text.begin(), text.end()), false, {}};
  }
  // The JSON with `placeholder` (a string value the row put somewhere) replaced by `literal`, e.g. 1e999.
  Input gltfWithLiteral(const std::string& placeholder, const std::string& literal) const {
    std::string text = embedded().dump();
    const size_t at = text.find("\"" + placeholder + "\"");
    REQUIRE(at != std::string::npos);
    text.replace(at, placeholder.size() + 2, literal);
    return {std::vector<uint8_t>(text.begin(), text.end()), false, {}};
  }
  Input glb(bool withBin = true) const {
    json d = doc;
    if (!d["buffers"][0].contains("byteLength")) d["buffers"][0]["byteLength"] = bin.size();
    return {glbBytes(d.dump(), bin, withBin), true, {}};
  }
};

Asset base() {
  Asset a;
  json& d = a.doc;
  d["asset"] = {{"version", "2.0"}, {"generator", "raybridge malformed-input matrix"}};
  d["bufferViews"] = json::array();
  const float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  const float normals[] = {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1};
  const float uvs[] = {0, 0, 1, 0, 1, 1, 0, 1};
  const uint8_t joints[16] = {};
  const float weights[] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3};
  const float times[] = {0, 1};
  const float translations[] = {0, 0, 0, 0, 0.1f, 0};
  const float inverseBind[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  a.addView(positions, sizeof positions);
  a.addView(normals, sizeof normals);
  a.addView(uvs, sizeof uvs);
  a.addView(joints, sizeof joints);
  a.addView(weights, sizeof weights);
  a.addView(indices, sizeof indices);
  a.addView(times, sizeof times);
  a.addView(translations, sizeof translations);
  a.addView(inverseBind, sizeof inverseBind);
  auto acc = [](int view, int componentType, int count, const char* type) {
    return json{{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}};
  };
  d["accessors"] = json::array({acc(kPositions, kFloat, 4, "VEC3"), acc(kNormals, kFloat, 4, "VEC3"),
                                acc(kUvs, kFloat, 4, "VEC2"), acc(kJoints, kUnsignedByte, 4, "VEC4"),
                                acc(kWeights, kFloat, 4, "VEC4"), acc(kIndices, kUnsignedShort, 6, "SCALAR"),
                                acc(kTimes, kFloat, 2, "SCALAR"), acc(kTranslations, kFloat, 2, "VEC3"),
                                acc(kInverseBinds, kFloat, 1, "MAT4")});
  d["accessors"][kPositions]["min"] = {0, 0, 0};
  d["accessors"][kPositions]["max"] = {1, 1, 0};
  d["accessors"][kTimes]["min"] = {0};
  d["accessors"][kTimes]["max"] = {1};
  d["buffers"] = json::array({json::object()});
  d["meshes"] = json::array({{{"name", "quad"},
                              {"primitives",
                               {{{"attributes",
                                  {{"POSITION", kPositions},
                                   {"NORMAL", kNormals},
                                   {"TEXCOORD_0", kUvs},
                                   {"JOINTS_0", kJoints},
                                   {"WEIGHTS_0", kWeights}}},
                                 {"indices", kIndices},
                                 {"material", 0}}}}}});
  d["materials"] = json::array({{{"name", "quad"},
                                 {"pbrMetallicRoughness",
                                  {{"baseColorFactor", {1, 1, 1, 1}},
                                   {"baseColorTexture", {{"index", 0}}},
                                   {"metallicFactor", 0},
                                   {"roughnessFactor", 1}}},
                                 {"emissiveFactor", {0, 0, 0}}}});
  d["textures"] = json::array({{{"sampler", 0}, {"source", 0}}});
  d["samplers"] = json::array({{{"magFilter", 9729}, {"minFilter", 9729}}});
  d["images"] = json::array({{{"name", "checker"}, {"uri", "data:image/png;base64," + base64(pngBytes())}}});
  d["skins"] = json::array({{{"name", "skin"}, {"joints", {2}}, {"inverseBindMatrices", kInverseBinds}}});
  d["animations"] = json::array(
      {{{"name", "move"},
        {"samplers", {{{"input", kTimes}, {"output", kTranslations}}}},
        {"channels", {{{"sampler", 0}, {"target", {{"node", 2}, {"path", "translation"}}}}}}}});
  d["cameras"] = json::array(
      {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}, {"zfar", 100}, {"aspectRatio", 1}}}}});
  d["extensionsUsed"] = {"KHR_lights_punctual"};
  d["extensions"] = {{"KHR_lights_punctual", {{"lights", {{{"name", "lamp"}, {"type", "point"}, {"intensity", 2}}}}}}};
  d["nodes"] = json::array(
      {{{"name", "root"}, {"children", {1, 2, 3, 4}}},
       {{"name", "quad"}, {"mesh", 0}, {"skin", 0}},
       {{"name", "joint"}, {"translation", {0, 0, 0}}},
       {{"name", "camera"}, {"camera", 0}, {"translation", {0.5, 0.5, 3}}},
       {{"name", "light"}, {"translation", {0.5, 0.5, 1}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}}});
  d["scenes"] = json::array({{{"nodes", {0}}}});
  d["scene"] = 0;
  return a;
}

Input text(const std::string& s) { return {std::vector<uint8_t>(s.begin(), s.end()), false, {}}; }

// The base as .gltf with one kind of damage.
std::function<Input()> gltfWith(std::function<void(Asset&)> damage) {
  return [damage] {
    Asset a = base();
    damage(a);
    return a.gltf();
  };
}

// What a row expects: a failure whose message holds every `error` substring, or (no `error`) a scene holding
// `instances` instances of `triangles` triangles in all, textured or not, with a warning holding each `warnings`
// substring.
struct Expect {
  std::vector<std::string> error;
  std::vector<std::string> warnings;
  size_t instances = 1, triangles = 2;
  bool textured = true;
};
Expect fails(std::vector<std::string> error) { return Expect{std::move(error), {}, 0, 0, false}; }
Expect loads(std::vector<std::string> warnings = {}, size_t instances = 1, size_t triangles = 2, bool textured = true) {
  return Expect{{}, std::move(warnings), instances, triangles, textured};
}

struct Row {
  const char* name;
  std::function<Input()> make;
  Expect expect;
};

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

// Loads every row, checks its outcome and renders each scene that loads on one engine (created on the first).
void runRows(const std::vector<Row>& rows) {
  std::unique_ptr<Engine> engine;
  for (const Row& row : rows) {
    INFO("row: " << row.name);
    const Input in = row.make();
    GltfMemoryDesc desc;
    desc.bytes = in.bytes;
    desc.binary = in.binary;
    desc.baseDir = in.baseDir;
    desc.name = row.name;
    const SceneLoadResult r = loadGltfFromMemory(desc);
    INFO("error: " << r.error);
    INFO("warnings:\n" << joined(r.warnings));
    if (!row.expect.error.empty()) {
      CHECK_FALSE(r.ok());
      for (const std::string& s : row.expect.error) CHECK(r.error.find(s) != std::string::npos);
      continue;
    }
    REQUIRE(r.ok());
    for (const std::string& s : row.expect.warnings) CHECK(joined(r.warnings).find(s) != std::string::npos);
    if (row.expect.warnings.empty()) CHECK(r.warnings.empty());
    CHECK(r.scene.instances.size() == row.expect.instances);
    size_t triangles = 0;
    for (const Instance& i : r.scene.instances) triangles += r.scene.meshes.at(i.mesh).triangleCount();
    CHECK(triangles == row.expect.triangles);
    REQUIRE_FALSE(r.scene.materials.empty());
    CHECK((r.scene.materials[0].baseColorTexture >= 0) == row.expect.textured);

    if (!engine) {
      engine = test_support::makeEngine();
      REQUIRE(engine->setRenderSize(32, 32).ok());
    }
    Status s = engine->loadScene(r.scene);
    INFO(s.error);
    REQUIRE(s.ok());
    FrameParams p;
    p.camera = r.scene.camera ? *r.scene.camera : defaultCameraFor(engine->sceneBounds());
    p.shadow.mapSize = 256;
    p.time = 0.5;
    s = engine->renderFrame(p);
    INFO(s.error);
    REQUIRE(s.ok());
    REQUIRE(engine->readbackHdr().ok());  // waits for the frame
    CHECK(engine->validationErrorCount() == 0);
  }
}

}  // namespace

TEST_CASE("glTF malformed: the undamaged base loads as .gltf and .glb", "[gltf][malformed]") {
  runRows({
      {"base .gltf", [] { return base().gltf(); }, loads()},
      {"base .glb", [] { return base().glb(); }, loads()},
  });
  const SceneLoadResult r = loadGltfFromMemory({.bytes = base().gltf().bytes, .name = "base"});
  REQUIRE(r.ok());
  CHECK(r.scene.camera.has_value());
  CHECK(r.scene.lights.size() == 1);
  CHECK(r.scene.skins.size() == 1);
  CHECK(r.scene.animations.size() == 1);
  CHECK(r.scene.textures.at(0).width == 2);
}

TEST_CASE("glTF malformed: broken JSON fails naming where", "[gltf][malformed]") {
  runRows({
      {"empty file", [] { return text(""); }, fails({"is empty"})},
      {"whitespace only", [] { return text(" \n "); }, fails({"invalid JSON", "line 2"})},
      {"truncated JSON",
       [] {
         const std::string t = base().embedded().dump();
         return text(t.substr(0, t.find("\"scenes\":") + 9));
       },
       fails({"invalid JSON at scenes (line 1, column ", "unexpected end of input"})},
      {"truncated inside a string",
       [] {
         const std::string t = base().embedded().dump();
         return text(t.substr(0, t.find("base64,") + 20));
       },
       fails({"invalid JSON at buffers[0].uri", "missing closing quote"})},
      {"trailing garbage", [] { return text(base().embedded().dump() + "}garbage"); },
       fails({"invalid JSON", "expected end of input"})},
      {"root is an array", [] { return text(json::array({base().embedded()}).dump()); },
       fails({"the document is an array, not a JSON object"})},
      {"root is a number", [] { return text("42"); }, fails({"the document is 42, not a JSON object"})},
      {"NaN literal",
       [] {
         Asset a = base();
         a.doc["cameras"][0]["perspective"]["yfov"] = "@nan@";
         return a.gltfWithLiteral("@nan@", "NaN");
       },
       fails({"invalid JSON at cameras[0].perspective.yfov", "invalid literal"})},
      {"extras nested 100000 levels",
       [] {
         Asset a = base();
         a.node(2)["extras"] = "@deep@";
         return a.gltfWithLiteral("@deep@", std::string(100000, '[') + std::string(100000, ']'));
       },
       fails({"nodes: JSON nested deeper than 128 levels"})},
      {"no asset",
       [] {
         Asset a = base();
         a.doc.erase("asset");
         return a.gltf();
       },
       fails({"asset.version is missing"})},
  });
}

TEST_CASE("glTF malformed: wrong JSON types fail naming the member", "[gltf][malformed]") {
  runRows({
      {"count is a string", gltfWith([](Asset& a) { a.accessor(kPositions)["count"] = "4"; }),
       fails({"accessors[0].count = \"4\" is not an integer"})},
      {"mesh index is a string", gltfWith([](Asset& a) { a.node(1)["mesh"] = "0"; }),
       fails({"nodes[1].mesh = \"0\" is not an index"})},
      {"metallicFactor is a string",
       gltfWith([](Asset& a) { a.doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = "0"; }),
       fails({"materials[0].pbrMetallicRoughness.metallicFactor is \"0\", not a number"})},
      {"node is an array", gltfWith([](Asset& a) { a.node(2) = json::array(); }),
       fails({"nodes[2] is an array, not an object"})},
      {"attributes is an array", gltfWith([](Asset& a) { a.primitive()["attributes"] = json::array({0}); }),
       fails({"meshes[0].primitives[0].attributes is an array, not an object"})},
      {"pbrMetallicRoughness is an array",
       gltfWith([](Asset& a) { a.doc["materials"][0]["pbrMetallicRoughness"] = json::array(); }),
       fails({"materials[0].pbrMetallicRoughness is an array, not an object"})},
      {"negative mesh index", gltfWith([](Asset& a) { a.node(1)["mesh"] = -1; }),
       fails({"nodes[1].mesh = -1 is not an index"})},
      {"negative bufferView index", gltfWith([](Asset& a) { a.accessor(kNormals)["bufferView"] = -1; }),
       fails({"accessors[1].bufferView = -1 is not an index"})},
      {"fractional indices accessor", gltfWith([](Asset& a) { a.primitive()["indices"] = 5.5; }),
       fails({"meshes[0].primitives[0].indices = 5.5 is not an index"})},
      {"fractional child", gltfWith([](Asset& a) { a.node(0)["children"][0] = 1.5; }),
       fails({"nodes[0].children[0] = 1.5 is not an index"})},
      {"index 2^32 (tinygltf would wrap it to 0)", gltfWith([](Asset& a) { a.node(1)["mesh"] = 4294967296u; }),
       fails({"nodes[1].mesh = 4294967296 is out of range (the file has 1 meshes)"})},
      {"translation of 2 numbers", gltfWith([](Asset& a) {
         a.node(2)["translation"] = {1, 2};
       }),
       fails({"nodes[2].translation has 2 elements; it needs 3"})},
      {"extensionsRequired entry is a number", gltfWith([](Asset& a) { a.doc["extensionsRequired"] = {7}; }),
       fails({"extensionsRequired[0] is 7, not a name"})},
  });
}

TEST_CASE("glTF malformed: .glb container damage fails naming the field", "[gltf][malformed]") {
  auto glb = [](std::function<void(std::vector<uint8_t>&)> damage) {
    return [damage] {
      Input in = base().glb();
      damage(in.bytes);
      return in;
    };
  };
  runRows({
      {"bad magic", glb([](std::vector<uint8_t>& b) { b[3] = 'X'; }), fails({"the .glb magic is", "not \"glTF\""})},
      {"version 1", glb([](std::vector<uint8_t>& b) { put32(b, 4, 1); }),
       fails({".glb version 1; the loader reads version 2"})},
      {"length larger than the data", glb([](std::vector<uint8_t>& b) { put32(b, 8, uint32_t(b.size() + 4)); }),
       fails({"the .glb header's length is", "bytes but the file has"})},
      {"length smaller than the data", glb([](std::vector<uint8_t>& b) { put32(b, 8, uint32_t(b.size() - 4)); }),
       fails({"the .glb header's length is", "bytes but the file has"})},
      {"truncated inside the BIN chunk", glb([](std::vector<uint8_t>& b) { b.resize(b.size() - 8); }),
       fails({"the .glb header's length is", "bytes but the file has"})},
      {"fewer than 12 bytes", glb([](std::vector<uint8_t>& b) { b.resize(8); }),
       fails({"the file has 8 bytes, fewer than a .glb header's 12"})},
      {"JSON chunk length overflow", glb([](std::vector<uint8_t>& b) { put32(b, 12, 0xFFFFFFF0u); }),
       fails({"the JSON chunk's length 4294967280 does not fit"})},
      {"BIN chunk length overflow", glb([](std::vector<uint8_t>& b) { put32(b, binChunkHeader(b), 0xFFFFFFF0u); }),
       fails({"the BIN chunk's length 4294967280 does not fit"})},
      {"first chunk is BIN", glb([](std::vector<uint8_t>& b) { put32(b, 16, 0x004E4942); }),
       fails({"the first .glb chunk has type 0x004E4942, not JSON"})},
      {"BIN chunk 8 bytes longer than the file (tinygltf read past it)",
       [] {
         Asset a = base();
         a.doc["buffers"][0]["byteLength"] = a.bin.size() + 8;
         Input in = a.glb();
         put32(in.bytes, binChunkHeader(in.bytes), uint32_t(a.bin.size() + 8));
         return in;
       },
       fails({"the BIN chunk's length", "does not fit the", "bytes after its header"})},
      {"missing BIN chunk", [] { return base().glb(false); },
       fails({"buffers[0] has no uri and the .glb has no BIN chunk"})},
      {"buffer longer than the BIN chunk",
       [] {
         Asset a = base();
         a.doc["buffers"][0]["byteLength"] = a.bin.size() + 64;
         return a.glb();
       },
       fails({"buffers[0].byteLength = ", "but the BIN chunk has"})},
      {"JSON chunk is not JSON",
       [] {
         return Input{glbBytes("this is not JSON", base().bin), true, {}};
       },
       fails({"invalid JSON", "line 1"})},
  });
}

TEST_CASE("glTF malformed: missing and short buffers, views and accessors past their data", "[gltf][malformed]") {
  runRows({
      {"buffer uri names a missing file",
       gltfWith([](Asset& a) { a.doc["buffers"][0]["uri"] = "rb_malformed_missing.bin"; }),
       fails({"File not found", "rb_malformed_missing.bin"})},
      {"buffer without uri in a .gltf",
       [] {
         json d = base().embedded();
         d["buffers"][0].erase("uri");
         return text(d.dump());
       },
       fails({"buffers[0] has no uri"})},
      {"data: URI that is not base64",
       gltfWith([](Asset& a) { a.doc["buffers"][0]["uri"] = "data:application/octet-stream,abcd"; }),
       fails({"buffers[0].uri is a data: URI of type 'application/octet-stream'", "cannot read"})},
      {"data: URI with a non-base64 character",
       gltfWith([](Asset& a) { a.doc["buffers"][0]["uri"] = "data:application/octet-stream;base64,AAAA@AAA"; }),
       fails({"buffers[0].uri: its base64 data has '@' at character 4"})},
      {"short buffer (byteLength larger than the data)",
       gltfWith([](Asset& a) { a.doc["buffers"][0]["byteLength"] = a.bin.size() + 4; }),
       fails({"buffers[0].byteLength = ", "but its data: URI holds"})},
      {"bufferView past the buffer end", gltfWith([](Asset& a) { a.doc["bufferViews"][kUvs]["byteLength"] = 1000; }),
       fails({"bufferViews[2] (byteOffset 96, byteLength 1000) ends past the end of buffers[0]"})},
      {"image bufferView past the buffer end (tinygltf decoded it unchecked)", gltfWith([](Asset& a) {
         const uint8_t png[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
         const int view = a.addView(png, sizeof png);
         a.doc["bufferViews"][size_t(view)]["byteLength"] = 4096;
         a.doc["images"][0] = {{"bufferView", view}, {"mimeType", "image/png"}};
       }),
       fails({"bufferViews[9] (byteOffset", "byteLength 4096) ends past the end of buffers[0]"})},
      {"accessor past its bufferView (count)", gltfWith([](Asset& a) { a.accessor(kUvs)["count"] = 5; }),
       fails({"TEXCOORD_0: accessor 2: 5 elements of 8 bytes, 8 apart from byteOffset 0, reach past buffer view 2 "
              "(byteLength 32)"})},
      {"accessor past its bufferView (byteOffset)", gltfWith([](Asset& a) { a.accessor(kNormals)["byteOffset"] = 12; }),
       fails({"NORMAL: accessor 1: 4 elements of 12 bytes, 12 apart from byteOffset 12, reach past buffer view 1"})},
      {"byteStride smaller than the element",
       gltfWith([](Asset& a) { a.doc["bufferViews"][kPositions]["byteStride"] = 8; }),
       fails({"POSITION: accessor 0: buffer view 0's byteStride 8 is shorter than the accessor's 12-byte elements"})},
      {"misaligned accessor offset", gltfWith([](Asset& a) {
         a.accessor(kPositions)["byteOffset"] = 2;
         a.accessor(kPositions)["count"] = 3;
       }),
       fails({"accessor 0: its data starts at byte 2 of its buffer", "not a multiple of its 4-byte components"})},
      {"misaligned bufferView offset", gltfWith([](Asset& a) { a.doc["bufferViews"][kNormals]["byteOffset"] = 50; }),
       fails({"accessor 1: its data starts at byte 50 of its buffer", "not a multiple of its 4-byte components"})},
  });
}

TEST_CASE("glTF malformed: out-of-range indices fail naming index and count", "[gltf][malformed]") {
  runRows({
      {"index value >= vertex count", gltfWith([](Asset& a) {
         const uint16_t nine = 9;
         std::memcpy(a.bin.data() + a.offset(kIndices) + 4, &nine, 2);
       }),
       fails({"mesh 'quad' primitive 0: index accessor 5: index 2 = 9 is out of range (the primitive has 4 "
              "vertices)"})},
      {"accessor index", gltfWith([](Asset& a) { a.primitive()["attributes"]["POSITION"] = 99; }),
       fails({"meshes[0].primitives[0].attributes.POSITION = 99 is out of range (the file has 9 accessors)"})},
      {"bufferView index", gltfWith([](Asset& a) { a.accessor(kPositions)["bufferView"] = 99; }),
       fails({"accessors[0].bufferView = 99 is out of range (the file has 9 bufferViews)"})},
      {"buffer index", gltfWith([](Asset& a) { a.doc["bufferViews"][0]["buffer"] = 3; }),
       fails({"bufferViews[0].buffer = 3 is out of range (the file has 1 buffers)"})},
      {"mesh index", gltfWith([](Asset& a) { a.node(1)["mesh"] = 5; }),
       fails({"nodes[1].mesh = 5 is out of range (the file has 1 meshes)"})},
      {"child node index", gltfWith([](Asset& a) { a.node(0)["children"][0] = 50; }),
       fails({"nodes[0].children[0] = 50 is out of range (the file has 5 nodes)"})},
      {"scene root node index", gltfWith([](Asset& a) { a.doc["scenes"][0]["nodes"][0] = 50; }),
       fails({"scenes[0].nodes[0] = 50 is out of range (the file has 5 nodes)"})},
      {"default scene index", gltfWith([](Asset& a) { a.doc["scene"] = 3; }),
       fails({"scene = 3 is out of range (the file has 1 scenes)"})},
      {"material index", gltfWith([](Asset& a) { a.primitive()["material"] = 4; }),
       fails({"meshes[0].primitives[0].material = 4 is out of range (the file has 1 materials)"})},
      {"texture index",
       gltfWith([](Asset& a) { a.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 3; }),
       fails({"materials[0].pbrMetallicRoughness.baseColorTexture.index = 3 is out of range (the file has 1 "
              "textures)"})},
      {"image index", gltfWith([](Asset& a) { a.doc["textures"][0]["source"] = 2; }),
       fails({"textures[0].source = 2 is out of range (the file has 1 images)"})},
      {"sampler index", gltfWith([](Asset& a) { a.doc["textures"][0]["sampler"] = 2; }),
       fails({"textures[0].sampler = 2 is out of range (the file has 1 samplers)"})},
      {"skin index", gltfWith([](Asset& a) { a.node(1)["skin"] = 2; }),
       fails({"nodes[1].skin = 2 is out of range (the file has 1 skins)"})},
      {"skin joint node index", gltfWith([](Asset& a) { a.doc["skins"][0]["joints"][0] = 40; }),
       fails({"skins[0].joints[0] = 40 is out of range (the file has 5 nodes)"})},
      {"inverseBindMatrices accessor index", gltfWith([](Asset& a) { a.doc["skins"][0]["inverseBindMatrices"] = 9; }),
       fails({"skins[0].inverseBindMatrices = 9 is out of range (the file has 9 accessors)"})},
      {"camera index", gltfWith([](Asset& a) { a.node(3)["camera"] = 1; }),
       fails({"nodes[3].camera = 1 is out of range (the file has 1 cameras)"})},
      {"animation sampler index", gltfWith([](Asset& a) { a.doc["animations"][0]["channels"][0]["sampler"] = 1; }),
       fails({"animations[0].channels[0].sampler = 1 is out of range (the animation has 1 samplers)"})},
      {"animation target node index",
       gltfWith([](Asset& a) { a.doc["animations"][0]["channels"][0]["target"]["node"] = 9; }),
       fails({"animations[0].channels[0].target.node = 9 is out of range (the file has 5 nodes)"})},
      {"light index", gltfWith([](Asset& a) { a.node(4)["extensions"]["KHR_lights_punctual"]["light"] = 3; }),
       fails({"node 4 'light': KHR_lights_punctual light 3 is out of range (the file has 1 lights)"})},
      {"joint index beyond the skin's joints", gltfWith([](Asset& a) { a.bin[a.offset(kJoints) + 4] = 3; }),
       fails({"skin 0 'skin'", "vertex 1: JOINTS_0 index 3 is out of range (the skin has 1 joints)"})},
  });
}

TEST_CASE("glTF malformed: accessor types and component types the attribute does not allow", "[gltf][malformed]") {
  runRows({
      {"POSITION is VEC2", gltfWith([](Asset& a) { a.accessor(kPositions)["type"] = "VEC2"; }),
       fails({"POSITION accessor 0 is VEC2 FLOAT; POSITION must be VEC3 FLOAT"})},
      {"POSITION is UNSIGNED_INT", gltfWith([](Asset& a) { a.accessor(kPositions)["componentType"] = kUnsignedInt; }),
       fails({"POSITION accessor 0 is VEC3 UNSIGNED_INT; POSITION must be VEC3 FLOAT"})},
      {"POSITION is normalized FLOAT", gltfWith([](Asset& a) { a.accessor(kPositions)["normalized"] = true; }),
       fails({"POSITION accessor 0 is VEC3 normalized FLOAT"})},
      {"componentType 5124 (INT: glTF 1 only)",
       gltfWith([](Asset& a) { a.accessor(kPositions)["componentType"] = 5124; }),
       fails({"accessors[0].componentType = 5124 is not a glTF component type"})},
      {"componentType 5130 (DOUBLE)", gltfWith([](Asset& a) { a.accessor(kPositions)["componentType"] = 5130; }),
       fails({"accessors[0].componentType = 5130 is not a glTF component type"})},
      {"indices are FLOAT", gltfWith([](Asset& a) { a.accessor(kIndices)["componentType"] = kFloat; }),
       fails({"index accessor 5 is SCALAR FLOAT; indices must be SCALAR UNSIGNED_BYTE, UNSIGNED_SHORT or "
              "UNSIGNED_INT"})},
      {"indices are signed SHORT", gltfWith([](Asset& a) { a.accessor(kIndices)["componentType"] = kShort; }),
       fails({"index accessor 5 is SCALAR SHORT; indices must be"})},
      {"indices are VEC3", gltfWith([](Asset& a) {
         a.accessor(kIndices)["type"] = "VEC3";
         a.accessor(kIndices)["count"] = 2;
       }),
       fails({"index accessor 5 is VEC3 UNSIGNED_SHORT; indices must be"})},
      {"TEXCOORD_0 is VEC3", gltfWith([](Asset& a) { a.accessor(kUvs)["type"] = "VEC3"; }),
       fails({"TEXCOORD_0 accessor 2 is VEC3 FLOAT; TEXCOORD_0 must be VEC2"})},
      {"TEXCOORD_0 is UNSIGNED_INT", gltfWith([](Asset& a) { a.accessor(kUvs)["componentType"] = kUnsignedInt; }),
       fails({"TEXCOORD_0 accessor 2 is VEC2 UNSIGNED_INT; TEXCOORD_0 must be VEC2"})},
      {"JOINTS_0 is FLOAT", gltfWith([](Asset& a) { a.accessor(kJoints)["componentType"] = kFloat; }),
       fails({"JOINTS_0 accessor 3 is VEC4 FLOAT; JOINTS_0 must be VEC4 UNSIGNED_BYTE or UNSIGNED_SHORT"})},
      {"JOINTS_0 is normalized", gltfWith([](Asset& a) { a.accessor(kJoints)["normalized"] = true; }),
       fails({"JOINTS_0 accessor 3 is VEC4 normalized UNSIGNED_BYTE; JOINTS_0 must be"})},
      {"JOINTS_0 is VEC2", gltfWith([](Asset& a) { a.accessor(kJoints)["type"] = "VEC2"; }),
       fails({"JOINTS_0 accessor 3 is VEC2 UNSIGNED_BYTE"})},
      {"WEIGHTS_0 is UNSIGNED_INT", gltfWith([](Asset& a) { a.accessor(kWeights)["componentType"] = kUnsignedInt; }),
       fails({"WEIGHTS_0 accessor 4 is VEC4 UNSIGNED_INT; WEIGHTS_0 must be VEC4 FLOAT"})},
      {"WEIGHTS_0 is SCALAR", gltfWith([](Asset& a) { a.accessor(kWeights)["type"] = "SCALAR"; }),
       fails({"WEIGHTS_0 accessor 4 is SCALAR FLOAT"})},
      {"animation input is VEC3",
       gltfWith([](Asset& a) { a.doc["animations"][0]["samplers"][0]["input"] = kTranslations; }),
       fails({"animation 0 'move', sampler 0: input accessor 7 is VEC3 FLOAT; key times must be SCALAR FLOAT"})},
      {"unknown accessor type", gltfWith([](Asset& a) { a.accessor(kNormals)["type"] = "VEC5"; }),
       fails({"accessors[1].type = \"VEC5\" is not SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4"})},
  });
}

TEST_CASE("glTF malformed: non-finite values are skipped where documented, fail elsewhere", "[gltf][malformed]") {
  auto binary = [](int view, size_t index, float value) {
    return [=] {
      Asset a = base();
      a.setFloat(view, index, value);
      return a.gltf();
    };
  };
  // JSON has no NaN or infinity; 1e999 (a double overflow) is the only way to write one.
  auto literal = [](std::function<void(Asset&)> place, const char* value) {
    return [=] {
      Asset a = base();
      place(a);
      return a.gltfWithLiteral("@x@", value);
    };
  };
  runRows({
      {"NaN position", binary(kPositions, 1 * 3 + 1, kNaN),
       loads({"mesh 'quad' primitive 0: POSITION accessor 0 has non-finite values (first at vertex 1); skipped the 1 "
              "of 2 triangles that use them"},
             1, 1)},
      {"infinite position", binary(kPositions, 3 * 3 + 0, -kInf),
       loads({"POSITION accessor 0 has non-finite values (first at vertex 3); skipped the 1 of 2 triangles"}, 1, 1)},
      {"NaN normal", binary(kNormals, 1 * 3 + 2, kNaN),
       loads({"NORMAL accessor 1 has non-finite values (first at vertex 1); skipped the 1 of 2 triangles"}, 1, 1)},
      {"NaN UV", binary(kUvs, 2 * 2 + 1, kNaN),
       loads({"mesh 'quad' primitive 0: TEXCOORD_0 accessor 2 has non-finite values (first at vertex 2); replaced 1 "
              "of 4 by a default"})},
      {"infinite UV", binary(kUvs, 0, kInf),
       loads({"TEXCOORD_0 accessor 2 has non-finite values (first at vertex 0)"})},
      {"node translation 1e999", literal([](Asset& a) { a.node(2)["translation"][0] = "@x@"; }, "1e999"),
       fails({"invalid JSON at nodes[2].translation[0]", "number overflow parsing '1e999'"})},
      {"node rotation -1e999",
       literal(
           [](Asset& a) {
             a.node(2)["rotation"] = {0, 0, 0, "@x@"};
           },
           "-1e999"),
       fails({"invalid JSON at nodes[2].rotation[3]", "number overflow parsing '-1e999'"})},
      {"node scale 1e999",
       literal(
           [](Asset& a) {
             a.node(2)["scale"] = {1, "@x@", 1};
           },
           "1e999"),
       fails({"invalid JSON at nodes[2].scale[1]"})},
      {"node matrix 1e999",
       literal(
           [](Asset& a) {
             a.node(2).erase("translation");
             a.node(2)["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, "@x@", 0, 0, 1};
           },
           "1e999"),
       fails({"invalid JSON at nodes[2].matrix[12]"})},
      {"camera yfov 1e999", literal([](Asset& a) { a.doc["cameras"][0]["perspective"]["yfov"] = "@x@"; }, "1e999"),
       fails({"invalid JSON at cameras[0].perspective.yfov"})},
      {"camera znear -1e999", literal([](Asset& a) { a.doc["cameras"][0]["perspective"]["znear"] = "@x@"; }, "-1e999"),
       fails({"invalid JSON at cameras[0].perspective.znear"})},
      {"baseColorFactor 1e999",
       literal([](Asset& a) { a.doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"][1] = "@x@"; }, "1e999"),
       fails({"invalid JSON at materials[0].pbrMetallicRoughness.baseColorFactor[1]"})},
      {"emissiveFactor 1e999", literal([](Asset& a) { a.doc["materials"][0]["emissiveFactor"][0] = "@x@"; }, "1e999"),
       fails({"invalid JSON at materials[0].emissiveFactor[0]"})},
      {"light intensity 1e999",
       literal([](Asset& a) { a.doc["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = "@x@"; }, "1e999"),
       fails({"invalid JSON at extensions.KHR_lights_punctual.lights[0].intensity"})},
      {"NaN keyframe time", binary(kTimes, 1, kNaN),
       fails({"animation 0 'move', sampler 0: input accessor 6, key 1: the time is not finite"})},
      {"infinite keyframe value", binary(kTranslations, 4, kInf),
       fails({"animation 0 'move', sampler 0: output accessor 7, element 1: a non-finite value"})},
      {"NaN inverse bind matrix", binary(kInverseBinds, 5, kNaN),
       fails({"skin 0 'skin', inverseBindMatrices accessor 8: matrix 0 has a non-finite element"})},
      {"NaN skin weight", binary(kWeights, 4, kNaN),
       fails({"mesh 'quad' primitive 0, WEIGHTS_0: accessor 4 has a non-finite value at vertex 1"})},
  });
}

TEST_CASE("glTF malformed: node graphs (cycles, two parents, a root with a parent, deep chains)", "[gltf][malformed]") {
  runRows({
      {"node is its own child", gltfWith([](Asset& a) { a.node(2)["children"] = {2}; }),
       fails({"node 2 'joint' lists itself as a child"})},
      {"cycle A -> B -> A", gltfWith([](Asset& a) {
         a.node(0)["children"] = {1, 4};
         a.node(2)["children"] = {3};
         a.node(3)["children"] = {2};
       }),
       fails({"node 2 'joint' is its own ancestor (parents 2 -> 3 -> 2; glTF nodes form a tree)"})},
      {"node with two parents", gltfWith([](Asset& a) { a.node(1)["children"] = {2}; }),
       fails({"node 2 'joint' is a child of both node 0 and node 1"})},
      {"child listed twice", gltfWith([](Asset& a) {
         a.node(0)["children"] = {1, 2, 3, 4, 2};
       }),
       fails({"nodes[0].children[4] = 2 is listed twice"})},
      {"scene lists a root twice", gltfWith([](Asset& a) {
         a.doc["scenes"][0]["nodes"] = {0, 0};
       }),
       fails({"scenes[0].nodes[1] = 0 is listed twice"})},
      {"scene root that is another node's child", gltfWith([](Asset& a) {
         a.doc["scenes"][0]["nodes"] = {0, 1};
       }),
       fails({"scene 0 lists node 1 'quad' as a root, but it is a child of node 0"})},
      {"chain of 100000 nested nodes",
       [] {
         // Written as text: 100000 JSON objects built one by one would take most of the test's time under ASan.
         constexpr int kDepth = 100000;
         Asset a = base();
         const int first = int(a.doc["nodes"].size());
         a.node(0)["children"].push_back(first);
         a.doc["nodes"].push_back("@chain@");
         std::string chain;
         for (int i = 1; i < kDepth; ++i) chain += "{\"children\":[" + std::to_string(first + i) + "]},";
         return a.gltfWithLiteral("@chain@", chain + "{\"mesh\":0}");
       },
       fails({"is 1025 levels deep, deeper than the loader's limit kMaxGltfNodeDepth = 1024"})},
  });
}

TEST_CASE("glTF malformed: shared meshes and nodes are instancing, not damage", "[gltf][malformed]") {
  runRows({
      {"one mesh on 1000 nodes (instancing)", gltfWith([](Asset& a) {
         for (int i = 0; i < 1000; ++i) {
           a.node(0)["children"].push_back(int(a.doc["nodes"].size()));
           a.doc["nodes"].push_back({{"mesh", 0}, {"translation", {(i % 40) * 1.5, (i / 40) * 1.5, -5}}});
         }
       }),
       loads({}, 1001, 2002)},
      {"one node in two scenes", gltfWith([](Asset& a) {
         a.doc["scenes"].push_back({{"nodes", {0}}});
       }),
       loads()},
  });
}

TEST_CASE("glTF malformed: absurd counts fail fast without allocating", "[gltf][malformed]") {
  runRows({
      {"accessor count 2^31", gltfWith([](Asset& a) { a.accessor(kPositions)["count"] = 2147483648u; }),
       fails({"POSITION: accessor 0: 2147483648 elements of 12 bytes, 12 apart from byteOffset 0, reach past buffer "
              "view 0 (byteLength 48)"})},
      {"accessor count 2^32-1", gltfWith([](Asset& a) { a.accessor(kNormals)["count"] = 4294967295u; }),
       fails({"NORMAL: accessor 1: 4294967295 elements of 12 bytes"})},
      {"accessor count 2^64-1", gltfWith([](Asset& a) { a.accessor(kPositions)["count"] = UINT64_MAX; }),
       fails({"accessor 0: 18446744073709551615 elements of 12 bytes"})},
      {"count x stride beyond 32 bits", gltfWith([](Asset& a) { a.accessor(kPositions)["count"] = 357913942; }),
       fails({"accessor 0: 357913942 elements of 12 bytes"})},
      {"accessor byteOffset 2^63", gltfWith([](Asset& a) { a.accessor(kPositions)["byteOffset"] = uint64_t(1) << 63; }),
       fails({"accessor 0: 4 elements of 12 bytes, 12 apart from byteOffset 9223372036854775808, reach past"})},
      {"index accessor count 2^31", gltfWith([](Asset& a) { a.accessor(kIndices)["count"] = 2147483648u; }),
       fails({"index accessor 5: 2147483648 elements of 2 bytes"})},
      {"keyframe count 2^31", gltfWith([](Asset& a) { a.accessor(kTimes)["count"] = 2147483648u; }),
       fails({"animation 0 'move', sampler 0, input: accessor 6: 2147483648 elements of 4 bytes"})},
      {"zero-filled accessor (no bufferView) of count 2^31", gltfWith([](Asset& a) {
         a.accessor(kNormals).erase("bufferView");
         a.accessor(kNormals)["count"] = 2147483648u;
       }),
       fails({"accessor 1 has no buffer view (all zeros) and count 2147483648, more elements than the file's buffers "
              "hold bytes"})},
      {"sparse count 2^31", gltfWith([](Asset& a) {
         a.accessor(kPositions)["sparse"] = {{"count", 2147483648u},
                                             {"indices", {{"bufferView", kIndices}, {"componentType", kUnsignedShort}}},
                                             {"values", {{"bufferView", kNormals}}}};
       }),
       fails({"accessors[0].sparse.count = 2147483648 is not an integer from 1 to 2147483647"})},
      {"sparse count above the accessor's", gltfWith([](Asset& a) {
         a.accessor(kPositions)["sparse"] = {{"count", 5},
                                             {"indices", {{"bufferView", kIndices}, {"componentType", kUnsignedShort}}},
                                             {"values", {{"bufferView", kNormals}}}};
       }),
       fails({"accessors[0].sparse.count = 5 is more than the accessor's count 4"})},
      {"buffer byteLength 2^40", gltfWith([](Asset& a) { a.doc["buffers"][0]["byteLength"] = uint64_t(1) << 40; }),
       fails({"buffers[0].byteLength = 1099511627776 but its data: URI holds"})},
      {"bufferView byteLength 2^40",
       gltfWith([](Asset& a) { a.doc["bufferViews"][kPositions]["byteLength"] = uint64_t(1) << 40; }),
       fails({"bufferViews[0] (byteOffset 0, byteLength 1099511627776) ends past the end of buffers[0]"})},
  });
}

TEST_CASE("glTF malformed: unsupported required extensions and Draco", "[gltf][malformed]") {
  auto draco = [](Asset& a) {
    a.doc["extensionsUsed"].push_back("KHR_draco_mesh_compression");
    const uint8_t payload[4] = {'D', 'R', 'A', 'C'};
    const int view = a.addView(payload, sizeof payload);
    a.primitive()["extensions"] = {
        {"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}}}};
  };
  runRows({
      {"made-up required extension", gltfWith([](Asset& a) {
         a.doc["extensionsUsed"].push_back("EXT_made_up");
         a.doc["extensionsRequired"] = {"EXT_made_up"};
       }),
       fails({"requires extension EXT_made_up, which the sample engine does not support"})},
      {"KHR_draco_mesh_compression required", gltfWith([draco](Asset& a) {
         draco(a);
         a.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
       }),
       fails({"requires extension KHR_draco_mesh_compression (Draco-compressed meshes are unsupported)"})},
      {"Draco used, no uncompressed data", gltfWith([draco](Asset& a) {
         draco(a);
         for (int acc : {kPositions, kNormals, kUvs, kJoints, kWeights, kIndices}) a.accessor(acc).erase("bufferView");
       }),
       fails({"meshes[0].primitives[0] (mesh \"quad\") is compressed with KHR_draco_mesh_compression and has no "
              "uncompressed data",
              "Draco-compressed meshes are unsupported"})},
      {"Draco used, with the uncompressed fallback", gltfWith(draco), loads()},
      {"unknown extension used, not required",
       gltfWith([](Asset& a) { a.doc["extensionsUsed"].push_back("EXT_other"); }), loads()},
  });
}

TEST_CASE("glTF malformed: zero-sized, corrupt and unsupported images", "[gltf][malformed]") {
  auto image = [](std::function<void(Asset&, json & image)> damage) {
    return [damage] {
      Asset a = base();
      damage(a, a.doc["images"][0]);
      Input in = a.gltf();
      in.baseDir = scratchDir().string();
      return in;
    };
  };
  auto embedded = [](std::vector<uint8_t> bytes, const char* mime = "image/png") {
    return [bytes, mime](Asset&, json& img) {
      std::string uri = "data:";
      uri.append(mime).append(";base64,").append(base64(bytes));
      img["uri"] = uri;
    };
  };
  auto inView = [](std::vector<uint8_t> bytes, const char* mime) {
    return [bytes, mime](Asset& a, json& img) {
      img = {{"name", "checker"}, {"bufferView", a.addView(bytes.data(), bytes.size())}, {"mimeType", mime}};
    };
  };
  std::vector<uint8_t> zeroSize = pngBytes();
  std::fill(zeroSize.begin() + 16, zeroSize.begin() + 24, 0);  // IHDR width and height
  const std::vector<uint8_t> truncated(pngBytes().begin(), pngBytes().begin() + long(pngBytes().size() / 2));
  std::vector<uint8_t> garbage(64);
  for (size_t i = 0; i < garbage.size(); ++i) garbage[i] = uint8_t(i * 37 + 11);
  std::vector<uint8_t> ktx2 = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};
  ktx2.resize(64, 0);
  writeFile(scratchDir() / "empty.png", {});
  const char* ignored = "; the textures that use it are ignored";
  runRows({
      {"empty data: URI", image([](Asset&, json& img) { img["uri"] = "data:image/png;base64,"; }),
       fails({"images[0].uri is a data: URI without data (a zero-byte image)"})},
      {"zero-byte image bufferView", image([](Asset& a, json& img) {
         const int view = a.addView(nullptr, 0);
         img = {{"bufferView", view}, {"mimeType", "image/png"}};
       }),
       fails({"bufferViews[9].byteLength = 0 is not an integer from 1"})},
      {"zero-byte image file", image([](Asset&, json& img) { img["uri"] = "empty.png"; }),
       loads({std::string("image 0 'checker': its file 'empty.png' is missing, empty or unreadable") + ignored}, 1, 2,
             false)},
      {"missing image file", image([](Asset&, json& img) { img["uri"] = "missing.png"; }),
       loads({std::string("image 0 'checker': its file 'missing.png' is missing, empty or unreadable") + ignored}, 1, 2,
             false)},
      {"PNG of 0x0 pixels", image(embedded(zeroSize)),
       loads({"image 0 'checker' cannot be decoded (image/png, " + std::to_string(zeroSize.size()) + " bytes: ",
              ignored},
             1, 2, false)},
      {"truncated PNG", image(embedded(truncated)),
       loads({"image 0 'checker' cannot be decoded (image/png, " + std::to_string(truncated.size()) + " bytes: ",
              ignored},
             1, 2, false)},
      {"garbage image bytes", image(embedded(garbage)),
       loads({"image 0 'checker' cannot be decoded (image/png, 64 bytes: Unknown image format", ignored}, 1, 2, false)},
      {"garbage image in a bufferView", image(inView(garbage, "image/png")),
       loads({"image 0 'checker' cannot be decoded (image/png, 64 bytes", ignored}, 1, 2, false)},
      {"unsupported mime type image/ktx2", image(inView(ktx2, "image/ktx2")),
       loads({"image 0 'checker' cannot be decoded (image/ktx2, 64 bytes", ignored}, 1, 2, false)},
      {"unsupported data: URI type image/webp", image(embedded(garbage, "image/webp")),
       loads({"image 0 'checker': its data: URI of type 'image/webp;base64' is not one the loader reads", ignored}, 1,
             2, false)},
      {"image with uri and bufferView", image([](Asset&, json& img) { img["bufferView"] = int(kPositions); }),
       fails({"images[0] needs exactly one of uri and bufferView"})},
  });
}

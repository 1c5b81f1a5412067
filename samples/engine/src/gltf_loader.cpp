// glTF 2.0 loader on top of tinygltf: flattens the node hierarchy into Scene instances (keeping the nodes,
// skins and animations for animation), converts each triangle primitive (lists, strips and fans) into a
// MeshData and each image into an RGBA8 TextureData.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>

#include <tiny_gltf.h>

#include "gltf_accessors.h"
#include "gltf_animation.h"
#include "gltf_document_check.h"
#include "sample_engine/animation.h"
#include "sample_engine/gltf_loader.h"

namespace sample_engine {
namespace {

using detail::readFloats;
using detail::readIndices;

// The extensions a file may list in extensionsRequired. KHR_mesh_quantization needs nothing beyond the
// accessor reader's integer and normalized formats.
const char* const kSupportedExtensions[] = {"KHR_mesh_quantization", "KHR_texture_transform",
                                            "KHR_materials_emissive_strength", "KHR_lights_punctual"};

const char* modeName(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS: return "POINTS";
    case TINYGLTF_MODE_LINE: return "LINES";
    case TINYGLTF_MODE_LINE_LOOP: return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP: return "LINE_STRIP";
    default: return "unknown";
  }
}

double number(const tinygltf::Value& v, double fallback) { return v.IsNumber() ? v.GetNumberAsDouble() : fallback; }

glm::vec2 vec2Of(const tinygltf::Value& object, const char* key, glm::vec2 fallback) {
  if (!object.Has(key)) return fallback;
  const tinygltf::Value& a = object.Get(key);
  if (!a.IsArray() || a.ArrayLen() != 2) return fallback;
  return glm::vec2(float(number(a.Get(0), fallback.x)), float(number(a.Get(1), fallback.y)));
}

// textureInfo.texCoord and its KHR_texture_transform (whose texCoord, when present, overrides).
UvMapping uvMapping(int texCoord, const tinygltf::ExtensionMap& extensions) {
  UvMapping u;
  u.texCoord = uint32_t(std::max(texCoord, 0));
  auto it = extensions.find("KHR_texture_transform");
  if (it == extensions.end() || !it->second.IsObject()) return u;
  const tinygltf::Value& t = it->second;
  u.offset = vec2Of(t, "offset", u.offset);
  u.scale = vec2Of(t, "scale", u.scale);
  if (t.Has("rotation")) u.rotation = float(number(t.Get("rotation"), 0.0));
  if (t.Has("texCoord") && t.Get("texCoord").IsNumber())
    u.texCoord = uint32_t(std::max(t.Get("texCoord").GetNumberAsInt(), 0));
  return u;
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A message from tinygltf or a URI, shortened: either can hold a whole data: URI.
std::string shortened(const std::string& text, size_t maxLine = 200) {
  std::string out;
  for (size_t begin = 0; begin < text.size();) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(begin, end - begin);
    if (!line.empty())
      out += (out.empty() ? "" : "; ") + (line.size() > maxLine ? line.substr(0, maxLine) + "..." : line);
    begin = end + 1;
  }
  return out;
}

// The accessor formats glTF 2.0 (with KHR_mesh_quantization) allows for the vertex attributes the engine reads;
// the reader would convert any of them, so a wrong one would load as garbage instead of failing.
enum FormatBits : uint32_t {
  kFloat = 1u << 0,
  kByte = 1u << 1,
  kByteNormalized = 1u << 2,
  kUnsignedByte = 1u << 3,
  kUnsignedByteNormalized = 1u << 4,
  kShort = 1u << 5,
  kShortNormalized = 1u << 6,
  kUnsignedShort = 1u << 7,
  kUnsignedShortNormalized = 1u << 8,
  kAnyInteger8Or16 = kByte | kByteNormalized | kUnsignedByte | kUnsignedByteNormalized | kShort | kShortNormalized |
                     kUnsignedShort | kUnsignedShortNormalized,
};

uint32_t formatBit(const tinygltf::Accessor& a) {
  switch (a.componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return a.normalized ? 0u : uint32_t(kFloat);
    case TINYGLTF_COMPONENT_TYPE_BYTE: return a.normalized ? kByteNormalized : kByte;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return a.normalized ? kUnsignedByteNormalized : kUnsignedByte;
    case TINYGLTF_COMPONENT_TYPE_SHORT: return a.normalized ? kShortNormalized : kShort;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return a.normalized ? kUnsignedShortNormalized : kUnsignedShort;
    default: return 0;
  }
}

struct AttributeFormat {
  int type;
  uint32_t allowed;
  const char* text;
};

// POSITION, NORMAL, TANGENT, TEXCOORD_n, JOINTS_n, WEIGHTS_n (glTF 3.7.2.1, KHR_mesh_quantization); `target`: a
// morph target's POSITION / NORMAL.
const AttributeFormat* attributeFormat(const std::string& name, bool target) {
  static const AttributeFormat position{TINYGLTF_TYPE_VEC3, kFloat | kAnyInteger8Or16,
                                        "VEC3 FLOAT (or 8- or 16-bit integers with KHR_mesh_quantization)"};
  static const AttributeFormat normal{TINYGLTF_TYPE_VEC3, kFloat | kByteNormalized | kShortNormalized,
                                      "VEC3 FLOAT (or normalized BYTE or SHORT)"};
  static const AttributeFormat tangent{TINYGLTF_TYPE_VEC4, kFloat | kByteNormalized | kShortNormalized,
                                       "VEC4 FLOAT (or normalized BYTE or SHORT)"};
  static const AttributeFormat texCoord{TINYGLTF_TYPE_VEC2, kFloat | kAnyInteger8Or16,
                                        "VEC2 FLOAT (or 8- or 16-bit integers)"};
  static const AttributeFormat joints{TINYGLTF_TYPE_VEC4, kUnsignedByte | kUnsignedShort,
                                      "VEC4 UNSIGNED_BYTE or UNSIGNED_SHORT"};
  static const AttributeFormat weights{TINYGLTF_TYPE_VEC4, kFloat | kUnsignedByteNormalized | kUnsignedShortNormalized,
                                       "VEC4 FLOAT (or normalized UNSIGNED_BYTE or UNSIGNED_SHORT)"};
  static const AttributeFormat delta{TINYGLTF_TYPE_VEC3, kFloat | kByte | kByteNormalized | kShort | kShortNormalized,
                                     "VEC3 FLOAT (or BYTE or SHORT with KHR_mesh_quantization)"};
  if (target) return name == "POSITION" || name == "NORMAL" ? &delta : nullptr;
  if (name == "POSITION") return &position;
  if (name == "NORMAL") return &normal;
  if (name == "TANGENT") return &tangent;
  if (name.rfind("TEXCOORD_", 0) == 0) return &texCoord;
  if (name.rfind("JOINTS_", 0) == 0) return &joints;
  if (name.rfind("WEIGHTS_", 0) == 0) return &weights;
  return nullptr;
}

// Replaces the non-finite values of a UV or tangent array (they would only sample a wrong texel or tilt a normal
// map; positions and normals skip their triangles instead) and says so.
template <typename Vec>
void replaceNonFinite(std::vector<Vec>& values, const Vec& stand, const std::string& what,
                      std::vector<std::string>& warnings) {
  size_t first = values.size(), count = 0;
  for (size_t v = 0; v < values.size(); ++v)
    for (int c = 0; c < Vec::length(); ++c)
      if (!std::isfinite(values[v][c])) {
        first = std::min(first, v);
        ++count;
        values[v] = stand;
        break;
      }
  if (count)
    warnings.push_back(what + " has non-finite values (first at vertex " + std::to_string(first) + "); replaced " +
                       std::to_string(count) + " of " + std::to_string(values.size()) + " by a default");
}

TextureData convertImage(const tinygltf::Image& img) {
  TextureData t;
  t.name = img.name.empty() ? img.uri : img.name;
  if (img.width <= 0 || img.height <= 0 || img.component <= 0 || img.image.empty()) return t;
  t.width = uint32_t(img.width);
  t.height = uint32_t(img.height);
  t.rgba8.resize(size_t(t.width) * t.height * 4);
  const int bytesPerComp = img.bits == 16 ? 2 : 1;
  for (size_t i = 0; i < size_t(t.width) * t.height; ++i) {
    uint8_t rgba[4] = {0, 0, 0, 255};
    for (int c = 0; c < img.component && c < 4; ++c) {
      size_t at = (i * img.component + c) * bytesPerComp;
      if (at + bytesPerComp > img.image.size()) break;
      rgba[c] = bytesPerComp == 2 ? img.image[at + 1] : img.image[at];  // 16-bit: keep the high byte
    }
    if (img.component == 1) rgba[1] = rgba[2] = rgba[0];
    if (img.component == 2) {  // grey + alpha
      rgba[3] = rgba[1];
      rgba[1] = rgba[2] = rgba[0];
    }
    std::memcpy(&t.rgba8[i * 4], rgba, 4);
  }
  return t;
}

struct Loader {
  const tinygltf::Model& model;
  SceneLoadResult& result;
  std::map<int, std::vector<uint32_t>> meshPrimitives;  // glTF mesh -> Scene mesh indices
  std::vector<std::pair<int, int>> meshOrigin;          // Scene mesh -> glTF (mesh, primitive)
  std::set<std::pair<int, uint32_t>> checkedSkins;      // (skin, Scene mesh) pairs already validated
  std::vector<UvMapping> bakedUv;                       // per glTF material: the mapping baked into its UVs
  std::string error;                                    // the first fatal problem
  std::vector<PunctualLight> lights;                    // per KHR_lights_punctual light, checked, unplaced

  void fail(std::string message) {
    if (error.empty()) error = std::move(message);
  }

  int textureImage(int textureIndex) {
    if (textureIndex < 0 || textureIndex >= int(model.textures.size())) return -1;
    int source = model.textures[textureIndex].source;
    return source >= 0 && source < int(model.images.size()) ? source : -1;
  }

  void convertMaterials() {
    for (const tinygltf::Material& m : model.materials) {
      Material out;
      out.name = m.name;
      const auto& pbr = m.pbrMetallicRoughness;
      if (pbr.baseColorFactor.size() == 4)
        out.baseColorFactor = glm::vec4(pbr.baseColorFactor[0], pbr.baseColorFactor[1], pbr.baseColorFactor[2],
                                        pbr.baseColorFactor[3]);
      out.metallicFactor = float(pbr.metallicFactor);
      out.roughnessFactor = float(pbr.roughnessFactor);
      if (m.emissiveFactor.size() == 3)
        out.emissiveFactor = glm::vec3(m.emissiveFactor[0], m.emissiveFactor[1], m.emissiveFactor[2]);
      out.baseColorTexture = textureImage(pbr.baseColorTexture.index);
      out.metallicRoughnessTexture = textureImage(pbr.metallicRoughnessTexture.index);
      out.normalTexture = textureImage(m.normalTexture.index);
      out.emissiveTexture = textureImage(m.emissiveTexture.index);
      out.occlusionTexture = textureImage(m.occlusionTexture.index);
      out.occlusionStrength = float(m.occlusionTexture.strength);
      out.normalScale = float(m.normalTexture.scale);
      if (auto it = m.extensions.find("KHR_materials_emissive_strength");
          it != m.extensions.end() && it->second.IsObject() && it->second.Has("emissiveStrength"))
        out.emissiveFactor *= float(number(it->second.Get("emissiveStrength"), 1.0));
      out.baseColorUv = uvMapping(pbr.baseColorTexture.texCoord, pbr.baseColorTexture.extensions);
      out.metallicRoughnessUv = uvMapping(pbr.metallicRoughnessTexture.texCoord,
                                          pbr.metallicRoughnessTexture.extensions);
      out.normalUv = uvMapping(m.normalTexture.texCoord, m.normalTexture.extensions);
      out.emissiveUv = uvMapping(m.emissiveTexture.texCoord, m.emissiveTexture.extensions);
      out.occlusionUv = uvMapping(m.occlusionTexture.texCoord, m.occlusionTexture.extensions);
      // The engine samples every texture with one UV set: bake the textures' shared mapping into it; when
      // they differ, the base colour texture's (else the first present) wins.
      const std::pair<const char*, std::pair<int, const UvMapping*>> slots[] = {
          {"baseColorTexture", {pbr.baseColorTexture.index, &out.baseColorUv}},
          {"metallicRoughnessTexture", {pbr.metallicRoughnessTexture.index, &out.metallicRoughnessUv}},
          {"normalTexture", {m.normalTexture.index, &out.normalUv}},
          {"emissiveTexture", {m.emissiveTexture.index, &out.emissiveUv}},
          {"occlusionTexture", {m.occlusionTexture.index, &out.occlusionUv}}};
      const char* chosenSlot = nullptr;
      UvMapping chosen;
      bool differ = false;
      for (const auto& [slot, texture] : slots) {
        if (texture.first < 0) continue;
        if (!chosenSlot) {
          chosenSlot = slot;
          chosen = *texture.second;
        } else
          differ |= !(*texture.second == chosen);
      }
      if (differ)
        result.warnings.push_back("material '" + m.name +
                                  "': its textures use different UV mappings (texCoord / KHR_texture_transform); "
                                  "all are sampled with the " +
                                  chosenSlot + "'s");
      if (chosen.texCoord > 1) {
        result.warnings.push_back("material '" + m.name + "': TEXCOORD_" + std::to_string(chosen.texCoord) +
                                  " is unsupported; TEXCOORD_0 used");
        chosen.texCoord = 0;
      }
      bakedUv.push_back(chosen);
      out.alphaMode = m.alphaMode == "MASK"    ? AlphaMode::Mask
                      : m.alphaMode == "BLEND" ? AlphaMode::Blend
                                               : AlphaMode::Opaque;
      if (m.alphaMode != "OPAQUE" && m.alphaMode != "MASK" && m.alphaMode != "BLEND")
        result.warnings.push_back("material '" + m.name + "': unknown alphaMode '" + m.alphaMode + "', drawn opaque");
      out.alphaCutoff = std::isfinite(m.alphaCutoff) && m.alphaCutoff >= 0.0 ? float(m.alphaCutoff) : 0.5f;
      out.doubleSided = m.doubleSided;
      result.scene.materials.push_back(out);
    }
  }

  // The accessor of an attribute the engine reads has a format glTF allows for it (see attributeFormat).
  bool checkFormat(const std::string& where, const std::string& name, int accessor, bool target) {
    const AttributeFormat* format = attributeFormat(name, target);
    if (!format || accessor < 0 || accessor >= int(model.accessors.size())) return true;  // range: readFloats
    const tinygltf::Accessor& a = model.accessors[size_t(accessor)];
    if (a.type == format->type && (formatBit(a) & format->allowed)) return true;
    fail(where + ": " + name + " accessor " + std::to_string(accessor) + " is " + detail::formatName(a) + "; " + name +
         " must be " + format->text);
    return false;
  }

  // Converts one primitive; returns false (with a warning) when it is skipped, or after fail().
  bool convertPrimitive(const tinygltf::Mesh& mesh, size_t index, MeshData& out) {
    const tinygltf::Primitive& prim = mesh.primitives[index];
    const std::string where = "mesh '" + mesh.name + "' primitive " + std::to_string(index);
    const bool strip = prim.mode == TINYGLTF_MODE_TRIANGLE_STRIP, fan = prim.mode == TINYGLTF_MODE_TRIANGLE_FAN;
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1 && !strip && !fan) {
      result.warnings.push_back(where + ": skipped, mode " + std::to_string(prim.mode) + " (" + modeName(prim.mode) +
                                ") is not a triangle mode (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN)");
      return false;
    }
    for (const auto& [name, accessor] : prim.attributes)
      if (!checkFormat(where, name, accessor, false)) return false;
    auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) {
      result.warnings.push_back(where + ": skipped, no POSITION attribute");
      return false;
    }
    // A file whose accessors do not fit their data is corrupt: it fails (naming the accessor), never loads in part.
    std::vector<float> f;
    if (std::string e = readFloats(model, pos->second, 3, f); !e.empty()) {
      fail(where + ", POSITION: " + e);
      return false;
    }
    out.name = mesh.name.empty() ? "mesh" : mesh.name;
    out.positions.resize(f.size() / 3);
    // An empty accessor leaves both pointers null: memcpy from null is undefined even for 0 bytes (the fuzzer's UBSan).
    if (!f.empty()) std::memcpy(out.positions.data(), f.data(), f.size() * sizeof(float));
    auto optional = [&](const char* name, int comps, auto& dst) {
      auto it = prim.attributes.find(name);
      if (it == prim.attributes.end()) return;
      if (std::string e = readFloats(model, it->second, comps, f); !e.empty()) {
        fail(where + ", " + name + ": " + e);
        return;
      }
      if (f.size() / comps != out.positions.size()) {
        result.warnings.push_back(where + ": ignoring " + name + ": count differs from POSITION");
        return;
      }
      dst.resize(f.size() / comps);
      std::memcpy(dst.data(), f.data(), f.size() * sizeof(float));
    };
    optional("NORMAL", 3, out.normals);
    optional("TEXCOORD_0", 2, out.uvs);
    optional("TEXCOORD_1", 2, out.uvs1);
    optional("TANGENT", 4, out.tangents);
    if (!error.empty() || !readDeformation(prim, where, out)) return false;
    for (double w : mesh.weights) out.morphWeights.push_back(float(w));
    if (prim.indices >= 0) {
      if (std::string e = readIndices(model, prim.indices, out.indices); !e.empty()) {
        fail(where + ": " + e);
        return false;
      }
      for (size_t i = 0; i < out.indices.size(); ++i)
        if (out.indices[i] >= out.positions.size()) {
          fail(where + ": index accessor " + std::to_string(prim.indices) + ": index " + std::to_string(i) + " = " +
               std::to_string(out.indices[i]) + " is out of range (the primitive has " +
               std::to_string(out.positions.size()) + " vertices)");
          return false;
        }
    }
    if (strip || fan) toTriangleList(strip, out);
    skipNonFinite(prim, where, out);
    auto accessorOf = [&](const char* name) { return " accessor " + std::to_string(prim.attributes.at(name)); };
    if (!out.uvs.empty())
      replaceNonFinite(out.uvs, glm::vec2(0.0f), where + ": TEXCOORD_0" + accessorOf("TEXCOORD_0"), result.warnings);
    if (!out.uvs1.empty())
      replaceNonFinite(out.uvs1, glm::vec2(0.0f), where + ": TEXCOORD_1" + accessorOf("TEXCOORD_1"), result.warnings);
    if (!out.tangents.empty())
      replaceNonFinite(out.tangents, glm::vec4(1, 0, 0, 1), where + ": TANGENT" + accessorOf("TANGENT"),
                       result.warnings);
    out.material = prim.material >= 0 ? uint32_t(prim.material) : uint32_t(result.scene.materials.size());
    if (prim.material >= 0 && size_t(prim.material) < bakedUv.size())
      bakeUvs(bakedUv[size_t(prim.material)], where, out);
    if (out.triangleCount() == 0) {
      result.warnings.push_back(where + ": skipped, no triangles");
      return false;
    }
    return true;
  }

  // Strip / fan corners (indexed or not) into an indexed triangle list with the glTF 2.0 winding (3.7.2.1):
  // strip triangle i = (v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]), fan triangle i = (v[i + 1], v[i + 2], v[0]).
  // Strip triangles that repeat an index (degenerate, used to join strips) are dropped.
  static void toTriangleList(bool strip, MeshData& out) {
    std::vector<uint32_t> corners = std::move(out.indices);
    if (corners.empty()) {
      corners.resize(out.positions.size());
      for (size_t i = 0; i < corners.size(); ++i) corners[i] = uint32_t(i);
    }
    out.indices.clear();
    for (size_t i = 0; i + 2 < corners.size(); ++i) {
      const size_t odd = i % 2;
      const uint32_t a = strip ? corners[i] : corners[i + 1], b = strip ? corners[i + 1 + odd] : corners[i + 2],
                     c = strip ? corners[i + 2 - odd] : corners[0];
      if (strip && (a == b || b == c || a == c)) continue;
      out.indices.insert(out.indices.end(), {a, b, c});
    }
  }

  // Drops the triangles that use a non-finite position or normal (one warning naming the accessors) and
  // replaces those values with finite ones, so that bounds, camera framing and BLAS builds see finite data.
  void skipNonFinite(const tinygltf::Primitive& prim, const std::string& where, MeshData& out) {
    const size_t n = out.positions.size();
    std::vector<bool> bad(n, false);
    bool badPosition = false, badNormal = false;
    size_t firstBad = n;
    for (size_t v = 0; v < n; ++v) {
      const bool p = !finite(out.positions[v]), q = v < out.normals.size() && !finite(out.normals[v]);
      badPosition |= p;
      badNormal |= q;
      bad[v] = p || q;
      if (bad[v] && firstBad == n) firstBad = v;
    }
    if (firstBad == n) return;
    const size_t corners = out.indices.empty() ? n / 3 * 3 : out.indices.size() / 3 * 3;
    std::vector<uint32_t> kept;
    size_t skipped = 0;
    for (size_t t = 0; t < corners; t += 3) {
      uint32_t tri[3];
      for (size_t k = 0; k < 3; ++k) tri[k] = out.indices.empty() ? uint32_t(t + k) : out.indices[t + k];
      if (bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) {
        ++skipped;
        continue;
      }
      kept.insert(kept.end(), tri, tri + 3);
    }
    const glm::vec3 stand = kept.empty() ? glm::vec3(0.0f) : out.positions[kept[0]];
    for (size_t v = 0; v < n; ++v) {
      if (!finite(out.positions[v])) out.positions[v] = stand;
      if (v < out.normals.size() && !finite(out.normals[v])) out.normals[v] = glm::vec3(0.0f, 1.0f, 0.0f);
    }
    out.indices = std::move(kept);
    std::string accessors;
    if (badPosition) accessors = "POSITION accessor " + std::to_string(prim.attributes.at("POSITION"));
    if (badNormal)
      accessors += std::string(badPosition ? " and " : "") + "NORMAL accessor " +
                   std::to_string(prim.attributes.at("NORMAL"));
    result.warnings.push_back(where + ": " + accessors + " has non-finite values (first at vertex " +
                              std::to_string(firstBad) + "); skipped the " + std::to_string(skipped) + " of " +
                              std::to_string(corners / 3) + " triangles that use them");
  }

  // Replaces the mesh's UVs by `mapping` applied to its UV set (see Material).
  void bakeUvs(const UvMapping& mapping, const std::string& where, MeshData& out) {
    const std::vector<glm::vec2>& source = mapping.texCoord == 1 ? out.uvs1 : out.uvs;
    if (mapping.texCoord == 1 && source.empty()) {
      result.warnings.push_back(where + ": its material's textures use TEXCOORD_1, which it lacks; TEXCOORD_0 used");
      if (mapping.identity()) return;
    }
    if (mapping.texCoord == 0 && mapping.identity()) return;
    const std::vector<glm::vec2>& from = source.empty() ? out.uvs : source;
    std::vector<glm::vec2> mapped(from.size());
    for (size_t v = 0; v < from.size(); ++v) mapped[v] = mapping.apply(from[v]);
    out.uvs = std::move(mapped);
  }

  // Reads a required per-vertex attribute of `comps` floats; a problem is fatal (the mesh could not animate).
  bool readVertexAttribute(int accessor, const std::string& what, int comps, size_t vertexCount,
                           std::vector<float>& f) {
    if (std::string e = readFloats(model, accessor, comps, f); !e.empty()) {
      fail(what + ": " + e);
      return false;
    }
    if (f.size() / size_t(comps) != vertexCount) {
      fail(what + ": " + std::to_string(f.size() / size_t(comps)) + " elements for " + std::to_string(vertexCount) +
           " vertices");
      return false;
    }
    for (size_t i = 0; i < f.size(); ++i)
      if (!std::isfinite(f[i])) {
        fail(what + ": accessor " + std::to_string(accessor) + " has a non-finite value at vertex " +
             std::to_string(i / size_t(comps)));
        return false;
      }
    return true;
  }

  // JOINTS_n / WEIGHTS_n and morph targets. Returns false on a fatal problem (see `error`).
  bool readDeformation(const tinygltf::Primitive& prim, const std::string& where, MeshData& out) {
    const size_t n = out.positions.size();
    std::vector<float> f;
    for (int set = 0; set < 2; ++set) {
      const std::string jointsName = "JOINTS_" + std::to_string(set), weightsName = "WEIGHTS_" + std::to_string(set);
      auto joints = prim.attributes.find(jointsName), weights = prim.attributes.find(weightsName);
      if (joints == prim.attributes.end() && weights == prim.attributes.end()) break;
      if (joints == prim.attributes.end() || weights == prim.attributes.end()) {
        result.warnings.push_back(where + ": " + jointsName + " and " + weightsName +
                                  " come in pairs; ignoring the one present");
        break;
      }
      auto& dstJoints = set ? out.joints1 : out.joints0;
      auto& dstWeights = set ? out.weights1 : out.weights0;
      if (!readVertexAttribute(joints->second, where + ", " + jointsName, 4, n, f)) return false;
      dstJoints.resize(n);
      for (size_t v = 0; v < n; ++v)
        for (int k = 0; k < 4; ++k) dstJoints[v][k] = uint16_t(std::min(f[v * 4 + size_t(k)], 65535.0f));
      if (!readVertexAttribute(weights->second, where + ", " + weightsName, 4, n, f)) return false;
      dstWeights.resize(n);
      std::memcpy(dstWeights.data(), f.data(), n * sizeof(glm::vec4));
    }
    for (size_t t = 0; t < prim.targets.size(); ++t) {
      MorphTarget target;
      const std::string at = where + ", morph target " + std::to_string(t);
      for (const auto& [name, accessor] : prim.targets[t]) {
        std::vector<glm::vec3>* dst = name == "POSITION" ? &target.positionDeltas
                                      : name == "NORMAL" ? &target.normalDeltas
                                                         : nullptr;
        if (!dst) continue;  // TANGENT deltas: tangents are only skinned
        if (!checkFormat(at, name, accessor, true) || !readVertexAttribute(accessor, at + " " + name, 3, n, f))
          return false;
        dst->resize(n);
        std::memcpy(dst->data(), f.data(), n * sizeof(glm::vec3));
      }
      out.morphTargets.push_back(std::move(target));
    }
    return true;
  }

  // The skin must cover every joint index of the mesh, and every vertex needs some weight.
  void checkSkin(int skinIndex, uint32_t m) {
    if (!checkedSkins.insert({skinIndex, m}).second) return;
    const Skin& skin = result.scene.skins[size_t(skinIndex)];
    const MeshData& mesh = result.scene.meshes[m];
    const std::string skinName = "skin " + std::to_string(skinIndex) + " '" + skin.name + "'";
    const auto [gltfMesh, primitive] = meshOrigin[m];
    const std::string where = "mesh " + std::to_string(gltfMesh) + " '" + model.meshes[size_t(gltfMesh)].name +
                              "' primitive " + std::to_string(primitive);
    const size_t jointCount = skin.joints.size();
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
      float sum = 0.0f;
      for (int set = 0; set < (mesh.joints1.empty() ? 1 : 2); ++set) {
        const glm::u16vec4 j = set ? mesh.joints1[v] : mesh.joints0[v];
        const glm::vec4 w = set ? mesh.weights1[v] : mesh.weights0[v];
        for (int k = 0; k < 4; ++k)
          if (j[k] >= jointCount)
            return fail(skinName + ": " + where + ", vertex " + std::to_string(v) + ": JOINTS_" + std::to_string(set) +
                        " index " + std::to_string(j[k]) + " is out of range (the skin has " +
                        std::to_string(jointCount) + " joints)");
        sum += w.x + w.y + w.z + w.w;
      }
      if (!(sum > 1e-6f))
        return fail(where + ", vertex " + std::to_string(v) + " (" + skinName + "): its WEIGHTS_0" +
                    (mesh.weights1.empty() ? "" : " and WEIGHTS_1") + " sum to " + std::to_string(sum) +
                    "; skin weights must sum to 1");
    }
  }

  const std::vector<uint32_t>& meshesFor(int meshIndex) {
    auto it = meshPrimitives.find(meshIndex);
    if (it != meshPrimitives.end()) return it->second;
    std::vector<uint32_t>& list = meshPrimitives[meshIndex];
    const tinygltf::Mesh& mesh = model.meshes[meshIndex];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      MeshData data;
      if (!convertPrimitive(mesh, p, data)) continue;
      result.scene.meshes.push_back(std::move(data));
      meshOrigin.push_back({meshIndex, int(p)});
      list.push_back(uint32_t(result.scene.meshes.size() - 1));
    }
    return list;
  }

  // KHR_lights_punctual: tinygltf parses the root `lights` (applying the spec's defaults); the raw extension
  // value tells a given range (which must be > 0) from an absent one (unlimited).
  void convertLights() {
    const tinygltf::Value* rawLights = nullptr;
    if (auto it = model.extensions.find("KHR_lights_punctual"); it != model.extensions.end() && it->second.IsObject())
      if (it->second.Has("lights") && it->second.Get("lights").IsArray()) rawLights = &it->second.Get("lights");
    if (model.lights.size() > kMaxPunctualLights)
      return fail("KHR_lights_punctual: " + std::to_string(model.lights.size()) +
                  " lights, more than the engine's kMaxPunctualLights = " + std::to_string(kMaxPunctualLights));
    for (size_t i = 0; i < model.lights.size(); ++i) {
      const tinygltf::Light& in = model.lights[i];
      const std::string where = "KHR_lights_punctual light " + std::to_string(i) + " '" + in.name + "'";
      PunctualLight out;
      out.name = in.name;
      if (in.type == "directional") out.type = PunctualLight::Type::Directional;
      else if (in.type == "point")
        out.type = PunctualLight::Type::Point;
      else if (in.type == "spot")
        out.type = PunctualLight::Type::Spot;
      else
        return fail(where + ": type = '" + in.type + "': unknown (directional, point or spot)");
      if (!in.color.empty()) {
        if (in.color.size() != 3)
          return fail(where + ": color has " + std::to_string(in.color.size()) +
                      " components; it needs 3 (linear RGB)");
        out.color = glm::vec3(float(in.color[0]), float(in.color[1]), float(in.color[2]));
      }
      out.intensity = float(in.intensity);
      out.range = float(in.range);
      const bool rangeGiven = rawLights && i < rawLights->ArrayLen() && rawLights->Get(int(i)).IsObject() &&
                              rawLights->Get(int(i)).Has("range");
      if (rangeGiven && !(in.range > 0.0))
        return fail(where + ": range = " + std::to_string(in.range) +
                    ": it must be > 0 when given (absent = unlimited)");
      out.innerConeAngle = float(in.spot.innerConeAngle);
      out.outerConeAngle = float(in.spot.outerConeAngle);
      if (Status s = checkLight(out, i); !s) return fail("KHR_lights_punctual " + s.error);
      lights.push_back(std::move(out));
    }
  }

  // The light a node places (its KHR_lights_punctual.light), or -1.
  int nodeLight(const tinygltf::Node& node, const std::string& name) {
    auto it = node.extensions.find("KHR_lights_punctual");
    if (it == node.extensions.end()) return -1;
    if (!it->second.IsObject() || !it->second.Has("light") || !it->second.Get("light").IsInt()) {
      fail(name + ": extensions.KHR_lights_punctual.light must be an integer light index");
      return -1;
    }
    const int light = it->second.Get("light").GetNumberAsInt();
    if (light < 0 || size_t(light) >= lights.size()) {
      fail(name + ": KHR_lights_punctual light " + std::to_string(light) + " is out of range (the file has " +
           std::to_string(lights.size()) + " lights)");
      return -1;
    }
    return light;
  }

  void visit(int nodeIndex, const glm::mat4& parent, int depth) {
    if (!error.empty()) return;
    if (nodeIndex < 0 || nodeIndex >= int(model.nodes.size()))
      return fail("scene node " + std::to_string(nodeIndex) + " is out of range (the file has " +
                  std::to_string(model.nodes.size()) + " nodes)");
    if (depth >= kMaxGltfNodeDepth)  // visit() recurses: the limit keeps it off the end of the stack
      return fail(
          "node " + std::to_string(nodeIndex) + " is " + std::to_string(depth + 1) +
          " levels deep, deeper than the loader's limit kMaxGltfNodeDepth = " + std::to_string(kMaxGltfNodeDepth));
    const tinygltf::Node& node = model.nodes[size_t(nodeIndex)];
    glm::mat4 world = parent * result.scene.nodes[size_t(nodeIndex)].localTransform();
    const std::string name = "node " + std::to_string(nodeIndex) + " '" + node.name + "'";
    if (node.mesh >= int(model.meshes.size()))
      return fail(name + ": mesh " + std::to_string(node.mesh) + " is out of range (the file has " +
                  std::to_string(model.meshes.size()) + " meshes)");
    if (node.skin >= int(model.skins.size()))
      return fail(name + ": skin " + std::to_string(node.skin) + " is out of range (the file has " +
                  std::to_string(model.skins.size()) + " skins)");
    if (node.mesh >= 0) {
      for (uint32_t m : meshesFor(node.mesh)) {
        int skin = -1;
        if (node.skin >= 0 && result.scene.meshes[m].skinned()) {
          checkSkin(node.skin, m);
          skin = node.skin;
        } else if (node.skin >= 0) {
          result.warnings.push_back(name + ": mesh '" + result.scene.meshes[m].name +
                                    "' has a primitive without JOINTS_0/WEIGHTS_0; drawn unskinned");
        }
        result.scene.instances.push_back(Instance{m, world, nodeIndex, skin});
      }
      if (!error.empty()) return;
    }
    if (node.camera >= 0 && node.camera < int(model.cameras.size()) && !result.scene.camera &&
        model.cameras[node.camera].type == "perspective") {
      const auto& p = model.cameras[node.camera].perspective;
      Camera cam;
      cam.eye = glm::vec3(world * glm::vec4(0, 0, 0, 1));
      glm::vec3 forward = glm::normalize(glm::vec3(world * glm::vec4(0, 0, -1, 0)));
      cam.target = cam.eye + forward;
      cam.fovYDegrees = glm::degrees(float(p.yfov));
      cam.zNear = p.znear > 0.0 ? float(p.znear) : 0.05f;
      cam.zFar = p.zfar > p.znear ? float(p.zfar) : cam.zNear * 100000.0f;
      result.scene.camera = cam;
    }
    if (const int light = nodeLight(node, name); light >= 0) {
      if (result.scene.lights.size() >= kMaxPunctualLights)
        return fail(name + ": more than kMaxPunctualLights = " + std::to_string(kMaxPunctualLights) +
                    " placed KHR_lights_punctual lights");
      PunctualLight placed = lights[size_t(light)];
      placed.node = nodeIndex;
      placed.transform = world;
      result.scene.lights.push_back(std::move(placed));
    }
    if (!error.empty()) return;
    for (int child : node.children) visit(child, world, depth + 1);
  }
};

// tinygltf's file callbacks with GltfMemoryDesc::externalFiles applied. tinygltf looks for a URI's file at
// JoinPath(baseDir, uri), then at "./" + uri; only the first is the URI's place under baseDir.
struct ExternalFileGate {
  GltfExternalFiles policy = GltfExternalFiles::Anywhere;
  std::string prefix;   // what tinygltf's JoinPath puts before the URI: "" or baseDir with a trailing '/'
  std::string refused;  // the first URI refused, as it reads after the prefix
};

// Whether `relative` (a URI as a path under the base folder) stays inside it, lexically.
bool staysInside(const std::string& relative) {
  if (relative.empty() || relative.front() == '/' || relative.find('\0') != std::string::npos) return false;
  int depth = 0;
  for (const std::filesystem::path& part : std::filesystem::path(relative)) {
    if (part == "..") {
      if (--depth < 0) return false;
    } else if (part != "." && !part.empty()) {
      ++depth;
    }
  }
  return depth > 0;
}

bool allowedFile(const std::string& path, ExternalFileGate& gate) {
  if (gate.policy == GltfExternalFiles::Anywhere) return true;
  const bool underBase = path.compare(0, gate.prefix.size(), gate.prefix) == 0;
  if (!underBase) return false;  // the working-directory candidate: not the URI's place, not worth a message
  const std::string relative = path.substr(gate.prefix.size());
  if (gate.policy == GltfExternalFiles::InsideBaseDir && staysInside(relative)) return true;
  if (gate.refused.empty()) gate.refused = relative.substr(0, relative.find('\0'));
  return false;
}

bool gatedFileExists(const std::string& path, void* user) {
  std::error_code ec;
  return allowedFile(path, *static_cast<ExternalFileGate*>(user)) && std::filesystem::is_regular_file(path, ec);
}

bool gatedReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  if (!allowedFile(path, *static_cast<ExternalFileGate*>(user))) {
    if (err) *err = "refused";
    return false;
  }
  return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

// Why each image that did not decode failed (tinygltf's own decoder fails the whole file on one bad image; the
// loader drops its textures with a warning instead, as it does for a missing image file).
struct ImageDecodeFailures {
  std::map<int, std::string> reasons;  // image index -> why
};

bool decodeImage(tinygltf::Image* image, const int index, std::string* err, std::string* warn, int width, int height,
                 const unsigned char* bytes, int size, void* user) {
  (void)err;
  std::string why;
  // No option (nullptr): 4 channels, as convertImage expects.
  if (tinygltf::LoadImageData(image, index, &why, warn, width, height, bytes, size, nullptr)) return true;
  if (size_t cut = why.find(" for image["); cut != std::string::npos) why.erase(cut);
  static_cast<ImageDecodeFailures*>(user)->reasons[index] = (image->mimeType.empty() ? std::string()
                                                                                     : image->mimeType + ", ") +
                                                            std::to_string(size) + " bytes: " + shortened(why);
  image->image.clear();
  image->width = image->height = 0;
  return true;
}

// Why image `i` has no texels, for the warning.
std::string imageProblem(const tinygltf::Image& img, int i, const ImageDecodeFailures& failures) {
  std::string name = "image " + std::to_string(i) + " '" + img.name + "'";
  if (auto it = failures.reasons.find(i); it != failures.reasons.end())
    return name + " cannot be decoded (" + it->second + ")";
  if (img.uri.rfind("data:", 0) == 0)
    return name + ": its data: URI of type '" + shortened(img.uri.substr(5, img.uri.find(',') - 5), 40) +
           "' is not one the loader reads (base64 PNG, JPEG, BMP or GIF)";
  if (!img.uri.empty()) return name + ": its file '" + shortened(img.uri, 80) + "' is missing, empty or unreadable";
  return name + " has no pixels";
}

// Everything after parsing: the model into result.scene (or result.error, which names `path`).
void convertModel(const tinygltf::Model& model, const std::string& path, const ImageDecodeFailures& imageFailures,
                  SceneLoadResult& result) {
  for (const std::string& required : model.extensionsRequired)
    if (std::find(std::begin(kSupportedExtensions), std::end(kSupportedExtensions), required) ==
        std::end(kSupportedExtensions)) {
      result.error = "glTF '" + path + "' requires extension " + required +
                     (required == "KHR_draco_mesh_compression" ? " (Draco-compressed meshes are unsupported)" : "") +
                     ", which the sample engine does not support (it supports KHR_mesh_quantization, "
                     "KHR_texture_transform, KHR_materials_emissive_strength and KHR_lights_punctual)";
      return;
    }
  Loader loader{model, result, {}, {}, {}, {}, {}, {}};
  if (std::string e = detail::convertNodes(model, result.scene); !e.empty()) loader.fail(e);
  if (std::string e = detail::convertSkins(model, result.scene); !e.empty()) loader.fail(e);
  if (std::string e = detail::convertAnimations(model, result.scene, result.warnings); !e.empty()) loader.fail(e);
  if (!loader.error.empty()) {
    result.error = "glTF '" + path + "': " + loader.error;
    return;
  }
  loader.convertLights();
  if (!loader.error.empty()) {
    result.error = "glTF '" + path + "': " + loader.error;
    return;
  }
  for (size_t i = 0; i < model.images.size(); ++i) {
    result.scene.textures.push_back(convertImage(model.images[i]));
    if (result.scene.textures.back().rgba8.empty())
      result.warnings.push_back(imageProblem(model.images[i], int(i), imageFailures) +
                                "; the textures that use it are ignored");
  }
  loader.convertMaterials();
  // Textures that failed to decode must not be referenced.
  for (Material& m : result.scene.materials)
    for (int* t :
         {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture, &m.emissiveTexture, &m.occlusionTexture})
      if (*t >= 0 && result.scene.textures[*t].rgba8.empty()) *t = -1;

  // glTF: the file's "scene", else scene 0 (an application choice the spec allows), else every root node.
  std::vector<int> roots;
  if (model.defaultScene >= int(model.scenes.size())) {
    result.error = "glTF '" + path + "': the default scene " + std::to_string(model.defaultScene) +
                   " is out of range (the file has " + std::to_string(model.scenes.size()) + " scenes)";
    return;
  }
  const int sceneIndex = model.defaultScene >= 0 ? model.defaultScene : (model.scenes.empty() ? -1 : 0);
  if (sceneIndex >= 0) {
    roots = model.scenes[sceneIndex].nodes;
    // A root with a parent would be instanced twice (glTF: scene nodes are roots).
    for (int r : roots)
      if (r >= 0 && r < int(result.scene.nodes.size()) && result.scene.nodes[size_t(r)].parent >= 0) {
        result.error = "glTF '" + path + "': scene " + std::to_string(sceneIndex) + " lists node " + std::to_string(r) +
                       " '" + model.nodes[size_t(r)].name + "' as a root, but it is a child of node " +
                       std::to_string(result.scene.nodes[size_t(r)].parent);
        return;
      }
  } else {  // no scene declared: every node that is nobody's child is a root
    std::vector<bool> isChild(model.nodes.size(), false);
    for (const auto& n : model.nodes)
      for (int c : n.children)
        if (c >= 0 && c < int(isChild.size())) isChild[c] = true;
    for (size_t i = 0; i < model.nodes.size(); ++i)
      if (!isChild[i]) roots.push_back(int(i));
  }
  for (int r : roots) loader.visit(r, glm::mat4(1.0f), 0);
  if (!loader.error.empty()) {
    result.error = "glTF '" + path + "': " + loader.error;
    return;
  }
  // Primitives without a material use a default one appended at the end.
  bool needsDefault = false;
  for (const MeshData& m : result.scene.meshes) needsDefault |= m.material >= result.scene.materials.size();
  if (needsDefault) {
    uint32_t index = uint32_t(result.scene.materials.size());
    result.scene.materials.push_back(Material{.name = "gltf default"});
    for (MeshData& m : result.scene.meshes)
      if (m.material > index) m.material = index;
  }
  if (result.scene.instances.empty()) {
    result.error = "glTF '" + path + "' contains no renderable triangles";
    for (size_t w = 0; w < result.warnings.size() && w < 3; ++w) result.error += (w ? "; " : " (") + result.warnings[w];
    if (!result.warnings.empty()) result.error += result.warnings.size() > 3 ? "; ...)" : ")";
  }
  // Whatever the checks above did not name in glTF terms (e.g. a cycle among unvisited nodes).
  else if (Status s = ScenePose().reset(result.scene); !s)
    result.error = "glTF '" + path + "': " + s.error;
}

}  // namespace

SceneLoadResult loadGltfFromMemory(const GltfMemoryDesc& desc) {
  SceneLoadResult result;
  const std::string name = desc.name.empty() ? std::string("memory") : desc.name;
  try {
    if (desc.bytes.empty()) {
      result.error = "glTF '" + name + "' is empty";
      return result;
    }
    if (desc.bytes.size() > UINT32_MAX) {
      result.error = "glTF '" + name + "' has " + std::to_string(desc.bytes.size()) + " bytes; at most 4 GiB load";
      return result;
    }
    // What tinygltf does not check, or checks after reading past the data (gltf_document_check.h). The JSON is
    // parsed twice (here and by tinygltf); the first copy is dropped before the second is made.
    {
      detail::GlbChunks chunks;
      std::span<const uint8_t> text = desc.bytes;
      if (desc.binary) {
        if (std::string e = detail::splitGlb(desc.bytes, chunks); !e.empty()) {
          result.error = "failed to parse glTF '" + name + "': " + e;
          return result;
        }
        text = chunks.json;
      }
      nlohmann::json doc;
      if (std::string e = detail::parseJson(text, doc); !e.empty()) {
        result.error = "failed to parse glTF '" + name + "': " + e;
        return result;
      }
      const std::optional<size_t> bin = chunks.bin ? std::optional<size_t>(chunks.bin->size()) : std::nullopt;
      if (std::string e = detail::checkDocument(doc, desc.binary, bin); !e.empty()) {
        result.error = "glTF '" + name + "': " + e;
        return result;
      }
    }
    ExternalFileGate gate;
    gate.policy = desc.externalFiles;
    gate.prefix = desc.baseDir.empty() || desc.baseDir.back() == '/' ? desc.baseDir : desc.baseDir + "/";
    tinygltf::TinyGLTF gltf;
    gltf.SetFsCallbacks(
        tinygltf::FsCallbacks{gatedFileExists, tinygltf::ExpandFilePath, gatedReadWholeFile, nullptr, &gate});
    ImageDecodeFailures imageFailures;
    gltf.SetImageLoader(decodeImage, &imageFailures);
    tinygltf::Model model;
    std::string err, warn;
    const auto size = static_cast<unsigned int>(desc.bytes.size());
    bool ok = desc.binary
                  ? gltf.LoadBinaryFromMemory(&model, &err, &warn, desc.bytes.data(), size, desc.baseDir)
                  : gltf.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(desc.bytes.data()),
                                             size, desc.baseDir);
    if (!gate.refused.empty()) {
      result.error =
          "glTF '" + name + "': the URI '" + shortened(gate.refused, 80) + "' names " +
          (desc.externalFiles == GltfExternalFiles::None
               ? std::string("an external file, which GltfExternalFiles::None refuses (embed it as a data: URI)")
               : "a file outside the base folder '" + desc.baseDir +
                     "', which GltfExternalFiles::InsideBaseDir refuses");
      return result;
    }
    if (!warn.empty()) result.warnings.push_back(shortened(warn));
    if (!ok) {
      result.error = "failed to parse glTF '" + name + "': " + (err.empty() ? "unknown error" : shortened(err));
      return result;
    }
    convertModel(model, name, imageFailures, result);
  } catch (const std::exception& e) {
    result.error = std::string("glTF loading failed: ") + e.what();
  }
  return result;
}

SceneLoadResult loadGltf(const std::string& path) {
  SceneLoadResult result;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    result.error = "glTF file not found: " + path;
    return result;
  }
  std::ifstream file(path, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (!file && !file.eof()) {
    result.error = "glTF file cannot be read: " + path;
    return result;
  }
  const std::string ext = std::filesystem::path(path).extension().string();
  GltfMemoryDesc desc;
  desc.bytes = bytes;
  desc.binary = ext == ".glb" || ext == ".GLB";
  desc.baseDir = std::filesystem::path(path).parent_path().string();
  desc.name = path;
  return loadGltfFromMemory(desc);
}

}  // namespace sample_engine

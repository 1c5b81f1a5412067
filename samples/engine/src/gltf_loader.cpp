// glTF 2.0 loader on top of tinygltf: flattens the node hierarchy into Scene instances, converts each
// triangle primitive into a MeshData and each image into an RGBA8 TextureData.
#include <cstring>
#include <filesystem>
#include <map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>

#include "sample_engine/gltf_loader.h"

namespace sample_engine {
namespace {

// Reads accessor element `i`, component `c` as float, honouring normalized integer types.
float readComponent(const uint8_t* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0f : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      float v = static_cast<int8_t>(p[0]);
      return normalized ? std::max(v / 127.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0f : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0f, -1.0f) : v;
    }
    default: return 0.0f;
  }
}

// Returns the accessor as `components` floats per element, or an error message.
std::string readFloats(const tinygltf::Model& model, int accessorIndex, int components, std::vector<float>& out) {
  if (accessorIndex < 0 || accessorIndex >= int(model.accessors.size())) return "accessor index out of range";
  const tinygltf::Accessor& acc = model.accessors[accessorIndex];
  if (acc.sparse.isSparse) return "sparse accessors are not supported";
  int have = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (have < components) return "accessor has " + std::to_string(have) + " components, need " + std::to_string(components);
  out.assign(acc.count * components, 0.0f);
  if (acc.bufferView < 0) return {};  // all zeros per spec
  const tinygltf::BufferView& view = model.bufferViews.at(acc.bufferView);
  const tinygltf::Buffer& buffer = model.buffers.at(view.buffer);
  int compSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (compSize <= 0) return "bad component type";
  size_t stride = view.byteStride ? view.byteStride : size_t(compSize) * have;
  size_t base = view.byteOffset + acc.byteOffset;
  if (acc.count > 0 && base + stride * (acc.count - 1) + size_t(compSize) * have > buffer.data.size())
    return "accessor reads past the end of its buffer";
  for (size_t i = 0; i < acc.count; ++i)
    for (int c = 0; c < components; ++c)
      out[i * components + c] =
          readComponent(&buffer.data[base + i * stride + size_t(c) * compSize], acc.componentType, acc.normalized);
  return {};
}

std::string readIndices(const tinygltf::Model& model, int accessorIndex, std::vector<uint32_t>& out) {
  if (accessorIndex < 0 || accessorIndex >= int(model.accessors.size())) return "index accessor out of range";
  const tinygltf::Accessor& acc = model.accessors[accessorIndex];
  if (acc.bufferView < 0) return "index accessor has no buffer view";
  const tinygltf::BufferView& view = model.bufferViews.at(acc.bufferView);
  const tinygltf::Buffer& buffer = model.buffers.at(view.buffer);
  int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (size != 1 && size != 2 && size != 4) return "unsupported index component type";
  size_t stride = view.byteStride ? view.byteStride : size_t(size);
  size_t base = view.byteOffset + acc.byteOffset;
  if (acc.count > 0 && base + stride * (acc.count - 1) + size > buffer.data.size())
    return "index accessor reads past the end of its buffer";
  out.resize(acc.count);
  for (size_t i = 0; i < acc.count; ++i) {
    const uint8_t* p = &buffer.data[base + i * stride];
    if (size == 1) out[i] = p[0];
    else if (size == 2) {
      uint16_t v;
      std::memcpy(&v, p, 2);
      out[i] = v;
    } else std::memcpy(&out[i], p, 4);
  }
  return {};
}

glm::mat4 localTransform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    glm::mat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = static_cast<float>(node.matrix[i]);  // column-major
    return m;
  }
  glm::mat4 m(1.0f);
  if (node.translation.size() == 3)
    m = glm::translate(m, glm::vec3(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)  // glTF stores x, y, z, w; glm::quat takes w first
    m *= glm::mat4_cast(glm::quat(float(node.rotation[3]), float(node.rotation[0]), float(node.rotation[1]),
                                  float(node.rotation[2])));
  if (node.scale.size() == 3) m = glm::scale(m, glm::vec3(node.scale[0], node.scale[1], node.scale[2]));
  return m;
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
      out.normalScale = float(m.normalTexture.scale);
      if (m.alphaMode == "BLEND" || m.alphaMode == "MASK")
        result.warnings.push_back("material '" + m.name + "': alphaMode " + m.alphaMode + " rendered as opaque");
      result.scene.materials.push_back(out);
    }
  }

  // Converts one primitive; returns false (with a warning) when it is skipped.
  bool convertPrimitive(const tinygltf::Mesh& mesh, size_t index, MeshData& out) {
    const tinygltf::Primitive& prim = mesh.primitives[index];
    const std::string where = "mesh '" + mesh.name + "' primitive " + std::to_string(index);
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
      result.warnings.push_back(where + ": skipped, mode " + std::to_string(prim.mode) +
                                " is not TRIANGLES (points/lines/strips/fans are unsupported)");
      return false;
    }
    auto pos = prim.attributes.find("POSITION");
    if (pos == prim.attributes.end()) {
      result.warnings.push_back(where + ": skipped, no POSITION attribute");
      return false;
    }
    std::vector<float> f;
    if (std::string e = readFloats(model, pos->second, 3, f); !e.empty()) {
      result.warnings.push_back(where + ": skipped, POSITION: " + e);
      return false;
    }
    out.name = mesh.name.empty() ? "mesh" : mesh.name;
    out.positions.resize(f.size() / 3);
    std::memcpy(out.positions.data(), f.data(), f.size() * sizeof(float));
    auto optional = [&](const char* name, int comps, auto& dst) {
      auto it = prim.attributes.find(name);
      if (it == prim.attributes.end()) return;
      if (std::string e = readFloats(model, it->second, comps, f); !e.empty()) {
        result.warnings.push_back(where + ": ignoring " + name + ": " + e);
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
    optional("TANGENT", 4, out.tangents);
    if (prim.indices >= 0) {
      if (std::string e = readIndices(model, prim.indices, out.indices); !e.empty()) {
        result.warnings.push_back(where + ": skipped, indices: " + e);
        return false;
      }
      for (uint32_t i : out.indices)
        if (i >= out.positions.size()) {
          result.warnings.push_back(where + ": skipped, index out of range");
          return false;
        }
    }
    out.material = prim.material >= 0 ? uint32_t(prim.material) : uint32_t(result.scene.materials.size());
    if (out.triangleCount() == 0) {
      result.warnings.push_back(where + ": skipped, no triangles");
      return false;
    }
    return true;
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
      list.push_back(uint32_t(result.scene.meshes.size() - 1));
    }
    return list;
  }

  void visit(int nodeIndex, const glm::mat4& parent, int depth) {
    if (nodeIndex < 0 || nodeIndex >= int(model.nodes.size()) || depth > 256) return;  // bad index or cycle
    const tinygltf::Node& node = model.nodes[nodeIndex];
    glm::mat4 world = parent * localTransform(node);
    if (node.mesh >= 0 && node.mesh < int(model.meshes.size())) {
      if (node.skin >= 0) result.warnings.push_back("node '" + node.name + "': skinning ignored (bind pose)");
      for (uint32_t m : meshesFor(node.mesh)) result.scene.instances.push_back(Instance{m, world});
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
    for (int child : node.children) visit(child, world, depth + 1);
  }
};

}  // namespace

SceneLoadResult loadGltf(const std::string& path) {
  SceneLoadResult result;
  try {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      result.error = "glTF file not found: " + path;
      return result;
    }
    tinygltf::TinyGLTF gltf;
    tinygltf::Model model;
    std::string err, warn;
    const std::string ext = std::filesystem::path(path).extension().string();
    bool binary = ext == ".glb" || ext == ".GLB";
    bool ok = binary ? gltf.LoadBinaryFromFile(&model, &err, &warn, path)
                     : gltf.LoadASCIIFromFile(&model, &err, &warn, path);
    if (!warn.empty()) result.warnings.push_back(warn);
    if (!ok) {
      result.error = "failed to parse glTF '" + path + "': " + (err.empty() ? "unknown error" : err);
      return result;
    }
    Loader loader{model, result, {}};
    for (const tinygltf::Image& img : model.images) {
      result.scene.textures.push_back(convertImage(img));
      if (result.scene.textures.back().rgba8.empty())
        result.warnings.push_back("image '" + img.uri + "' could not be decoded; texture ignored");
    }
    loader.convertMaterials();
    // Textures that failed to decode must not be referenced.
    for (Material& m : result.scene.materials)
      for (int* t : {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture, &m.emissiveTexture})
        if (*t >= 0 && result.scene.textures[*t].rgba8.empty()) *t = -1;

    std::vector<int> roots;
    int sceneIndex = model.defaultScene >= 0 ? model.defaultScene : (model.scenes.empty() ? -1 : 0);
    if (sceneIndex >= 0 && sceneIndex < int(model.scenes.size())) {
      roots = model.scenes[sceneIndex].nodes;
    } else {  // no scene declared: every node that is nobody's child is a root
      std::vector<bool> isChild(model.nodes.size(), false);
      for (const auto& n : model.nodes)
        for (int c : n.children)
          if (c >= 0 && c < int(isChild.size())) isChild[c] = true;
      for (size_t i = 0; i < model.nodes.size(); ++i)
        if (!isChild[i]) roots.push_back(int(i));
    }
    for (int r : roots) loader.visit(r, glm::mat4(1.0f), 0);
    // Primitives without a material use a default one appended at the end.
    bool needsDefault = false;
    for (const MeshData& m : result.scene.meshes) needsDefault |= m.material >= result.scene.materials.size();
    if (needsDefault) {
      uint32_t index = uint32_t(result.scene.materials.size());
      result.scene.materials.push_back(Material{.name = "gltf default"});
      for (MeshData& m : result.scene.meshes)
        if (m.material > index) m.material = index;
    }
    if (result.scene.instances.empty()) result.error = "glTF '" + path + "' contains no renderable triangles";
  } catch (const std::exception& e) {
    result.error = std::string("glTF loading failed: ") + e.what();
  }
  return result;
}

}  // namespace sample_engine

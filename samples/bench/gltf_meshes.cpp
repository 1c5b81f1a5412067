#include "gltf_meshes.h"

#include <algorithm>
#include <filesystem>

#if RAYBRIDGE_BENCH_GLTF
#include <tiny_gltf.h>
#endif

namespace rbbench {

uint64_t GltfModel::uniqueTriangles() const {
  uint64_t n = 0;
  for (const auto& m : meshes) n += m.triangleCount();
  return n;
}

#if RAYBRIDGE_BENCH_GLTF
namespace {

using Mat4 = std::array<double, 16>;  // column-major, as glTF stores it

Mat4 identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr)
      for (int k = 0; k < 4; ++k) r[c * 4 + rr] += a[k * 4 + rr] * b[c * 4 + k];
  return r;
}

Mat4 localMatrix(const tinygltf::Node& n) {
  if (n.matrix.size() == 16) {
    Mat4 m;
    std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
    return m;
  }
  Mat4 t = identity(), r = identity(), s = identity();
  if (n.translation.size() == 3) {
    t[12] = n.translation[0];
    t[13] = n.translation[1];
    t[14] = n.translation[2];
  }
  if (n.rotation.size() == 4) {
    double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
    r = {1 - 2 * (y * y + z * z),
         2 * (x * y + z * w),
         2 * (x * z - y * w),
         0,
         2 * (x * y - z * w),
         1 - 2 * (x * x + z * z),
         2 * (y * z + x * w),
         0,
         2 * (x * z + y * w),
         2 * (y * z - x * w),
         1 - 2 * (x * x + y * y),
         0,
         0,
         0,
         0,
         1};
  }
  if (n.scale.size() == 3) {
    s[0] = n.scale[0];
    s[5] = n.scale[1];
    s[10] = n.scale[2];
  }
  return mul(t, mul(r, s));
}

// Address of accessor element `i` (honours the buffer view's byte stride).
const unsigned char* elementPtr(const tinygltf::Model& m, const tinygltf::Accessor& a, size_t i) {
  const tinygltf::BufferView& v = m.bufferViews[a.bufferView];
  size_t stride = a.ByteStride(v);
  return m.buffers[v.buffer].data.data() + v.byteOffset + a.byteOffset + i * stride;
}

bool appendPrimitive(const tinygltf::Model& m, const tinygltf::Primitive& p, rbsamples::CpuMesh& out) {
  if (p.mode != -1 && p.mode != TINYGLTF_MODE_TRIANGLES) return false;
  auto pos = p.attributes.find("POSITION");
  if (pos == p.attributes.end()) return false;
  const tinygltf::Accessor& pa = m.accessors[pos->second];
  if (pa.bufferView < 0 || pa.sparse.isSparse) return false;
  if (pa.type != TINYGLTF_TYPE_VEC3 || pa.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) return false;
  const tinygltf::Accessor* ia = p.indices >= 0 ? &m.accessors[p.indices] : nullptr;
  if (ia && ia->bufferView < 0) return false;
  const uint32_t base = out.vertexCount();
  for (size_t i = 0; i < pa.count; ++i) {
    const float* f = reinterpret_cast<const float*>(elementPtr(m, pa, i));
    out.positions.insert(out.positions.end(), {f[0], f[1], f[2]});
  }
  // Non-indexed primitives: every three consecutive vertices form a triangle.
  const size_t triIndices = (ia ? ia->count : pa.count) / 3 * 3;
  for (size_t i = 0; i < triIndices; ++i) {
    uint32_t v = static_cast<uint32_t>(i);
    if (ia) {
      const unsigned char* e = elementPtr(m, *ia, i);
      switch (ia->componentType) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = *e; break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: v = *reinterpret_cast<const uint16_t*>(e); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: v = *reinterpret_cast<const uint32_t*>(e); break;
        default: return false;
      }
    }
    if (v >= pa.count) return false;
    out.indices.push_back(base + v);
  }
  return true;
}

bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;  // textures are irrelevant to acceleration structures
}

bool loadOne(const std::filesystem::path& file, GltfModel& out, std::string& error) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skipImage, nullptr);
  tinygltf::Model m;
  std::string err, warn;
  bool ok = file.extension() == ".glb" ? loader.LoadBinaryFromFile(&m, &err, &warn, file.string())
                                       : loader.LoadASCIIFromFile(&m, &err, &warn, file.string());
  if (!ok) {
    error = err.empty() ? "tinygltf could not load it" : err;
    return false;
  }
  std::vector<int> meshIndex(m.meshes.size(), -1);
  for (size_t i = 0; i < m.meshes.size(); ++i) {
    rbsamples::CpuMesh cpu;
    for (const auto& p : m.meshes[i].primitives) appendPrimitive(m, p, cpu);
    if (cpu.triangleCount() == 0) continue;
    meshIndex[i] = static_cast<int>(out.meshes.size());
    out.meshes.push_back(std::move(cpu));
  }
  auto visit = [&](auto&& self, int node, const Mat4& parent) -> void {
    const tinygltf::Node& n = m.nodes[node];
    Mat4 world = mul(parent, localMatrix(n));
    if (n.mesh >= 0 && meshIndex[n.mesh] >= 0) {
      Transform t;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) t[4 * r + c] = static_cast<float>(world[c * 4 + r]);
      out.instances.push_back({static_cast<uint32_t>(meshIndex[n.mesh]), t});
    }
    for (int child : n.children) self(self, child, world);
  };
  int scene = m.defaultScene >= 0 ? m.defaultScene : 0;
  if (scene < int(m.scenes.size())) {
    for (int root : m.scenes[scene].nodes) visit(visit, root, identity());
  }
  if (out.meshes.empty() || out.instances.empty()) {
    error = "no triangle mesh with float POSITION in its default scene";
    return false;
  }
  return true;
}

}  // namespace

std::vector<GltfModel> loadGltfModels(const std::string& dir, std::vector<std::string>& messages) {
  namespace fs = std::filesystem;
  std::vector<GltfModel> models;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    messages.push_back("glTF scenes: '" + dir + "' does not exist; glTF rows skipped");
    return models;
  }
  std::vector<fs::path> folders;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.is_directory()) folders.push_back(e.path());
  }
  std::sort(folders.begin(), folders.end());
  for (const fs::path& folder : folders) {
    fs::path file;
    for (const auto& e : fs::directory_iterator(folder, ec)) {
      auto ext = e.path().extension();
      if ((ext == ".gltf" || ext == ".glb") && (file.empty() || e.path() < file)) file = e.path();
    }
    if (file.empty()) continue;
    GltfModel model;
    model.name = folder.filename().string();
    std::string error;
    if (loadOne(file, model, error)) {
      models.push_back(std::move(model));
    } else {
      messages.push_back("glTF scenes: skipped " + file.string() + ": " + error);
    }
  }
  return models;
}
#else
std::vector<GltfModel> loadGltfModels(const std::string&, std::vector<std::string>& messages) {
  messages.push_back("glTF scenes: built without TinyGLTF; glTF rows skipped");
  return {};
}
#endif

}  // namespace rbbench

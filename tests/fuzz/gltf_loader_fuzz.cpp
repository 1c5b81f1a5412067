// libFuzzer target: the sample engine's glTF loader (loadGltfFromMemory) on whole .gltf (JSON) and .glb files,
// then what the engine does with a loaded scene on the CPU when it uploads it: finalizeScene(), then posing it
// (ScenePose at a few times).
//
// Input: the file's bytes. Bytes that start with the GLB magic "glTF" load as .glb, anything else as .gltf, so a
// mutation of the first bytes moves an input between the two paths.
// External URIs: confined to $RAYBRIDGE_FUZZ_GLTF_FILES (GltfExternalFiles::InsideBaseDir; scripts/fuzz.sh points
// it at a temporary copy of the shared scenes' buffers); without it every external URI is refused
// (GltfExternalFiles::None), so no input can make the fuzzer read a file of its choosing.
//
// A loaded scene must keep the loader's contract with the engine (checked below); a breach aborts, as a crash
// would, because the engine indexes its arrays without checking them again.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "sample_engine/animation.h"
#include "sample_engine/gltf_loader.h"

namespace {

using namespace sample_engine;

std::string gFilesDir;

[[noreturn]] void breach(const std::string& what) {
  std::fprintf(stderr, "gltf_loader_fuzz: a loaded scene breaks the loader's contract: %s\n", what.c_str());
  std::abort();
}

template <typename Array>
void perVertex(const Array& array, size_t vertices, const std::string& what) {
  if (!array.empty() && array.size() != vertices)
    breach(what + " has " + std::to_string(array.size()) + " entries for " + std::to_string(vertices) + " vertices");
}

void checkContract(const Scene& scene) {
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const MeshData& mesh = scene.meshes[m];
    const std::string name = "mesh " + std::to_string(m);
    const size_t n = mesh.positions.size();
    if (mesh.triangleCount() == 0) breach(name + " has no triangle");
    for (uint32_t i : mesh.indices)
      if (i >= n) breach(name + ": index " + std::to_string(i) + " >= " + std::to_string(n) + " vertices");
    perVertex(mesh.normals, n, name + " normals");
    perVertex(mesh.uvs, n, name + " uvs");
    perVertex(mesh.uvs1, n, name + " uvs1");
    perVertex(mesh.tangents, n, name + " tangents");
    perVertex(mesh.joints0, n, name + " joints0");
    perVertex(mesh.weights0, n, name + " weights0");
    perVertex(mesh.joints1, n, name + " joints1");
    perVertex(mesh.weights1, n, name + " weights1");
    if (mesh.joints0.size() != mesh.weights0.size() || mesh.joints1.size() != mesh.weights1.size())
      breach(name + ": joints and weights differ in count");
    if (!mesh.joints1.empty() && mesh.joints0.empty()) breach(name + ": JOINTS_1 without JOINTS_0");
    for (const MorphTarget& t : mesh.morphTargets) {
      perVertex(t.positionDeltas, n, name + " morph position deltas");
      perVertex(t.normalDeltas, n, name + " morph normal deltas");
    }
    if (mesh.material >= scene.materials.size()) breach(name + ": material out of range");
  }
  for (const Material& mat : scene.materials)
    for (int t : {mat.baseColorTexture, mat.metallicRoughnessTexture, mat.normalTexture, mat.emissiveTexture,
                  mat.occlusionTexture})
      if (t >= int(scene.textures.size()) || (t >= 0 && scene.textures[size_t(t)].rgba8.empty()))
        breach("material '" + mat.name + "' refers to texture " + std::to_string(t) + ", which has no texels");
  for (const TextureData& tex : scene.textures)
    if (tex.rgba8.size() != size_t(tex.width) * tex.height * 4) breach("texture '" + tex.name + "' size");
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    if (inst.mesh >= scene.meshes.size()) breach("instance " + std::to_string(i) + ": mesh out of range");
    if (inst.node >= int(scene.nodes.size())) breach("instance " + std::to_string(i) + ": node out of range");
    if (inst.skin >= int(scene.skins.size())) breach("instance " + std::to_string(i) + ": skin out of range");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("RAYBRIDGE_FUZZ_GLTF_FILES"); dir && *dir) gFilesDir = dir;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  GltfMemoryDesc desc;
  desc.bytes = {data, size};
  desc.binary = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  desc.baseDir = gFilesDir;
  desc.externalFiles = gFilesDir.empty() ? GltfExternalFiles::None : GltfExternalFiles::InsideBaseDir;
  desc.name = desc.binary ? "fuzz.glb" : "fuzz.gltf";
  SceneLoadResult loaded = loadGltfFromMemory(desc);
  if (!loaded.ok()) {
    if (loaded.error.empty()) breach("an error without a message");
    return 0;
  }
  Scene& scene = loaded.scene;
  checkContract(scene);

  // What the engine's upload does: finalize its copy (a trailing partial triangle goes, missing attributes are
  // derived), then pose it every frame.
  finalizeScene(scene);
  checkContract(scene);
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const MeshData& mesh = scene.meshes[m];
    const size_t n = mesh.positions.size();
    if ((mesh.indices.empty() ? n : mesh.indices.size()) % 3 != 0)
      breach("mesh " + std::to_string(m) + ": finalized corner count is not a multiple of 3");
    if (mesh.normals.size() != n || mesh.uvs.size() != n || mesh.tangents.size() != n)
      breach("mesh " + std::to_string(m) + ": finalized attributes do not cover every vertex");
  }
  ScenePose pose;
  if (Status s = pose.reset(scene); !s) breach("ScenePose::reset fails after a successful load: " + s.error);
  double duration = 0.0;
  for (const Animation& a : scene.animations) duration = std::max(duration, double(a.duration));
  for (double t : {0.0, 0.37, 0.5 * duration, duration, 1e6}) {
    if (!std::isfinite(t)) continue;
    if (Status s = pose.evaluate(scene, t, {}, false); !s)
      breach("ScenePose::evaluate(" + std::to_string(t) + ") fails on a loaded scene: " + s.error);
  }
  return 0;
}

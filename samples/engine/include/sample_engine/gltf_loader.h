// glTF 2.0 (.gltf / .glb) loading into the engine's Scene.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sample_engine/scene.h"

namespace sample_engine {

// The deepest node hierarchy loadGltf() accepts: a scene node deeper than this fails naming it (the loader walks
// the hierarchy recursively).
inline constexpr int kMaxGltfNodeDepth = 1024;

struct SceneLoadResult {
  Scene scene;
  std::string error;                  // empty on success
  std::vector<std::string> warnings;  // e.g. skipped non-triangle primitives, unsupported features

  bool ok() const { return error.empty(); }
};

// Loads the default scene of the file (or scene 0, or every root node when none is declared): the node
// hierarchy is flattened into instances (scene roots in order, depth-first pre-order, a node's primitives in
// order; Instance::node / skin name the glTF node and skin), each glTF primitive becomes one MeshData, the
// first perspective camera found in the hierarchy becomes Scene::camera. Animation data is kept: every glTF
// node (same indices, TRS or matrix, parent), skins (joints, inverse bind matrices), animations (translation,
// rotation, scale and weights channels; LINEAR, STEP, CUBICSPLINE; duration = the largest key time), per
// primitive JOINTS_0/WEIGHTS_0 (+ JOINTS_1/WEIGHTS_1) and morph targets (POSITION / NORMAL deltas, sparse
// accessors included) with the mesh's default weights. KHR_lights_punctual: one Scene::lights entry per node
// that places a light, in the order the hierarchy is visited (as instances), with PunctualLight::node = that
// node (so it follows the node's animation) and transform = its rest-pose world transform; the light's
// fields as the file gives them (absent range = 0 = unlimited; spot cones default to 0 and pi/4). A bad light
// (unknown type, negative colour or intensity, a given range <= 0, inner cone >= outer or outer > pi/2, a
// light index out of range, more than kMaxPunctualLights) fails naming the light index and the field.
//
// Malformed input fails with an error naming the member (as a JSON path such as nodes[2].mesh, or the glTF object:
// "accessor 3", "mesh 'body' primitive 0") and the value, before anything is allocated for it: JSON that does not
// parse (path, line and column; JSON cannot write NaN or infinity, and a literal beyond a double such as 1e999 fails
// here), nesting deeper than 128 levels; a .glb whose magic, version (2), length or chunk lengths do not match its
// bytes; a member of the wrong type, an index that is negative, fractional or out of range, a list of nodes or joints
// that names one twice; a buffer whose data is not byteLength bytes (data: URIs must be base64), a buffer view past
// its buffer, an accessor past its buffer view, with a byteStride shorter than its element or data not aligned to
// its components, an accessor without a buffer view counting more elements than the file's buffers hold bytes;
// an accessor whose type or component type its use does not allow (POSITION VEC3 FLOAT or, with
// KHR_mesh_quantization, 8/16-bit integers; indices SCALAR UNSIGNED_BYTE/SHORT/INT; JOINTS_n VEC4 UNSIGNED_BYTE/SHORT;
// ...), an index value >= the primitive's vertex count, a joint index beyond its skin's joint count, a skinned
// vertex whose weights sum to 0; a non-finite animation key time or value, inverse bind matrix, skin weight or morph
// target delta; a node that is its own ancestor or the child of two nodes, a scene root that has a parent, a scene
// node deeper than kMaxGltfNodeDepth; an extension in extensionsRequired the loader does not support; a primitive
// compressed with KHR_draco_mesh_compression without uncompressed accessors (Draco is unsupported); an image whose
// data: URI holds no bytes.
// Tolerated, with a warning naming what was skipped: a primitive that is not triangles (points, lines) or has no
// POSITION is skipped (a file left without any triangle fails); triangles with a non-finite position or normal are
// skipped; non-finite TEXCOORD_n values become 0 and non-finite tangents (1, 0, 0, 1); a NORMAL, TANGENT or
// TEXCOORD_n whose count differs from POSITION's is ignored; an image that cannot be
// decoded (corrupt, truncated, 0 x 0 pixels, a format stb_image does not read such as KTX2 or WebP, a missing or
// empty file) leaves the materials that use it untextured. Never throws.
SceneLoadResult loadGltf(const std::string& path);

// Which files the URIs of a glTF held in memory may read (buffers, images; data: URIs and a .glb's BIN chunk are
// always fine). The check is lexical, on the path the URI resolves to: a symbolic link inside baseDir is followed.
enum class GltfExternalFiles : uint8_t {
  Anywhere = 0,   // default: relative to baseDir wherever they lead ("../textures/a.png"), as loadGltf() reads
  InsideBaseDir,  // only files inside baseDir: a URI that leaves it (through "..", or absolute) fails naming it
  None,           // no file at all: a URI that names a file fails naming it
};

// A glTF file's contents in memory. A zero-initialised description is valid (and loads nothing: "is empty").
struct GltfMemoryDesc {
  std::span<const uint8_t> bytes;  // the whole file; need not outlive the call
  bool binary = false;             // false = .gltf (JSON), true = .glb (binary container)
  std::string baseDir;             // folder that relative URIs start from; "" = the working directory
  GltfExternalFiles externalFiles = GltfExternalFiles::Anywhere;
  std::string name;  // what messages call the file in place of a path; "" = "memory"
};

// loadGltf() on bytes: the same scene, warnings and errors (which name desc.name), plus a named error for a URI that
// desc.externalFiles refuses. loadGltf() reads the file and calls this with the file's folder as baseDir. Never
// throws.
SceneLoadResult loadGltfFromMemory(const GltfMemoryDesc& desc);

}  // namespace sample_engine

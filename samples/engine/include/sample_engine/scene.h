// The in-memory scene description. Procedural builders and the glTF loader both produce this struct; the
// engine uploads it as-is (one GPU mesh per MeshData, one draw per Instance). Animated scenes add a node
// hierarchy, skins and animations (glTF 2.0 semantics); animation.h evaluates them.
// Plain data: not thread-safe; distinct Scene objects are independent.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "sample_engine/result.h"

namespace sample_engine {

// A morph target (glTF): per-vertex deltas the target adds to the bind pose, scaled by its weight.
struct MorphTarget {
  std::vector<glm::vec3> positionDeltas;  // empty (no position change) or one per vertex
  std::vector<glm::vec3> normalDeltas;    // empty (no normal change) or one per vertex
};

// One triangle list. Arrays other than `positions` may be empty: missing normals are computed flat-ish
// (area-weighted), missing UVs become zero, missing tangents are derived from UVs (see finalizeMesh()).
struct MeshData {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uvs;  // what every texture of the material is sampled with (glTF loader: see Material)
  // A second UV set (glTF TEXCOORD_1), untransformed; CPU only: the GPU vertex layout carries `uvs` alone.
  // Empty or one per vertex.
  std::vector<glm::vec2> uvs1;
  std::vector<glm::vec4> tangents;  // xyz tangent, w = bitangent sign (glTF convention)
  std::vector<uint32_t> indices;    // empty: non-indexed, every 3 consecutive vertices form a triangle
  uint32_t material = 0;            // index into Scene::materials

  // Linear-blend skinning (glTF JOINTS_0/WEIGHTS_0, JOINTS_1/WEIGHTS_1): per vertex, indices into the
  // Skin::joints of the instance that draws the mesh and their weights, which sum to 1. All empty = rigid;
  // joints0/weights0 one per vertex = 4 influences; joints1/weights1 too = 8 influences.
  std::vector<glm::u16vec4> joints0, joints1;
  std::vector<glm::vec4> weights0, weights1;
  // Morph targets (POSITION and NORMAL deltas), blended before skinning. Empty = none.
  std::vector<MorphTarget> morphTargets;
  // Default morph weights (glTF mesh.weights), used when the instance has no node; missing entries are 0.
  std::vector<float> morphWeights;

  bool skinned() const { return !joints0.empty(); }
  bool morphed() const { return !morphTargets.empty(); }
  uint32_t influences() const { return joints0.empty() ? 0u : joints1.empty() ? 4u : 8u; }
  uint32_t triangleCount() const {
    return static_cast<uint32_t>((indices.empty() ? positions.size() : indices.size()) / 3);
  }
};

// 8-bit RGBA texels, rows from the top. Color space is decided by use: base color is sampled as sRGB,
// metallic-roughness and normal maps as linear.
struct TextureData {
  std::string name;
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> rgba8;
};

// How a texture of a glTF material maps its UV set (textureInfo.texCoord and KHR_texture_transform):
// uv' = offset + R(rotation) * (scale * TEXCOORD_<texCoord>), R = [cos sin; -sin cos] (glTF's clockwise
// rotation in UV space).
struct UvMapping {
  uint32_t texCoord = 0;  // 0 = TEXCOORD_0, 1 = TEXCOORD_1
  glm::vec2 offset{0.0f};
  float rotation = 0.0f;  // radians
  glm::vec2 scale{1.0f};

  glm::vec2 apply(const glm::vec2& uv) const;
  bool identity() const { return offset == glm::vec2(0.0f) && rotation == 0.0f && scale == glm::vec2(1.0f); }
  bool operator==(const UvMapping&) const = default;
};

// How a material's coverage is decided (glTF alphaMode). alpha = baseColorFactor.a * the base colour
// texture's alpha, sampled with MeshData::uvs like every other texture.
enum class AlphaMode : uint8_t {
  Opaque,  // covers everything, alpha ignored (glTF OPAQUE)
  Mask,    // cut out where alpha < Material::alphaCutoff (glTF MASK): discarded in every raster pass (pre-pass,
           // lighting, shadow map, reflection-probe capture)
  Blend,   // blended over what is behind with opacity alpha (glTF BLEND): drawn after the opaque lighting,
           // back to front, never into the pre-pass / G-buffer; casts a hashed shadow (see engine.h)
};

// glTF 2.0 metallic-roughness material. Texture indices are into Scene::textures, -1 = none.
// The engine samples every texture with MeshData::uvs; the glTF loader bakes the material's UvMapping into
// them (the base colour texture's when the textures disagree, with a warning). The *Uv fields keep the
// file's mappings for reference; the engine does not apply them again.
struct Material {
  std::string name;
  glm::vec4 baseColorFactor{1.0f};
  float metallicFactor = 0.0f;
  float roughnessFactor = 0.5f;    // perceptual roughness
  glm::vec3 emissiveFactor{0.0f};  // glTF emissiveFactor times KHR_materials_emissive_strength
  float normalScale = 1.0f;
  int baseColorTexture = -1;
  int metallicRoughnessTexture = -1;  // glTF layout: G = roughness, B = metallic
  int normalTexture = -1;
  int emissiveTexture = -1;  // sRGB, multiplied by emissiveFactor
  // Ambient occlusion (glTF occlusionTexture, R channel, linear): the ambient (sky) and environment terms are
  // multiplied by mix(1, R, occlusionStrength), whichever image it is (a packed ORM's metallic-roughness
  // texture or a separate one). Strength is clamped to [0, 1].
  int occlusionTexture = -1;
  float occlusionStrength = 1.0f;
  UvMapping baseColorUv, metallicRoughnessUv, normalUv, emissiveUv, occlusionUv;
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;  // Mask only (glTF's default 0.5)
  // false: back faces (clockwise in the image; a model matrix with a negative determinant flips the winding)
  // are culled in the camera passes: pre-pass, lighting, blend pass, reflection-probe capture. The shadow map
  // draws both sides (a surface seen from behind still blocks the sun). true: both sides are drawn and the
  // shading normal faces the viewer. Default true, so hand-built meshes need not be closed or consistently
  // wound (the procedural ones are counter-clockwise outward); the glTF loader sets the file's value (glTF's
  // default false).
  bool doubleSided = true;
};

// A placement of a mesh in the world.
struct Instance {
  uint32_t mesh = 0;
  // World transform. For an instance with a node: that node's world transform in the rest pose (what
  // Scene::bounds() uses); the engine places it with the node's animated world transform every frame.
  glm::mat4 transform{1.0f};
  int node = -1;  // Scene::nodes index that places the instance (e.g. the glTF node); -1 = `transform`, fixed
  int skin = -1;  // Scene::skins index that deforms the mesh (the mesh must have joints0/weights0); -1 = none
};

// A node of the transform hierarchy (glTF node). Its local transform is `matrix` when set, else T * R * S;
// its world transform is parent's world * local.
struct Node {
  std::string name;
  int parent = -1;  // Scene::nodes index; -1 = a root
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // glm order: w, x, y, z
  glm::vec3 scale{1.0f};
  std::optional<glm::mat4> matrix;  // replaces T * R * S; such a node is not animated (glTF)
  // Morph weights of the meshes this node places (glTF node.weights, else mesh.weights); missing entries are 0.
  std::vector<float> weights;

  glm::mat4 localTransform() const;
};

// A skeleton (glTF skin): the joint nodes and their inverse bind matrices. A skinned vertex at time t is
// sum_k weight_k * jointWorld[joint_k](t) * inverseBindMatrices[joint_k] * bindPosition.
struct Skin {
  std::string name;
  std::vector<uint32_t> joints;                // Scene::nodes indices
  std::vector<glm::mat4> inverseBindMatrices;  // one per joint, or empty = all identity
};

enum class AnimationPath : uint8_t { Translation, Rotation, Scale, Weights };
enum class AnimationInterpolation : uint8_t { Linear, Step, CubicSpline };

// Keyframes of one animated property (glTF animation sampler). LINEAR rotations are slerped (shortest arc),
// CUBICSPLINE ones normalized after the spline; before the first key the first value holds, after the last
// the last.
struct AnimationSampler {
  AnimationInterpolation interpolation = AnimationInterpolation::Linear;
  std::vector<float> times;  // seconds, non-decreasing
  // Per key `width` floats (3 for translation / scale, 4 for rotation as x, y, z, w, the morph target count
  // for weights); CUBICSPLINE keys hold in-tangent, value, out-tangent (3 * width floats).
  std::vector<float> values;
};

struct AnimationChannel {
  uint32_t sampler = 0;  // index into Animation::samplers
  uint32_t node = 0;     // Scene::nodes index whose property it drives
  AnimationPath path = AnimationPath::Translation;
};

struct Animation {
  std::string name;  // may be empty
  std::vector<AnimationSampler> samplers;
  std::vector<AnimationChannel> channels;  // applied in order
  float duration = 0.0f;                   // seconds: the largest key time of its samplers; playback loops over it
};

// Which animation plays, and where in it (FrameParams::animations).
struct AnimationPlayback {
  uint32_t animation = 0;   // index into Scene::animations
  double timeOffset = 0.0;  // seconds added to FrameParams::time (finite; the sum loops over the duration)
};

// Right-handed, up = +Y. fovY in degrees. Pixel (0,0) is the top-left corner of the image.
struct Camera {
  glm::vec3 eye{0.0f, 1.0f, 5.0f};
  glm::vec3 target{0.0f};
  float fovYDegrees = 60.0f;
  float zNear = 0.05f;
  float zFar = 500.0f;
};

// Directional light. `direction` points TOWARDS the sun (from the surface to the light).
struct Sun {
  glm::vec3 direction = glm::normalize(glm::vec3(-0.5f, 0.6f, 0.4f));
  glm::vec3 color{1.0f, 0.96f, 0.9f};
  float intensity = 3.5f;
};

struct Bounds {
  glm::vec3 min{1e30f};
  glm::vec3 max{-1e30f};

  bool valid() const { return min.x <= max.x; }
  glm::vec3 center() const { return (min + max) * 0.5f; }
  float radius() const { return glm::length(max - min) * 0.5f; }
  void extend(const glm::vec3& p) {  // non-finite points are ignored
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
};

// A KHR_lights_punctual light. Units are the spec's: intensity in candela (point, spot) or lux (directional).
// It shines along its node's local -Z (spot, directional) from the node's origin (point, spot).
// Scene::lights holds them; the engine lights every one of them (engine.h, LocalLightSettings).
inline constexpr float kDefaultSpotOuterConeAngle = 0.78539816339f;  // pi / 4, the glTF default
inline constexpr uint32_t kMaxPunctualLights = 4096;                 // per scene; more is a load error
struct PunctualLight {
  enum class Type : uint32_t { Directional = 0, Point, Spot };
  std::string name;
  Type type = Type::Point;
  glm::vec3 color{1.0f};                              // linear RGB, >= 0
  float intensity = 1.0f;                             // finite, >= 0
  float range = 0.0f;                                 // 0 = unlimited (no range window); else > 0
  float innerConeAngle = 0.0f;                        // spot, radians, in [0, outer)
  float outerConeAngle = kDefaultSpotOuterConeAngle;  // spot, radians, in (inner, pi/2]
  int32_t node = -1;          // Scene::nodes index it hangs from (animated with it); -1 = use `transform`
  glm::mat4 transform{1.0f};  // world transform when node < 0 (procedural scenes)
};

struct Scene {
  std::vector<MeshData> meshes;
  std::vector<Material> materials;  // at least one is added by finalizeScene() if empty
  std::vector<TextureData> textures;
  std::vector<Instance> instances;
  std::optional<Camera> camera;  // e.g. the first perspective camera of a glTF file
  std::optional<Sun> sun;
  std::vector<Node> nodes;  // empty for a static scene
  std::vector<Skin> skins;
  std::vector<Animation> animations;
  // KHR_lights_punctual lights (glTF root `lights`, placed by the nodes that reference them) and the ones a
  // procedural builder adds; at most kMaxPunctualLights, each valid for checkLight().
  std::vector<PunctualLight> lights;

  // World-space bounds over all instances (transformed mesh AABBs, rest pose).
  Bounds bounds() const;
  // The animation called `nameOrNumber`, else the one at that decimal index; nullopt when neither exists.
  std::optional<uint32_t> animationIndex(std::string_view nameOrNumber) const;
  std::vector<std::string> animationNames() const;
  // "0 'Survey', 1 'Walk', 2 'Run'" (or "none"), for error messages.
  std::string describeAnimations() const;
};

// Appends src's meshes, materials, textures, nodes, skins, animations, instances and lights to dst, under a new
// root node (named "placement") whose matrix is `placement`; instances and lights without a node get
// placement * transform. Every append is an independent copy (its own nodes, skins and animations, so the engine gives
// its deforming instances their own buffers): this is how a scene holds K animated characters. dst keeps its
// own camera and sun. Returns the index in dst.animations of src's first animation.
uint32_t appendScene(Scene& dst, const Scene& src, const glm::mat4& placement);

// Checks one light against the ranges PunctualLight documents (type known, colour and intensity finite and
// >= 0, range 0 or > 0, spot cones 0 <= inner < outer <= pi/2). The error names the light index and the
// field, e.g. "light 3 'lamp': intensity = -1: it must be finite and >= 0 (candela or lux)". The node index
// is checked by checkLights(), which knows the scene.
Status checkLight(const PunctualLight& light, size_t index);
// Every light of the scene (checkLight(), node in range, at most kMaxPunctualLights). loadScene() and the glTF
// loader call it.
Status checkLights(const Scene& scene);

// Fills missing normals/UVs/tangents, clamps material and texture indices, adds a default material if needed,
// and reads an AlphaMode beyond Blend as Opaque and a non-finite alphaCutoff as 0.5.
// The engine calls this on its own copy during upload; call it yourself to inspect the final arrays.
void finalizeMesh(MeshData& mesh);
void finalizeScene(Scene& scene);

// A camera looking at the scene bounds from a pleasant 3/4 view, fully framing them.
Camera defaultCameraFor(const Bounds& bounds, float fovYDegrees = 50.0f);

// Matrices with the engine's conventions: right-handed view, Vulkan clip space with depth in [0,1]
// (standard, not reversed Z) and Y flipped so that NDC y = -1 is the top row of the image.
glm::mat4 viewMatrix(const Camera& camera);
glm::mat4 projectionMatrix(const Camera& camera, float aspect);

}  // namespace sample_engine

// The in-memory scene description. Procedural builders and the glTF loader both produce this struct; the
// engine uploads it as-is (one GPU mesh per MeshData, one draw per Instance).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace sample_engine {

// One triangle list. Arrays other than `positions` may be empty: missing normals are computed flat-ish
// (area-weighted), missing UVs become zero, missing tangents are derived from UVs (see finalizeMesh()).
struct MeshData {
  std::string name;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;
  std::vector<glm::vec2> uvs;
  std::vector<glm::vec4> tangents;  // xyz tangent, w = bitangent sign (glTF convention)
  std::vector<uint32_t> indices;    // empty: non-indexed, every 3 consecutive vertices form a triangle
  uint32_t material = 0;            // index into Scene::materials

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

// glTF 2.0 metallic-roughness material (opaque only). Texture indices are into Scene::textures, -1 = none.
struct Material {
  std::string name;
  glm::vec4 baseColorFactor{1.0f};
  float metallicFactor = 0.0f;
  float roughnessFactor = 0.5f;  // perceptual roughness
  glm::vec3 emissiveFactor{0.0f};
  float normalScale = 1.0f;
  int baseColorTexture = -1;
  int metallicRoughnessTexture = -1;  // glTF layout: G = roughness, B = metallic
  int normalTexture = -1;
  int emissiveTexture = -1;  // sRGB, multiplied by emissiveFactor
};

// A placement of a mesh in the world.
struct Instance {
  uint32_t mesh = 0;
  glm::mat4 transform{1.0f};
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
  void extend(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
};

struct Scene {
  std::vector<MeshData> meshes;
  std::vector<Material> materials;  // at least one is added by finalizeScene() if empty
  std::vector<TextureData> textures;
  std::vector<Instance> instances;
  std::optional<Camera> camera;     // e.g. the first perspective camera of a glTF file
  std::optional<Sun> sun;

  // World-space bounds over all instances (transformed mesh AABBs).
  Bounds bounds() const;
};

// Fills missing normals/UVs/tangents, clamps material indices and adds a default material if needed.
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

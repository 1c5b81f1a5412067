// Builds the glossy scene (see the header).
#include "glossy_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <string>
#include <utility>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/procedural.h"

namespace rbRender {

namespace se = sample_engine;

namespace {

// splitmix64's finaliser: the same numbers on every platform and standard library (std's distributions are not).
uint64_t mix(uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A number in [0, 1) for item `index` and property `salt`: each property of each object is drawn independently.
float unit(uint32_t index, uint32_t salt) { return float(mix((uint64_t(salt) << 32) | index) >> 40) * 0x1p-24f; }

uint8_t byteOf(float v) { return uint8_t(std::clamp(v, 0.0f, 255.0f) + 0.5f); }

// The floor textures: kFloorTiles^2 tiles of 1 m per repeat, kFloorTexels^2 texels, grout kGroutTexels wide.
constexpr uint32_t kFloorTexels = 256, kFloorTiles = 4, kGroutTexels = 3;
// The floor material's roughness factor; the texture's G (kFloorRoughnessMinByte..Max, grout kGroutRoughnessByte)
// scales it to 0.25-0.47, inside [kGlossyMinRoughness, kGlossyMaxRoughness].
constexpr float kFloorRoughnessFactor = 0.5f;
constexpr uint32_t kFloorRoughnessMinByte = 128, kFloorRoughnessMaxByte = 240, kGroutRoughnessByte = 230;

// Base colour (sRGB) and metallic-roughness (glTF layout: G roughness, B metallic) of polished tiles in a chequer of
// brushed metal and stone, each tile its own tint and roughness, with dark, non-metallic grout between them.
std::pair<se::TextureData, se::TextureData> makeFloorTextures() {
  se::TextureData color{.name = "glossy floor tiles", .width = kFloorTexels, .height = kFloorTexels, .rgba8 = {}};
  se::TextureData mr{.name = "glossy floor roughness", .width = kFloorTexels, .height = kFloorTexels, .rgba8 = {}};
  color.rgba8.resize(size_t(kFloorTexels) * kFloorTexels * 4);
  mr.rgba8.resize(color.rgba8.size());
  const uint32_t tileTexels = kFloorTexels / kFloorTiles;
  for (uint32_t y = 0; y < kFloorTexels; ++y)
    for (uint32_t x = 0; x < kFloorTexels; ++x) {
      const uint32_t tile = (y / tileTexels) * kFloorTiles + x / tileTexels;
      const bool grout = x % tileTexels < kGroutTexels || y % tileTexels < kGroutTexels;
      const bool metal = ((x / tileTexels) + (y / tileTexels)) % 2 == 0;
      const float tint = unit(tile, 1), grain = unit(y * kFloorTexels + x, 2) * 16.0f - 8.0f;
      glm::vec3 c = metal ? glm::vec3(200.0f + 30.0f * tint) : glm::vec3(190.0f, 160.0f, 125.0f) * (0.8f + 0.3f * tint);
      if (grout) c = glm::vec3(55.0f);
      uint8_t* p = &color.rgba8[(size_t(y) * kFloorTexels + x) * 4];
      p[0] = byteOf(c.r + grain), p[1] = byteOf(c.g + grain), p[2] = byteOf(c.b + grain), p[3] = 255;
      const float roughness = float(kFloorRoughnessMinByte) +
                              float(kFloorRoughnessMaxByte - kFloorRoughnessMinByte) * unit(tile, 3);
      uint8_t* q = &mr.rgba8[(size_t(y) * kFloorTexels + x) * 4];
      q[0] = 255, q[1] = grout ? uint8_t(kGroutRoughnessByte) : byteOf(roughness), q[2] = metal && !grout ? 255 : 0;
      q[3] = 255;
    }
  return {std::move(color), std::move(mr)};
}

// The objects' base colour (sRGB, tinted by each material's factor): kObjectChecks^2 light and darker checks
// with thin dark seams, so that reflections of the objects show the texture the hit shading samples.
constexpr uint32_t kObjectTexels = 256, kObjectChecks = 8;
se::TextureData makeObjectTexture() {
  se::TextureData t{.name = "glossy object checker", .width = kObjectTexels, .height = kObjectTexels, .rgba8 = {}};
  t.rgba8.resize(size_t(kObjectTexels) * kObjectTexels * 4);
  const uint32_t check = kObjectTexels / kObjectChecks;
  for (uint32_t y = 0; y < kObjectTexels; ++y)
    for (uint32_t x = 0; x < kObjectTexels; ++x) {
      const bool seam = x % check < 2 || y % check < 2;
      const bool on = (x / check + y / check) % 2 == 0;
      const uint8_t v = seam ? 140 : on ? 245 : 195;
      uint8_t* p = &t.rgba8[(size_t(y) * kObjectTexels + x) * 4];
      p[0] = p[1] = p[2] = v, p[3] = 255;
    }
  return t;
}

// One object shape: its mesh, how its texture repeats, and how it stands on the floor.
struct Shape {
  se::MeshData mesh;
  glm::vec2 uvScale;
  float lift;           // metres from the floor to the mesh's origin, at scale 1
  bool contrastMirror;  // the contrast material: a mirror (true) or a rough clay (false)
};

struct Finish {
  const char* name;
  glm::vec3 color;  // linear base colour factor
  float metallic;
};
// Glossy finishes, four per shape from this list (shape k takes k, k+1, k+2, k+3), at the roughness of kRoughness.
constexpr Finish kFinishes[] = {
    {"gold", {1.0f, 0.78f, 0.34f}, 1.0f},        {"copper", {0.95f, 0.64f, 0.54f}, 1.0f},
    {"steel", {0.56f, 0.57f, 0.58f}, 1.0f},      {"aluminium", {0.91f, 0.92f, 0.92f}, 1.0f},
    {"red lacquer", {0.7f, 0.08f, 0.06f}, 0.0f}, {"blue ceramic", {0.1f, 0.25f, 0.65f}, 0.0f},
    {"brass", {0.89f, 0.75f, 0.42f}, 1.0f}};
constexpr float kRoughness[4] = {0.24f, 0.31f, 0.38f, 0.46f};
constexpr uint32_t kVariants = 5;  // four glossy materials and the contrast one
// The share of objects in the contrast material.
constexpr float kContrastShare = 0.1f;

std::array<Shape, 4> makeShapes() {
  return {Shape{se::makeSphere(1.0f, 160, 80), {2.0f, 1.0f}, 1.0f, true},
          Shape{se::makeArch(0.9f, 0.32f, glm::two_pi<float>(), 160, 64), {4.0f, 1.0f}, 0.9f + 0.32f, true},
          Shape{se::makeBox(glm::vec3(1.6f), 24), {1.0f, 1.0f}, 0.8f, false},
          Shape{se::makeCylinder(0.6f, 2.2f, 128, 48, true), {2.0f, 1.0f}, 0.0f, false}};
}

// The shapes' meshes, kVariants per shape (same geometry, one material each): returns the first mesh's index.
uint32_t addObjectMeshes(se::Scene& s, std::array<Shape, 4>& shapes, int texture) {
  const uint32_t first = uint32_t(s.meshes.size());
  for (uint32_t k = 0; k < shapes.size(); ++k) {
    for (glm::vec2& uv : shapes[k].mesh.uvs) uv *= shapes[k].uvScale;
    for (uint32_t v = 0; v < kVariants; ++v) {
      se::Material m{.baseColorTexture = texture};
      if (v < 4) {
        const Finish& f = kFinishes[(k + v) % std::size(kFinishes)];
        m.name = f.name, m.baseColorFactor = glm::vec4(f.color, 1.0f), m.metallicFactor = f.metallic;
        m.roughnessFactor = kRoughness[(k + v) % 4];
      } else if (shapes[k].contrastMirror) {
        m.name = "mirror", m.baseColorFactor = glm::vec4(0.95f, 0.95f, 0.95f, 1.0f), m.metallicFactor = 1.0f;
        m.roughnessFactor = 0.03f;
      } else {
        m.name = "rough clay", m.baseColorFactor = glm::vec4(0.55f, 0.35f, 0.25f, 1.0f), m.metallicFactor = 0.0f;
        m.roughnessFactor = 0.8f;
      }
      s.materials.push_back(m);
      se::MeshData mesh = shapes[k].mesh;
      mesh.name += std::string(" ") + s.materials.back().name;
      mesh.material = uint32_t(s.materials.size() - 1);
      s.meshes.push_back(std::move(mesh));
    }
  }
  return first;
}

// One object per grid cell, jittered, of a random shape, material, size and heading; a torus stands upright or
// lies flat.
void placeObjects(se::Scene& s, const std::array<Shape, 4>& shapes, uint32_t firstMesh) {
  const float half = 0.5f * float(kGlossyGridCells - 1);
  for (uint32_t i = 0; i < kGlossyGridCells * kGlossyGridCells; ++i) {
    const float x = (float(i % kGlossyGridCells) - half) * kGlossyGridSpacing + (unit(i, 10) - 0.5f) * 1.2f;
    const float z = (float(i / kGlossyGridCells) - half) * kGlossyGridSpacing + (unit(i, 11) - 0.5f) * 1.2f;
    const uint32_t shape = std::min(uint32_t(unit(i, 12) * 4.0f), 3u);
    const uint32_t variant = unit(i, 13) < kContrastShare ? 4u : std::min(uint32_t(unit(i, 14) * 4.0f), 3u);
    const float scale = 0.8f + 0.45f * unit(i, 15), yaw = glm::two_pi<float>() * unit(i, 16);
    const bool flatTorus = shape == 1 && unit(i, 17) < 0.5f;
    const float lift = flatTorus ? 0.32f : shapes[shape].lift;
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(x, lift * scale, z)) *
                  glm::rotate(glm::mat4(1.0f), yaw, glm::vec3(0, 1, 0));
    if (flatTorus) m = glm::rotate(m, -glm::half_pi<float>(), glm::vec3(1, 0, 0));
    s.instances.push_back(
        se::Instance{.mesh = firstMesh + shape * kVariants + variant, .transform = glm::scale(m, glm::vec3(scale))});
  }
}

}  // namespace

se::Scene makeGlossyScene() {
  se::Scene s;
  auto [floorColor, floorRoughness] = makeFloorTextures();
  s.textures.push_back(std::move(floorColor));
  s.textures.push_back(std::move(floorRoughness));
  s.textures.push_back(makeObjectTexture());
  se::Material floor{.name = "polished tiles", .metallicFactor = 1.0f, .roughnessFactor = kFloorRoughnessFactor};
  floor.baseColorTexture = 0;
  floor.metallicRoughnessTexture = 1;
  s.materials.push_back(floor);
  se::MeshData plane = se::makePlane(kGlossyFloorSize, kGlossyFloorSize, kGlossyFloorSegments, kGlossyFloorSegments);
  for (glm::vec2& uv : plane.uvs) uv *= kGlossyFloorSize / float(kFloorTiles);  // 1 m tiles
  plane.material = 0;
  s.meshes.push_back(std::move(plane));
  s.instances.push_back(se::Instance{.mesh = 0});

  std::array<Shape, 4> shapes = makeShapes();
  placeObjects(s, shapes, addObjectMeshes(s, shapes, 2));

  // scripts/gpu/glossy_path.json's first keyframe: above the grid's corner, 40 degrees down
  // into it.
  s.camera = se::Camera{.eye = {-16.0f, 8.0f, 16.0f},
                        .target = {-9.26f, 0.0f, 9.26f},
                        .fovYDegrees = 55.0f,
                        .zNear = 0.1f,
                        .zFar = 300.0f};
  // Low and from the side, like the performance scene's: long shadows across the floor and the objects.
  s.sun = se::Sun{.direction = glm::normalize(glm::vec3(-0.55f, 0.5f, 0.3f))};
  return s;
}

}  // namespace rbRender

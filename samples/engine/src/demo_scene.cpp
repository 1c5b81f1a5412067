// The default demo scene: a small colonnade on a checkered ground with a few test objects chosen to show
// what a ray-tracing add-on changes (sharp metal, mirrors, contact shadows under arches, a leaf canopy's
// alpha-tested dappled shadow) and a handful of coloured KHR lights in the shade.
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/procedural.h"

namespace sample_engine {
namespace {

TextureData makeChecker(uint32_t size, uint32_t checks, uint8_t light, uint8_t dark) {
  TextureData t{.name = "checker", .width = size, .height = size, .rgba8 = {}};
  t.rgba8.resize(size_t(size) * size * 4);
  for (uint32_t y = 0; y < size; ++y)
    for (uint32_t x = 0; x < size; ++x) {
      bool on = ((x * checks / size) + (y * checks / size)) % 2 == 0;
      uint8_t* p = &t.rgba8[(size_t(y) * size + x) * 4];
      p[0] = p[1] = p[2] = on ? light : dark;
      p[3] = 255;
    }
  return t;
}

uint32_t addMaterial(Scene& s, const char* name, glm::vec3 color, float metallic, float roughness, int texture = -1) {
  s.materials.push_back(Material{.name = name,
                                 .baseColorFactor = glm::vec4(color, 1.0f),
                                 .metallicFactor = metallic,
                                 .roughnessFactor = roughness,
                                 .baseColorTexture = texture});
  return static_cast<uint32_t>(s.materials.size() - 1);
}

uint32_t addMesh(Scene& s, MeshData mesh, uint32_t material) {
  mesh.material = material;
  s.meshes.push_back(std::move(mesh));
  return static_cast<uint32_t>(s.meshes.size() - 1);
}

void place(Scene& s, uint32_t mesh, glm::vec3 position, float yawDegrees = 0.0f) {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), position);
  m = glm::rotate(m, glm::radians(yawDegrees), glm::vec3(0, 1, 0));
  s.instances.push_back(Instance{mesh, m});
}

// A plane card whose texture repeats every `tile` metres.
MeshData makeCard(float sizeX, float sizeZ, float tile) {
  MeshData card = makePlane(sizeX, sizeZ, 1, 1);
  for (glm::vec2& uv : card.uvs) uv *= glm::vec2(sizeX, sizeZ) / tile;
  return card;
}

// A wooden pergola under a leaf canopy, centred at (centre.x, 0, centre.y): four posts, two beams along X,
// rafters along Z, a horizontal leaf card on the rafters and leaf curtains hanging from its +Z and +X edges
// (the sides the camera sees). The leaves are alpha-tested (Mask, cutoff 0.5) and double-sided.
void addPergola(Scene& s, glm::vec2 centre) {
  const float postHeight = 2.5f, span = 3.2f, overhang = 0.25f;  // span: between post centres
  const float beamHeight = 0.2f, rafterHeight = 0.14f;
  const int rafters = 6;
  // The leaves reach 0.1 m past the rafter ends; leafTile: metres per texture repeat.
  const float canopySize = span + 2.0f * overhang + 0.2f, curtainDrop = 0.45f, leafTile = 2.0f;
  const float canopyY = postHeight + rafterHeight + 0.02f;

  const int leafTexture = int(s.textures.size());
  s.textures.push_back(makeLeafTexture(512, 7));
  const uint32_t wood = addMaterial(s, "weathered wood", {0.46f, 0.33f, 0.21f}, 0.0f, 0.8f);
  const uint32_t leaves = addMaterial(s, "leaf canopy", {1.0f, 1.0f, 1.0f}, 0.0f, 0.6f, leafTexture);
  s.materials[leaves].alphaMode = AlphaMode::Mask;
  s.materials[leaves].alphaCutoff = 0.5f;
  s.materials[leaves].doubleSided = true;

  const glm::vec3 c(centre.x, 0.0f, centre.y);
  const float h = span * 0.5f;
  const uint32_t post = addMesh(s, makeBox({0.14f, postHeight, 0.14f}), wood);
  for (float dx : {-h, h})
    for (float dz : {-h, h}) place(s, post, c + glm::vec3(dx, postHeight * 0.5f, dz));
  const uint32_t beam = addMesh(s, makeBox({span + 2.0f * overhang, beamHeight, 0.12f}), wood);
  for (float dz : {-h, h}) place(s, beam, c + glm::vec3(0.0f, postHeight - beamHeight * 0.5f, dz));
  const uint32_t rafter = addMesh(s, makeBox({0.07f, rafterHeight, span + 2.0f * overhang}), wood);
  for (int i = 0; i < rafters; ++i) {
    const float dx = -h + span * float(i) / float(rafters - 1);
    place(s, rafter, c + glm::vec3(dx, postHeight + rafterHeight * 0.5f, 0.0f));
  }

  place(s, addMesh(s, makeCard(canopySize, canopySize, leafTile), leaves), c + glm::vec3(0.0f, canopyY, 0.0f));
  // The curtain card stands in the XY plane facing +Z (the plane's +Y turned by 90 degrees about X).
  const uint32_t curtain = addMesh(s, makeCard(canopySize, curtainDrop, leafTile), leaves);
  const glm::vec3 curtainCentreY(0.0f, canopyY - curtainDrop * 0.5f, 0.0f);
  for (float yaw : {0.0f, 90.0f}) {
    const glm::vec3 edge = yaw == 0.0f ? glm::vec3(0.0f, 0.0f, canopySize * 0.5f) : glm::vec3(canopySize * 0.5f, 0, 0);
    glm::mat4 m = glm::translate(glm::mat4(1.0f), c + curtainCentreY + edge);
    m = glm::rotate(m, glm::radians(yaw), glm::vec3(0, 1, 0));
    m = glm::rotate(m, glm::radians(90.0f), glm::vec3(1, 0, 0));
    s.instances.push_back(Instance{curtain, m});
  }
}

PunctualLight localLight(const char* name, PunctualLight::Type type, glm::vec3 position, glm::vec3 color,
                         float intensity, float range) {
  PunctualLight l;
  l.name = name;
  l.type = type;
  l.color = color;
  l.intensity = intensity;
  l.range = range;
  // Local -Z turned to world -Y: spots shine straight down (points do not care).
  l.transform = glm::rotate(glm::translate(glm::mat4(1.0f), position), -glm::half_pi<float>(), glm::vec3(1, 0, 0));
  return l;
}

// A few coloured KHR lights (candela, windowed by their range) that make sense in the scene: a warm lantern
// under the pergola, two spots under the arches, small glows by the red sphere and the copper cylinder. Their
// irradiance on the ground below them (1.5-2.5 lux) stays below the sun's 3.5, so the sunlit image is not
// blown out; they show best in the shade (under the canopy, behind the objects).
void addLocalLights(Scene& s) {
  using T = PunctualLight::Type;
  s.lights.push_back(localLight("pergola lantern", T::Point, {-7.8f, 2.1f, 5.4f}, {1.0f, 0.72f, 0.42f}, 8.0f, 7.0f));
  PunctualLight left = localLight("left arch spot", T::Spot, {-4.5f, 3.2f, -3.5f}, {0.55f, 0.75f, 1.0f}, 24.0f, 9.0f);
  left.innerConeAngle = 0.3f;
  left.outerConeAngle = 0.6f;
  s.lights.push_back(left);
  PunctualLight right = localLight("right arch spot", T::Spot, {4.5f, 3.2f, -3.5f}, {1.0f, 0.6f, 0.35f}, 24.0f, 9.0f);
  right.innerConeAngle = 0.3f;
  right.outerConeAngle = 0.6f;
  s.lights.push_back(right);
  s.lights.push_back(localLight("sphere glow", T::Point, {0.6f, 0.35f, 2.3f}, {1.0f, 0.35f, 0.6f}, 1.2f, 3.0f));
  s.lights.push_back(localLight("copper glow", T::Point, {5.4f, 1.6f, 3.2f}, {0.35f, 1.0f, 0.7f}, 3.0f, 4.0f));
}

}  // namespace

Scene makeDefaultDemoScene() {
  Scene s;
  s.textures.push_back(makeChecker(256, 8, 200, 110));

  const uint32_t ground = addMaterial(s, "ground", {0.85f, 0.82f, 0.78f}, 0.0f, 0.75f, 0);
  const uint32_t stone = addMaterial(s, "stone", {0.78f, 0.74f, 0.66f}, 0.0f, 0.6f);
  const uint32_t gold = addMaterial(s, "polished gold", {1.0f, 0.78f, 0.34f}, 1.0f, 0.15f);
  const uint32_t redPlastic = addMaterial(s, "red plastic", {0.75f, 0.08f, 0.06f}, 0.0f, 0.35f);
  const uint32_t blue = addMaterial(s, "blue matte", {0.1f, 0.25f, 0.7f}, 0.0f, 0.8f);
  const uint32_t mirror = addMaterial(s, "mirror", {0.95f, 0.95f, 0.95f}, 1.0f, 0.02f);
  const uint32_t copper = addMaterial(s, "brushed copper", {0.95f, 0.64f, 0.54f}, 1.0f, 0.45f);
  const uint32_t white = addMaterial(s, "white ceramic", {0.9f, 0.9f, 0.88f}, 0.0f, 0.2f);

  // Ground: 40 m square; the 8x8 checker repeats 5 times, giving 1 m squares.
  MeshData plane = makePlane(40.0f, 40.0f, 8, 8);
  for (glm::vec2& uv : plane.uvs) uv *= 5.0f;
  place(s, addMesh(s, std::move(plane), ground), {0, 0, 0});

  // Colonnade: four columns in the back carrying two arches, two free-standing columns in front.
  const float columnHeight = 3.2f;
  const uint32_t column = addMesh(s, makeCylinder(0.32f, columnHeight, 48, 4, true), stone);
  const uint32_t plinth = addMesh(s, makeBox({0.9f, 0.3f, 0.9f}, 2), stone);
  for (float x : {-6.5f, -2.5f, 2.5f, 6.5f}) {
    place(s, column, {x, 0.0f, -3.5f});
    place(s, plinth, {x, 0.15f, -3.5f});
  }
  for (float x : {-6.5f, 6.5f}) {
    place(s, column, {x, 0.0f, 2.5f});
    place(s, plinth, {x, 0.15f, 2.5f});
  }
  const uint32_t arch = addMesh(s, makeArch(2.0f, 0.3f, glm::pi<float>(), 64, 24), stone);
  place(s, arch, {-4.5f, columnHeight, -3.5f});
  place(s, arch, {4.5f, columnHeight, -3.5f});

  // Test objects.
  place(s, addMesh(s, makeSphere(1.0f, 96, 48), gold), {-1.6f, 1.0f, 0.0f});
  place(s, addMesh(s, makeSphere(0.7f, 80, 40), redPlastic), {1.4f, 0.7f, 1.3f});
  place(s, addMesh(s, makeSphere(0.45f, 64, 32), white), {0.2f, 0.45f, 2.6f});
  place(s, addMesh(s, makeBox({1.2f, 1.2f, 1.2f}, 4), blue), {3.6f, 0.6f, 0.2f}, 30.0f);
  place(s, addMesh(s, makeBox({1.4f, 1.6f, 0.3f}, 4), mirror), {-4.3f, 0.8f, 0.8f}, 35.0f);
  place(s, addMesh(s, makeCylinder(0.5f, 1.4f, 64, 2, true), copper), {4.6f, 0.0f, 2.4f});
  // Mirror patch lying on the ground in front of the objects (a thin box so it has real thickness).
  place(s, addMesh(s, makeBox({3.0f, 0.02f, 1.8f}, 1), mirror), {0.0f, 0.01f, 4.2f});

  // A pergola at the frame's left edge, in front of the colonnade's left end: the sun (from the left, behind
  // the camera) throws the canopy's dappled shadow to the right, onto open ground in front of the mirror box,
  // in the camera's view. Sight lines to the columns and test objects pass right of it or behind its rear edge.
  addPergola(s, {-7.8f, 5.4f});

  addLocalLights(s);

  s.camera = Camera{
      .eye = {0.0f, 4.2f, 12.5f}, .target = {0.0f, 1.2f, 0.0f}, .fovYDegrees = 50.0f, .zNear = 0.1f, .zFar = 200.0f};
  s.sun = Sun{};
  return s;
}

}  // namespace sample_engine

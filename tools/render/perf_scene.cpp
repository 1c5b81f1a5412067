// Builds the performance scene (see the header).
#include "perf_scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"

namespace rbRender {

namespace se = sample_engine;

namespace {

// One model of the scene: its largest extent in metres once placed, and the rings it stands on.
struct PerfModel {
  const char* name;
  float size;        // metres along the model's largest extent
  uint32_t copies;   // instances of the whole model
  float ringRadius;  // metres from the centre
};

// Largest first, on rings from the inside out; 2 x ~140k + 6 x ~76k + ... with the ground: about 2.3M triangles.
constexpr PerfModel kModels[] = {
    {"ReciprocatingSaw", 3.0f, 2, 5.0f},
    {"2CylinderEngine", 2.6f, 6, 10.0f},
    {"MetalRoughSpheresNoTextures", 4.0f, 1, 0.0f},
    {"DamagedHelmet", 1.2f, 10, 15.0f},
    {"Suzanne", 1.0f, 14, 19.0f},
    {"Duck", 0.9f, 18, 23.0f},
};

}  // namespace

se::Result<se::Scene> makePerfScene(const std::string& scenesDir, PerfSceneInfo& info, const PerfSceneShape& shape) {
  using R = se::Result<se::Scene>;
  info = PerfSceneInfo{};
  se::Scene s;
  // A slightly glossy ground, so reflections (rough up to the render command's 0.5 threshold) cover the floor.
  se::Material ground{.name = "polished concrete", .baseColorFactor = {0.62f, 0.6f, 0.57f, 1.0f}};
  ground.roughnessFactor = 0.3f;
  s.materials.push_back(ground);
  const uint32_t segments = shape.groundSegments ? shape.groundSegments : kPerfGroundSegments;
  se::MeshData plane = se::makePlane(kPerfGroundSize, kPerfGroundSize, segments, segments);
  plane.material = 0;
  s.meshes.push_back(std::move(plane));
  s.instances.push_back(se::Instance{.mesh = 0});

  std::string looked;
  const uint32_t copiesScale = shape.copiesScale ? shape.copiesScale : 1u;
  for (const PerfModel& m : kModels) {
    if (shape.groundOnly) break;
    const std::string path = scenesDir + "/" + m.name + "/" + m.name + ".gltf";
    if (!std::filesystem::is_regular_file(path)) {
      looked += (looked.empty() ? "" : ", ") + path;
      info.missing += (info.missing.empty() ? "" : ", ") + std::string(m.name);
      continue;
    }
    se::SceneLoadResult r = se::loadGltf(path);
    if (!r.ok()) return R::failure("cannot load " + path + ": " + r.error);
    if (!r.scene.animations.empty() || !r.scene.skins.empty())
      return R::failure(path + " is animated; the performance scene instances static models only");
    // Scale to m.size along the largest extent, resting on the ground, centred on x/z.
    const se::Bounds b = r.scene.bounds();
    const glm::vec3 extent = b.max - b.min;
    const float scale = m.size / std::max({extent.x, extent.y, extent.z, 1e-6f});
    const glm::mat4 normalize = glm::scale(glm::mat4(1.0f), glm::vec3(scale)) *
                                glm::translate(glm::mat4(1.0f), -glm::vec3(b.center().x, b.min.y, b.center().z));
    // The model's meshes, materials and textures once; its instances once per copy (one BLAS each in the SDK,
    // many TLAS instances).
    se::Scene meshesOnly = r.scene;
    meshesOnly.instances.clear();
    meshesOnly.lights.clear();
    const uint32_t meshBase = uint32_t(s.meshes.size());
    se::appendScene(s, meshesOnly, glm::mat4(1.0f));
    // More copies go on further rings outside the default one, as many per ring, each ring 1.2 model sizes out.
    for (uint32_t k = 0; k < m.copies * copiesScale; ++k) {
      const uint32_t ring = k / m.copies, slot = k % m.copies;
      // Evenly round the ring, the ring turned by half a step against the previous one; each copy faces the centre.
      const float angle = (float(slot) + 0.5f * float((info.models + ring) % 2)) * glm::two_pi<float>() /
                          float(m.copies);
      const float radius = m.ringRadius + float(ring) * 1.2f * m.size;
      const glm::vec3 at(radius * std::sin(angle), 0.0f, radius * std::cos(angle));
      const glm::mat4 placement = glm::translate(glm::mat4(1.0f), at) *
                                  glm::rotate(glm::mat4(1.0f), angle + glm::pi<float>(), glm::vec3(0, 1, 0)) *
                                  normalize;
      for (const se::Instance& inst : r.scene.instances)
        s.instances.push_back(se::Instance{.mesh = meshBase + inst.mesh, .transform = placement * inst.transform});
    }
    ++info.models;
  }
  if (info.models == 0 && !shape.groundOnly)
    return R::failure("no model of the performance scene found (looked for " + looked +
                      "); pass --models-from with the folder of the shared glTF models");
  for (const se::Instance& inst : s.instances) info.triangles += s.meshes[inst.mesh].triangleCount();
  info.instances = s.instances.size();
  s.camera = se::Camera{
      .eye = {0.0f, 9.0f, 30.0f}, .target = {0.0f, 0.5f, 0.0f}, .fovYDegrees = 55.0f, .zNear = 0.1f, .zFar = 200.0f};
  // Low and from the side, so that shadows are long and cross the models and the ground.
  s.sun = se::Sun{.direction = glm::normalize(glm::vec3(-0.6f, 0.45f, 0.35f))};
  return R::success(std::move(s));
}

}  // namespace rbRender

// Builds the animated benchmark's scene (see the header).
#include "animated_scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/gltf_loader.h"
#include "sample_engine/procedural.h"

namespace rbAnimated {

namespace se = sample_engine;

namespace {

constexpr float kCharacterSize = 1.7f;  // metres: a model's largest extent (a person's height, the fox's length)
constexpr float kSpacing = 1.6f;        // metres between neighbouring characters on the grid

}  // namespace

const std::vector<std::string>& characterModels() {
  static const std::vector<std::string> models = {"CesiumMan", "Fox", "BrainStem"};
  return models;
}

se::Result<AnimatedScene> makeAnimatedScene(const std::string& scenesDir, uint32_t characters,
                                            std::optional<glm::vec2> gridCentreXZ) {
  using R = se::Result<AnimatedScene>;
  struct Model {
    std::string name;
    se::Scene scene;
    glm::mat4 normalize{1.0f};  // to kCharacterSize, feet at y = 0, centred on x/z
  };
  std::vector<Model> models;
  std::string missing;
  for (const std::string& name : characterModels()) {
    const std::string path = scenesDir + "/" + name + "/" + name + ".gltf";
    if (!std::filesystem::is_regular_file(path)) {
      missing += (missing.empty() ? "" : ", ") + path;
      continue;
    }
    se::SceneLoadResult r = se::loadGltf(path);
    if (!r.ok()) return R::failure("cannot load " + path + ": " + r.error);
    if (r.scene.animations.empty()) return R::failure(path + " has no animation");
    const se::Bounds b = r.scene.bounds();
    const glm::vec3 extent = b.max - b.min;
    const float s = kCharacterSize / std::max({extent.x, extent.y, extent.z, 1e-6f});
    Model m{name, std::move(r.scene), glm::mat4(1.0f)};
    m.normalize = glm::scale(glm::mat4(1.0f), glm::vec3(s)) *
                  glm::translate(glm::mat4(1.0f), -glm::vec3(b.center().x, b.min.y, b.center().z));
    models.push_back(std::move(m));
  }
  if (models.empty()) return R::failure("no character model found (looked for " + missing + ")");

  AnimatedScene out;
  out.scene = se::makeDefaultDemoScene();
  const se::Bounds floor = out.scene.bounds();
  const glm::vec2 centre = gridCentreXZ ? *gridCentreXZ : glm::vec2(floor.center().x, floor.center().z);
  // A square grid centred on the demo scene, on its lowest level.
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(characters))));
  for (uint32_t k = 0; k < characters; ++k) {
    const Model& m = models[k % models.size()];
    const float x = (float(k % side) - 0.5f * float(side - 1)) * kSpacing;
    const float z = (float(k / side) - 0.5f * float(side - 1)) * kSpacing;
    const float yaw = float(k) * 2.39996f;  // golden angle: neighbours face different ways
    const glm::mat4 placement = glm::translate(glm::mat4(1.0f), glm::vec3(centre.x + x, floor.min.y, centre.y + z)) *
                                glm::rotate(glm::mat4(1.0f), yaw, glm::vec3(0, 1, 0)) * m.normalize;
    const size_t firstMesh = out.scene.meshes.size();
    const uint32_t animation = se::appendScene(out.scene, m.scene, placement);
    for (size_t i = firstMesh; i < out.scene.meshes.size(); ++i)
      out.characterTriangles += out.scene.meshes[i].triangleCount();
    // Offsets spread the characters over their cycles, so no two share a pose.
    out.playbacks.push_back({animation, 0.37 * double(k)});
    out.characterNames.push_back(m.name);
  }
  return R::success(std::move(out));
}

}  // namespace rbAnimated

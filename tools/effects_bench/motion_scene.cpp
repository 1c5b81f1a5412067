// The motion benchmark's scene (see the header).
#include "motion_scene.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "animated_scene.h"
#include "sample_engine/procedural.h"

namespace rbEffects {

namespace se = sample_engine;

namespace {

int addNode(se::Scene& s, const char* name, glm::vec3 translation, int parent = -1) {
  se::Node n;
  n.name = name;
  n.parent = parent;
  n.translation = translation;
  s.nodes.push_back(n);
  return int(s.nodes.size()) - 1;
}

// A mesh placed by `node` (whose rest world transform is `rest`).
void addNodeInstance(se::Scene& s, se::MeshData mesh, uint32_t material, int node, const glm::mat4& rest) {
  mesh.material = material;
  s.meshes.push_back(std::move(mesh));
  se::Instance i;
  i.mesh = uint32_t(s.meshes.size()) - 1;
  i.transform = rest;
  i.node = node;
  s.instances.push_back(i);
}

uint32_t addAnimation(se::Scene& s, const char* name, uint32_t node, se::AnimationPath path,
                      se::AnimationInterpolation interpolation, std::vector<float> times, std::vector<float> values) {
  se::Animation a;
  a.name = name;
  se::AnimationSampler sampler;
  sampler.interpolation = interpolation;
  sampler.times = std::move(times);
  sampler.values = std::move(values);
  a.duration = sampler.times.back();
  a.samplers.push_back(std::move(sampler));
  a.channels.push_back({0, node, path});
  s.animations.push_back(std::move(a));
  return uint32_t(s.animations.size()) - 1;
}

}  // namespace

MotionScene makeMotionScene(const std::string& scenesDir, uint32_t characters) {
  MotionScene m;
  if (characters > 0 && !scenesDir.empty()) {
    // In front of the colonnade, left of the props, in the camera's view.
    auto animated = rbAnimated::makeAnimatedScene(scenesDir, characters, glm::vec2(-3.0f, 3.0f));
    if (animated) {
      m.scene = std::move(animated.value.scene);
      m.walkers = animated.value.playbacks;
      for (const std::string& n : animated.value.characterNames)
        m.walkersNote += (m.walkersNote.empty() ? "" : ", ") + n;
    } else {
      m.walkersNote = "no walkers: " + animated.error;
    }
  } else {
    m.walkersNote = "no walkers: no character models given";
  }
  if (m.walkers.empty()) m.scene = se::makeDefaultDemoScene();
  se::Scene& s = m.scene;

  se::Material prop;
  prop.name = "motion prop";
  prop.baseColorFactor = {0.8f, 0.55f, 0.3f, 1.0f};
  prop.roughnessFactor = 0.5f;
  s.materials.push_back(prop);
  const uint32_t material = uint32_t(s.materials.size()) - 1;
  // The animations' end times hold the last key: a case's frames stay inside them.
  const float end = float(kMotionEventTime) + 60.0f;

  // Pillar: 0.6 x 1.8 x 0.6, from left of the mirror patch to its right (its reflection jumps too).
  const glm::vec3 from(-2.2f, 0.9f, 5.6f), to(1.8f, 0.9f, 6.4f);
  const int pillar = addNode(s, "teleporting pillar", from);
  addNodeInstance(s, se::makeBox({0.6f, 1.8f, 0.6f}, 2), material, pillar, glm::translate(glm::mat4(1.0f), from));
  m.teleportAnimation = addAnimation(s, "teleport", uint32_t(pillar), se::AnimationPath::Translation,
                                     se::AnimationInterpolation::Step, {0.0f, float(kMotionEventTime), end},
                                     {from.x, from.y, from.z, to.x, to.y, to.z, to.x, to.y, to.z});

  // Door: 1.2 wide, 2 tall, hinged at its left edge; swings 150 degrees over 5 s, in the sun.
  const glm::vec3 hingeAt(2.6f, 0.0f, 4.4f);
  const int hinge = addNode(s, "door hinge", hingeAt);
  const int leaf = addNode(s, "door leaf", {0.6f, 1.0f, 0.0f}, hinge);
  addNodeInstance(s, se::makeBox({1.2f, 2.0f, 0.08f}, 2), material, leaf,
                  glm::translate(glm::mat4(1.0f), hingeAt + glm::vec3(0.6f, 1.0f, 0.0f)));
  std::vector<float> rotations;
  for (float degrees : {0.0f, 150.0f, 150.0f}) {
    const glm::quat q = glm::angleAxis(glm::radians(degrees), glm::vec3(0, 1, 0));
    rotations.insert(rotations.end(), {q.x, q.y, q.z, q.w});
  }
  m.doorAnimation = addAnimation(s, "door", uint32_t(hinge), se::AnimationPath::Rotation,
                                 se::AnimationInterpolation::Linear, {0.0f, 5.0f, end}, rotations);

  // Lamp: a warm point light that jumps from the left of the objects to their right.
  const glm::vec3 lampFrom(-2.8f, 0.9f, 3.2f), lampTo(2.2f, 0.9f, 2.8f);
  const int lampNode = addNode(s, "jumping lamp", lampFrom);
  se::PunctualLight lamp;
  lamp.name = "jumping lamp";
  lamp.type = se::PunctualLight::Type::Point;
  lamp.color = {1.0f, 0.8f, 0.55f};
  lamp.intensity = 6.0f;
  lamp.range = 6.0f;
  lamp.node = lampNode;
  s.lights.push_back(lamp);
  m.lampAnimation = addAnimation(s, "lamp jump", uint32_t(lampNode), se::AnimationPath::Translation,
                                 se::AnimationInterpolation::Step, {0.0f, float(kMotionEventTime), end},
                                 {lampFrom.x, lampFrom.y, lampFrom.z, lampTo.x, lampTo.y, lampTo.z, lampTo.x, lampTo.y,
                                  lampTo.z});
  return m;
}

}  // namespace rbEffects

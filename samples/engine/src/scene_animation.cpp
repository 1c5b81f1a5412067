// The animated part of a Scene: node transforms, animation lookup by name, and appending one scene into
// another (K independent characters in one scene).
#include <charconv>

#include <glm/gtc/matrix_transform.hpp>

#include "sample_engine/scene.h"

namespace sample_engine {

glm::mat4 Node::localTransform() const {
  if (matrix) return *matrix;
  return glm::translate(glm::mat4(1.0f), translation) * glm::mat4_cast(rotation) * glm::scale(glm::mat4(1.0f), scale);
}

std::optional<uint32_t> Scene::animationIndex(std::string_view nameOrNumber) const {
  for (size_t i = 0; i < animations.size(); ++i)
    if (animations[i].name == nameOrNumber) return uint32_t(i);
  uint32_t index = 0;
  const char* end = nameOrNumber.data() + nameOrNumber.size();
  auto [ptr, ec] = std::from_chars(nameOrNumber.data(), end, index);
  if (ec != std::errc() || ptr != end || nameOrNumber.empty() || index >= animations.size()) return std::nullopt;
  return index;
}

std::vector<std::string> Scene::animationNames() const {
  std::vector<std::string> names;
  names.reserve(animations.size());
  for (const Animation& a : animations) names.push_back(a.name);
  return names;
}

std::string Scene::describeAnimations() const {
  if (animations.empty()) return "none";
  std::string out;
  for (size_t i = 0; i < animations.size(); ++i)
    out += (i ? ", " : "") + std::to_string(i) + " '" + animations[i].name + "'";
  return out;
}

uint32_t appendScene(Scene& dst, const Scene& src, const glm::mat4& placement) {
  const uint32_t meshBase = uint32_t(dst.meshes.size()), materialBase = uint32_t(dst.materials.size());
  const int textureBase = int(dst.textures.size());
  const uint32_t skinBase = uint32_t(dst.skins.size()), animationBase = uint32_t(dst.animations.size());
  // src instances without a material refer to "the default material", which finalizeScene() adds to an
  // empty list; keep that meaning by giving the copy one.
  const bool srcNeedsDefault = src.materials.empty();

  dst.textures.insert(dst.textures.end(), src.textures.begin(), src.textures.end());
  for (Material m : src.materials) {
    for (int* t : {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture, &m.emissiveTexture})
      if (*t >= 0) *t += textureBase;
    dst.materials.push_back(std::move(m));
  }
  if (srcNeedsDefault) dst.materials.push_back(Material{.name = "default"});
  for (MeshData m : src.meshes) {
    m.material = srcNeedsDefault || m.material >= src.materials.size() ? materialBase : m.material + materialBase;
    dst.meshes.push_back(std::move(m));
  }

  const int root = int(dst.nodes.size());
  dst.nodes.push_back(Node{.name = "placement", .matrix = placement});
  const int nodeBase = int(dst.nodes.size());
  for (Node n : src.nodes) {
    n.parent = n.parent >= 0 ? n.parent + nodeBase : root;
    dst.nodes.push_back(std::move(n));
  }
  for (Skin s : src.skins) {
    for (uint32_t& j : s.joints) j += uint32_t(nodeBase);
    dst.skins.push_back(std::move(s));
  }
  for (Animation a : src.animations) {
    for (AnimationChannel& c : a.channels) c.node += uint32_t(nodeBase);
    dst.animations.push_back(std::move(a));
  }
  for (Instance inst : src.instances) {
    inst.mesh += meshBase;
    inst.transform = placement * inst.transform;
    if (inst.node >= 0) inst.node += nodeBase;
    if (inst.skin >= 0) inst.skin += int(skinBase);
    dst.instances.push_back(inst);
  }
  for (PunctualLight light : src.lights) {
    if (light.node >= 0) light.node += nodeBase;
    else
      light.transform = placement * light.transform;
    dst.lights.push_back(std::move(light));
  }
  return animationBase;
}

}  // namespace sample_engine

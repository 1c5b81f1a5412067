#include "gltf_animation.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/type_ptr.hpp>

#include "gltf_accessors.h"

namespace sample_engine::detail {
namespace {

std::string nodeName(const tinygltf::Model& model, int n) {
  return "node " + std::to_string(n) + " '" + model.nodes[size_t(n)].name + "'";
}

}  // namespace

std::string convertNodes(const tinygltf::Model& model, Scene& scene) {
  const int count = int(model.nodes.size());
  scene.nodes.resize(model.nodes.size());
  for (int i = 0; i < count; ++i) {
    const tinygltf::Node& in = model.nodes[size_t(i)];
    Node& out = scene.nodes[size_t(i)];
    out.name = in.name;
    if (in.matrix.size() == 16) {
      glm::mat4 m;
      for (int k = 0; k < 16; ++k) glm::value_ptr(m)[k] = float(in.matrix[size_t(k)]);  // column-major
      out.matrix = m;
    }
    if (in.translation.size() == 3)
      out.translation = glm::vec3(in.translation[0], in.translation[1], in.translation[2]);
    if (in.rotation.size() == 4)  // glTF stores x, y, z, w
      out.rotation = glm::quat(float(in.rotation[3]), float(in.rotation[0]), float(in.rotation[1]),
                               float(in.rotation[2]));
    if (in.scale.size() == 3) out.scale = glm::vec3(in.scale[0], in.scale[1], in.scale[2]);
    const std::vector<double>* weights = &in.weights;
    if (weights->empty() && in.mesh >= 0 && in.mesh < int(model.meshes.size()))
      weights = &model.meshes[size_t(in.mesh)].weights;
    for (double w : *weights) out.weights.push_back(float(w));
  }
  for (int p = 0; p < count; ++p)
    for (int c : model.nodes[size_t(p)].children) {
      if (c < 0 || c >= count)
        return nodeName(model, p) + ": child " + std::to_string(c) + " is out of range (the file has " +
               std::to_string(count) + " nodes)";
      if (c == p) return nodeName(model, p) + " lists itself as a child";
      if (scene.nodes[size_t(c)].parent >= 0)
        return nodeName(model, c) + " is a child of both node " + std::to_string(scene.nodes[size_t(c)].parent) +
               " and node " + std::to_string(p) + " (glTF nodes form a tree)";
      scene.nodes[size_t(c)].parent = p;
    }
  // With one parent per node, a cycle (A -> B -> A) is a parent chain that comes back to a node of the same walk.
  // Each node is walked once (0: not yet, 1: on this walk, 2: done), so a long chain costs linear time.
  std::vector<uint8_t> state(size_t(count), 0);
  std::vector<int> walk;
  for (int n = 0; n < count; ++n) {
    walk.clear();
    int at = n;
    for (; at >= 0 && state[size_t(at)] == 0; at = scene.nodes[size_t(at)].parent) {
      state[size_t(at)] = 1;
      walk.push_back(at);
    }
    if (at >= 0 && state[size_t(at)] == 1) {
      std::string chain = std::to_string(at);
      int steps = 0;
      for (int c = scene.nodes[size_t(at)].parent; steps < 8; c = scene.nodes[size_t(c)].parent, ++steps) {
        chain += " -> " + std::to_string(c);
        if (c == at) break;
      }
      return nodeName(model, at) + " is its own ancestor (parents " + chain + (steps == 8 ? " -> ..." : "") +
             "; glTF nodes form a tree)";
    }
    for (int w : walk) state[size_t(w)] = 2;
  }
  return {};
}

std::string convertSkins(const tinygltf::Model& model, Scene& scene) {
  for (size_t s = 0; s < model.skins.size(); ++s) {
    const tinygltf::Skin& in = model.skins[s];
    const std::string where = "skin " + std::to_string(s) + " '" + in.name + "'";
    Skin out;
    out.name = in.name;
    for (int j : in.joints) {
      if (j < 0 || j >= int(model.nodes.size()))
        return where + ": joint node " + std::to_string(j) + " is out of range (the file has " +
               std::to_string(model.nodes.size()) + " nodes)";
      out.joints.push_back(uint32_t(j));
    }
    if (in.inverseBindMatrices >= 0) {
      std::vector<float> f;
      if (std::string e = readFloats(model, in.inverseBindMatrices, 16, f); !e.empty())
        return where + ", inverseBindMatrices: " + e;
      if (f.size() / 16 < out.joints.size())
        return where + ": " + std::to_string(f.size() / 16) + " inverse bind matrices for " +
               std::to_string(out.joints.size()) + " joints";
      for (size_t i = 0; i < out.joints.size() * 16; ++i)
        if (!std::isfinite(f[i]))
          return where + ", inverseBindMatrices accessor " + std::to_string(in.inverseBindMatrices) + ": matrix " +
                 std::to_string(i / 16) + " has a non-finite element";
      out.inverseBindMatrices.resize(out.joints.size());
      for (size_t j = 0; j < out.joints.size(); ++j) out.inverseBindMatrices[j] = glm::make_mat4(&f[j * 16]);
    }
    scene.skins.push_back(std::move(out));
  }
  return {};
}

std::string convertAnimations(const tinygltf::Model& model, Scene& scene, std::vector<std::string>& warnings) {
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Animation& in = model.animations[a];
    const std::string where = "animation " + std::to_string(a) + " '" + in.name + "'";
    Animation out;
    out.name = in.name;
    std::vector<int> outputComponents;
    for (size_t s = 0; s < in.samplers.size(); ++s) {
      const tinygltf::AnimationSampler& smp = in.samplers[s];
      const std::string at = where + ", sampler " + std::to_string(s);
      AnimationSampler o;
      if (smp.interpolation == "LINEAR" || smp.interpolation.empty()) o.interpolation = AnimationInterpolation::Linear;
      else if (smp.interpolation == "STEP")
        o.interpolation = AnimationInterpolation::Step;
      else if (smp.interpolation == "CUBICSPLINE")
        o.interpolation = AnimationInterpolation::CubicSpline;
      else
        return at + ": unknown interpolation '" + smp.interpolation + "' (LINEAR, STEP or CUBICSPLINE)";
      // Key times are SCALAR FLOAT, outputs FLOAT or normalized integers (glTF 3.11): the reader would convert any
      // format, so a wrong one would animate garbage.
      if (smp.input >= 0 && smp.input < int(model.accessors.size())) {
        const tinygltf::Accessor& input = model.accessors[size_t(smp.input)];
        if (input.type != TINYGLTF_TYPE_SCALAR || input.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
          return at + ": input accessor " + std::to_string(smp.input) + " is " + formatName(input) +
                 "; key times must be SCALAR FLOAT";
      }
      if (smp.output >= 0 && smp.output < int(model.accessors.size())) {
        const tinygltf::Accessor& output = model.accessors[size_t(smp.output)];
        if (output.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT && !output.normalized)
          return at + ": output accessor " + std::to_string(smp.output) + " is " + formatName(output) +
                 "; animation outputs must be FLOAT or normalized integers";
      }
      if (std::string e = readFloats(model, smp.input, 1, o.times); !e.empty()) return at + ", input: " + e;
      if (o.times.empty()) return at + ": input accessor " + std::to_string(smp.input) + " has no keys";
      int components = 0;
      if (std::string e = readAllFloats(model, smp.output, o.values, components); !e.empty())
        return at + ", output: " + e;
      // A non-finite key time or value would make every pose of the animation NaN.
      for (size_t k = 0; k < o.times.size(); ++k)
        if (!std::isfinite(o.times[k]))
          return at + ": input accessor " + std::to_string(smp.input) + ", key " + std::to_string(k) +
                 ": the time is not finite";
      for (size_t v = 0; v < o.values.size(); ++v)
        if (!std::isfinite(o.values[v]))
          return at + ": output accessor " + std::to_string(smp.output) + ", element " +
                 std::to_string(v / size_t(components)) + ": a non-finite value";
      const size_t perKey = o.interpolation == AnimationInterpolation::CubicSpline ? 3 : 1;
      if (o.values.size() % (o.times.size() * perKey) != 0)
        return at + ": " + std::to_string(o.values.size() / size_t(components)) + " output elements for " +
               std::to_string(o.times.size()) + " keys" + (perKey == 3 ? " (CUBICSPLINE needs 3 per key)" : "");
      out.duration = std::max(out.duration, *std::max_element(o.times.begin(), o.times.end()));
      outputComponents.push_back(components);
      out.samplers.push_back(std::move(o));
    }
    for (size_t c = 0; c < in.channels.size(); ++c) {
      const tinygltf::AnimationChannel& ch = in.channels[c];
      const std::string at = where + ", channel " + std::to_string(c);
      if (ch.sampler < 0 || ch.sampler >= int(out.samplers.size()))
        return at + ": sampler " + std::to_string(ch.sampler) + " is out of range (" +
               std::to_string(out.samplers.size()) + " samplers)";
      if (ch.target_node < 0) {
        warnings.push_back(at + ": no target node; ignored");
        continue;
      }
      if (ch.target_node >= int(model.nodes.size()))
        return at + ": target node " + std::to_string(ch.target_node) + " is out of range (the file has " +
               std::to_string(model.nodes.size()) + " nodes)";
      AnimationChannel o;
      o.sampler = uint32_t(ch.sampler);
      o.node = uint32_t(ch.target_node);
      int expected = 1;
      if (ch.target_path == "translation") o.path = AnimationPath::Translation, expected = 3;
      else if (ch.target_path == "rotation")
        o.path = AnimationPath::Rotation, expected = 4;
      else if (ch.target_path == "scale")
        o.path = AnimationPath::Scale, expected = 3;
      else if (ch.target_path == "weights")
        o.path = AnimationPath::Weights, expected = 1;
      else {
        warnings.push_back(at + ": path '" + ch.target_path + "' is not supported; ignored");
        continue;
      }
      const AnimationSampler& smp = out.samplers[o.sampler];
      const size_t perKey = smp.interpolation == AnimationInterpolation::CubicSpline ? 3 : 1;
      const int components = outputComponents[o.sampler];
      if (components != expected ||
          (o.path != AnimationPath::Weights && smp.values.size() != smp.times.size() * perKey * size_t(expected)))
        return at + " (" + ch.target_path + "): sampler " + std::to_string(o.sampler) + " outputs " +
               std::to_string(smp.values.size() / size_t(components)) + " elements of " + std::to_string(components) +
               " components for " + std::to_string(smp.times.size()) + " keys";
      if (scene.nodes[o.node].matrix) {
        warnings.push_back(at + ": " + nodeName(model, int(o.node)) +
                           " has a matrix, which glTF does not animate; ignored");
        continue;
      }
      out.channels.push_back(o);
    }
    scene.animations.push_back(std::move(out));
  }
  return {};
}

}  // namespace sample_engine::detail

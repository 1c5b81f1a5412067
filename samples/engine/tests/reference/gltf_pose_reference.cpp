// The reference poser: loads a glTF with tinygltf, evaluates one animation at one time, then morphs and skins
// every TRIANGLES primitive of the scene in double precision (glTF 2.0 spec sections 3.5, 3.7.3, 3.8, 3.11).
#include "gltf_pose_reference.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "accessor_reader.h"
#include "keyframe_sampler.h"

namespace pose_reference {
namespace {

// The poser needs geometry only; decoding textures would cost time and fail on files without their images.
bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

bool loadModel(const std::string& path, tinygltf::Model& model, std::string& error) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skipImage, nullptr);
  std::string err, warn;
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  const bool binary = lower.size() >= 4 && lower.compare(lower.size() - 4, 4, ".glb") == 0;
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  if (!ok) error = "cannot load " + path + ": " + (err.empty() ? std::string("unknown tinygltf error") : err);
  return ok;
}

// A node's local transform: either the stored matrix or translation/rotation/scale, which animation channels
// replace one property at a time.
struct LocalPose {
  bool hasMatrix = false;
  glm::dmat4 matrix{1.0};
  glm::dvec3 translation{0.0};
  glm::dquat rotation{1.0, 0.0, 0.0, 0.0};  // glm order: w, x, y, z
  glm::dvec3 scale{1.0};
  bool weightsAnimated = false;  // the played animation has a `weights` channel for this node
  std::vector<double> weights;   // animated morph weights, when weightsAnimated

  glm::dmat4 local() const {
    if (hasMatrix) return matrix;
    return glm::translate(glm::dmat4(1.0), translation) * glm::mat4_cast(rotation) * glm::scale(glm::dmat4(1.0), scale);
  }
};

class Poser {
 public:
  explicit Poser(const tinygltf::Model& model) : model_(model) {}

  bool pose(int animation, double time, std::vector<PosedPrimitive>& out) {
    const int animationCount = int(model_.animations.size());
    if (animation < -1 || animation >= animationCount)
      return fail("animation " + std::to_string(animation) + " is out of range: the file has " +
                  std::to_string(animationCount) + " (use -1 for the rest pose)");
    if (!std::isfinite(time) || time < 0.0) return fail("time " + std::to_string(time) + " must be finite and >= 0");
    if (!buildHierarchy() || !initLocalPoses()) return false;
    if (animation >= 0 && !applyAnimation(animation, time)) return false;
    if (!computeWorlds()) return false;
    std::vector<int> roots;
    if (!sceneRoots(roots)) return false;
    for (int root : roots)
      if (!visit(root, out)) return false;
    return true;
  }

  const std::string& error() const { return error_; }

 private:
  bool fail(std::string message) {
    error_ = std::move(message);
    return false;
  }

  std::optional<AccessorValues> read(int accessor, const std::string& what, int components) {
    std::string e;
    std::optional<AccessorValues> v = readAccessor(model_, accessor, &e);
    if (!v) {
      fail(what + ": " + e);
      return std::nullopt;
    }
    if (components > 0 && v->components != components) {
      fail(what + ": accessor " + std::to_string(accessor) + " has " + std::to_string(v->components) +
           " components per element, expected " + std::to_string(components));
      return std::nullopt;
    }
    return v;
  }

  bool buildHierarchy() {
    const size_t n = model_.nodes.size();
    parent_.assign(n, -1);
    for (size_t i = 0; i < n; ++i)
      for (int child : model_.nodes[i].children) {
        if (child < 0 || size_t(child) >= n)
          return fail("node " + std::to_string(i) + " has child " + std::to_string(child) + ", out of range (" +
                      std::to_string(n) + " nodes)");
        if (parent_[size_t(child)] != -1)
          return fail("node " + std::to_string(child) + " is a child of both node " +
                      std::to_string(parent_[size_t(child)]) + " and node " + std::to_string(i) +
                      " (glTF nodes form a tree)");
        parent_[size_t(child)] = int(i);
      }
    return true;
  }

  bool initLocalPoses() {
    poses_.assign(model_.nodes.size(), LocalPose{});
    for (size_t i = 0; i < model_.nodes.size(); ++i) {
      const tinygltf::Node& node = model_.nodes[i];
      LocalPose& p = poses_[i];
      if (node.matrix.size() == 16) {
        p.hasMatrix = true;
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) p.matrix[c][r] = node.matrix[size_t(c * 4 + r)];  // column-major
      } else if (!node.matrix.empty()) {
        return fail("node " + std::to_string(i) + ": matrix has " + std::to_string(node.matrix.size()) +
                    " values, expected 16");
      }
      if (node.translation.size() == 3) p.translation = {node.translation[0], node.translation[1], node.translation[2]};
      if (node.scale.size() == 3) p.scale = {node.scale[0], node.scale[1], node.scale[2]};
      if (node.rotation.size() == 4)
        p.rotation = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    }
    return true;
  }

  bool applyAnimation(int animationIndex, double time) {
    const tinygltf::Animation& animation = model_.animations[size_t(animationIndex)];
    const std::string where = "animation " + std::to_string(animationIndex) + " ('" + animation.name + "')";
    // Inputs of every sampler, read once: they also give the duration.
    std::vector<std::vector<double>> inputs(animation.samplers.size());
    double duration = 0.0;
    for (size_t s = 0; s < animation.samplers.size(); ++s) {
      const std::string what = where + " sampler " + std::to_string(s) + " input";
      std::optional<AccessorValues> input = read(animation.samplers[s].input, what, 1);
      if (!input) return false;
      if (input->count == 0) return fail(what + ": no keyframes");
      for (size_t k = 1; k < input->count; ++k)
        if (input->values[k] < input->values[k - 1])
          return fail(what + ": keyframe time " + std::to_string(input->values[k]) + " (key " + std::to_string(k) +
                      ") is before the previous one");
      duration = std::max(duration, input->values.back());
      inputs[s] = std::move(input->values);
    }
    const double t = duration > 0.0 ? std::fmod(time, duration) : 0.0;

    for (size_t c = 0; c < animation.channels.size(); ++c) {
      const tinygltf::AnimationChannel& channel = animation.channels[c];
      const std::string what = where + " channel " + std::to_string(c);
      if (channel.target_node < 0) continue;  // the spec: a channel without a node is ignored
      if (size_t(channel.target_node) >= model_.nodes.size())
        return fail(what + ": target node " + std::to_string(channel.target_node) + " is out of range");
      if (channel.sampler < 0 || size_t(channel.sampler) >= animation.samplers.size())
        return fail(what + ": sampler " + std::to_string(channel.sampler) + " is out of range");
      const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
      Interpolation interpolation;
      if (sampler.interpolation.empty() || sampler.interpolation == "LINEAR") interpolation = Interpolation::Linear;
      else if (sampler.interpolation == "STEP")
        interpolation = Interpolation::Step;
      else if (sampler.interpolation == "CUBICSPLINE")
        interpolation = Interpolation::CubicSpline;
      else
        return fail(what + ": unknown interpolation '" + sampler.interpolation + "'");

      const std::string& path = channel.target_path;
      const size_t expectedWidth = path == "translation" || path == "scale" ? 3 : path == "rotation" ? 4 : 0;
      if (expectedWidth == 0 && path != "weights")
        return fail(what + ": target path '" + path + "' is not supported (translation, rotation, scale, weights)");
      std::optional<AccessorValues> output = read(sampler.output, what + " output", 0);
      if (!output) return false;
      const std::vector<double>& times = inputs[size_t(channel.sampler)];
      const size_t perKey = (interpolation == Interpolation::CubicSpline ? 3 : 1) * times.size();
      const size_t width = output->values.size() / perKey;
      if (width == 0 || width * perKey != output->values.size() || (expectedWidth && width != expectedWidth))
        return fail(what + ": output has " + std::to_string(output->values.size()) + " values for " +
                    std::to_string(times.size()) + " keys of " + sampler.interpolation + " " + path);

      LocalPose& pose = poses_[size_t(channel.target_node)];
      if (pose.hasMatrix && path != "weights")
        return fail(what + ": node " + std::to_string(channel.target_node) +
                    " has a matrix, which the spec forbids for animated nodes");
      const std::vector<double> v = sampleKeyframes(times, output->values, width, interpolation, path == "rotation", t);
      if (path == "translation") pose.translation = {v[0], v[1], v[2]};
      else if (path == "scale")
        pose.scale = {v[0], v[1], v[2]};
      else if (path == "rotation")
        pose.rotation = glm::dquat(v[3], v[0], v[1], v[2]);
      else {
        pose.weightsAnimated = true;
        pose.weights = v;
      }
    }
    return true;
  }

  // World transforms of all nodes (joints may lie outside the scene), parents before children.
  bool computeWorlds() {
    const size_t n = model_.nodes.size();
    world_.assign(n, glm::dmat4(1.0));
    std::vector<bool> done(n, false);
    std::vector<int> stack;
    for (size_t i = 0; i < n; ++i)
      if (parent_[i] == -1) stack.push_back(int(i));
    while (!stack.empty()) {
      const int node = stack.back();
      stack.pop_back();
      const int parent = parent_[size_t(node)];
      world_[size_t(node)] = (parent >= 0 ? world_[size_t(parent)] : glm::dmat4(1.0)) * poses_[size_t(node)].local();
      done[size_t(node)] = true;
      for (int child : model_.nodes[size_t(node)].children) stack.push_back(child);
    }
    for (size_t i = 0; i < n; ++i)
      if (!done[i]) return fail("node " + std::to_string(i) + " is part of a cycle in the node hierarchy");
    return true;
  }

  bool sceneRoots(std::vector<int>& roots) {
    const int sceneCount = int(model_.scenes.size());
    if (model_.defaultScene >= sceneCount)
      return fail("default scene " + std::to_string(model_.defaultScene) + " is out of range (" +
                  std::to_string(sceneCount) + " scenes)");
    if (sceneCount > 0) {
      roots = model_.scenes[size_t(model_.defaultScene >= 0 ? model_.defaultScene : 0)].nodes;
      for (int r : roots)
        if (r < 0 || size_t(r) >= model_.nodes.size())
          return fail("scene root node " + std::to_string(r) + " is out of range");
      return true;
    }
    for (size_t i = 0; i < model_.nodes.size(); ++i)
      if (parent_[i] == -1) roots.push_back(int(i));
    return true;
  }

  bool visit(int nodeIndex, std::vector<PosedPrimitive>& out) {
    const tinygltf::Node& node = model_.nodes[size_t(nodeIndex)];
    if (node.mesh >= 0) {
      if (size_t(node.mesh) >= model_.meshes.size())
        return fail("node " + std::to_string(nodeIndex) + ": mesh " + std::to_string(node.mesh) + " is out of range");
      std::vector<glm::dmat4> joints;
      if (node.skin >= 0 && !jointMatrices(nodeIndex, joints)) return false;
      const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
      for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const int mode = mesh.primitives[p].mode;
        if (mode != -1 && mode != TINYGLTF_MODE_TRIANGLES) continue;
        PosedPrimitive posed;
        posed.node = nodeIndex;
        posed.mesh = node.mesh;
        posed.primitive = int(p);
        posed.nodeWorld = world_[size_t(nodeIndex)];
        if (!posePrimitive(mesh.primitives[p], node.skin >= 0 ? &joints : nullptr, posed)) return false;
        out.push_back(std::move(posed));
      }
    }
    for (int child : node.children)
      if (!visit(child, out)) return false;
    return true;
  }

  // jointMatrix[j] = world(joint j) * inverseBindMatrix[j] (spec 3.7.3.3); the mesh node's own transform is
  // not part of it, as the spec says.
  bool jointMatrices(int nodeIndex, std::vector<glm::dmat4>& joints) {
    const int skinIndex = model_.nodes[size_t(nodeIndex)].skin;
    const std::string what = "node " + std::to_string(nodeIndex) + " skin " + std::to_string(skinIndex);
    if (size_t(skinIndex) >= model_.skins.size()) return fail(what + " is out of range");
    const tinygltf::Skin& skin = model_.skins[size_t(skinIndex)];
    std::optional<AccessorValues> ibm;
    if (skin.inverseBindMatrices >= 0) {
      ibm = read(skin.inverseBindMatrices, what + " inverseBindMatrices", 16);
      if (!ibm) return false;
      if (ibm->count < skin.joints.size())
        return fail(what + ": " + std::to_string(ibm->count) + " inverse bind matrices for " +
                    std::to_string(skin.joints.size()) + " joints");
    }
    joints.resize(skin.joints.size());
    for (size_t j = 0; j < skin.joints.size(); ++j) {
      const int jointNode = skin.joints[j];
      if (jointNode < 0 || size_t(jointNode) >= model_.nodes.size())
        return fail(what + ": joint " + std::to_string(j) + " names node " + std::to_string(jointNode) +
                    ", out of range");
      glm::dmat4 inverseBind(1.0);
      if (ibm)
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) inverseBind[c][r] = ibm->at(j, c * 4 + r);
      joints[j] = world_[size_t(jointNode)] * inverseBind;
    }
    return true;
  }

  // Morph weights in the spec's order of precedence: animated, node, mesh, zeros.
  bool morphWeights(int nodeIndex, size_t targetCount, const std::string& what, std::vector<double>& weights) {
    const tinygltf::Node& node = model_.nodes[size_t(nodeIndex)];
    const LocalPose& pose = poses_[size_t(nodeIndex)];
    const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
    if (pose.weightsAnimated) weights = pose.weights;
    else if (!node.weights.empty())
      weights = node.weights;
    else if (!mesh.weights.empty())
      weights = mesh.weights;
    else
      weights.assign(targetCount, 0.0);
    if (weights.size() != targetCount)
      return fail(what + ": " + std::to_string(weights.size()) + " morph weights (" +
                  (pose.weightsAnimated    ? "animated"
                   : !node.weights.empty() ? "node"
                                           : "mesh") +
                  ") for " + std::to_string(targetCount) + " morph targets");
    return true;
  }

  bool posePrimitive(const tinygltf::Primitive& prim, const std::vector<glm::dmat4>* joints, PosedPrimitive& posed) {
    const std::string what = "node " + std::to_string(posed.node) + " mesh " + std::to_string(posed.mesh) +
                             " primitive " + std::to_string(posed.primitive);
    auto attribute = [&](const std::map<std::string, int>& attrs, const char* name) {
      auto it = attrs.find(name);
      return it == attrs.end() ? -1 : it->second;
    };
    const int positionAccessor = attribute(prim.attributes, "POSITION");
    if (positionAccessor < 0) return fail(what + ": no POSITION attribute");
    size_t n = 0;  // the vertex count, set by the POSITION read
    auto readVec3 = [&](int accessor, const std::string& name) -> std::optional<std::vector<glm::dvec3>> {
      std::optional<AccessorValues> v = read(accessor, what + " " + name, 3);
      if (!v) return std::nullopt;
      if (name == "POSITION") n = v->count;
      if (v->count != n) {
        fail(what + " " + name + ": " + std::to_string(v->count) + " elements for " + std::to_string(n) + " vertices");
        return std::nullopt;
      }
      std::vector<glm::dvec3> r(n);
      for (size_t i = 0; i < n; ++i) r[i] = {v->at(i, 0), v->at(i, 1), v->at(i, 2)};
      return r;
    };
    std::optional<std::vector<glm::dvec3>> pos = readVec3(positionAccessor, "POSITION");
    if (!pos) return false;
    std::optional<std::vector<glm::dvec3>> nrm;
    if (int a = attribute(prim.attributes, "NORMAL"); a >= 0 && !(nrm = readVec3(a, "NORMAL"))) return false;

    // Morph targets first (spec 3.7.2.2): p = base + sum_k w_k * delta_k.
    if (!prim.targets.empty()) {
      std::vector<double> weights;
      if (!morphWeights(posed.node, prim.targets.size(), what, weights)) return false;
      for (size_t k = 0; k < prim.targets.size(); ++k) {
        const std::string target = "morph target " + std::to_string(k);
        if (int a = attribute(prim.targets[k], "POSITION"); a >= 0) {
          std::optional<std::vector<glm::dvec3>> d = readVec3(a, target + " POSITION");
          if (!d) return false;
          for (size_t i = 0; i < n; ++i) (*pos)[i] += weights[k] * (*d)[i];
        }
        if (int a = attribute(prim.targets[k], "NORMAL"); a >= 0 && nrm) {
          std::optional<std::vector<glm::dvec3>> d = readVec3(a, target + " NORMAL");
          if (!d) return false;
          for (size_t i = 0; i < n; ++i) (*nrm)[i] += weights[k] * (*d)[i];
        }
      }
    }

    // Per-vertex transform: the weight-blended joint matrix, or the node's world transform.
    std::vector<glm::dmat4> vertexMatrix(n, posed.nodeWorld);
    if (joints && !blendJoints(prim, *joints, what, n, vertexMatrix)) return false;

    auto safeNormalize = [](glm::dvec3 v) { return glm::length(v) > 0.0 ? glm::normalize(v) : v; };
    const glm::dmat4 toLocal = glm::inverse(posed.nodeWorld);
    posed.worldPositions.resize(n);
    posed.localPositions.resize(n);
    if (nrm) posed.worldNormals.resize(n);
    for (size_t i = 0; i < n; ++i) {
      posed.worldPositions[i] = glm::dvec3(vertexMatrix[i] * glm::dvec4((*pos)[i], 1.0));
      posed.localPositions[i] = glm::dvec3(toLocal * glm::dvec4(posed.worldPositions[i], 1.0));
      if (nrm)
        posed.worldNormals[i] = safeNormalize(glm::inverseTranspose(glm::dmat3(vertexMatrix[i])) *
                                              safeNormalize((*nrm)[i]));
    }

    if (prim.indices >= 0) {
      std::optional<AccessorValues> idx = read(prim.indices, what + " indices", 1);
      if (!idx) return false;
      posed.indices.resize(idx->count);
      for (size_t i = 0; i < idx->count; ++i) {
        if (idx->values[i] >= double(n))
          return fail(what + ": index " + std::to_string(uint64_t(idx->values[i])) + " (entry " + std::to_string(i) +
                      ") is >= the vertex count " + std::to_string(n));
        posed.indices[i] = uint32_t(idx->values[i]);
      }
    } else {
      posed.indices.resize(n);
      for (size_t i = 0; i < n; ++i) posed.indices[i] = uint32_t(i);
    }
    return true;
  }

  // Linear-blend skinning matrices: sum_i w_i * jointMatrix[j_i] over JOINTS_0/WEIGHTS_0 and
  // JOINTS_1/WEIGHTS_1.
  bool blendJoints(const tinygltf::Primitive& prim, const std::vector<glm::dmat4>& joints, const std::string& what,
                   size_t n, std::vector<glm::dmat4>& out) {
    if (prim.attributes.count("JOINTS_2") || prim.attributes.count("WEIGHTS_2"))
      return fail(what + ": JOINTS_2/WEIGHTS_2 (more than 8 influences) are not supported");
    std::vector<AccessorValues> jointSets, weightSets;
    for (int set = 0; set < 2; ++set) {
      const std::string j = "JOINTS_" + std::to_string(set), w = "WEIGHTS_" + std::to_string(set);
      auto ji = prim.attributes.find(j), wi = prim.attributes.find(w);
      if (ji == prim.attributes.end() && wi == prim.attributes.end()) {
        if (set == 0) return fail(what + ": skinned (its node has a skin) but has no JOINTS_0/WEIGHTS_0");
        break;
      }
      if (ji == prim.attributes.end() || wi == prim.attributes.end())
        return fail(what + ": has one of " + j + " and " + w + " without the other");
      std::optional<AccessorValues> jv = read(ji->second, what + " " + j, 4);
      std::optional<AccessorValues> wv = jv ? read(wi->second, what + " " + w, 4) : std::nullopt;
      if (!wv) return false;
      if (jv->count != n || wv->count != n)
        return fail(what + ": " + j + "/" + w + " have " + std::to_string(jv->count) + "/" + std::to_string(wv->count) +
                    " elements for " + std::to_string(n) + " vertices");
      jointSets.push_back(std::move(*jv));
      weightSets.push_back(std::move(*wv));
    }
    for (size_t v = 0; v < n; ++v) {
      glm::dmat4 m(0.0);
      bool anyWeight = false;
      for (size_t set = 0; set < jointSets.size(); ++set)
        for (int i = 0; i < 4; ++i) {
          const double joint = jointSets[set].at(v, i), weight = weightSets[set].at(v, i);
          if (joint >= double(joints.size()))
            return fail(what + ": vertex " + std::to_string(v) + " JOINTS_" + std::to_string(set) + "[" +
                        std::to_string(i) + "] = joint index " + std::to_string(uint64_t(joint)) +
                        ", which is >= the skin's joint count " + std::to_string(joints.size()));
          if (weight != 0.0) anyWeight = true;
          m += weight * joints[size_t(joint)];
        }
      if (!anyWeight)
        return fail(what + ": vertex " + std::to_string(v) + " has all skinning weights zero (WEIGHTS_0" +
                    (jointSets.size() > 1 ? " and WEIGHTS_1" : "") + ")");
      out[v] = m;
    }
    return true;
  }

  const tinygltf::Model& model_;
  std::string error_;
  std::vector<int> parent_;
  std::vector<LocalPose> poses_;
  std::vector<glm::dmat4> world_;
};

}  // namespace

std::optional<std::vector<PosedPrimitive>> poseGltf(const std::string& path, int animation, double time,
                                                    std::string* error) {
  tinygltf::Model model;
  std::string e;
  std::vector<PosedPrimitive> out;
  if (loadModel(path, model, e)) {
    Poser poser(model);
    if (poser.pose(animation, time, out)) return out;
    e = "poseGltf(" + path + "): " + poser.error();
  } else {
    e = "poseGltf: " + e;
  }
  if (error) *error = e;
  return std::nullopt;
}

std::vector<std::string> animationNames(const std::string& path) {
  tinygltf::Model model;
  std::string e;
  std::vector<std::string> names;
  if (loadModel(path, model, e))
    for (const tinygltf::Animation& a : model.animations) names.push_back(a.name);
  return names;
}

}  // namespace pose_reference

// Animation evaluation in double precision (the results are rounded to float once, at the end), so that deep
// hierarchies and skinning matrices stay as exact as the data allows.
#include "sample_engine/animation.h"

#include "keyframes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <unordered_map>

#include <glm/gtc/type_ptr.hpp>

namespace sample_engine {
namespace {

using detail::KeyLocation;
using detail::locate;
using detail::sample;

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

std::string meshName(const Scene& scene, uint32_t m) {
  return "mesh " + std::to_string(m) + " '" + scene.meshes[m].name + "'";
}

uint32_t pathWidth(AnimationPath path) {
  switch (path) {
    case AnimationPath::Translation:
    case AnimationPath::Scale: return 3;
    case AnimationPath::Rotation: return 4;
    case AnimationPath::Weights: return 0;  // decided by the data
  }
  return 0;
}

// Keys x floats per key of a sampler driving `path`; 0 when inconsistent.
uint32_t samplerWidth(const AnimationSampler& s, AnimationPath path) {
  const size_t keys = s.times.size(), perKey = s.interpolation == AnimationInterpolation::CubicSpline ? 3 : 1;
  if (keys == 0 || s.values.size() % (keys * perKey) != 0) return 0;
  const uint32_t width = uint32_t(s.values.size() / (keys * perKey));
  const uint32_t expected = pathWidth(path);
  return expected == 0 || width == expected ? width : 0;
}

std::string checkMeshDeformation(const Scene& scene, uint32_t m, const Instance& inst, size_t instanceIndex) {
  const MeshData& mesh = scene.meshes[m];
  const size_t n = mesh.positions.size();
  for (const MorphTarget& t : mesh.morphTargets)
    for (const auto* d : {&t.positionDeltas, &t.normalDeltas})
      if (!d->empty() && d->size() != n)
        return meshName(scene, m) + ": a morph target has " + std::to_string(d->size()) + " deltas for " +
               std::to_string(n) + " vertices";
  if (inst.skin < 0) return {};
  const std::string where = "instance " + std::to_string(instanceIndex) + " (" + meshName(scene, m) + ", skin " +
                            std::to_string(inst.skin) + " '" + scene.skins[size_t(inst.skin)].name + "')";
  if (!mesh.skinned()) return where + ": the mesh has no joints0/weights0 to skin with";
  if (mesh.joints0.size() != n || mesh.weights0.size() != n)
    return where + ": joints0/weights0 have " + std::to_string(mesh.joints0.size()) + "/" +
           std::to_string(mesh.weights0.size()) + " entries for " + std::to_string(n) + " vertices";
  const bool eight = !mesh.joints1.empty() || !mesh.weights1.empty();
  if (eight && (mesh.joints1.size() != n || mesh.weights1.size() != n))
    return where + ": joints1/weights1 have " + std::to_string(mesh.joints1.size()) + "/" +
           std::to_string(mesh.weights1.size()) + " entries for " + std::to_string(n) + " vertices";
  const size_t jointCount = scene.skins[size_t(inst.skin)].joints.size();
  for (size_t v = 0; v < n; ++v) {
    double sum = 0.0;
    for (int set = 0; set < (eight ? 2 : 1); ++set) {
      const glm::u16vec4 j = set ? mesh.joints1[v] : mesh.joints0[v];
      const glm::vec4 w = set ? mesh.weights1[v] : mesh.weights0[v];
      for (int k = 0; k < 4; ++k) {
        if (j[k] >= jointCount)
          return where + ", vertex " + std::to_string(v) + ": joint index " + std::to_string(j[k]) +
                 " is out of range (the skin has " + std::to_string(jointCount) + " joints)";
        if (!(w[k] >= 0.0f))
          return where + ", vertex " + std::to_string(v) + ": weight " + number(w[k]) + " is negative or NaN";
        sum += w[k];
      }
    }
    if (!(sum > 1e-6))
      return where + ", vertex " + std::to_string(v) + ": skin weights sum to " + number(sum) + "; they must sum to 1";
  }
  return {};
}

}  // namespace

Status checkPlayback(const Scene& scene, double time, std::span<const AnimationPlayback> animations) {
  if (!std::isfinite(time) || time < 0.0)
    return Status::failure("FrameParams::time = " + number(time) + ": it must be finite and >= 0 (seconds)");
  for (size_t i = 0; i < animations.size(); ++i) {
    const AnimationPlayback& p = animations[i];
    if (p.animation < scene.animations.size() && std::isfinite(p.timeOffset)) continue;  // no allocation when valid
    const std::string field = "FrameParams::animations[" + std::to_string(i) + "]";
    if (p.animation >= scene.animations.size())
      return Status::failure(field + ".animation = " + std::to_string(p.animation) +
                             " is out of range: the scene has " + std::to_string(scene.animations.size()) +
                             " animations: " + scene.describeAnimations());
    if (!std::isfinite(p.timeOffset))
      return Status::failure(field + ".timeOffset = " + number(p.timeOffset) + ": it must be finite");
  }
  return Status::success();
}

double animationLocalTime(double time, double duration) {
  if (!(duration > 0.0) || !std::isfinite(time)) return 0.0;
  double t = std::fmod(time, duration);
  if (t < 0.0) t += duration;
  return t;
}

Status ScenePose::reset(const Scene& scene) {
  ready_ = false;
  const size_t nodeCount = scene.nodes.size();
  // --- Hierarchy: parents in range, no cycles; order parents first ---
  for (size_t n = 0; n < nodeCount; ++n) {
    const int p = scene.nodes[n].parent;
    if (p < -1 || p >= int(nodeCount))
      return Status::failure("node " + std::to_string(n) + " '" + scene.nodes[n].name + "': parent " +
                             std::to_string(p) + " is out of range (the scene has " + std::to_string(nodeCount) +
                             " nodes)");
  }
  std::vector<int> depth(nodeCount, -1);
  for (size_t n = 0; n < nodeCount; ++n) {
    // Walk up to a node of known depth; a walk longer than the node count is a cycle.
    size_t steps = 0;
    int at = int(n);
    while (at >= 0 && depth[size_t(at)] < 0) {
      at = scene.nodes[size_t(at)].parent;
      if (++steps > nodeCount)
        return Status::failure("node " + std::to_string(n) + " '" + scene.nodes[n].name +
                               "': its parent chain is a cycle");
    }
    int d = at >= 0 ? depth[size_t(at)] : -1;
    std::vector<int> chain;
    for (int c = int(n); c >= 0 && depth[size_t(c)] < 0; c = scene.nodes[size_t(c)].parent) chain.push_back(c);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) depth[size_t(*it)] = ++d;
  }
  order_.resize(nodeCount);
  for (size_t n = 0; n < nodeCount; ++n) order_[n] = uint32_t(n);
  std::stable_sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) { return depth[a] < depth[b]; });

  // --- Skins ---
  for (size_t s = 0; s < scene.skins.size(); ++s) {
    const Skin& skin = scene.skins[s];
    const std::string where = "skin " + std::to_string(s) + " '" + skin.name + "'";
    for (uint32_t j : skin.joints)
      if (j >= nodeCount)
        return Status::failure(where + ": joint node " + std::to_string(j) + " is out of range (the scene has " +
                               std::to_string(nodeCount) + " nodes)");
    if (!skin.inverseBindMatrices.empty() && skin.inverseBindMatrices.size() != skin.joints.size())
      return Status::failure(where + ": " + std::to_string(skin.inverseBindMatrices.size()) +
                             " inverse bind matrices for " + std::to_string(skin.joints.size()) + " joints");
  }

  // --- Animations ---
  durations_.assign(scene.animations.size(), 0.0);
  size_t widest = 4;
  for (size_t a = 0; a < scene.animations.size(); ++a) {
    const Animation& anim = scene.animations[a];
    const std::string where = "animation " + std::to_string(a) + " '" + anim.name + "'";
    double maxTime = 0.0;
    for (size_t s = 0; s < anim.samplers.size(); ++s) {
      const AnimationSampler& smp = anim.samplers[s];
      if (smp.times.empty()) return Status::failure(where + ", sampler " + std::to_string(s) + ": no keys");
      for (size_t k = 0; k < smp.times.size(); ++k)
        if (!std::isfinite(smp.times[k]) || (k > 0 && smp.times[k] < smp.times[k - 1]))
          return Status::failure(where + ", sampler " + std::to_string(s) + ": key time " + std::to_string(k) + " = " +
                                 number(smp.times[k]) + " is not finite or decreases");
      maxTime = std::max(maxTime, double(smp.times.back()));
    }
    for (size_t c = 0; c < anim.channels.size(); ++c) {
      const AnimationChannel& ch = anim.channels[c];
      const std::string at = where + ", channel " + std::to_string(c);
      if (ch.node >= nodeCount)
        return Status::failure(at + ": node " + std::to_string(ch.node) + " is out of range (the scene has " +
                               std::to_string(nodeCount) + " nodes)");
      if (ch.sampler >= anim.samplers.size())
        return Status::failure(at + ": sampler " + std::to_string(ch.sampler) + " is out of range (" +
                               std::to_string(anim.samplers.size()) + " samplers)");
      if (samplerWidth(anim.samplers[ch.sampler], ch.path) == 0)
        return Status::failure(at + ": sampler " + std::to_string(ch.sampler) + " has " +
                               std::to_string(anim.samplers[ch.sampler].values.size()) + " values for " +
                               std::to_string(anim.samplers[ch.sampler].times.size()) +
                               " keys, which does not fit the animated property");
      widest = std::max<size_t>(widest, samplerWidth(anim.samplers[ch.sampler], ch.path));
    }
    durations_[a] = anim.duration > 0.0f ? double(anim.duration) : maxTime;
  }
  samplerBase_.assign(scene.animations.size() + 1, 0);
  groupBase_.assign(scene.animations.size() + 1, 0);
  samplerGroup_.clear();
  groupSampler_.clear();
  for (size_t a = 0; a < scene.animations.size(); ++a) {
    const Animation& anim = scene.animations[a];
    samplerBase_[a] = uint32_t(samplerGroup_.size());
    groupBase_[a] = uint32_t(groupSampler_.size());
    for (size_t s = 0; s < anim.samplers.size(); ++s) {
      uint32_t group = uint32_t(groupSampler_.size());
      for (uint32_t g = groupBase_[a]; g < groupSampler_.size(); ++g)
        if (anim.samplers[groupSampler_[g] - samplerBase_[a]].times == anim.samplers[s].times) {
          group = g;
          break;
        }
      if (group == groupSampler_.size()) groupSampler_.push_back(uint32_t(samplerGroup_.size()));
      samplerGroup_.push_back(group);
    }
  }
  samplerBase_.back() = uint32_t(samplerGroup_.size());
  // Equal samplers (appendScene copies of one character) are read from one copy: K characters then share
  // a cache-sized working set instead of K copies of the key data.
  canonical_.assign(samplerGroup_.size(), nullptr);
  std::unordered_map<uint64_t, std::vector<const AnimationSampler*>> byHash;
  for (size_t a = 0; a < scene.animations.size(); ++a)
    for (size_t sm = 0; sm < scene.animations[a].samplers.size(); ++sm) {
      const AnimationSampler& smp = scene.animations[a].samplers[sm];
      // A cheap key (sizes and a few samples of the data); equality is then checked in full.
      uint64_t h = 1469598103934665603ull ^ uint64_t(smp.interpolation);
      auto mix = [&h](const std::vector<float>& data) {
        h = (h ^ data.size()) * 1099511628211ull;
        for (size_t i = 0; i < data.size(); i += data.size() / 8 + 1) {
          uint32_t bits;
          std::memcpy(&bits, &data[i], 4);
          h = (h ^ bits) * 1099511628211ull;
        }
      };
      mix(smp.times);
      mix(smp.values);
      const AnimationSampler*& out = canonical_[samplerBase_[a] + sm];
      for (const AnimationSampler* c : byHash[h])
        if (c->interpolation == smp.interpolation && c->times == smp.times && c->values == smp.values) out = c;
      if (!out) {
        out = &smp;
        byHash[h].push_back(&smp);
      }
    }
  groupBase_.back() = uint32_t(groupSampler_.size());
  groupLocation_.assign(groupSampler_.size(), KeyLocation{});

  // --- Instances, per-node weight storage, packed joint / weight ranges ---
  nodeWeightCount_.assign(nodeCount, 0);
  for (size_t n = 0; n < nodeCount; ++n) nodeWeightCount_[n] = uint32_t(scene.nodes[n].weights.size());
  ranges_.assign(scene.instances.size(), InstanceRange{});
  jointGroups_.clear();
  std::map<std::pair<int, int>, uint32_t> jointGroupOf;  // (node, skin) -> jointGroups_ index
  uint32_t jointTotal = 0, weightTotal = 0;
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    const std::string where = "instance " + std::to_string(i);
    if (inst.mesh >= scene.meshes.size())
      return Status::failure(where + ": mesh " + std::to_string(inst.mesh) + " is out of range (the scene has " +
                             std::to_string(scene.meshes.size()) + " meshes)");
    if (inst.node < -1 || inst.node >= int(nodeCount))
      return Status::failure(where + ": node " + std::to_string(inst.node) + " is out of range (the scene has " +
                             std::to_string(nodeCount) + " nodes)");
    if (inst.skin < -1 || inst.skin >= int(scene.skins.size()))
      return Status::failure(where + ": skin " + std::to_string(inst.skin) + " is out of range (the scene has " +
                             std::to_string(scene.skins.size()) + " skins)");
    if (std::string e = checkMeshDeformation(scene, inst.mesh, inst, i); !e.empty()) return Status::failure(e);
    const MeshData& mesh = scene.meshes[inst.mesh];
    InstanceRange& r = ranges_[i];
    if (inst.skin >= 0) {
      // Instances on the same node with the same skin (the primitives of one skinned glTF mesh) share their
      // matrices: computed and uploaded once.
      r.jointCount = uint32_t(scene.skins[size_t(inst.skin)].joints.size());
      auto shared = inst.node >= 0 ? jointGroupOf.find({inst.node, inst.skin}) : jointGroupOf.end();
      if (shared != jointGroupOf.end()) {
        r.jointOffset = jointGroups_[shared->second].offset;
      } else {
        r.jointOffset = jointTotal;
        jointTotal += r.jointCount;
        if (inst.node >= 0) jointGroupOf[{inst.node, inst.skin}] = uint32_t(jointGroups_.size());
        jointGroups_.push_back({uint32_t(i), r.jointOffset});
      }
    }
    if (mesh.morphed()) {
      r.weightOffset = weightTotal;
      r.weightCount = uint32_t(mesh.morphTargets.size());
      weightTotal += r.weightCount;
      if (inst.node >= 0)
        nodeWeightCount_[size_t(inst.node)] = std::max(nodeWeightCount_[size_t(inst.node)], r.weightCount);
    }
  }
  nodeWeightOffset_.resize(nodeCount);
  uint32_t nodeWeightTotal = 0;
  for (size_t n = 0; n < nodeCount; ++n) {
    nodeWeightOffset_[n] = nodeWeightTotal;
    nodeWeightTotal += nodeWeightCount_[n];
  }
  nodeWeights_.assign(nodeWeightTotal, 0.0);
  scratch_.assign(widest, 0.0);
  translation_.resize(nodeCount);
  scale_.resize(nodeCount);
  rotation_.resize(nodeCount);
  nodeWorld_.resize(nodeCount);
  nodeWorldF_.resize(nodeCount);
  instanceWorldF_.resize(scene.instances.size());
  joints_.assign(jointTotal, glm::mat4(1.0f));
  weights_.assign(weightTotal, 0.0f);
  nodeCount_ = nodeCount;
  instanceCount_ = scene.instances.size();
  animationCount_ = scene.animations.size();
  ready_ = true;
  return Status::success();
}

Status ScenePose::evaluate(const Scene& scene, double time, std::span<const AnimationPlayback> animations,
                           bool restPose) {
  if (Status s = checkPlayback(scene, time, animations); !s) return s;
  if (!ready_ || scene.nodes.size() != nodeCount_ || scene.instances.size() != instanceCount_ ||
      scene.animations.size() != animationCount_)
    return Status::failure("ScenePose::evaluate: the scene differs from the one given to reset()");

  // Rest pose.
  for (size_t n = 0; n < nodeCount_; ++n) {
    const Node& node = scene.nodes[n];
    translation_[n] = glm::dvec3(node.translation);
    rotation_[n] = glm::dquat(node.rotation);
    scale_[n] = glm::dvec3(node.scale);
    double* w = nodeWeights_.data() + nodeWeightOffset_[n];
    for (uint32_t k = 0; k < nodeWeightCount_[n]; ++k) w[k] = k < node.weights.size() ? node.weights[k] : 0.0;
  }

  // Channels. Empty list = the first animation at `time`.
  const AnimationPlayback first{};
  std::span<const AnimationPlayback> playing = animations;
  if (playing.empty() && !scene.animations.empty()) playing = std::span<const AnimationPlayback>(&first, 1);
  if (restPose) playing = {};
  double* values = scratch_.data();
  for (const AnimationPlayback& p : playing) {
    const Animation& anim = scene.animations[p.animation];
    const double t = animationLocalTime(time + p.timeOffset, durations_[p.animation]);
    // Samplers with the same key times (usually all of an animation's) are located once.
    const uint32_t firstSampler = samplerBase_[p.animation];
    for (uint32_t g = groupBase_[p.animation]; g < groupBase_[p.animation + 1]; ++g) {
      groupLocation_[g] = locate(canonical_[groupSampler_[g]]->times, t, groupLocation_[g].k1);
    }
    for (const AnimationChannel& ch : anim.channels) {
      const Node& node = scene.nodes[ch.node];
      if (node.matrix) continue;  // glTF: animated nodes have TRS
      const AnimationSampler& smp = *canonical_[firstSampler + ch.sampler];
      const KeyLocation& at = groupLocation_[samplerGroup_[firstSampler + ch.sampler]];
      switch (ch.path) {
        case AnimationPath::Translation:
          sample(smp, 3, false, at, values);
          translation_[ch.node] = glm::dvec3(values[0], values[1], values[2]);
          break;
        case AnimationPath::Scale:
          sample(smp, 3, false, at, values);
          scale_[ch.node] = glm::dvec3(values[0], values[1], values[2]);
          break;
        case AnimationPath::Rotation:
          sample(smp, 4, true, at, values);
          rotation_[ch.node] = glm::dquat(values[3], values[0], values[1], values[2]);
          break;
        case AnimationPath::Weights: {
          // The sampler may be wider than the node's storage: only the targets its meshes have are kept.
          const uint32_t width = samplerWidth(smp, ch.path);
          sample(smp, width, false, at, scratch_.data());
          double* w = nodeWeights_.data() + nodeWeightOffset_[ch.node];
          for (uint32_t k = 0; k < std::min(width, nodeWeightCount_[ch.node]); ++k) w[k] = scratch_[k];
          break;
        }
      }
    }
  }

  // World transforms, parents first.
  for (uint32_t n : order_) {
    const Node& node = scene.nodes[n];
    glm::dmat4 local;
    if (node.matrix) {
      local = glm::dmat4(*node.matrix);
    } else {  // T * R * S, composed directly
      const glm::dmat3 r = glm::mat3_cast(rotation_[n]);
      local = glm::dmat4(glm::dvec4(r[0] * scale_[n].x, 0.0), glm::dvec4(r[1] * scale_[n].y, 0.0),
                         glm::dvec4(r[2] * scale_[n].z, 0.0), glm::dvec4(translation_[n], 1.0));
    }
    nodeWorld_[n] = node.parent >= 0 ? nodeWorld_[size_t(node.parent)] * local : local;
    nodeWorldF_[n] = glm::mat4(nodeWorld_[n]);
  }

  // Skinning matrices, once per joint group.
  for (const JointGroup& g : jointGroups_) {
    const Instance& inst = scene.instances[g.instance];
    const Skin& skin = scene.skins[size_t(inst.skin)];
    const glm::dmat4 toLocal = glm::inverse(inst.node >= 0 ? nodeWorld_[size_t(inst.node)]
                                                           : glm::dmat4(inst.transform));
    for (size_t j = 0; j < skin.joints.size(); ++j) {
      glm::dmat4 m = toLocal * nodeWorld_[skin.joints[j]];
      if (!skin.inverseBindMatrices.empty()) m = m * glm::dmat4(skin.inverseBindMatrices[j]);
      joints_[g.offset + j] = glm::mat4(m);
    }
  }

  // Instances: transforms, morph weights.
  for (size_t i = 0; i < instanceCount_; ++i) {
    const Instance& inst = scene.instances[i];
    instanceWorldF_[i] = inst.node >= 0 ? nodeWorldF_[size_t(inst.node)] : inst.transform;
    const InstanceRange& r = ranges_[i];
    if (r.weightCount > 0) {
      const MeshData& mesh = scene.meshes[inst.mesh];
      float* out = weights_.data() + r.weightOffset;
      for (uint32_t k = 0; k < r.weightCount; ++k) {
        if (inst.node >= 0) out[k] = float(nodeWeights_[nodeWeightOffset_[size_t(inst.node)] + k]);
        else
          out[k] = k < mesh.morphWeights.size() ? mesh.morphWeights[k] : 0.0f;
      }
    }
  }
  return Status::success();
}

std::span<const glm::mat4> ScenePose::jointMatrices(uint32_t instance) const {
  if (instance >= ranges_.size() || ranges_[instance].jointCount == 0) return {};
  return std::span<const glm::mat4>(joints_).subspan(ranges_[instance].jointOffset, ranges_[instance].jointCount);
}

std::span<const float> ScenePose::morphWeights(uint32_t instance) const {
  if (instance >= ranges_.size() || ranges_[instance].weightCount == 0) return {};
  return std::span<const float>(weights_).subspan(ranges_[instance].weightOffset, ranges_[instance].weightCount);
}

uint32_t ScenePose::jointOffset(uint32_t instance) const {
  return instance < ranges_.size() ? ranges_[instance].jointOffset : UINT32_MAX;
}

uint32_t ScenePose::weightOffset(uint32_t instance) const {
  return instance < ranges_.size() ? ranges_[instance].weightOffset : UINT32_MAX;
}

}  // namespace sample_engine

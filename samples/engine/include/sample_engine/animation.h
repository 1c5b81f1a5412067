// CPU evaluation of a Scene's animation (glTF 2.0 semantics): node hierarchy, TRS / weights channels with
// LINEAR, STEP and CUBICSPLINE samplers, linear-blend skinning matrices and morph weights. The engine runs
// it once per frame (FrameParams::time / animations / restPose); tools can run it on their own.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "sample_engine/result.h"
#include "sample_engine/scene.h"

namespace sample_engine {

// Fails, naming the value, when `time` is negative, NaN or infinite, when an entry's animation index is not
// one of scene.animations (the message lists them) or its timeOffset is not finite.
Status checkPlayback(const Scene& scene, double time, std::span<const AnimationPlayback> animations);

// Seconds into `animation` at `time`: time looped over `duration` (the positive remainder); 0 when the
// duration is 0.
double animationLocalTime(double time, double duration);

// The pose of one scene at one time. reset() sizes it (allocates); evaluate() does not allocate.
// Not thread-safe: one thread at a time per object; distinct objects are independent.
class ScenePose {
 public:
  struct KeyLocation {        // where a time falls among a sampler's keys
    uint32_t k0 = 0, k1 = 0;  // surrounding keys (equal outside the key range)
    double s = 0.0;           // fraction from k0 to k1
  };

  // Checks the scene's nodes (parents in range, no cycles), skins, animations and the node / skin of every
  // instance (a skinned instance's mesh has per-vertex joints below its skin's joint count, weights summing to
  // more than 0), failing with a message that names the bad value; then sizes the pose for it.
  Status reset(const Scene& scene);

  // Evaluates `scene` (the one given to reset(), unchanged since) at `time` seconds: the playing animations
  // (empty = the first one, if any, at `time`; each at time + timeOffset, looping over its own duration;
  // applied in order, later channels overriding earlier ones), none when `restPose`. Fails like checkPlayback().
  Status evaluate(const Scene& scene, double time, std::span<const AnimationPlayback> animations, bool restPose);

  // World transform per Scene::nodes entry.
  std::span<const glm::mat4> nodeWorld() const { return nodeWorldF_; }
  // World transform per Scene::instances entry: its node's world transform, else Instance::transform.
  std::span<const glm::mat4> instanceTransforms() const { return instanceWorldF_; }
  // Skinning matrices of instance `i`, one per joint of its skin, in the instance's local space:
  // inverse(instance world) * joint world * inverse bind matrix. Empty for an instance that is not skinned.
  std::span<const glm::mat4> jointMatrices(uint32_t instance) const;
  // Morph weights of instance `i`, one per morph target of its mesh (its node's weights, else the mesh's
  // defaults). Empty for a mesh without morph targets.
  std::span<const float> morphWeights(uint32_t instance) const;
  // Every skinned instance's jointMatrices() back to back, in instance order (instances with the same node and
  // skin share one copy), and every morphed instance's morphWeights(): the layout the engine uploads.
  // jointOffset() / weightOffset() give an instance's first entry (UINT32_MAX for none).
  std::span<const glm::mat4> packedJointMatrices() const { return joints_; }
  std::span<const float> packedMorphWeights() const { return weights_; }
  uint32_t jointOffset(uint32_t instance) const;
  uint32_t weightOffset(uint32_t instance) const;

 private:
  struct InstanceRange {
    uint32_t jointOffset = UINT32_MAX, jointCount = 0;
    uint32_t weightOffset = UINT32_MAX, weightCount = 0;
  };

  std::vector<uint32_t> order_;  // node indices, parents before children
  // Samplers with equal key times form a group, located once per playback and frame (flat over animations).
  std::vector<uint32_t> samplerBase_, groupBase_;   // per animation (+1): first sampler / group
  std::vector<uint32_t> samplerGroup_;              // per sampler: its group
  std::vector<uint32_t> groupSampler_;              // per group: its first sampler (flat index)
  std::vector<KeyLocation> groupLocation_;          // per group: this frame's location (and next frame's hint)
  std::vector<const AnimationSampler*> canonical_;  // per sampler: the first equal one in the scene
  std::vector<double> durations_;
  std::vector<glm::dvec3> translation_, scale_;
  std::vector<glm::dquat> rotation_;
  std::vector<uint32_t> nodeWeightOffset_, nodeWeightCount_;
  std::vector<double> nodeWeights_;
  std::vector<double> scratch_;  // one sampled value (the widest sampler's width)
  std::vector<glm::dmat4> nodeWorld_;
  std::vector<glm::mat4> nodeWorldF_, instanceWorldF_, joints_;
  std::vector<float> weights_;
  struct JointGroup {       // skinned instances sharing a node and a skin share their matrices
    uint32_t instance = 0;  // the first of them
    uint32_t offset = 0;    // into joints_
  };
  std::vector<InstanceRange> ranges_;
  std::vector<JointGroup> jointGroups_;
  size_t nodeCount_ = 0, instanceCount_ = 0, animationCount_ = 0;
  bool ready_ = false;
};

}  // namespace sample_engine

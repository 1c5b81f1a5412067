// Small generated glTF test models, each written as a self-contained .gltf with an embedded base64 buffer.
// Their exact numbers (node layout, key times and values, which vertex is bad) are in
// gltf_fixture_constants.h. Each writer returns "" on success or an error naming the path. Thread-safe when
// the paths differ.
#pragma once

#include <string>

namespace pose_reference {

// A 3-bone skinned strip (42 vertices), every vertex with 8 influences (JOINTS_0/WEIGHTS_0 and
// JOINTS_1/WEIGHTS_1), an animation "bend" with three channels: rotation LINEAR, translation STEP and
// scale CUBICSPLINE, duration 2 s.
std::string writeSkinnedStrip(const std::string& path);
// A cube (24 vertices) with 2 morph targets (POSITION and NORMAL deltas), default mesh weights {0.25, 0},
// and an animation "morph" on weights: LINEAR over 0..1 s (node 0), then CUBICSPLINE over 1..2 s (node 1: a
// second instance of the same mesh, since one animation may target a node's weights only once).
std::string writeMorphCube(const std::string& path);
// Bad inputs: like writeSkinnedStrip, but a JOINTS_0 entry equals the skin's joint count (out of range) /
// the WEIGHTS_0 and WEIGHTS_1 of vertex 5 are all zero.
std::string writeSkinnedStripBadJoint(const std::string& path);
std::string writeSkinnedStripZeroWeights(const std::string& path);

}  // namespace pose_reference

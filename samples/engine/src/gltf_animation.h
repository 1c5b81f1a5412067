// glTF nodes, skins and animations into Scene::nodes / skins / animations (indices kept: Scene node i is
// glTF node i). Each returns an error message naming the bad value, empty on success.
#pragma once

#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "sample_engine/scene.h"

namespace sample_engine::detail {

std::string convertNodes(const tinygltf::Model& model, Scene& scene);
std::string convertSkins(const tinygltf::Model& model, Scene& scene);
std::string convertAnimations(const tinygltf::Model& model, Scene& scene, std::vector<std::string>& warnings);

}  // namespace sample_engine::detail

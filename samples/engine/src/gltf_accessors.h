// Reading glTF accessors (dense and sparse) into flat arrays, with messages that name the accessor.
#pragma once

#include <string>
#include <vector>

#include <tiny_gltf.h>

namespace sample_engine::detail {

// The accessor as `components` floats per element (normalized integers mapped to [0,1] / [-1,1]), sparse
// substitutions applied. Returns an error message naming the accessor, empty on success.
std::string readFloats(const tinygltf::Model& model, int accessorIndex, int components, std::vector<float>& out);
// The accessor as `components` per element, however many it has (0 = all of them).
std::string readAllFloats(const tinygltf::Model& model, int accessorIndex, std::vector<float>& out, int& components);
std::string readIndices(const tinygltf::Model& model, int accessorIndex, std::vector<uint32_t>& out);

}  // namespace sample_engine::detail

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
// The accessor's indices; it must be SCALAR UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT (glTF 3.7.2.1).
std::string readIndices(const tinygltf::Model& model, int accessorIndex, std::vector<uint32_t>& out);
// "VEC3 FLOAT", "VEC4 normalized UNSIGNED_BYTE", ...: an accessor's format for messages.
std::string formatName(const tinygltf::Accessor& accessor);

}  // namespace sample_engine::detail

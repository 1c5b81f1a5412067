// Reads glTF accessors into doubles, following the glTF 2.0 spec (section 3.6.2) rather than any engine's
// loader. Internal to the pose reference (tests may use it to read raw attributes). Thread-safe: pure
// functions.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <tiny_gltf.h>

namespace pose_reference {

// One accessor's elements as doubles, element-major (`components` values per element, `count` elements).
// Normalized integer accessors are converted to [0,1] / [-1,1] as the spec's "normalized" rules say; other
// integer accessors (indices, JOINTS_n) keep their integer values. Matrices are column-major, padding
// dropped.
struct AccessorValues {
  std::vector<double> values;
  size_t count = 0;
  int components = 0;  // 1 for SCALAR, 2..4 for VECn, 4/9/16 for MATn
  double at(size_t element, int component) const { return values[element * size_t(components) + size_t(component)]; }
};

// Handles byteStride, a missing bufferView (all zeros, as sparse accessors allow) and sparse substitution.
// Returns std::nullopt and sets *error (naming the accessor and the bad value) on out-of-range indices, reads
// past a buffer view, or unknown component types / types.
std::optional<AccessorValues> readAccessor(const tinygltf::Model& model, int accessorIndex, std::string* error);

}  // namespace pose_reference

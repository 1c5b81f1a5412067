// Assembles a small glTF 2.0 document whose single buffer is embedded as a base64 data URI, for the fixtures.
// Internal to the pose reference. Not thread-safe (one builder per document).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace pose_reference {

class GltfDocumentBuilder {
 public:
  GltfDocumentBuilder();

  // Appends `bytes` (4-byte aligned) as a new bufferView; `target` 0 = none (animation and sparse data).
  int addBufferView(const void* data, size_t bytes, int target);
  // An accessor over a whole bufferView (-1 = none, zeros) with optional per-component min/max (POSITION and
  // animation inputs require them).
  int addAccessor(int bufferView, int componentType, size_t count, const char* type, bool normalized = false,
                  const std::vector<double>& min = {}, const std::vector<double>& max = {});
  // Float data in one call: `components` per element, min/max computed when `bounds`.
  int addFloats(const std::vector<float>& values, int components, int target, bool bounds = false);
  template <typename T>
  int addIntegers(const std::vector<T>& values, int components, int componentType, int target, bool normalized) {
    const int view = addBufferView(values.data(), values.size() * sizeof(T), target);
    return addAccessor(view, componentType, values.size() / size_t(components), typeName(components), normalized);
  }

  nlohmann::json& document() { return doc_; }   // the caller adds nodes, meshes, skins, animations
  static const char* typeName(int components);  // 1 -> SCALAR, 2..4 -> VECn, 16 -> MAT4

  // Adds the buffer and writes the file; "" or an error naming the path.
  std::string write(const std::string& path);

 private:
  nlohmann::json doc_;
  std::vector<uint8_t> bytes_;
};

}  // namespace pose_reference

// Checks of a glTF file before tinygltf parses it: the .glb container, the JSON syntax, and the parts of the
// document that tinygltf takes on trust or drops without a word (an index of the wrong type, negative, fractional
// or out of range; a buffer view past its buffer, which tinygltf hands to the image decoder unchecked; a data: URI
// of the wrong size; extras nested deep enough to overflow tinygltf's recursive copy of them). Each function
// returns an error naming the member (as a JSON path such as nodes[2].mesh) and the value, empty on success.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include <nlohmann/json.hpp>

namespace sample_engine::detail {

// The deepest JSON nesting a glTF may have (the document itself needs about 8 levels; extras may add more).
// tinygltf copies extras and extensions recursively, so a deeper file could overflow the stack.
inline constexpr size_t kMaxGltfJsonDepth = 128;

struct GlbChunks {
  std::span<const uint8_t> json;
  std::optional<std::span<const uint8_t>> bin;  // absent when the file has no BIN chunk
};

// Splits a .glb into its JSON and BIN chunks, checking the header (magic, version 2, length = the file's size)
// and that each chunk lies inside the file.
std::string splitGlb(std::span<const uint8_t> bytes, GlbChunks& out);

// Parses JSON text; a failure names where (JSON path, line and column) and why (nlohmann's message), including
// a number too large for a double (such as 1e999, the only way JSON can write a non-finite value).
std::string parseJson(std::span<const uint8_t> text, nlohmann::json& out);

// The document checks listed above. `bin`: the .glb's BIN chunk size (nullopt for .gltf or a .glb without one).
std::string checkDocument(const nlohmann::json& doc, bool binary, std::optional<size_t> bin);

}  // namespace sample_engine::detail

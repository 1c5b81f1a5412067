// The fixtures' glTF writer: JSON through nlohmann, binary data packed into one base64 buffer.
#include "gltf_document_builder.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <limits>

namespace pose_reference {
namespace {

std::string base64(const std::vector<uint8_t>& data) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((data.size() + 2) / 3 * 4);
  for (size_t i = 0; i < data.size(); i += 3) {
    const uint32_t b0 = data[i], b1 = i + 1 < data.size() ? data[i + 1] : 0, b2 = i + 2 < data.size() ? data[i + 2] : 0;
    const uint32_t triple = (b0 << 16) | (b1 << 8) | b2;
    out += alphabet[(triple >> 18) & 63];
    out += alphabet[(triple >> 12) & 63];
    out += i + 1 < data.size() ? alphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < data.size() ? alphabet[triple & 63] : '=';
  }
  return out;
}

}  // namespace

GltfDocumentBuilder::GltfDocumentBuilder() {
  doc_["asset"] = {{"version", "2.0"}, {"generator", "raybridge pose_reference fixtures"}};
  doc_["bufferViews"] = nlohmann::json::array();
  doc_["accessors"] = nlohmann::json::array();
}

const char* GltfDocumentBuilder::typeName(int components) {
  switch (components) {
    case 1: return "SCALAR";
    case 2: return "VEC2";
    case 3: return "VEC3";
    case 4: return "VEC4";
    default: return "MAT4";
  }
}

int GltfDocumentBuilder::addBufferView(const void* data, size_t bytes, int target) {
  bytes_.resize((bytes_.size() + 3) / 4 * 4, 0);  // accessor offsets must be multiples of the component size
  const size_t offset = bytes_.size();
  bytes_.resize(offset + bytes);
  std::memcpy(bytes_.data() + offset, data, bytes);
  nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
  if (target != 0) view["target"] = target;
  doc_["bufferViews"].push_back(view);
  return int(doc_["bufferViews"].size()) - 1;
}

int GltfDocumentBuilder::addAccessor(int bufferView, int componentType, size_t count, const char* type, bool normalized,
                                     const std::vector<double>& min, const std::vector<double>& max) {
  nlohmann::json a = {{"componentType", componentType}, {"count", count}, {"type", type}};
  if (bufferView >= 0) a["bufferView"] = bufferView;
  if (normalized) a["normalized"] = true;
  if (!min.empty()) a["min"] = min;
  if (!max.empty()) a["max"] = max;
  doc_["accessors"].push_back(a);
  return int(doc_["accessors"].size()) - 1;
}

int GltfDocumentBuilder::addFloats(const std::vector<float>& values, int components, int target, bool bounds) {
  const int view = addBufferView(values.data(), values.size() * sizeof(float), target);
  std::vector<double> lo, hi;
  if (bounds) {
    lo.assign(size_t(components), std::numeric_limits<double>::max());
    hi.assign(size_t(components), std::numeric_limits<double>::lowest());
    for (size_t i = 0; i < values.size(); ++i) {
      lo[i % size_t(components)] = std::min(lo[i % size_t(components)], double(values[i]));
      hi[i % size_t(components)] = std::max(hi[i % size_t(components)], double(values[i]));
    }
  }
  return addAccessor(view, 5126 /* FLOAT */, values.size() / size_t(components), typeName(components), false, lo, hi);
}

std::string GltfDocumentBuilder::write(const std::string& path) {
  doc_["buffers"] = nlohmann::json::array(
      {{{"byteLength", bytes_.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes_)}}});
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) return "cannot open " + path + " for writing";
  file << doc_.dump(1) << '\n';
  if (!file) return "cannot write " + path;
  return "";
}

}  // namespace pose_reference

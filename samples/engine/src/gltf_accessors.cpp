#include "gltf_accessors.h"

#include <algorithm>
#include <cstring>

namespace sample_engine::detail {
namespace {

float readComponent(const uint8_t* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float f;
      std::memcpy(&f, p, 4);
      return f;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0f : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      float v = static_cast<int8_t>(p[0]);
      return normalized ? std::max(v / 127.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0f : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0f, -1.0f) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return float(v);
    }
    default: return 0.0f;
  }
}

// Locates `count` elements of `elementSize` bytes, `stride` apart, at `offset` in buffer view `viewIndex`.
std::string viewData(const tinygltf::Model& model, int viewIndex, size_t offset, size_t count, size_t elementSize,
                     size_t stride, const uint8_t*& out) {
  if (viewIndex < 0 || viewIndex >= int(model.bufferViews.size()))
    return "buffer view " + std::to_string(viewIndex) + " is out of range (the file has " +
           std::to_string(model.bufferViews.size()) + ")";
  const tinygltf::BufferView& view = model.bufferViews[size_t(viewIndex)];
  if (view.buffer < 0 || view.buffer >= int(model.buffers.size()))
    return "buffer " + std::to_string(view.buffer) + " of buffer view " + std::to_string(viewIndex) +
           " is out of range";
  const tinygltf::Buffer& buffer = model.buffers[size_t(view.buffer)];
  const size_t base = view.byteOffset + offset;
  if (count > 0 && base + stride * (count - 1) + elementSize > buffer.data.size())
    return "reads past the end of its buffer (" + std::to_string(buffer.data.size()) + " bytes)";
  out = buffer.data.data() + base;
  return {};
}

std::string read(const tinygltf::Model& model, int accessorIndex, int components, std::vector<float>& out,
                 int& outComponents) {
  if (accessorIndex < 0 || accessorIndex >= int(model.accessors.size()))
    return "accessor " + std::to_string(accessorIndex) + " is out of range (the file has " +
           std::to_string(model.accessors.size()) + ")";
  const std::string name = "accessor " + std::to_string(accessorIndex);
  const tinygltf::Accessor& acc = model.accessors[size_t(accessorIndex)];
  const int have = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  if (have <= 0) return name + ": unknown type " + std::to_string(acc.type);
  if (components == 0) components = have;
  if (have < components)
    return name + " has " + std::to_string(have) + " components, need " + std::to_string(components);
  const int compSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (compSize <= 0) return name + ": bad component type " + std::to_string(acc.componentType);
  outComponents = components;
  out.assign(acc.count * size_t(components), 0.0f);
  const size_t elementSize = size_t(compSize) * size_t(have);
  if (acc.bufferView >= 0) {  // without one, the base values are zeros (glTF)
    const tinygltf::BufferView* view = acc.bufferView < int(model.bufferViews.size())
                                           ? &model.bufferViews[size_t(acc.bufferView)]
                                           : nullptr;
    const size_t stride = view && view->byteStride ? view->byteStride : elementSize;
    const uint8_t* data = nullptr;
    if (std::string e = viewData(model, acc.bufferView, acc.byteOffset, acc.count, elementSize, stride, data);
        !e.empty())
      return name + ": " + e;
    for (size_t i = 0; i < acc.count; ++i)
      for (int c = 0; c < components; ++c)
        out[i * size_t(components) + size_t(c)] = readComponent(data + i * stride + size_t(c) * size_t(compSize),
                                                                acc.componentType, acc.normalized);
  }
  if (acc.sparse.isSparse) {
    const size_t count = size_t(std::max(acc.sparse.count, 0));
    const int indexSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.sparse.indices.componentType));
    if (indexSize != 1 && indexSize != 2 && indexSize != 4) return name + ": bad sparse index component type";
    const uint8_t* indices = nullptr;
    const uint8_t* values = nullptr;
    if (std::string e = viewData(model, acc.sparse.indices.bufferView, size_t(acc.sparse.indices.byteOffset), count,
                                 size_t(indexSize), size_t(indexSize), indices);
        !e.empty())
      return name + " (sparse indices): " + e;
    if (std::string e = viewData(model, acc.sparse.values.bufferView, size_t(acc.sparse.values.byteOffset), count,
                                 elementSize, elementSize, values);
        !e.empty())
      return name + " (sparse values): " + e;
    for (size_t i = 0; i < count; ++i) {
      uint32_t index = 0;
      if (indexSize == 1) index = indices[i];
      else if (indexSize == 2) {
        uint16_t v;
        std::memcpy(&v, indices + i * 2, 2);
        index = v;
      } else
        std::memcpy(&index, indices + i * 4, 4);
      if (index >= acc.count)
        return name + ": sparse index " + std::to_string(index) + " is out of range (count " +
               std::to_string(acc.count) + ")";
      for (int c = 0; c < components; ++c)
        out[size_t(index) * size_t(components) + size_t(c)] =
            readComponent(values + i * elementSize + size_t(c) * size_t(compSize), acc.componentType, acc.normalized);
    }
  }
  return {};
}

}  // namespace

std::string readFloats(const tinygltf::Model& model, int accessorIndex, int components, std::vector<float>& out) {
  int ignored = 0;
  return read(model, accessorIndex, components, out, ignored);
}

std::string readAllFloats(const tinygltf::Model& model, int accessorIndex, std::vector<float>& out, int& components) {
  return read(model, accessorIndex, 0, out, components);
}

std::string readIndices(const tinygltf::Model& model, int accessorIndex, std::vector<uint32_t>& out) {
  if (accessorIndex < 0 || accessorIndex >= int(model.accessors.size()))
    return "index accessor " + std::to_string(accessorIndex) + " is out of range";
  const tinygltf::Accessor& acc = model.accessors[size_t(accessorIndex)];
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (size != 1 && size != 2 && size != 4) return "unsupported index component type";
  if (acc.bufferView < 0 || acc.sparse.isSparse) {
    // Rare for indices; the float path handles both exactly up to 2^24 vertices.
    std::vector<float> f;
    if (std::string e = readFloats(model, accessorIndex, 1, f); !e.empty()) return e;
    out.resize(f.size());
    for (size_t i = 0; i < f.size(); ++i) out[i] = uint32_t(f[i]);
    return {};
  }
  const tinygltf::BufferView* view = acc.bufferView < int(model.bufferViews.size())
                                         ? &model.bufferViews[size_t(acc.bufferView)]
                                         : nullptr;
  const size_t stride = view && view->byteStride ? view->byteStride : size_t(size);
  const uint8_t* data = nullptr;
  if (std::string e = viewData(model, acc.bufferView, acc.byteOffset, acc.count, size_t(size), stride, data);
      !e.empty())
    return "index accessor " + std::to_string(accessorIndex) + ": " + e;
  out.resize(acc.count);
  for (size_t i = 0; i < acc.count; ++i) {
    const uint8_t* p = data + i * stride;
    if (size == 1) out[i] = p[0];
    else if (size == 2) {
      uint16_t v;
      std::memcpy(&v, p, 2);
      out[i] = v;
    } else
      std::memcpy(&out[i], p, 4);
  }
  return {};
}

}  // namespace sample_engine::detail

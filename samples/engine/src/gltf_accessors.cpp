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

// offset + (count - 1) * stride + elementSize <= limit, without overflow (counts come from the file).
bool fits(size_t offset, size_t count, size_t stride, size_t elementSize, size_t limit) {
  if (count == 0) return offset <= limit;
  size_t end = 0;
  return !__builtin_mul_overflow(count - 1, stride, &end) && !__builtin_add_overflow(end, elementSize, &end) &&
         !__builtin_add_overflow(end, offset, &end) && end <= limit;
}

// Locates `count` elements of `elementSize` bytes, `stride` apart, at `offset` in buffer view `viewIndex`. Checked
// against the view's byteLength (and the view against its buffer) before anything is read or allocated.
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
  if (!fits(view.byteOffset, 1, 0, view.byteLength, buffer.data.size()))
    return "buffer view " + std::to_string(viewIndex) + " (byteOffset " + std::to_string(view.byteOffset) +
           ", byteLength " + std::to_string(view.byteLength) + ") ends past its buffer's " +
           std::to_string(buffer.data.size()) + " bytes";
  if (!fits(offset, count, stride, elementSize, view.byteLength))
    return std::to_string(count) + " elements of " + std::to_string(elementSize) + " bytes, " + std::to_string(stride) +
           " apart from byteOffset " + std::to_string(offset) + ", reach past buffer view " +
           std::to_string(viewIndex) + " (byteLength " + std::to_string(view.byteLength) + ")";
  out = buffer.data.data() + view.byteOffset + offset;
  return {};
}

// The buffer view's layout for elements of `elementSize` bytes of `componentSize`-byte components: the stride,
// or an error (a stride shorter than an element, data not aligned to its components as glTF requires).
std::string layout(const tinygltf::Model& model, const tinygltf::Accessor& acc, size_t elementSize,
                   size_t componentSize, size_t& stride) {
  const tinygltf::BufferView& view = model.bufferViews[size_t(acc.bufferView)];  // in range: viewData checks first
  stride = view.byteStride ? view.byteStride : elementSize;
  if (stride < elementSize)
    return "buffer view " + std::to_string(acc.bufferView) + "'s byteStride " + std::to_string(stride) +
           " is shorter than the accessor's " + std::to_string(elementSize) + "-byte elements";
  if ((view.byteOffset + acc.byteOffset) % componentSize != 0)
    return "its data starts at byte " + std::to_string(view.byteOffset + acc.byteOffset) + " of its buffer (view " +
           "byteOffset " + std::to_string(view.byteOffset) + " + accessor byteOffset " +
           std::to_string(acc.byteOffset) + "), not a multiple of its " + std::to_string(componentSize) +
           "-byte components";
  return {};
}

// An accessor without a buffer view is all zeros (plus sparse values), so its count costs no bytes in the file;
// the loader refuses one with more elements than the file's buffers hold bytes rather than allocate for it.
size_t bufferBytes(const tinygltf::Model& model) {
  size_t total = 0;
  for (const tinygltf::Buffer& b : model.buffers) total += b.data.size();
  return total;
}

bool glTFComponentType(int componentType) {
  return (componentType >= TINYGLTF_COMPONENT_TYPE_BYTE && componentType <= TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) ||
         componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT || componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
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
  if (compSize <= 0 || !glTFComponentType(acc.componentType))
    return name + ": bad component type " + std::to_string(acc.componentType);
  outComponents = components;
  const size_t elementSize = size_t(compSize) * size_t(have);
  // Every size is checked against the data before the output is allocated: a count of 2^31 must fail, not
  // allocate.
  const uint8_t* data = nullptr;
  size_t stride = elementSize;
  if (acc.bufferView >= 0) {  // without one, the base values are zeros (glTF)
    if (std::string e = viewData(model, acc.bufferView, 0, 0, elementSize, elementSize, data); !e.empty())
      return name + ": " + e;
    if (std::string e = layout(model, acc, elementSize, size_t(compSize), stride); !e.empty()) return name + ": " + e;
    if (std::string e = viewData(model, acc.bufferView, acc.byteOffset, acc.count, elementSize, stride, data);
        !e.empty())
      return name + ": " + e;
  } else if (const size_t limit = bufferBytes(model); acc.count > limit) {
    return name + " has no buffer view (all zeros) and count " + std::to_string(acc.count) +
           ", more elements than the file's buffers hold bytes (" + std::to_string(limit) + "); refused";
  }
  const size_t sparseCount = acc.sparse.isSparse ? size_t(std::max(acc.sparse.count, 0)) : 0;
  if (acc.sparse.isSparse && (acc.sparse.count < 1 || sparseCount > acc.count))
    return name + ": sparse count " + std::to_string(acc.sparse.count) + " is not from 1 to the accessor's count " +
           std::to_string(acc.count);
  out.assign(acc.count * size_t(components), 0.0f);
  if (data) {
    for (size_t i = 0; i < acc.count; ++i)
      for (int c = 0; c < components; ++c)
        out[i * size_t(components) + size_t(c)] = readComponent(data + i * stride + size_t(c) * size_t(compSize),
                                                                acc.componentType, acc.normalized);
  }
  if (acc.sparse.isSparse) {
    const size_t count = sparseCount;
    const int indexSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.sparse.indices.componentType));
    if (indexSize != 1 && indexSize != 2 && indexSize != 4) return name + ": bad sparse index component type";
    const uint8_t* indices = nullptr;
    const uint8_t* values = nullptr;
    if (acc.sparse.indices.byteOffset < 0 || acc.sparse.values.byteOffset < 0)
      return name + ": negative sparse byteOffset";
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

std::string formatName(const tinygltf::Accessor& acc) {
  std::string type;
  switch (acc.type) {
    case TINYGLTF_TYPE_SCALAR: type = "SCALAR"; break;
    case TINYGLTF_TYPE_VEC2: type = "VEC2"; break;
    case TINYGLTF_TYPE_VEC3: type = "VEC3"; break;
    case TINYGLTF_TYPE_VEC4: type = "VEC4"; break;
    case TINYGLTF_TYPE_MAT2: type = "MAT2"; break;
    case TINYGLTF_TYPE_MAT3: type = "MAT3"; break;
    case TINYGLTF_TYPE_MAT4: type = "MAT4"; break;
    default: type = "type " + std::to_string(acc.type);
  }
  const char* component = "?";
  switch (acc.componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: component = "BYTE"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: component = "UNSIGNED_BYTE"; break;
    case TINYGLTF_COMPONENT_TYPE_SHORT: component = "SHORT"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: component = "UNSIGNED_SHORT"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: component = "UNSIGNED_INT"; break;
    case TINYGLTF_COMPONENT_TYPE_FLOAT: component = "FLOAT"; break;
    default: return type + " of component type " + std::to_string(acc.componentType);
  }
  return type + " " + (acc.normalized ? "normalized " : "") + component;
}

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
  const std::string name = "index accessor " + std::to_string(accessorIndex);
  if (acc.type != TINYGLTF_TYPE_SCALAR || acc.normalized ||
      (acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
       acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
       acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
    return name + " is " + formatName(acc) + "; indices must be SCALAR UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT";
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (acc.bufferView < 0 || acc.sparse.isSparse) {
    // Rare for indices; the float path handles both exactly up to 2^24 vertices.
    std::vector<float> f;
    if (std::string e = readFloats(model, accessorIndex, 1, f); !e.empty()) return e;
    out.resize(f.size());
    for (size_t i = 0; i < f.size(); ++i) out[i] = uint32_t(f[i]);
    return {};
  }
  const uint8_t* data = nullptr;
  size_t stride = size_t(size);
  if (std::string e = viewData(model, acc.bufferView, 0, 0, stride, stride, data); !e.empty()) return name + ": " + e;
  if (std::string e = layout(model, acc, size_t(size), size_t(size), stride); !e.empty()) return name + ": " + e;
  if (std::string e = viewData(model, acc.bufferView, acc.byteOffset, acc.count, size_t(size), stride, data);
      !e.empty())
    return name + ": " + e;
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

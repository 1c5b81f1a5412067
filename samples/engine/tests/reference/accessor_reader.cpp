// glTF accessor decoding: component types, normalization, strides, matrix column padding and sparse
// accessors.
#include "accessor_reader.h"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace pose_reference {
namespace {

int componentSize(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// Columns and rows of the accessor type (VECn is one column of n rows).
bool typeShape(int type, int& columns, int& rows) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: columns = 1, rows = 1; return true;
    case TINYGLTF_TYPE_VEC2: columns = 1, rows = 2; return true;
    case TINYGLTF_TYPE_VEC3: columns = 1, rows = 3; return true;
    case TINYGLTF_TYPE_VEC4: columns = 1, rows = 4; return true;
    case TINYGLTF_TYPE_MAT2: columns = 2, rows = 2; return true;
    case TINYGLTF_TYPE_MAT3: columns = 3, rows = 3; return true;
    case TINYGLTF_TYPE_MAT4: columns = 4, rows = 4; return true;
    default: return false;
  }
}

template <typename T>
T load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));  // buffers need not be aligned for T
  return v;
}

// The spec's normalization formulas (3.11, "Animations" and 3.6.2.3): signed values clamp at -1.
double decode(const unsigned char* p, int componentType, bool normalized) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      double c = load<int8_t>(p);
      return normalized ? std::max(c / 127.0, -1.0) : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      double c = load<uint8_t>(p);
      return normalized ? c / 255.0 : c;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      double c = load<int16_t>(p);
      return normalized ? std::max(c / 32767.0, -1.0) : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      double c = load<uint16_t>(p);
      return normalized ? c / 65535.0 : c;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      double c = load<uint32_t>(p);
      return normalized ? c / 4294967295.0 : c;
    }
    default: return double(load<float>(p));
  }
}

// Bytes [offset, offset + size) of buffer view `viewIndex`, or nullptr with *error set.
const unsigned char* viewBytes(const tinygltf::Model& model, int viewIndex, size_t offset, size_t size,
                               const std::string& what, std::string* error) {
  if (viewIndex < 0 || size_t(viewIndex) >= model.bufferViews.size()) {
    *error = what + ": bufferView " + std::to_string(viewIndex) + " is out of range (the file has " +
             std::to_string(model.bufferViews.size()) + ")";
    return nullptr;
  }
  const tinygltf::BufferView& view = model.bufferViews[size_t(viewIndex)];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) {
    *error = what + ": bufferView " + std::to_string(viewIndex) + " names buffer " + std::to_string(view.buffer) +
             ", out of range (the file has " + std::to_string(model.buffers.size()) + ")";
    return nullptr;
  }
  const std::vector<unsigned char>& data = model.buffers[size_t(view.buffer)].data;
  if (view.byteOffset + view.byteLength > data.size() || offset + size > view.byteLength) {
    *error = what + ": needs bytes up to " + std::to_string(offset + size) + " of bufferView " +
             std::to_string(viewIndex) + ", which has " + std::to_string(view.byteLength) + " (buffer holds " +
             std::to_string(data.size()) + " bytes from offset " + std::to_string(view.byteOffset) + ")";
    return nullptr;
  }
  return data.data() + view.byteOffset + offset;
}

}  // namespace

std::optional<AccessorValues> readAccessor(const tinygltf::Model& model, int accessorIndex, std::string* error) {
  if (accessorIndex < 0 || size_t(accessorIndex) >= model.accessors.size()) {
    *error = "accessor " + std::to_string(accessorIndex) + " is out of range (the file has " +
             std::to_string(model.accessors.size()) + ")";
    return std::nullopt;
  }
  const tinygltf::Accessor& acc = model.accessors[size_t(accessorIndex)];
  const std::string what = "accessor " + std::to_string(accessorIndex);
  int columns = 0, rows = 0;
  const int csize = componentSize(acc.componentType);
  if (!typeShape(acc.type, columns, rows) || csize == 0) {
    *error = what + ": unsupported type " + std::to_string(acc.type) + " / componentType " +
             std::to_string(acc.componentType);
    return std::nullopt;
  }
  // Matrix columns start on 4-byte boundaries (spec 3.6.2.4); for VECn and 4-byte matrices this is a no-op.
  const size_t columnStride = columns > 1 ? (size_t(rows * csize) + 3) / 4 * 4 : size_t(rows * csize);
  const size_t elementSize = columnStride * size_t(columns);

  AccessorValues out;
  out.count = acc.count;
  out.components = columns * rows;
  out.values.assign(acc.count * size_t(out.components), 0.0);  // no bufferView: zeros (sparse base)

  auto decodeElement = [&](const unsigned char* p, size_t element) {
    for (int c = 0; c < columns; ++c)
      for (int r = 0; r < rows; ++r)
        out.values[element * size_t(out.components) + size_t(c * rows + r)] =
            decode(p + size_t(c) * columnStride + size_t(r * csize), acc.componentType, acc.normalized);
  };

  if (acc.bufferView >= 0 && acc.count > 0) {
    const size_t viewStride = size_t(acc.bufferView) < model.bufferViews.size()
                                  ? model.bufferViews[size_t(acc.bufferView)].byteStride
                                  : 0;
    const size_t stride = viewStride ? viewStride : elementSize;
    const unsigned char* base = viewBytes(model, acc.bufferView, acc.byteOffset, stride * (acc.count - 1) + elementSize,
                                          what, error);
    if (!base) return std::nullopt;
    for (size_t i = 0; i < acc.count; ++i) decodeElement(base + i * stride, i);
  }

  if (acc.sparse.isSparse && acc.sparse.count > 0) {
    const size_t n = size_t(acc.sparse.count);
    const int indexType = acc.sparse.indices.componentType;
    const int isize = componentSize(indexType);
    if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
      *error = what + ": sparse indices have componentType " + std::to_string(indexType) +
               ", expected 5121, 5123 or 5125 (unsigned integers)";
      return std::nullopt;
    }
    const unsigned char* indices = viewBytes(model, acc.sparse.indices.bufferView,
                                             size_t(acc.sparse.indices.byteOffset), n * size_t(isize),
                                             what + " (sparse indices)", error);
    if (!indices) return std::nullopt;
    const unsigned char* values = viewBytes(model, acc.sparse.values.bufferView, size_t(acc.sparse.values.byteOffset),
                                            n * elementSize, what + " (sparse values)", error);
    if (!values) return std::nullopt;
    for (size_t i = 0; i < n; ++i) {
      const double index = decode(indices + i * size_t(isize), indexType, false);
      if (index >= double(acc.count)) {
        *error = what + ": sparse index " + std::to_string(size_t(index)) + " (entry " + std::to_string(i) +
                 ") is >= the accessor's count " + std::to_string(acc.count);
        return std::nullopt;
      }
      decodeElement(values + i * elementSize, size_t(index));
    }
  }
  return out;
}

}  // namespace pose_reference

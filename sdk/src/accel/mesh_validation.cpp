#include "mesh_validation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "content_hash.h"
#include "context_impl.h"

namespace rb {

uint32_t vertexFormatSize(VkFormat format) {
  switch (format) {
    case VK_FORMAT_R32G32B32_SFLOAT: return 12;
    case VK_FORMAT_R32G32_SFLOAT: return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    case VK_FORMAT_R16G16B16A16_SFLOAT: return 8;
    case VK_FORMAT_R16G16_SFLOAT: return 4;
    case VK_FORMAT_R16G16B16A16_SNORM: return 8;
    case VK_FORMAT_R16G16_SNORM: return 4;
    case VK_FORMAT_R8G8B8A8_SNORM: return 4;
    default: return 0;
  }
}

Status checkBounds(const MeshBounds& b) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(b.min[i]) || !std::isfinite(b.max[i]) || b.min[i] > b.max[i]) {
      return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                   "bounds: axis " + std::to_string(i) + " has min " + std::to_string(b.min[i]) + " and max " +
                       std::to_string(b.max[i]) +
                       "; give finite values with min <= max (the object-space box of the vertices), or all zero "
                       "when the box is unknown"};
    }
  }
  return {};
}

namespace {

// The box of MeshDesc::bounds, else the one of hostVertices when its positions are 32-bit floats, else none
// (all zero). Host pointers are only read here and by the content hash, during registerMesh.
Status resolveBounds(const MeshDesc& in, MeshBounds& out, uint64_t vertexBytes) {
  out = {};
  if (in.bounds.given()) {
    if (Status st = checkBounds(in.bounds); !st) return st;
    out = in.bounds;
    return {};
  }
  const VkFormat format = in.vertexFormat == VK_FORMAT_UNDEFINED ? VK_FORMAT_R32G32B32_SFLOAT : in.vertexFormat;
  if (!in.hostVertices || in.vertexCount == 0 ||
      (format != VK_FORMAT_R32G32B32_SFLOAT && format != VK_FORMAT_R32G32B32A32_SFLOAT)) {
    return {};
  }
  const uint32_t stride = in.vertexStride ? in.vertexStride : vertexFormatSize(format);
  if (uint64_t(in.vertexCount - 1) * stride + 12 > vertexBytes) return {};
  MeshBounds b;
  for (int i = 0; i < 3; ++i) b.min[i] = INFINITY, b.max[i] = -INFINITY;
  const auto* bytes = static_cast<const uint8_t*>(in.hostVertices);
  for (uint32_t v = 0; v < in.vertexCount; ++v) {
    float p[3];
    std::memcpy(p, bytes + uint64_t(v) * stride, sizeof p);
    for (int i = 0; i < 3; ++i) {
      // A non-finite position makes the box unknown rather than infinite (the BLAS build treats it as inactive).
      if (!std::isfinite(p[i])) return {};
      b.min[i] = std::min(b.min[i], p[i]);
      b.max[i] = std::max(b.max[i], p[i]);
    }
  }
  // A box at exactly zero would read as "not given": widen it by one float step.
  if (!b.given()) b.max[0] = std::nextafter(0.0f, 1.0f);
  out = b;
  return {};
}

}  // namespace

Result<ValidatedMesh> validateMesh(const MeshDesc& in, const DeviceFunctions& vk, VkPhysicalDevice physicalDevice,
                                   uint64_t maxPrimitiveCount) {
  std::string name = in.debugName ? std::string("mesh '") + in.debugName + "'" : std::string("mesh");
  auto invalid = [&](const std::string& m) { return Error{ErrorCode::InvalidArgument, VK_SUCCESS, name + ": " + m}; };
  ValidatedMesh out;
  MeshDesc& d = out.desc;
  d = in;
  d.hostVertices = nullptr;
  d.hostIndices = nullptr;
  if (in.debugName) out.debugName = in.debugName;
  d.debugName = nullptr;
  if (d.vertexFormat == VK_FORMAT_UNDEFINED) d.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
  uint32_t formatSize = vertexFormatSize(d.vertexFormat);
  // Only a format Raybridge knows reaches the driver: any other value may be no VkFormat at all, which
  // vkGetPhysicalDeviceFormatProperties must not be given (VUID-vkGetPhysicalDeviceFormatProperties-format-parameter).
  VkFormatProperties fp{};
  if (formatSize != 0) vk.vkGetPhysicalDeviceFormatProperties(physicalDevice, d.vertexFormat, &fp);
  if (formatSize == 0 || !(fp.bufferFeatures & VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR)) {
    return invalid(std::string("vertexFormat ") + formatName(d.vertexFormat) + " (" +
                   std::to_string(static_cast<int>(d.vertexFormat)) +
                   ") cannot be used for acceleration structure builds on this device; use "
                   "VK_FORMAT_R32G32B32_SFLOAT (or another format with "
                   "VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR)");
  }
  if (d.vertexStride == 0) d.vertexStride = formatSize;
  if (d.vertexStride < formatSize) {
    return invalid("vertexStride " + std::to_string(d.vertexStride) + " is smaller than the vertex format (" +
                   std::to_string(formatSize) + " bytes)");
  }
  if (d.vertexStride % 4 != 0 && formatSize >= 4) {
    // The spec requires the stride to be a multiple of the format's smallest component.
    return invalid("vertexStride " + std::to_string(d.vertexStride) + " must be a multiple of 4 for this format");
  }
  if (d.vertexAddress == 0) return invalid("vertexAddress is 0; pass the device address of the position buffer");
  if (d.triangleCount == 0) return invalid("triangleCount is 0; a mesh needs at least one triangle");
  if (d.triangleCount > maxPrimitiveCount) {
    return invalid("triangleCount " + std::to_string(d.triangleCount) + " exceeds the device limit of " +
                   std::to_string(maxPrimitiveCount) + " primitives per BLAS; split the mesh");
  }
  if (d.vertexCount == 0) return invalid("vertexCount is 0");
  VkDeviceSize vertexBytes = VkDeviceSize(d.vertexCount - 1) * d.vertexStride + formatSize;
  if (vertexBytes > d.vertexBufferBytes) {
    return invalid("vertexCount " + std::to_string(d.vertexCount) + " with stride " + std::to_string(d.vertexStride) +
                   " reads " + std::to_string(vertexBytes) + " bytes but vertexBufferBytes declares " +
                   std::to_string(d.vertexBufferBytes));
  }
  uint64_t indexCount = uint64_t(d.triangleCount) * 3;
  switch (d.indexType) {
    case IndexType::Uint32: out.indexSize = 4; break;
    case IndexType::Uint16: out.indexSize = 2; break;
    case IndexType::None: out.indexSize = 0; break;
    default: return invalid("indexType " + std::to_string(static_cast<int>(d.indexType)) + " is not a valid IndexType");
  }
  if (out.indexSize) {
    if (d.indexAddress == 0) return invalid("indexAddress is 0 but indexType is not IndexType::None");
    if (d.indexAddress % out.indexSize != 0) {
      return invalid("indexAddress is not aligned to the index size (" + std::to_string(out.indexSize) + " bytes)");
    }
    if (indexCount * out.indexSize > d.indexBufferBytes) {
      return invalid("triangleCount " + std::to_string(d.triangleCount) + " reads " +
                     std::to_string(indexCount * out.indexSize) + " index bytes but indexBufferBytes declares " +
                     std::to_string(d.indexBufferBytes));
    }
  } else {
    if (indexCount > d.vertexCount) {
      return invalid("non-indexed triangleCount " + std::to_string(d.triangleCount) + " needs " +
                     std::to_string(indexCount) + " vertices but vertexCount is " + std::to_string(d.vertexCount));
    }
    d.indexAddress = 0;
    d.indexBufferBytes = 0;
  }
  if (in.hostIndices && out.indexSize) {
    // With a CPU copy at hand, an index past the vertex range is caught here instead of reading out of bounds.
    // Read byte-wise: MeshDesc asks for no alignment of the host copy (a packed file buffer may hold it).
    const auto* indices = static_cast<const unsigned char*>(in.hostIndices);
    for (uint64_t i = 0; i < indexCount; ++i) {
      uint32_t v = 0;
      if (out.indexSize == 4) {
        std::memcpy(&v, indices + i * 4, 4);
      } else {
        uint16_t v16 = 0;
        std::memcpy(&v16, indices + i * 2, 2);
        v = v16;
      }
      if (v >= d.vertexCount) {
        return invalid("index " + std::to_string(i) + " is " + std::to_string(v) + " but vertexCount is " +
                       std::to_string(d.vertexCount));
      }
    }
  }

  if (d.normalAddress && d.normalStride == 0) d.normalStride = 12;
  if (d.texcoordAddress && d.texcoordStride == 0) d.texcoordStride = 8;
  if ((d.normalAddress && d.normalStride < 12) || (d.texcoordAddress && d.texcoordStride < 8)) {
    return invalid("normalStride must be >= 12 and texcoordStride >= 8 bytes");
  }
  uint64_t layout = hashCombine(hashCombine(d.vertexFormat, d.vertexStride),
                                hashCombine(uint64_t(d.indexType) << 32 | d.triangleCount,
                                            uint64_t(d.vertexCount) << 1 | (d.nonOpaque ? 1 : 0)));
  if (Status st = resolveBounds(in, d.bounds, vertexBytes); !st) return invalid(st.error().message);
  if (d.contentKey != 0) {
    out.key = hashCombine(0x6b6579ull, d.contentKey);
  } else if (in.hostVertices && (in.hostIndices || !out.indexSize)) {
    uint64_t h = hashBytes(in.hostVertices, static_cast<size_t>(vertexBytes), layout);
    if (out.indexSize) h = hashBytes(in.hostIndices, static_cast<size_t>(indexCount * out.indexSize), h);
    out.key = hashCombine(0x636f6e74656e74ull, h);
  } else {
    out.key = hashCombine(hashCombine(0x6964656e74ull, layout), hashCombine(d.vertexAddress, d.indexAddress));
  }
  return out;
}

}  // namespace rb

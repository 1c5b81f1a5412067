// Checks a MeshDesc against the device and the engine's declared buffer sizes, and derives its dedup key.
#pragma once

#include <raybridge/acceleration_structures.h>

#include <string>

#include "device_functions.h"

namespace rb {

struct ValidatedMesh {
  MeshDesc desc;  // with defaults resolved (format, stride); host pointers and debugName cleared
  // A copy of MeshDesc::debugName ("" = none), for later messages: the engine's string need only live through
  // the call that passed it.
  std::string debugName;
  uint64_t key = 0;
  uint32_t indexSize = 0;  // bytes per index, 0 for non-indexed
};

uint32_t vertexFormatSize(VkFormat format);  // 0 for formats Raybridge does not know
// A given MeshBounds (MeshDesc::bounds, MeshUpdate::bounds): finite, min <= max. The message starts "bounds: ".
Status checkBounds(const MeshBounds& b);

Result<ValidatedMesh> validateMesh(const MeshDesc& desc, const DeviceFunctions& vk, VkPhysicalDevice physicalDevice,
                                   uint64_t maxPrimitiveCount);

}  // namespace rb

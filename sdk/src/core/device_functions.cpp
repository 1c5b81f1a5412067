#include "device_functions.h"

namespace rb {

const char* loadDeviceFunctions(DeviceFunctions& table, PFN_vkGetInstanceProcAddr getInstanceProcAddr,
                                VkInstance instance, VkDevice device) {
#define RB_LOAD_INSTANCE(name)                                                     \
  table.name = reinterpret_cast<PFN_##name>(getInstanceProcAddr(instance, #name)); \
  if (!table.name) return #name;
  RB_INSTANCE_FUNCTIONS(RB_LOAD_INSTANCE)
#undef RB_LOAD_INSTANCE
#define RB_LOAD_DEVICE(name)                                                           \
  table.name = reinterpret_cast<PFN_##name>(table.vkGetDeviceProcAddr(device, #name)); \
  if (!table.name) return #name;
  RB_DEVICE_FUNCTIONS(RB_LOAD_DEVICE)
#undef RB_LOAD_DEVICE
  return nullptr;
}

}  // namespace rb

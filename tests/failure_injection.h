// Failure injection for the SDK's Vulkan calls, with no hook in the SDK: a vkGetInstanceProcAddr for ContextDesc
// whose vkGetDeviceProcAddr hands out wrappers of every function the SDK creates or allocates with (and of those
// that report a lost device), and forwards the rest. The wrappers count the calls, make a chosen one fail, and
// keep the objects created through them, so a test can see what an error path leaked.
//
// A failed create leaves its output handle undefined (the Vulkan spec), so the wrappers write a poison value
// there, except where the spec says VK_NULL_HANDLE (pipelines, descriptor sets, command buffers); destroying the
// poison, or any handle no wrapped create returned, is recorded as misuse and not passed on to the driver.
//
// The wrappers are plain function pointers, so they reach the injector through a global: one injector at a time.
#pragma once

#include <raybridge/context.h>

#include <cstdint>
#include <string>
#include <vector>

namespace rbtest {

// One call the injector made fail.
struct InjectedFailure {
  uint64_t call = 0;     // index among the counted allocation calls (1-based); 0 for an injected lost device
  std::string function;  // e.g. "vkCreateImageView"
  VkResult result = VK_SUCCESS;
};

class FailureInjector {
 public:
  // `real`: the loader's vkGetInstanceProcAddr everything is forwarded to.
  explicit FailureInjector(PFN_vkGetInstanceProcAddr real);
  ~FailureInjector();
  FailureInjector(const FailureInjector&) = delete;
  FailureInjector& operator=(const FailureInjector&) = delete;

  // `desc` with getInstanceProcAddr replaced by the injecting one.
  rb::ContextDesc wrap(rb::ContextDesc desc) const;

  // Forgets the counts, the plans, the failures and the misuse (the live objects stay).
  void reset();

  // Allocation sites: every call that creates or allocates something (vkAllocateMemory, vkCreate*, vkAllocate*,
  // vkMapMemory, vkBind*Memory, vkGetRayTracingShaderGroupHandlesKHR) is counted; call number `k` (1-based since
  // reset()) fails with the error the spec lists first for running out of memory there. 0 = none fails.
  void failCall(uint64_t k);
  uint64_t calls() const;                                // counted since reset()
  const std::vector<std::string>& callLog() const;       // the function of each counted call, in order
  const std::vector<InjectedFailure>& failures() const;  // what was made to fail since reset()

  // Lost device: calls of `function` (vkGetQueryPoolResults, vkQueueSubmit, vkGetSemaphoreCounterValue, or any
  // counted one) return VK_ERROR_DEVICE_LOST from its `from`-th call since reset() (1-based) on.
  void loseDevice(const std::string& function, uint64_t from = 1);
  uint64_t callsOf(const std::string& function) const;  // since reset()

  // Objects created through the wrappers and not destroyed: "VkBuffer from vkCreateBuffer (call 12)", one each.
  std::vector<std::string> liveObjects() const;
  // Destroys of handles that no wrapped create returned (the undefined output of a failed one, a double destroy).
  const std::vector<std::string>& misuse() const;

  struct State;

 private:
  State* state_;
};

}  // namespace rbtest

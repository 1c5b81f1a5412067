// The SDK's access to a Context's internals (its function table and shared machinery), for the SDK's sources and,
// through the raybridge_internal build target, its tests and benchmarks. Not installed; engines never see it.
#pragma once

#include <raybridge/context.h>

namespace rb {

struct DeviceFunctions;

namespace internal {

struct ContextAccess {
  static Context::Impl& impl(Context& ctx) { return *ctx.impl_; }
  static const Context::Impl& impl(const Context& ctx) { return *ctx.impl_; }
  // The Impl of another public SDK type that befriends ContextAccess (DenoiserScratch).
  template <typename T>
  static typename T::Impl& implOf(T& object) {
    return *object.impl_;
  }
};

inline Context::Impl& contextImpl(Context& ctx) { return ContextAccess::impl(ctx); }
inline const Context::Impl& contextImpl(const Context& ctx) { return ContextAccess::impl(ctx); }
// The per-context Vulkan function table every SDK call goes through.
const DeviceFunctions& deviceFunctions(const Context& ctx);

}  // namespace internal
}  // namespace rb

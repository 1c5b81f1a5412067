// The width and height every pass description carries (ShadowPassDesc, AoPassDesc, ..., DenoiserDesc): both zero =
// the images are created at the first record(); both set = created at create(), by the pass's own prepare().
#pragma once

#include <raybridge/result.h>

#include <string>

namespace rb::internal {

template <typename Pass>
Status prepareAtCreation(Pass& pass, uint32_t width, uint32_t height, const char* descName) {
  if (width == 0 && height == 0) return {};
  if (width == 0 || height == 0) {
    return Error{ErrorCode::InvalidArgument, VK_SUCCESS,
                 std::string(descName) + ": width " + std::to_string(width) + " and height " + std::to_string(height) +
                     ": set both (the images are created now) or neither (at the first record())"};
  }
  return pass.prepare(width, height);
}

}  // namespace rb::internal

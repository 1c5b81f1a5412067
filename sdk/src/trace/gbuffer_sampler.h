// The nearest-neighbour sampler the passes read G-buffer images through (texelFetch ignores filtering, but a
// combined image sampler needs one).
#pragma once

#include "gpu_memory.h"

namespace rb {

Result<VkSampler> createNearestSampler(Context& ctx);
void destroySampler(Context& ctx, VkSampler& sampler);

}  // namespace rb

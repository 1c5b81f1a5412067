// Shared by the RGB denoiser's compute shaders. The noise tracked is that of the colour as a whole: the variance
// is the sum of the three channels' (the trace of the covariance), so a pixel flickering between a red and a
// blue light of equal luminance counts as noisy, and a colour edge as an edge.
#ifndef RAYBRIDGE_DENOISE_RGB_COMMON_GLSL
#define RAYBRIDGE_DENOISE_RGB_COMMON_GLSL

#include "denoise_common.glsl"
#include "denoise_rgb_interface.glsl"

// The guide image (RG32UI), written once per frame by the temporal pass so that each a-trous tap reads one
// 8-byte texel instead of depth and normal, and rebuilds no position through the inverse projection:
// x = the float bits of the view distance (0 = sky), y = the normal, octahedral, packSnorm2x16.
uvec2 rbDnPackGuide(float viewDistance, vec3 n) {
  return uvec2(floatBitsToUint(viewDistance), packSnorm2x16(rbEncodeOctahedral(n)));
}
float rbDnGuideDistance(uvec2 g) { return uintBitsToFloat(g.x); }
vec3 rbDnGuideNormal(uvec2 g) { return rbDecodeOctahedral(unpackSnorm2x16(g.y)); }

// SVGF's threshold: with fewer frames the variance comes from the neighbourhood instead.
const float kRbDnMinTemporalVarianceFrames = 4.0;

#endif

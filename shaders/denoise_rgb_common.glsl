// Shared by the RGB denoiser's compute shaders. The noise tracked is that of the colour as a whole: the variance
// is the sum of the three channels' (the trace of the covariance), so a pixel flickering between a red and a
// blue light of equal luminance counts as noisy, and a colour edge as an edge.
#ifndef RAYBRIDGE_DENOISE_RGB_COMMON_GLSL
#define RAYBRIDGE_DENOISE_RGB_COMMON_GLSL

#include "denoise_common.glsl"
#include "denoise_rgb_interface.glsl"

// SVGF's threshold: with fewer frames the variance comes from the neighbourhood instead.
const float kRbDnMinTemporalVarianceFrames = 4.0;

#endif

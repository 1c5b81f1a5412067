// Shared by the RGB denoiser's compute shaders: luminance (the quantity whose noise is tracked) and the
// number of frames below which the temporal moments are too few to estimate the variance.
#ifndef RAYBRIDGE_DENOISE_RGB_COMMON_GLSL
#define RAYBRIDGE_DENOISE_RGB_COMMON_GLSL

#include "denoise_common.glsl"
#include "denoise_rgb_interface.glsl"

float rbDnLuminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// SVGF's threshold: with fewer frames the variance comes from the 3x3 neighbourhood instead.
const float kRbDnMinTemporalVarianceFrames = 4.0;
// The least of four window variances underestimates noise: this scales it back (measured on the many-light
// test scene).
const float kRbDnWindowMinCorrection = 1.5;

#endif

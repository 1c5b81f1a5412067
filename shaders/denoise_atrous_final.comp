#version 460
#extension GL_GOOGLE_include_directive : require
// The last a-trous step of the scalar denoiser: writes its output (see denoise_atrous.glsl).
#define RB_DN_ATROUS_FINAL
#include "denoise_atrous.glsl"

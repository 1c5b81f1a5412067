#version 460
#extension GL_GOOGLE_include_directive : require
// An a-trous step of the scalar denoiser that another step follows (see denoise_atrous.glsl).
#include "denoise_atrous.glsl"

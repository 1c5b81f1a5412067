// The numbers the RGB denoiser's C++ (sdk/src/denoise/denoiser.cpp) and its shaders must agree on: descriptor bindings
// and the flag bits it adds to DenoiseConstants::flags (above the RB_DN_* of raybridge_shader_interface.glsl).
// Only #defines, so the one file is included by both.
#ifndef RAYBRIDGE_DENOISE_RGB_INTERFACE_GLSL
#define RAYBRIDGE_DENOISE_RGB_INTERFACE_GLSL

// Temporal pass (denoise_rgb_temporal.comp).
#define RB_RGB_TEMPORAL_BINDING_DEPTH 0
#define RB_RGB_TEMPORAL_BINDING_MOTION 1  // the depth image again without motion vectors
#define RB_RGB_TEMPORAL_BINDING_SIGNAL 2
#define RB_RGB_TEMPORAL_BINDING_HISTORY_IN 3  // rgb: mean colour, a: frames accumulated
#define RB_RGB_TEMPORAL_BINDING_SURFACE_IN 4  // x: view distance, y: variance of one frame's colour
#define RB_RGB_TEMPORAL_BINDING_HISTORY_OUT 5
#define RB_RGB_TEMPORAL_BINDING_SURFACE_OUT 6
#define RB_RGB_TEMPORAL_BINDING_VALUE_OUT 7  // rgb: accumulated colour, a: its standard deviation
#define RB_RGB_TEMPORAL_BINDING_GUIDE_OUT 8  // the a-trous steps' geometry (denoise_rgb_common.glsl)
#define RB_RGB_TEMPORAL_BINDING_NORMAL 9
#define RB_RGB_TEMPORAL_BINDING_ROUGHNESS 10  // with RB_DN_RGB_REFLECTION: .x, or the normal's .w
#define RB_RGB_TEMPORAL_BINDING_REACTIVE 11   // the reactive mask, or the depth image again without one
// A-trous pass (denoise_rgb_atrous.comp).
#define RB_RGB_ATROUS_BINDING_GUIDE 0
#define RB_RGB_ATROUS_BINDING_SIGNAL_IN 1
#define RB_RGB_ATROUS_BINDING_SIGNAL_OUT 2

// This dispatch writes the denoiser's output: a = 1 instead of the standard deviation.
#define RB_DN_RGB_FINAL 0x100u
// DenoiseSignal::Reflection: .a of the signal is coverage (0 = no reflection: passed through, not a tap, a = 0 in
// the output), and the roughness guides the filter; RB_DN_RGB_ROUGHNESS_IMAGE: roughness is the roughness image's
// .x, else the normal's .w.
#define RB_DN_RGB_REFLECTION 0x200u
#define RB_DN_RGB_ROUGHNESS_IMAGE 0x400u

#endif

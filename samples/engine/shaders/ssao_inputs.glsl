// Bindings and constants of the two SSAO compute passes (ssao.comp, ssao_blur.comp); needs
// frame_uniforms.glsl. Keep in sync with SsaoConstants and Pipelines::ssaoSetLayout in src/pipelines.h.

layout(set = 1, binding = 0) uniform sampler2D depthTex;   // pre-pass depth, nearest
layout(set = 1, binding = 1) uniform sampler2D normalTex;  // pre-pass geometric normal (world), nearest
layout(set = 1, binding = 2) uniform sampler2D rawAo;      // ssao_blur.comp: ssao.comp's output (else unused)
layout(set = 1, binding = 3, r16f) uniform writeonly image2D outAo;  // 1 = open

layout(push_constant) uniform SsaoConstants {
  float radius;      // world (= view) units: occluders farther than this do not count
  float bias;        // world units: the horizon search starts this far above the surface, along its normal
  float power;       // ao = visibility^power
  uint sliceCount;   // slice directions per pixel
  uint stepsPerSide;  // depth taps along each side of a slice
} pc;

// Both passes run 8x8 groups over the render size.
layout(local_size_x = 8, local_size_y = 8) in;

// A pixel of the render size, or false for the threads of a partial group past the edge.
bool ssaoPixel(out ivec2 pixel) {
  pixel = ivec2(gl_GlobalInvocationID.xy);
  return all(lessThan(pixel, ivec2(frame.viewport.xy)));
}

#version 450
// Exposure + ACES filmic fit; the 8-bit sRGB target encodes. CPU reference: tonemapLinear() in image_io.cpp.
layout(set = 0, binding = 0) uniform sampler2D hdr;
layout(push_constant) uniform Tonemap { float exposure; } pc;
layout(location = 0) out vec4 outColor;

void main() {
  vec3 x = max(texelFetch(hdr, ivec2(gl_FragCoord.xy), 0).rgb * pc.exposure, vec3(0.0));
  vec3 y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
  outColor = vec4(clamp(y, 0.0, 1.0), 1.0);
}

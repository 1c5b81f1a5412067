// Helpers of the fullscreen passes that read the pre-pass (needs frame_uniforms.glsl).

// Pixel centre -> UV in [0,1]; pixel (0,0) is the top-left, matching NDC y = -1 (the projection flips Y).
vec2 pixelUv(ivec2 pixel) { return (vec2(pixel) + 0.5) * frame.viewport.zw; }

// Camera-relative position (world position - eye, world axes): invViewProj has a rotation-only view.
vec3 eyeRelativeFromDepth(vec2 uv, float depth) {
  vec4 p = frame.invViewProj * vec4(uv * 2.0 - 1.0, depth, 1.0);
  return p.xyz / p.w;
}

// View-space z of a depth value: only the z and w rows of invProj matter for a perspective projection, which
// makes this two FMAs and a divide (the SSAO horizon search runs it once per depth tap).
float viewZFromDepth(float depth) {
  return (frame.invProj[2][2] * depth + frame.invProj[3][2]) / (frame.invProj[2][3] * depth + frame.invProj[3][3]);
}

// View-space position; assumes the engine's centred perspective (no off-axis terms), where view x, y are
// NDC x, y scaled by -z / proj[0][0] and -z / proj[1][1].
vec3 viewFromDepth(vec2 uv, float depth) {
  float z = viewZFromDepth(depth);
  return vec3((uv * 2.0 - 1.0) * vec2(frame.invProj[0][0], frame.invProj[1][1]) * -z, z);
}

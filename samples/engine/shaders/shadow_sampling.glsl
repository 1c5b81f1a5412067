// Sun visibility from the shadow map, shared by the lighting pass and the shadow-visibility output pass so
// that the image an application reads back is exactly the term the lighting multiplies by.
// Needs frame_uniforms.glsl.

float shadowMapVisibility(sampler2DShadow shadowMap, vec3 worldPos, vec3 ng) {
  // Normal offset moves the lookup off the surface to avoid acne on slopes.
  vec4 lp = frame.lightViewProj * vec4(worldPos + ng * frame.shadow.z, 1.0);
  vec3 ndc = lp.xyz / lp.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z >= 1.0) return 1.0;
  int taps = int(frame.shadow.y);
  int half_ = taps / 2;
  float sum = 0.0;
  for (int y = -half_; y <= half_; ++y)
    for (int x = -half_; x <= half_; ++x)
      sum += texture(shadowMap, vec3(uv + vec2(x, y) * frame.shadow.x, ndc.z));
  return sum / float(taps * taps);
}

// The lighting's sun visibility: surfaces whose shading normal faces away from the sun get none.
float sunVisibility(sampler2DShadow shadowMap, vec3 worldPos, vec3 n, vec3 ng) {
  return dot(n, frame.sunDirection.xyz) > 0.0 ? shadowMapVisibility(shadowMap, worldPos, ng) : 0.0;
}

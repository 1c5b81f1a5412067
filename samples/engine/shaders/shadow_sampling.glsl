// Sun visibility from the shadow map, shared by the lighting pass and the shadow-visibility output pass so
// that the image an application reads back is exactly the term the lighting multiplies by.
// Needs frame_uniforms.glsl.

// PCF over frame.shadow.y x frame.shadow.y taps (0 = no shadow map this frame: unshadowed), each a 2x2
// hardware-filtered compare, one texel apart and centred on the lookup: offsets -(n-1)/2 .. +(n-1)/2 texels,
// so an even kernel samples at half-texel offsets and its penumbra is as centred as an odd one's.
float shadowMapVisibility(sampler2DShadow shadowMap, vec3 worldPos, vec3 ng) {
  int taps = int(frame.shadow.y);
  if (taps <= 0) return 1.0;
  // Normal offset moves the lookup off the surface to avoid acne on slopes.
  vec4 lp = frame.lightViewProj * vec4(worldPos + ng * frame.shadow.z, 1.0);
  vec3 ndc = lp.xyz / lp.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0))) || ndc.z >= 1.0) return 1.0;
  float first = -0.5 * float(taps - 1);
  float sum = 0.0;
  for (int y = 0; y < taps; ++y)
    for (int x = 0; x < taps; ++x)
      sum += texture(shadowMap, vec3(uv + (vec2(x, y) + first) * frame.shadow.x, ndc.z));
  return sum / float(taps * taps);
}

// The lighting's sun visibility: surfaces whose shading normal faces away from the sun get none.
float sunVisibility(sampler2DShadow shadowMap, vec3 worldPos, vec3 n, vec3 ng) {
  return dot(n, frame.sunDirection.xyz) > 0.0 ? shadowMapVisibility(shadowMap, worldPos, ng) : 0.0;
}

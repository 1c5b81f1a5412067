// Material evaluation shared by the pre-pass and the lighting pass (and the blend pass and probe capture).
layout(set = 1, binding = 0) uniform sampler2D baseColorTex;          // sRGB view; A = alpha (coverage)
layout(set = 1, binding = 1) uniform sampler2D metallicRoughnessTex;  // G roughness, B metallic
layout(set = 1, binding = 2) uniform sampler2D normalTex;
layout(set = 1, binding = 3) uniform sampler2D emissiveTex;   // sRGB view
layout(set = 1, binding = 4) uniform sampler2D occlusionTex;  // R = ambient occlusion; white when none

// True in the pipelines that draw MASK materials (Pipelines::*Masked). The others carry no discard at all, so
// the depth-writing passes keep their early depth test for opaque draws.
layout(constant_id = 0) const bool kAlphaTested = false;

layout(location = 0) in vec3 inEyeRelativePos;  // world position - eye (world axes)
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in vec4 inTangent;

struct Surface {
  vec3 n;   // shading normal, facing the camera
  vec3 ng;  // geometric normal, facing the camera
  vec3 v;   // towards the camera
  vec3 baseColor;
  float metallic;
  float roughness;  // perceptual
  vec3 emissive;
  float occlusion;  // material ambient occlusion (1 = none)
  float alpha;      // baseColorFactor.a * base colour texture alpha: MASK coverage, BLEND opacity
};

Surface evaluateSurface() {
  Surface s;
  s.v = normalize(-inEyeRelativePos);
  // Triangle normal from screen-space derivatives; independent of winding and index order.
  s.ng = normalize(cross(dFdx(inEyeRelativePos), dFdy(inEyeRelativePos)));
  if (dot(s.ng, s.v) < 0.0) s.ng = -s.ng;
  vec3 n = normalize(inNormal);
  float side = dot(n, s.ng) < 0.0 ? -1.0 : 1.0;  // seen from the back: shade the back side
  n *= side;
  vec3 t = inTangent.xyz - n * dot(n, inTangent.xyz);
  if (dot(t, t) > 1e-10) {
    t = normalize(t);
    vec3 b = cross(n, t) * inTangent.w * side;
    vec3 tn = texture(normalTex, inUv).xyz * 2.0 - 1.0;
    tn.xy *= draw.material.z;
    n = normalize(mat3(t, b, n) * tn);
  }
  s.n = n;
  vec4 base = texture(baseColorTex, inUv) * draw.baseColorFactor;
  vec4 mr = texture(metallicRoughnessTex, inUv);
  s.baseColor = base.rgb;
  s.alpha = base.a;
  s.metallic = clamp(draw.material.x * mr.b, 0.0, 1.0);
  s.roughness = clamp(draw.material.y * mr.g, 0.02, 1.0);
  s.emissive = draw.emissive.rgb * texture(emissiveTex, inUv).rgb;
  // glTF occlusionTexture (R channel), whichever image it is (a packed ORM binds the metallic-roughness one).
  s.occlusion = mix(1.0, texture(occlusionTex, inUv).r, draw.material.w);
  return s;
}

// MASK: drops the fragment where alpha < alphaCutoff (glTF), in the pipelines built with kAlphaTested. Call it
// after evaluateSurface(): derivatives and implicit-LOD lookups are undefined after a quad neighbour's discard.
void alphaTest(Surface s) {
  if (kAlphaTested && s.alpha < draw.alphaCutoff) discard;
}

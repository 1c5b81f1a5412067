// Material evaluation shared by the pre-pass and the lighting pass.
layout(set = 1, binding = 0) uniform sampler2D baseColorTex;          // sRGB view
layout(set = 1, binding = 1) uniform sampler2D metallicRoughnessTex;  // G roughness, B metallic
layout(set = 1, binding = 2) uniform sampler2D normalTex;
layout(set = 1, binding = 3) uniform sampler2D emissiveTex;          // sRGB view

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
  s.metallic = clamp(draw.material.x * mr.b, 0.0, 1.0);
  s.roughness = clamp(draw.material.y * mr.g, 0.02, 1.0);
  s.emissive = draw.emissive.rgb * texture(emissiveTex, inUv).rgb;
  // glTF occlusion packed in the metallic-roughness texture's R channel; draw.material.w = strength (0 = none).
  s.occlusion = mix(1.0, mr.r, draw.material.w);
  return s;
}

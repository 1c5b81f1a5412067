#version 450
#extension GL_GOOGLE_include_directive : require
// Forward PBR lighting: GGX specular + Lambert diffuse for the sun, constant-sky ambient, with optional
// external sun visibility / AO / reflection images replacing the engine's own terms.
#include "common.glsl"
#include "surface.glsl"

layout(set = 2, binding = 0) uniform sampler2DShadow shadowMap;
layout(set = 2, binding = 1) uniform sampler2D externalVisibility;
layout(set = 2, binding = 2) uniform sampler2D externalAo;
layout(set = 2, binding = 3) uniform sampler2D externalReflection;

layout(location = 0) out vec4 outColor;

const float PI = 3.14159265358979;

float shadowMapVisibility(vec3 worldPos, vec3 ng) {
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

// Karis' analytic approximation of the split-sum environment BRDF.
vec3 environmentBrdf(vec3 f0, float roughness, float nDotV) {
  const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
  const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
  vec4 r = roughness * c0 + c1;
  float a004 = min(r.x * r.x, exp2(-9.28 * nDotV)) * r.x + r.y;
  vec2 ab = vec2(-1.04, 1.04) * a004 + r.zw;
  return f0 * ab.x + ab.y;
}

void main() {
  Surface s = evaluateSurface();
  vec2 screenUv = gl_FragCoord.xy * frame.viewport.zw;
  vec3 l = frame.sunDirection.xyz;
  vec3 h = normalize(l + s.v);
  float nDotL = max(dot(s.n, l), 0.0);
  float nDotV = max(dot(s.n, s.v), 1e-4);
  float nDotH = max(dot(s.n, h), 0.0);
  float vDotH = max(dot(s.v, h), 0.0);

  vec3 f0 = mix(vec3(0.04), s.baseColor, s.metallic);
  float a = s.roughness * s.roughness;
  float a2 = a * a;
  float d = a2 / (PI * pow(nDotH * nDotH * (a2 - 1.0) + 1.0, 2.0));
  // Height-correlated Smith visibility term (includes the 1 / (4 NdotL NdotV) factor).
  float vis = 0.5 / (nDotL * sqrt(nDotV * nDotV * (1.0 - a2) + a2) + nDotV * sqrt(nDotL * nDotL * (1.0 - a2) + a2) + 1e-7);
  vec3 f = f0 + (1.0 - f0) * pow(1.0 - vDotH, 5.0);
  vec3 specular = d * vis * f;
  vec3 diffuse = (1.0 - f) * (1.0 - s.metallic) * s.baseColor / PI;

  float sunVisibility = frame.inputs.x != 0u ? clamp(texture(externalVisibility, screenUv).r, 0.0, 1.0)
                                             : (nDotL > 0.0 ? shadowMapVisibility(inWorldPos, s.ng) : 0.0);
  float ao = frame.inputs.y != 0u ? clamp(texture(externalAo, screenUv).r, 0.0, 1.0) : 1.0;

  vec3 color = (diffuse + specular) * frame.sunRadiance.rgb * nDotL * sunVisibility;
  vec3 ambient = frame.sky.rgb * frame.sky.w;
  color += ambient * s.baseColor * (1.0 - s.metallic) * ao;  // Lambert under a uniform sky
  vec3 specularWeight = environmentBrdf(f0, s.roughness, nDotV);
  vec3 reflected = frame.inputs.z != 0u ? texture(externalReflection, screenUv).rgb : ambient * ao;
  color += reflected * specularWeight;
  color += s.emissive;
  outColor = vec4(color, 1.0);
}

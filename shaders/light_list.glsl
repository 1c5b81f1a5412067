// The light list as the GPU reads it (ManyLightPass uploads it) and each light's unshadowed irradiance at a
// surface point (the formula of many_light_pass.h). Shared by the many-light culling and rays, and the
// reflection hits lit by the same list.
#ifndef RAYBRIDGE_LIGHT_LIST_GLSL
#define RAYBRIDGE_LIGHT_LIST_GLSL

#include "raybridge_shader_interface.glsl"

// Mirrors GpuLight in sdk/src/trace/many_light_pass_impl.h (std430, 64 bytes). Filled on the host.
struct GpuLight {
  vec3 position;   // point, spot: TLAS space
  float range;     // point, spot: 0 = unlimited
  vec3 direction;  // directional: towards the light; spot: the axis it shines along (unit)
  uint type;       // RB_LIGHT_*
  vec3 intensity;  // colour * intensity
  float softness;  // point, spot: radius; directional: tan(angular radius); 0 = hard
  float cosOuter;  // spot cone: cos(outer angle)
  float coneScale;   // 1 / max(1e-3, cos(inner) - cos(outer))
  float coneOffset;  // -cos(outer) * coneScale
  float pad0;
};

float rbLuminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }

// The light's unshadowed irradiance at `p` with shading normal `n` (0 where it cannot light the point, or the
// geometric side `facing` faces away from it); `toLight` and `lightDistance` say where to trace.
vec3 rbLightIrradiance(GpuLight light, vec3 p, vec3 n, vec3 facing, out vec3 toLight, out float lightDistance) {
  float falloff = 1.0;
  if (light.type == RB_LIGHT_DIRECTIONAL) {
    toLight = light.direction;
    lightDistance = 1e30;
  } else {
    toLight = light.position - p;
    float d2 = max(dot(toLight, toLight), 1e-12);
    lightDistance = sqrt(d2);
    toLight /= lightDistance;
    falloff = 1.0 / d2;
    if (light.range > 0.0) {
      float r = lightDistance / light.range;
      falloff *= clamp(1.0 - r * r * r * r, 0.0, 1.0);
    }
    if (light.type == RB_LIGHT_SPOT) {
      float c = clamp(dot(-toLight, light.direction) * light.coneScale + light.coneOffset, 0.0, 1.0);
      falloff *= c * c;
    }
  }
  float cosine = dot(n, toLight);
  if (cosine <= 0.0 || dot(facing, toLight) <= -0.05) return vec3(0.0);
  return light.intensity * (cosine * falloff);
}

#endif

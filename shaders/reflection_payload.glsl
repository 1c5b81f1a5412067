// The reflection rays' payload, shared by the ray generation, closest-hit and miss shaders.
#ifndef RAYBRIDGE_REFLECTION_PAYLOAD_GLSL
#define RAYBRIDGE_REFLECTION_PAYLOAD_GLSL

struct ReflectionPayload {
  vec3 radiance;
  // Shadow rays the closest-hit shader traced from the hit (sun, local light): the ray generation shader counts
  // them with its own rays in one atomic, instead of one atomic per shadow ray.
  uint shadowRays;
  // Distance to the hit, written by the closest-hit shader; the ray generation shader sets it below 0 before
  // tracing, so a ray that escaped keeps that (ReflectionSettings::changedBoxes tests the ray's path).
  float hitT;
  // Set by the ray generation shader: 1 = the ray's pixel is rough enough that its hit may read the sun's visibility
  // from the screen (ReflectionSettings::sunVisibilityMinRoughness), 0 = the hit traces its sun ray.
  uint sunFromScreen;
};

#endif

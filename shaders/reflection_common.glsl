// Shared by the reflection shaders: the payload, and (shading_records.glsl) the per-instance shading records
// and the material table.
#ifndef RAYBRIDGE_REFLECTION_COMMON_GLSL
#define RAYBRIDGE_REFLECTION_COMMON_GLSL

#include "reflection_payload.glsl"
#include "shading_records.glsl"

#endif

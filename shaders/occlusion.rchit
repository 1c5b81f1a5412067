#version 460
#extension GL_EXT_ray_tracing : require
// Shadow and AO rays that want the nearest occluder's distance (rays that do not, skip this shader).
layout(location = 0) rayPayloadInEXT float hitT;
void main() { hitT = gl_HitTEXT; }

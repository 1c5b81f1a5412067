#version 460
#extension GL_EXT_ray_tracing : require
// Only used when the hit distance is requested: the nearest occluder's distance.
layout(location = 0) rayPayloadInEXT float hitT;
void main() { hitT = gl_HitTEXT; }

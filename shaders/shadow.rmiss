#version 460
#extension GL_EXT_ray_tracing : require
// A shadow ray that reaches the light: the payload stays 0 (visible).
layout(location = 0) rayPayloadInEXT float hitT;
void main() { hitT = 0.0; }

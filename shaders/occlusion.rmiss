#version 460
#extension GL_EXT_ray_tracing : require
// Shadow and AO rays: a ray that reaches the light or leaves the AO range unobstructed sets the payload to 0.
layout(location = 0) rayPayloadInEXT float hitT;
void main() { hitT = 0.0; }

#version 460
#extension GL_GOOGLE_include_directive : require
#define RB_WRITE_HIT_DISTANCE 1
#include "shadow_classify.glsl"

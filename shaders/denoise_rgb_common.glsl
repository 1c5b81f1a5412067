// Shared by the RGB denoiser's compute shaders. The noise tracked is that of the colour as a whole: the variance
// is the sum of the three channels' (the trace of the covariance), so a pixel flickering between a red and a
// blue light of equal luminance counts as noisy, and a colour edge as an edge.
#ifndef RAYBRIDGE_DENOISE_RGB_COMMON_GLSL
#define RAYBRIDGE_DENOISE_RGB_COMMON_GLSL

#include "denoise_common.glsl"
#include "denoise_rgb_interface.glsl"

// The guide image (RG32UI), written once per frame by the temporal pass so that each a-trous tap reads one
// 8-byte texel instead of depth and normal, and rebuilds no position through the inverse projection:
// x = the float bits of the view distance (0 = sky), y = the normal, octahedral, packSnorm2x16.
uvec2 rbDnPackGuide(float viewDistance, vec3 n) {
  return uvec2(floatBitsToUint(viewDistance), packSnorm2x16(rbEncodeOctahedral(n)));
}
float rbDnGuideDistance(uvec2 g) { return uintBitsToFloat(g.x); }
vec3 rbDnGuideNormal(uvec2 g) { return rbDecodeOctahedral(unpackSnorm2x16(g.y)); }

// SVGF's threshold: with fewer frames the variance comes from the neighbourhood instead.
const float kRbDnMinTemporalVarianceFrames = 4.0;

// A pixel of the signal that the reflection pass did not trace because its tile had converged (RB_DN_KEPT_MARKS,
// rgb_converged.comp): .a = -1, .rgb its reprojected history mean. It keeps its history unchanged.
bool rbDnRgbKeptMark(float a) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && a < -0.5; }
// A pixel traced this frame whose converged tile's refresh found a change (rgb_converged_check.comp): .a = 2.
// Its history is stale: it starts afresh, as a disoccluded pixel does.
bool rbDnRgbStaleMark(float a) { return (pc.flags & RB_DN_KEPT_MARKS) != 0u && a > 1.5; }

// Where the surface at `pixel` (camera-relative position `rel`) was in the latest history, read bilinearly over the
// four history texels around the reprojected point, each kept only where it holds the same surface (its distance
// from last frame's camera matches); nearest-texel reprojection would drift and blur the history by up to half a
// pixel every frame the camera moves. Returns whether any did: then `h` is the history (rgb mean, a frames) and `v`
// the variance of one frame's colour there; none where the engine's reactive mask is set (rbDnReactive). The temporal
// pass's test, shared with the converged reflection tiles, which must find the history it finds.
bool rbDnRgbFindHistory(uvec2 pixel, vec3 rel, sampler2D motion, sampler2D reactive, sampler2D historyIn,
                        sampler2D surfaceIn, out vec4 h, out float v) {
  h = vec4(0.0);
  v = 0.0;
  if ((pc.flags & RB_DN_HISTORY) == 0u || rbDnReactive(pixel, reactive)) return false;
  vec3 prevRel;
  vec2 f = rbDnPreviousPixel(pixel, rel, motion, prevRel) - 0.5;
  ivec2 base = ivec2(floor(f));
  vec2 t = f - vec2(base);
  float expected = length(prevRel);
  float weights = 0.0;
  for (int k = 0; k < 4; ++k) {
    ivec2 o = ivec2(k & 1, k >> 1);
    ivec2 pp = base + o;
    if (any(lessThan(pp, ivec2(0))) || any(greaterThanEqual(pp, ivec2(pc.size)))) continue;
    vec2 prevSurface = texelFetch(surfaceIn, pp, 0).xy;
    if (!(prevSurface.x > 0.0 && abs(prevSurface.x - expected) <= 0.02 * expected + 1e-3)) continue;
    float w = (o.x == 1 ? t.x : 1.0 - t.x) * (o.y == 1 ? t.y : 1.0 - t.y);
    h += w * texelFetch(historyIn, pp, 0);
    v += w * prevSurface.y;
    weights += w;
  }
  if (weights <= 1e-3) return false;
  h /= weights;
  v /= weights;
  return true;
}

#endif

// Sampling helpers for the effect passes: hashes for per-pixel decorrelation, stratified disk and hemisphere
// samples, and the robust ray-origin offset.
#ifndef RAYBRIDGE_SAMPLING_GLSL
#define RAYBRIDGE_SAMPLING_GLSL

const float RB_PI = 3.14159265358979;
const float RB_GOLDEN_ANGLE = 2.39996322972865;

// PCG hash (Jarzynski & Olano 2020): decorrelates pixels and frames.
uint rbPcg(uint v) {
  uint state = v * 747796405u + 2891336453u;
  uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
  return (word >> 22u) ^ word;
}
float rbToUnit(uint v) { return float(v >> 8) * (1.0 / 16777216.0); }

// Sample i of n on the unit disk: a Fibonacci spiral, stratified in r^2 with jitter `jitter` in [0, 1) and
// rotated by `rotation` radians. With a uniformly random jitter and rotation each sample is uniform over the
// disk, so the average of n samples is an unbiased, stratified estimate.
vec2 rbFibonacciDisk(uint i, uint n, float jitter, float rotation) {
  float r = sqrt((float(i) + jitter) / float(n));
  float phi = float(i) * RB_GOLDEN_ANGLE + rotation;
  return r * vec2(cos(phi), sin(phi));
}

// An orthonormal basis around n (Duff et al. 2017).
void rbBasis(vec3 n, out vec3 t, out vec3 b) {
  float s = n.z >= 0.0 ? 1.0 : -1.0;
  float a = -1.0 / (s + n.z);
  float c = n.x * n.y * a;
  t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
  b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-weighted hemisphere direction around n from a disk sample (Malley's method).
vec3 rbCosineHemisphere(vec3 n, vec2 disk) {
  vec3 t, b;
  rbBasis(n, t, b);
  float z = sqrt(max(0.0, 1.0 - dot(disk, disk)));
  return normalize(disk.x * t + disk.y * b + z * n);
}

// Moves a surface point off its surface along the geometric normal so a ray leaving it does not hit the
// surface it starts on (Waechter & Binder, Ray Tracing Gems ch. 6): an offset in float ulps that grows with
// the magnitude of the coordinates, plus a fixed offset near the origin.
vec3 rbOffsetRayOrigin(vec3 p, vec3 n) {
  const float kOrigin = 1.0 / 32.0;
  const float kFloatScale = 1.0 / 65536.0;
  const float kIntScale = 256.0;
  ivec3 ofi = ivec3(kIntScale * n);
  vec3 pi = vec3(intBitsToFloat(floatBitsToInt(p.x) + (p.x < 0.0 ? -ofi.x : ofi.x)),
                 intBitsToFloat(floatBitsToInt(p.y) + (p.y < 0.0 ? -ofi.y : ofi.y)),
                 intBitsToFloat(floatBitsToInt(p.z) + (p.z < 0.0 ? -ofi.z : ofi.z)));
  return vec3(abs(p.x) < kOrigin ? p.x + kFloatScale * n.x : pi.x,
              abs(p.y) < kOrigin ? p.y + kFloatScale * n.y : pi.y,
              abs(p.z) < kOrigin ? p.z + kFloatScale * n.z : pi.z);
}

#endif

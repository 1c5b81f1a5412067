#include "content_hash.h"

#include <cstring>

namespace rb {

namespace {

// 64x64 -> 128 multiply folded to 64 bits: the mixing step of wyhash-style hashes; one multiply per 8 bytes
// keeps hashing a million-vertex mesh well under a millisecond per megabyte.
inline uint64_t mix(uint64_t a, uint64_t b) {
  __uint128_t r = static_cast<__uint128_t>(a) * b;
  return static_cast<uint64_t>(r) ^ static_cast<uint64_t>(r >> 64);
}

constexpr uint64_t kP0 = 0xa0761d6478bd642full;
constexpr uint64_t kP1 = 0xe7037ed1a0b428dbull;
constexpr uint64_t kP2 = 0x8ebc6af09c88c6e3ull;

}  // namespace

uint64_t hashBytes(const void* data, size_t size, uint64_t seed) {
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t h = seed ^ mix(seed ^ kP0, size ^ kP1);
  size_t i = 0;
  for (; i + 16 <= size; i += 16) {
    uint64_t a, b;
    std::memcpy(&a, p + i, 8);
    std::memcpy(&b, p + i + 8, 8);
    h = mix(a ^ kP1 ^ h, b ^ kP2);
  }
  uint64_t tail[2] = {0, 0};
  std::memcpy(tail, p + i, size - i);
  h = mix(tail[0] ^ kP1 ^ h, tail[1] ^ kP2 ^ (size - i));
  return mix(h ^ kP0, size ^ kP2);
}

uint64_t hashCombine(uint64_t a, uint64_t b) { return mix(a ^ kP0, b ^ kP1); }

}  // namespace rb

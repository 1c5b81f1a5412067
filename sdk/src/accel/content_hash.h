// A fast 64-bit hash of mesh contents for BLAS dedup (not cryptographic; collisions are 2^-64 unlikely).
#pragma once

#include <cstddef>
#include <cstdint>

namespace rb {

uint64_t hashBytes(const void* data, size_t size, uint64_t seed);
uint64_t hashCombine(uint64_t a, uint64_t b);

}  // namespace rb

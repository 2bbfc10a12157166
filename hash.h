// splitmix64's finaliser (Steele, Lea and Flood 2014): a bijection of
// 64-bit words with full avalanche, for hashes and reproducible
// pseudo-random values (the mesh hash, the hemicube's shot angle).
#ifndef RADIOSITY_HASH_H
#define RADIOSITY_HASH_H

#include <cstdint>

inline uint64_t SplitMix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

#endif

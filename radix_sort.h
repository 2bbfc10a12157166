// A stable sort of a vector by an unsigned 64-bit key, least significant
// byte first: linear in the items where std::sort is n log n, for the
// millions of edges joining sorts and of elements the groups' tree
// orders at 10^6 faces. Items whose keys are equal keep their order, so
// sorting items that come in order of a second key sorts by both.
#ifndef RADIOSITY_RADIX_SORT_H
#define RADIOSITY_RADIX_SORT_H

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

// Sorts *items by key(item)'s bits [from, 64): each byte of them in turn,
// skipping a byte every key shares.
template <class T, class Key>
void RadixSort(std::vector<T>* items, Key key, int from = 0) {
  std::vector<T> tmp;
  for (int shift = from; shift < 64; shift += 8) {
    std::array<size_t, 257> at{};
    for (const T& x : *items) ++at[((key(x) >> shift) & 0xff) + 1];
    if (std::find(at.begin(), at.end(), items->size()) != at.end()) continue;
    for (size_t b = 0; b < 256; ++b) at[b + 1] += at[b];
    tmp.resize(items->size());
    for (const T& x : *items) tmp[at[(key(x) >> shift) & 0xff]++] = x;
    items->swap(tmp);
  }
}

#endif

// How much memory a run may take, and whether a scene fits in it: a scene
// that would not fit is refused at load with one line (exit 2) instead of
// being killed by the kernel half-way (man page, LIMITS).
//
// The bytes per element are the peak resident size of a run at about
// 10^6 elements divided by its elements (bench/memory.sh; README, Layout:
// memory, says which structures hold them). They are double: estimates.
#ifndef RADIOSITY_MEMORY_H
#define RADIOSITY_MEMORY_H

#include <cstddef>
#include <cstdlib>
#include <string>

// The master: mesh, solver, subdivision's adjacency, the hemicube (-j 0)
// or the scene frame (with workers), the pictures at the end of a wave.
// Measured at 1.06 M elements with shooter groups (the default): 263 to
// 264 with -j 0 and 249 to 250 with -j 1 over 2 shots (336 and 336 at
// 7afbefc, when the group search at start-up was the peak), but 401 to
// 404 and 404 in a first wave that divided and split 263,927 patches
// into 537,470: its picture (Shade's polygons and colours, AutoExposure's
// weights) beside the adjacency and the solver grown for the children
// and the pieces (394 to 395 and 392 to 393 at 4f9cb58, when
// AutoExposure made its weights again for every walk, a quarter of the
// vertices at a time: 4 times its time; 401 and 406 at d8ab6ac, when it
// kept a bin per vertex too; 412 and 418 at 597cf95, with the noise and
// direct tracks kept through the picture: Solver::EndWave). The rate is
// the highest, 404, with about 11% room, since subdivision's limit
// (app.cpp) takes it as the cost of every element (460 at d8ab6ac; 490
// at 597cf95, from 429; 520 at 7afbefc, from that pass's 462 at
// 0cd4817). Since a wave's picture is shaded on the writers' thread
// from a copy of its radiosity (MasterRun::PictureLater: 24 bytes an
// element while it shades, beside the next wave's arrays), the master of
// -j 1 peaks at 424 to 425 (-j 0, which makes it on its own thread, at
// 399 to 402): 470, about 11% room again (450 before).
constexpr double kMasterBytesPerElement = 470;
// A worker: the mesh, its adjacency once divisions come, the hemicube.
// It forms no shooter groups (the master sends them with the work), so
// groups or not it measured the same: 147 to 148 over 2 shots, at the
// end of BuildMesh's cutting and at its columns; 170 to 196 once that
// pass's divisions and splits have come, its hemicube cache rebuilt
// beside the adjacency. The rate is the highest, 196, with about 13% room
// as for the master (290 while a worker searched for groups itself, 254
// at its start-up; 275 from the dividing run's 242 before that).
constexpr double kWorkerBytesPerElement = 225;

// Bytes this process may still use: physical memory, or less where
// ulimit -v / -d or a cgroup's memory.max says so.
double UsableMemory();

// False with *err (one line, no prefix) when `elements` elements at
// `bytes_per_element` would not fit in `usable` bytes.
bool FitsInMemory(double elements, double bytes_per_element, double usable, std::string* err);

// Arrays of kMappedBytes and more in mappings of their own from here on,
// given back to the system as soon as they are freed. glibc's threshold
// for that rises otherwise to the size of each such block freed (up to 32
// MB), and arrays under it come from the heap, where freed they stay
// resident: a run's passing arrays (a wave's picture, a division pass's)
// then raised the peak by 8% of the master's. Called first by the master
// and by a worker.
constexpr size_t kMappedBytes = size_t(1) << 20;
void MapLargeArrays();

// Gives the heap's free pages back to the system now (malloc_trim): glibc
// keeps freed small blocks resident otherwise, so after many are freed a
// process stays as large as it ever was.
void ReturnFreeMemory();

// Empties *v and gives its storage back now (clear() keeps the capacity).
template <class V>
void FreeStorage(V* v) {
  V().swap(*v);
}

// Arrays read at scattered places and larger than the TLB reaches with
// 4 KB pages (the solver's per element and per patch, at 10^5 of them
// and more) wait on a page walk per access; backed by 2 MB pages where
// the kernel has them (transparent huge pages not off), they do not.
//
// PreferHugePages: the whole 2 MB pages inside [p, p + bytes), for an
// array allocated elsewhere; the bytes stay as they are.
void PreferHugePages(const void* p, size_t bytes);
// Storage of `bytes` aligned to 64: in 2 MB pages from the start when it
// is 2 MB and more (its last part less than 2 MB in small pages, so
// nothing more is resident); freed by std::free.
void* AllocateHuge(size_t bytes);
template <class T>
struct HugePageAllocator {
  typedef T value_type;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  static_assert(alignof(T) <= 64, "AllocateHuge aligns to 64");
  T* allocate(size_t n) { return static_cast<T*>(AllocateHuge(n * sizeof(T))); }
  void deallocate(T* p, size_t) { std::free(p); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const HugePageAllocator<U>&) const { return false; }
};

#endif

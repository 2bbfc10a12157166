// How much memory a run may take, and whether a scene fits in it: a scene
// that would not fit is refused at load with one line (exit 2) instead of
// being killed by the kernel half-way (man page, LIMITS).
//
// The bytes per element are the peak resident size of a run at about
// 10^6 elements divided by its elements (bench/memory.sh; README, Layout:
// memory, says which structures hold them). They are double: estimates.
#ifndef RADIOSITY_MEMORY_H
#define RADIOSITY_MEMORY_H

#include <string>

// The master: mesh, solver, subdivision's adjacency, the hemicube (-j 0)
// or the scene frame (with workers), the pictures at the end of a wave
// (measured 413 with -j 0, 367 with -j 1, at 1.06 M elements; room left
// for a few bytes an element more and for scenes that mesh less evenly).
constexpr double kMasterBytesPerElement = 470;
// A worker: the mesh, its adjacency once divisions come, the hemicube
// (measured 219: the end of BuildMesh, the mesh beside the surfaces, just
// above the columns' mesh and hemicube cache).
constexpr double kWorkerBytesPerElement = 250;

// Bytes this process may still use: physical memory, or less where
// ulimit -v / -d or a cgroup's memory.max says so.
double UsableMemory();

// False with *err (one line, no prefix) when `elements` elements at
// `bytes_per_element` would not fit in `usable` bytes.
bool FitsInMemory(double elements, double bytes_per_element, double usable, std::string* err);

#endif

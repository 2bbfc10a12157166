// Shooter groups (Kok, "Grouping of patches in progressive radiosity",
// EGRW 1993): small patches near one another that face about the same way
// shoot together, from one hemicube at their area centroid with their
// area-weighted normal, their summed unshot power Σ unshot·A. Progressive
// refinement needs about one shot per shooter, so a scene of 50,000 small
// faces needs 50,000 shots however fast each is; a group of k patches
// drains them in one. Each member gives up exactly its own unshot
// radiosity, so energy stays exact; the approximation is only where the
// light leaves from (the centroid instead of each member), which is why a
// group is kept small against the distance to what it lights and never
// spans a wall.
//
// The rule (man page, MESH), Kok's: a group is small against the distance
// to what it lights. For a patch p that emits nothing and is at most
// kSmallPatch patch sizes across (the mesh's own patches shoot alone), d(p) is the
// distance from its centre to the nearest element it can light (of
// another patch, in front of p's plane, facing p; bounding boxes, so that
// d is never too large); p may be in a group at most
// min(G, kGroupReach · d(p)) across (G = MeshOptions::group_size, default
// kGroupPatches patch sizes, at least patch size / 16), and is a
// candidate when it is that small itself. So a group shoots from one
// point only what its receivers see as coming from about one point: in a
// dense scene (boxes a gap apart) nothing groups, far from everything
// (small faces high under a ceiling) groups grow to G. Groups are formed
// inside the cells of a grid of cell G over the patch centres, greedily in
// patch order, looking at most kLookAhead candidates past each first
// member; a group's members' bounding box stays within the smallest limit
// among them, and a patch joins only when, against every member already
// in: the normals are within kGroupAngle; each lies in front of the
// other's plane, or behind it by at most patch size / 16 (they neither
// face each other nor sit back to back, nor one behind the other); and the
// segment between their centres, lifted by patch size / 32 along each
// normal, crosses no element of another patch (no wall, no box in
// between). At most kMaxGroup members.
//
// Derived from the mesh as built and the options alone, deterministically,
// so a checkpoint need not save them. Only the master forms them: a
// worker builds its mesh with groups off (their search, its element
// boxes, orders and tree beside the finished mesh, was a worker's memory
// peak and seconds of its start-up at 10^6 elements), and each group
// travels with its first member's assignment (protocol.h, Assignment),
// which Hemicube::Column takes instead of reading Mesh::group_of.
//
// Numbers: double, as the mesh's geometry; the search keeps its element
// boxes in float, rounded outward, only to rule elements out (an element
// it does not rule out is measured in double, so the groups are those of
// boxes in double).
#ifndef RADIOSITY_GROUPS_H
#define RADIOSITY_GROUPS_H

#include "mesh.h"

constexpr double kGroupAngle = 25.0;  // degrees between members' normals, at most
constexpr double kGroupReach = 1.0;   // a group's width over the distance to its nearest receiver, at most
constexpr double kGroupPatches = 4.0; // default G, in patch sizes
constexpr double kSmallPatch = 0.5;   // the widest patch that may group, in patch sizes
constexpr int kMaxGroup = 64;         // members of a group, at most
constexpr int kLookAhead = 512;       // candidates looked at past a group's first member

// Fills mesh->groups and mesh->group_of for the patches as built (no
// groups when !opts.groups). Subdivision divides elements, not patches,
// so the groups hold for the whole run.
void FormGroups(const MeshOptions& opts, Mesh* mesh);

// The group patch p shoots for, or null when p shoots alone. Only a
// group's first member is a shooter (Solver::Select, the hemicube); the
// others are never selected.
inline const PatchGroup* GroupOf(const Mesh& mesh, int p) {
  return mesh.group_of.empty() || mesh.group_of[p] < 0 ? nullptr
                                                        : &mesh.groups[mesh.group_of[p]];
}
inline bool IsShooter(const Mesh& mesh, int p) {
  const PatchGroup* g = GroupOf(mesh, p);
  return !g || g->members[0] == p;
}
// The patches that shoot as shooter p: its group's members, or p alone
// (the span then points at p, which must outlive it).
inline IdSpan ShootsAs(const Mesh& mesh, const int32_t& p) {
  const PatchGroup* g = GroupOf(mesh, p);
  if (!g) return {&p, &p + 1};
  return {g->members.data(), g->members.data() + g->members.size()};
}
// Patches alone plus groups: what progressive refinement has to shoot.
inline size_t Shooters(const Mesh& mesh) {
  size_t n = mesh.patches.size();
  for (const PatchGroup& g : mesh.groups) n -= g.members.size() - 1;
  return n;
}

#endif

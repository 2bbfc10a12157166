// Shooter groups (Kok, "Grouping of patches in progressive radiosity",
// EGRW 1993): small patches near one another that face about the same way
// shoot together, from one hemicube at their area centroid with their
// area-weighted normal, their summed unshot power Σ unshot·A. Progressive
// refinement needs about one shot per shooter, so a scene of 50,000 small
// faces needs 50,000 shots however fast each is; a group of k patches
// drains them in one. Each member gives up exactly its own unshot
// radiosity, so energy stays exact; the approximation is only where the
// light leaves from (the centroid instead of each member), which is why a
// group is kept small against the patch size and never spans a wall.
//
// The rule (man page, MESH): a patch may join a group when it emits
// nothing and its bounding box is at most L across (L =
// MeshOptions::group_size, default the patch size, at least patch size /
// 16). Groups are formed inside the cells of a grid of cell L over the
// patch centres, greedily in patch order; a group's members' bounding box
// stays at most L across (no wider than a patch, whose light the mesh
// already sends from one centre), and a patch joins only when, against
// every member already in: the normals are within kGroupAngle; each lies
// in front of the other's plane, or behind it by at most L/16 (they
// neither face each other nor sit back to back, nor one behind the
// other); and the segment between their centres, lifted by L/32 along
// each normal, crosses no element of another patch
// (no wall, no box in between). At most kMaxGroup members.
//
// Derived from the mesh as built and the options alone, deterministically:
// the master and every worker form the same groups (workers get the
// options in the scene setup), and a checkpoint need not save them.
//
// Numbers: double, as the mesh's geometry.
#ifndef RADIOSITY_GROUPS_H
#define RADIOSITY_GROUPS_H

#include "mesh.h"

constexpr double kGroupAngle = 25.0;  // degrees between members' normals, at most
constexpr int kMaxGroup = 32;         // members of a group, at most

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
// Patches alone plus groups: what progressive refinement has to shoot.
inline size_t Shooters(const Mesh& mesh) {
  size_t n = mesh.patches.size();
  for (const PatchGroup& g : mesh.groups) n -= g.members.size() - 1;
  return n;
}

#endif

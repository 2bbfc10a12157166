// Surfaces from faces: adjacent coplanar faces of one material joined into
// convex polygons before the mesh is cut (man page, MESH), so that a wall
// exported as 128 triangles is cut as the one quad it is; and the exact
// overlap of an element with one of the input faces it covers, for the
// per-face results.
//
// Joining is greedy, in the manner of Hertel and Mehlhorn: two pieces
// that share a run of edges are joined while the union stays convex, the
// pairs with the longest common boundary first, in passes until no pair
// joins. Pieces stay convex, so a non-convex surface becomes a few convex
// pieces and elements stay convex planar triangles and quads.
#ifndef RADIOSITY_SURFACE_H
#define RADIOSITY_SURFACE_H

#include <vector>

#include <glm/glm.hpp>

#include "scene.h"

// Plane tolerance: every corner of a surface lies within this fraction of
// the surface's bounding-box diagonal from its plane, plus a term for
// coordinates printed with 7 significant digits (their rounding grows with
// the coordinates' magnitude, not with the surface's size). Corners this
// close to the line through their neighbours count as straight.
constexpr double kSurfaceRel = 1e-4;
constexpr double kSurfaceDigits = 2e-6;

struct Surface {
  // Counter-clockwise from the front. A surface of one face is that face's
  // polygon as read (any simple polygon); a joined one is convex, with the
  // straight corners of its pieces' common edges left out.
  std::vector<glm::dvec3> poly;
  std::vector<int> faces;  // Scene::faces indices, ascending
  // Unit normal and plane dot(normal, x) == offset: the face's own for one
  // face; for a join the area-weighted fit (double: see Element::area).
  glm::dvec3 normal{0.0};
  double offset = 0.0;
  double area = 0.0;       // its faces' areas summed
  int material = 0;
};

// The scene's surfaces, ordered by their first face (one per face, in
// face order, when `join` is false or nothing joins).
std::vector<Surface> BuildSurfaces(const Scene& scene, bool join);

// Orthonormal coordinates in a surface's plane, for exact overlaps.
struct PlaneFrame {
  glm::dvec3 origin{0.0}, u{0.0}, v{0.0};
  PlaneFrame(const glm::dvec3& origin, const glm::dvec3& normal);
  glm::dvec2 At(const glm::dvec3& p) const {
    const glm::dvec3 d = p - origin;
    return {glm::dot(d, u), glm::dot(d, v)};
  }
};

// Signed area of a 2D polygon (positive counter-clockwise).
double Area2(const std::vector<glm::dvec2>& poly);

// Area of the part of polygon `subject` inside convex counter-clockwise
// polygon `clip` (Sutherland-Hodgman).
double OverlapArea(const std::vector<glm::dvec2>& subject, const std::vector<glm::dvec2>& clip);

#endif

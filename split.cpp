// Shooter division's side of the mesh (declared in mesh.h): cutting a
// patch into patches along its elements. The policy that chooses them is
// subdivide.cpp's, the sharing of the unshot power the solver's.
#include <vector>

#include "check.h"
#include "mesh.h"

namespace {

// The top elements the pieces of `patch` would have.
void PieceTops(const Mesh& m, int patch, std::vector<int>* tops) {
  tops->clear();
  const IdSpan el = m.Tops(patch);
  if (el.size() > 1) {
    tops->assign(el.begin(), el.end());
  } else if (el.size() == 1 && !m.elems[size_t(el[0])].IsLeaf()) {
    for (int k = 0; k < kChildren; ++k) tops->push_back(m.elems[size_t(el[0])].first_child + k);
  }
}

// Element `top` and everything below it to patch `patch`.
void MoveTo(Mesh* m, int top, int patch) {
  std::vector<int> stack{top};
  while (!stack.empty()) {
    Element& e = m->elems[size_t(stack.back())];
    stack.pop_back();
    e.patch = patch;
    if (!e.IsLeaf())
      for (int k = 0; k < kChildren; ++k) stack.push_back(e.first_child + k);
  }
}

}  // namespace

int SplitPieces(const Mesh& mesh, int patch, std::vector<int>* tops) {
  if (tops) tops->clear();
  if (patch < 0 || size_t(patch) >= mesh.patches.size()) return 0;
  if (!mesh.group_of.empty() && mesh.group_of[size_t(patch)] >= 0) return 0;
  std::vector<int> own;
  if (!tops) tops = &own;
  PieceTops(mesh, patch, tops);
  return int(tops->size());
}

void SplitPatch(Mesh* mesh, int patch) {
  std::vector<int> tops;
  CHECK(SplitPieces(*mesh, patch, &tops) > 1);
  const int face = mesh->patches[size_t(patch)].face;
  for (size_t i = 0; i < tops.size(); ++i) {
    const int id = i == 0 ? patch : int(mesh->patches.size());
    if (i > 0) {
      mesh->patches.emplace_back();
      mesh->faces[size_t(face)].patches.push_back(id);
      if (!mesh->group_of.empty()) mesh->group_of.push_back(-1);
    }
    // As BuildMesh makes a patch: its top elements' areas and centroids.
    Patch& p = mesh->patches[size_t(id)];
    p.face = face;
    // One top element: the first piece in the patch's first slot, the
    // others in slots appended.
    if (i > 0) {
      p.tops_at = int32_t(mesh->patch_tops.size());
      mesh->patch_tops.push_back(tops[i]);
    }
    mesh->patch_tops[size_t(p.tops_at)] = tops[i];
    p.tops = 1;
    p.area = mesh->elems[size_t(tops[i])].area;
    p.center = mesh->Centroid(tops[i]);
    MoveTo(mesh, tops[i], id);
  }
  // A divided top that gave its children away stays with the patch: its
  // children are what shoot and receive.
  mesh->splits.push_back(patch);
}

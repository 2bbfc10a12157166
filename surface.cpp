#include "surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "hash.h"
#include "mesh.h"
#include "point_ids.h"
#include "radix_sort.h"

namespace {

// A piece of a surface while faces are joined: its outline by welded
// vertex ids, every corner of its faces' common edges kept so that a
// neighbour's edge is found as one of its edges.
struct Piece {
  std::vector<int> loop;
  std::vector<int> faces;
  glm::dvec3 area_vec{0.0};  // the faces' area vectors summed: the fitted normal
  glm::dvec3 moment{0.0};    // area times centroid, summed: a point of the plane
  double area = 0.0;
  glm::dvec3 lo{0.0}, hi{0.0};
  int version = 0;  // bumped by each join, so that a failed pair is retried once changed
  int pass_version = 0;  // as it was when the pass began
  bool alive = true;
};

double Tolerance(const glm::dvec3& lo, const glm::dvec3& hi) {
  const double magnitude = glm::length(glm::max(glm::abs(lo), glm::abs(hi)));
  return kSurfaceRel * glm::length(hi - lo) + kSurfaceDigits * magnitude;
}

// Twice the signed area of corner a, b, c about n, and how far b may lie
// from the line a-c for the corner to count as straight.
double Turn(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& n) {
  return glm::dot(glm::cross(b - a, c - b), n);
}
bool Straight(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& n,
              double tol) {
  return std::abs(Turn(a, b, c, n)) <= tol * glm::length(c - a);
}
bool ConvexCorner(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                  const glm::dvec3& n, double tol) {
  return Turn(a, b, c, n) >= 0 || Straight(a, b, c, n, tol);
}

class Joiner {
 public:
  explicit Joiner(const Scene& scene) : scene_(scene) {}

  std::vector<Surface> Run() {
    Weld();
    Group();
    // Each group's faces in a row, in face order (a counting sort by root).
    const size_t n = group_.size();
    std::vector<int> begin(n + 1, 0), members(n);
    for (size_t f = 0; f < n; ++f) ++begin[size_t(Find(int(f))) + 1];
    for (size_t r = 0; r < n; ++r) begin[r + 1] += begin[r];
    // A piece for each face of a group of more than one, numbered in face
    // order (so pieces compare as their first faces did); a face alone
    // never joins and becomes its surface as read.
    piece_at_.assign(n, -1);
    for (size_t f = 0; f < n; ++f) {
      const size_t r = size_t(Find(int(f)));
      if (begin[r + 1] - begin[r] > 1) {
        piece_at_[f] = int(pieces_.size());
        pieces_.push_back(FacePiece(int(f)));
      }
    }
    piece_of_ = piece_at_;
    std::vector<int> fill(begin.begin(), begin.end() - 1);
    for (size_t f = 0; f < n; ++f) members[size_t(fill[size_t(Find(int(f)))]++)] = int(f);
    for (size_t r = 0; r < n; ++r)
      if (begin[r + 1] - begin[r] > 1)
        Whole(std::vector<int>(members.begin() + begin[r], members.begin() + begin[r + 1]));
    while (Pass()) {}
    std::vector<Surface> out;
    for (size_t f = 0; f < n; ++f) {
      const int i = piece_at_[f];
      if (i < 0)
        out.push_back(Alone(int(f)));
      else if (pieces_[size_t(i)].alive)
        out.push_back(Finish(i));
    }
    return out;
  }

 private:
  void Weld() {
    constexpr size_t kAhead = 4;
    const size_t n = scene_.faces.size();
    PointIds ids(&verts_);
    std::vector<uint64_t> used;  // every face's edges, undirected
    size_t corners = 0;
    for (const Face& face : scene_.faces) corners += face.verts.size();
    ids.Reserve(corners);
    used.reserve(corners);
    edges_.reserve(corners);
    loop_at_.resize(n + 1);
    loops_.reserve(corners);
    lo_.resize(n);
    hi_.resize(n);
    for (size_t f = 0; f < n; ++f) {
      const Face& face = scene_.faces[f];
      // The corners of a face a few ahead on their way while this one's
      // are welded.
      if (f + kAhead < n)
        for (const glm::dvec3& v : scene_.faces[f + kAhead].verts) ids.Prefetch(v);
      loop_at_[f] = int(loops_.size());
      glm::dvec3 lo = face.verts[0], hi = lo;
      for (const glm::dvec3& v : face.verts) {
        loops_.push_back(ids.Id(v));
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
      }
      lo_[f] = lo;
      hi_[f] = hi;
      const int* loop = loops_.data() + loop_at_[f];
      for (size_t k = 0, m = face.verts.size(); k < m; ++k) {
        const int a = loop[k], b = loop[(k + 1) % m];
        used.push_back(a < b ? EdgeKey(a, b) : EdgeKey(b, a));
      }
      // Only convex faces join: the pieces must stay convex.
      const double tol = Tolerance(lo, hi);
      bool convex = true;
      const size_t m = face.verts.size();
      for (size_t k = 0; k < m && convex; ++k)
        convex = ConvexCorner(face.verts[k], face.verts[(k + 1) % m], face.verts[(k + 2) % m],
                              face.normal, tol);
      if (!convex) continue;
      for (size_t k = 0; k < m; ++k)
        edges_.push_back({EdgeKey(loop[k], loop[(k + 1) % m]), int(f)});
    }
    loop_at_[n] = int(loops_.size());
    // An edge of more than two faces has something standing on it (a wall
    // on the line where a floor was cut): no join across it, or elements
    // would reach from one side of the wall to the other.
    RadixSort(&used, [](uint64_t k) { return k; });
    std::vector<uint64_t> crowded;  // sorted: those of more than two faces (few)
    for (size_t i = 0; i + 2 < used.size(); ++i)
      if (used[i] == used[i + 2] && (crowded.empty() || crowded.back() != used[i]))
        crowded.push_back(used[i]);
    std::vector<uint64_t>().swap(used);
    if (!crowded.empty())
      edges_.erase(std::remove_if(edges_.begin(), edges_.end(),
                                  [&](const std::pair<uint64_t, int>& e) {
                                    const int a = int(e.first >> 32), b = int(uint32_t(e.first));
                                    return std::binary_search(crowded.begin(), crowded.end(),
                                                              a < b ? e.first : EdgeKey(b, a));
                                  }),
                   edges_.end());
    // By edge, then by face: they came in face order.
    RadixSort(&edges_, [](const std::pair<uint64_t, int>& e) { return e.first; });
    // Where each vertex's edges begin (edges_ is sorted by the first
    // vertex), and each edge's reverse: FaceWith in a few steps, and
    // each pass without a search.
    from_.assign(verts_.size() + 1, 0);
    for (const auto& e : edges_) ++from_[size_t(e.first >> 32) + 1];
    for (size_t v = 0; v < verts_.size(); ++v) from_[v + 1] += from_[v];
    twin_.resize(edges_.size());
    for (size_t i = 0; i < edges_.size(); ++i)
      twin_[i] = FaceWith(int(uint32_t(edges_[i].first)), int(edges_[i].first >> 32));
  }

  // Faces f and g face the same way and each one's corners lie within the
  // tolerance of the other's plane.
  bool Coplanar(int f, int g) const {
    const Face &a = scene_.faces[f], &b = scene_.faces[g];
    if (!(glm::dot(a.normal, b.normal) > 0)) return false;
    const double tol = Tolerance(glm::min(lo_[size_t(f)], lo_[size_t(g)]),
                                 glm::max(hi_[size_t(f)], hi_[size_t(g)]));
    for (const glm::dvec3& v : b.verts)
      if (std::abs(glm::dot(v - a.verts[0], a.normal)) > tol) return false;
    for (const glm::dvec3& v : a.verts)
      if (std::abs(glm::dot(v - b.verts[0], b.normal)) > tol) return false;
    return true;
  }

  int Find(int f) {
    while (group_[f] != f) f = group_[f] = group_[group_[f]];
    return f;
  }

  // Groups: faces joined through shared edges to coplanar faces of their
  // material. Pieces join only inside a group.
  void Group() {
    group_.resize(scene_.faces.size());
    for (size_t f = 0; f < group_.size(); ++f) group_[f] = int(f);
    for (size_t i = 0; i < edges_.size(); ++i) {
      const int f = edges_[i].second, g = twin_[i];
      if (g < 0 || scene_.faces[g].material != scene_.faces[f].material || !Coplanar(f, g))
        continue;
      const int a = Find(f), b = Find(g);
      if (a != b) group_[std::max(a, b)] = std::min(a, b);
    }
  }

  // A group whose outline is one loop, convex and within the tolerance of
  // its plane, becomes one piece at once (a wall cut into triangles, a fan
  // of an n-gon): the pairwise joins below could stop short of it.
  void Whole(const std::vector<int>& members) {
    const int root = members[0];  // a face; its piece, piece_at_[root], takes the whole
    std::unordered_map<int, int> next;  // the outline's directed edges
    size_t edges = 0;
    int start = -1;
    for (int f : members) {
      const std::vector<int>& l = pieces_[size_t(piece_at_[size_t(f)])].loop;
      for (size_t k = 0; k < l.size(); ++k) {
        const int a = l[k], b = l[(k + 1) % l.size()];
        const int g = FaceWith(b, a);
        if (g >= 0 && Find(g) == root) continue;  // inside
        if (!next.emplace(a, b).second) return;  // the outline touches itself
        if (edges++ == 0) start = a;
      }
    }
    std::vector<int> loop;
    for (int v = start; loop.size() <= edges;) {
      loop.push_back(v);
      auto it = next.find(v);
      if (it == next.end()) return;
      if ((v = it->second) == start) break;
    }
    if (loop.size() != edges) return;  // more than one loop: holes
    Piece whole;
    whole.lo = lo_[size_t(root)];
    whole.hi = hi_[size_t(root)];
    for (int f : members) {
      const Piece& p = pieces_[size_t(piece_at_[size_t(f)])];
      whole.area_vec += p.area_vec;
      whole.moment += p.moment;
      whole.area += p.area;
      whole.lo = glm::min(whole.lo, p.lo);
      whole.hi = glm::max(whole.hi, p.hi);
    }
    const double tol = Tolerance(whole.lo, whole.hi);
    const glm::dvec3 normal = glm::normalize(whole.area_vec);
    const glm::dvec3 centre = whole.moment / whole.area;
    const size_t u = loop.size();
    for (size_t k = 0; k < u; ++k) {
      const glm::dvec3& v = verts_[loop[k]];
      if (std::abs(glm::dot(v - centre, normal)) > tol ||
          !ConvexCorner(verts_[loop[(k + u - 1) % u]], v, verts_[loop[(k + 1) % u]], normal, tol))
        return;
    }
    whole.loop = std::move(loop);
    whole.faces = members;
    for (int f : members) {
      pieces_[size_t(piece_at_[size_t(f)])].alive = false;
      piece_of_[size_t(f)] = piece_at_[size_t(root)];
    }
    pieces_[size_t(piece_at_[size_t(root)])] = std::move(whole);
  }

  // The face with directed edge a -> b, or -1 (the first, where faces
  // repeat an edge).
  int FaceWith(int a, int b) const {
    const uint64_t key = EdgeKey(a, b);
    for (int i = from_[size_t(a)]; i < from_[size_t(a) + 1]; ++i)
      if (edges_[size_t(i)].first == key) return edges_[size_t(i)].second;
    return -1;
  }

  // One pass: every pair of pieces sharing edges, the longest common
  // boundary first, joined where both are still as they were at the
  // start of the pass. True if any joined.
  bool Pass() {
    struct Pair {
      int a, b;
      double shared;
    };
    if (!open_ready_) {  // the first pass: the edges between faces of one group
      for (size_t i = 0; i < edges_.size(); ++i)
        if (twin_[i] >= 0 && Find(twin_[i]) == Find(edges_[i].second)) open_.push_back(int(i));
      open_ready_ = true;
    }
    std::vector<Pair> pairs;
    size_t kept = 0;  // an edge inside one piece stays inside: dropped, in order
    for (const int i : open_) {
      const auto& [key, f] = edges_[size_t(i)];
      const int pf = piece_of_[f], pg = piece_of_[twin_[size_t(i)]];
      if (pf == pg) continue;
      open_[kept++] = i;
      const int a = int(key >> 32), b = int(uint32_t(key));
      if (pf < pg) pairs.push_back({pf, pg, glm::length(verts_[b] - verts_[a])});
    }
    open_.resize(kept);
    std::sort(pairs.begin(), pairs.end(), [](const Pair& x, const Pair& y) {
      return x.a != y.a ? x.a < y.a : x.b < y.b;
    });
    size_t w = 0;
    for (size_t i = 0; i < pairs.size(); ++i) {
      if (w > 0 && pairs[w - 1].a == pairs[i].a && pairs[w - 1].b == pairs[i].b)
        pairs[w - 1].shared += pairs[i].shared;
      else
        pairs[w++] = pairs[i];
    }
    pairs.resize(w);
    std::stable_sort(pairs.begin(), pairs.end(),
                     [](const Pair& x, const Pair& y) { return x.shared > y.shared; });
    bool any = false;
    for (const Pair& pr : pairs) {
      Piece &p = pieces_[pr.a], &q = pieces_[pr.b];
      if (p.version != p.pass_version || q.version != q.pass_version) continue;
      const std::array<int, 4> key{{pr.a, p.version, pr.b, q.version}};
      if (failed_.count(key)) continue;
      if (!Join(pr.a, pr.b)) {
        failed_.insert(key);
        continue;
      }
      any = true;
    }
    for (const int i : joined_) pieces_[size_t(i)].pass_version = pieces_[size_t(i)].version;
    joined_.clear();
    return any;
  }

  // Joins piece b into piece a if they share one run of edges, the union
  // is convex at the run's two ends (every other corner is as it was) and
  // all its corners lie within the tolerance of the fitted plane.
  bool Join(int ia, int ib) {
    Piece &p = pieces_[ia], &q = pieces_[ib];
    if (!(glm::dot(p.area_vec, q.area_vec) > 0)) return false;  // facing apart
    const std::vector<int>&P = p.loop, &Q = q.loop;
    const int n = int(P.size()), m = int(Q.size());
    std::unordered_map<int, int> at_q;
    for (int j = 0; j < m; ++j) at_q.emplace(Q[j], j);
    auto shared = [&](int i) {  // P's edge i, i+1 is one of Q's, reversed
      auto it = at_q.find(P[(i + 1) % n]);
      return it != at_q.end() && Q[(it->second + 1) % m] == P[i];
    };
    std::vector<char> s(n);
    int runs = 0, start = -1, len = 0;
    for (int i = 0; i < n; ++i) len += s[i] = shared(i);
    for (int i = 0; i < n; ++i)
      if (s[i] && !s[(i + n - 1) % n]) ++runs, start = i;
    if (runs != 1 || len >= n) return false;
    const int ps = P[start], pe = P[(start + len) % n];
    // No other corner in common: the union is a simple polygon.
    for (int k = start + len + 1; k < start + n; ++k)
      if (at_q.count(P[k % n])) return false;
    std::vector<int> loop;
    loop.reserve(size_t(n + m - 2 * len));
    for (int k = start + len; k <= start + n; ++k) loop.push_back(P[k % n]);
    for (int j = at_q[ps] + 1; Q[j % m] != pe; ++j) loop.push_back(Q[j % m]);
    const glm::dvec3 lo = glm::min(p.lo, q.lo), hi = glm::max(p.hi, q.hi);
    const double tol = Tolerance(lo, hi);
    const glm::dvec3 normal = glm::normalize(p.area_vec + q.area_vec);
    const int u = int(loop.size());
    const int at_ps = n - len;  // ps's place in the union; pe is at 0
    auto corner = [&](int k) {
      return ConvexCorner(verts_[loop[(k + u - 1) % u]], verts_[loop[k]], verts_[loop[(k + 1) % u]],
                          normal, tol);
    };
    if (!corner(0) || !corner(at_ps)) return false;
    const glm::dvec3 centre = (p.moment + q.moment) / (p.area + q.area);
    for (int v : loop)
      if (std::abs(glm::dot(verts_[v] - centre, normal)) > tol) return false;
    p.loop = std::move(loop);
    p.faces.insert(p.faces.end(), q.faces.begin(), q.faces.end());
    for (int f : q.faces) piece_of_[f] = ia;
    p.area_vec += q.area_vec;
    p.moment += q.moment;
    p.area += q.area;
    p.lo = lo;
    p.hi = hi;
    ++p.version;
    joined_.push_back(ia);
    q.alive = false;
    q.loop.clear();
    q.faces.clear();
    return true;
  }

  // Face f's piece as it is before any join.
  Piece FacePiece(int f) const {
    const Face& face = scene_.faces[size_t(f)];
    Piece p;
    p.faces = {f};
    p.loop.assign(loops_.begin() + loop_at_[size_t(f)], loops_.begin() + loop_at_[size_t(f) + 1]);
    p.area_vec = face.normal * face.area;
    p.area = face.area;
    glm::dvec3 c(0.0);
    for (const glm::dvec3& v : face.verts) c += v;
    p.moment = face.area * (c / double(face.verts.size()));
    p.lo = lo_[size_t(f)];
    p.hi = hi_[size_t(f)];
    return p;
  }

  // The surface of face f alone, as read: the mesh of an unjoined face
  // does not change.
  Surface Alone(int f) const {
    const Face& face = scene_.faces[size_t(f)];
    Surface s;
    s.faces = {f};
    s.material = face.material;
    s.poly = face.verts;
    s.normal = face.normal;
    s.offset = glm::dot(face.normal, face.verts[0]);
    s.area = face.area;
    return s;
  }

  Surface Finish(int i) {
    const Piece& p = pieces_[size_t(i)];
    if (p.faces.size() == 1) return Alone(p.faces[0]);
    Surface s;
    s.faces = p.faces;
    std::sort(s.faces.begin(), s.faces.end());
    const Face& first = scene_.faces[s.faces[0]];
    s.material = first.material;
    s.normal = glm::normalize(p.area_vec);
    s.offset = glm::dot(s.normal, p.moment / p.area);
    for (int f : s.faces) s.area += scene_.faces[f].area;
    for (int v : p.loop) s.poly.push_back(verts_[v]);
    // The corners of the pieces' common edges are straight: left out.
    const double tol = Tolerance(p.lo, p.hi);
    for (bool again = true; again && s.poly.size() > 3;) {
      again = false;
      for (size_t k = 0; k < s.poly.size() && s.poly.size() > 3; ++k) {
        const size_t u = s.poly.size();
        if (Straight(s.poly[(k + u - 1) % u], s.poly[k], s.poly[(k + 1) % u], s.normal, tol)) {
          s.poly.erase(s.poly.begin() + long(k));
          again = true;
        }
      }
    }
    return s;
  }

  struct KeyHash {
    size_t operator()(const std::array<int, 4>& k) const {
      uint64_t h = 0;
      for (int x : k) h = SplitMix64(h ^ uint32_t(x));
      return size_t(h);
    }
  };

  const Scene& scene_;
  std::vector<glm::dvec3> verts_;
  std::vector<int> loops_;          // each face's corners, welded, face by face
  std::vector<int> loop_at_;        // per face: where its corners begin in loops_; one more
  std::vector<glm::dvec3> lo_, hi_; // per face: its bounding box
  std::vector<Piece> pieces_;       // for the faces of groups of more than one (piece_at_)
  std::vector<int> piece_at_;       // face -> the piece made of it, or -1: it joins nothing
  std::vector<int> piece_of_;       // face -> the piece it is in (faces with a piece)
  std::vector<int> group_;      // union-find parent of each face (Group)
  std::vector<std::pair<uint64_t, int>> edges_;  // directed edge -> face, sorted
  std::vector<int> from_;  // per vertex: its first edge in edges_; one more at the end
  std::vector<int> twin_;  // per edge: the face with its reverse (FaceWith), or -1
  std::vector<int> open_;  // edges (edges_ order) between two pieces of one group (Pass)
  bool open_ready_ = false;
  std::vector<int> joined_;  // pieces joined into this pass (their versions moved)
  std::unordered_set<std::array<int, 4>, KeyHash> failed_;  // pairs tried as they are
};

}  // namespace

std::vector<Surface> BuildSurfaces(const Scene& scene, bool join) {
  if (join) return Joiner(scene).Run();
  std::vector<Surface> out(scene.faces.size());
  for (size_t f = 0; f < out.size(); ++f) {
    const Face& face = scene.faces[f];
    out[f] = {face.verts, {int(f)}, face.normal, glm::dot(face.normal, face.verts[0]), face.area,
              face.material};
  }
  return out;
}

PlaneFrame::PlaneFrame(const glm::dvec3& o, const glm::dvec3& n) : origin(o) {
  // The axis least along the normal gives a well-conditioned tangent.
  const glm::dvec3 a = std::abs(n.x) < 0.6 ? glm::dvec3(1, 0, 0)
                       : std::abs(n.y) < 0.6 ? glm::dvec3(0, 1, 0)
                                             : glm::dvec3(0, 0, 1);
  u = glm::normalize(a - n * glm::dot(a, n));
  v = glm::cross(n, u);
}

double Area2(const std::vector<glm::dvec2>& poly) {
  double a = 0;
  for (size_t i = 0, n = poly.size(); i < n; ++i) {
    const glm::dvec2 &p = poly[i], &q = poly[(i + 1) % n];
    a += p.x * q.y - p.y * q.x;
  }
  return 0.5 * a;
}

double OverlapArea(const std::vector<glm::dvec2>& subject, const std::vector<glm::dvec2>& clip) {
  std::vector<glm::dvec2> cur = subject, next;
  for (size_t i = 0, n = clip.size(); i < n && !cur.empty(); ++i) {
    const glm::dvec2 a = clip[i], e = clip[(i + 1) % n] - a;
    auto side = [&](const glm::dvec2& p) { return e.x * (p.y - a.y) - e.y * (p.x - a.x); };
    next.clear();
    for (size_t k = 0, m = cur.size(); k < m; ++k) {
      const glm::dvec2 &p = cur[k], &q = cur[(k + 1) % m];
      const double sp = side(p), sq = side(q);
      if (sp >= 0) next.push_back(p);
      if ((sp >= 0) != (sq >= 0)) next.push_back(p + (q - p) * (sp / (sp - sq)));
    }
    std::swap(cur, next);
  }
  return cur.size() < 3 ? 0.0 : std::max(0.0, Area2(cur));
}

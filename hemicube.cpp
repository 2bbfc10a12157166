#include "hemicube.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "check.h"
#include "clock.h"
#include "groups.h"
#include "hash.h"

namespace {

// Outcode bits of one hemicube face for a point (a, b, d) in that face's
// frame: outside |a| <= d, outside the b range, or in front of the near plane.
enum : uint32_t { kAHi = 1, kALo = 2, kBHi = 4, kBLo = 8, kNear = 16 };

// Face f's frame from shooter-local (x, y, z), z along the normal:
// 0 top (x, y, z); 1 +x (y, z, x); 2 -x (y, z, -x); 3 +y (x, z, y); 4 -y (x, z, -y).
inline void ToFace(int f, const float* p, float* q) {
  switch (f) {
    case 0: q[0] = p[0]; q[1] = p[1]; q[2] = p[2]; break;
    case 1: q[0] = p[1]; q[1] = p[2]; q[2] = p[0]; break;
    case 2: q[0] = p[1]; q[1] = p[2]; q[2] = -p[0]; break;
    case 3: q[0] = p[0]; q[1] = p[2]; q[2] = p[1]; break;
    default: q[0] = p[0]; q[1] = p[2]; q[2] = -p[1]; break;
  }
}

// All five faces' outcodes of a shooter-local point, branch-free.
inline uint32_t Outcodes(float x, float y, float z, float near) {
  auto code = [near](float a, float b, float d, float blo) {
    return uint32_t(a > d) * kAHi | uint32_t(a < -d) * kALo | uint32_t(b > d) * kBHi |
           uint32_t(b < blo) * kBLo | uint32_t(d < near) * kNear;
  };
  return code(x, y, z, -z) | code(y, z, x, 0) << 5 | code(y, z, -x, 0) << 10 |
         code(x, z, y, 0) << 15 | code(x, z, -y, 0) << 20;
}

// ∫∫ over a pixel of the delta form factor, 3x3 Gauss-Legendre.
double PixelIntegral(double a0, double a1, double b0, double b1, bool side) {
  static const double x[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static const double w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  double s = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double a = 0.5 * (a0 + a1) + 0.5 * (a1 - a0) * x[i];
      double b = 0.5 * (b0 + b1) + 0.5 * (b1 - b0) * x[j];
      double r = a * a + b * b + 1;
      s += w[i] * w[j] * (side ? b : 1.0) / (M_PI * r * r);
    }
  return s * 0.25 * (a1 - a0) * (b1 - b0);
}

}  // namespace

Hemicube::Hemicube(int resolution) : res_(resolution) {
  CHECK(res_ >= 8 && res_ <= kMaxResolution && res_ % 2 == 0);
  const int R = res_, H = R / 2;
  std::vector<double> d(3 * size_t(R) * R);
  double total = 0;
  const double px = 2.0 / R;
  for (int y = 0; y < R; ++y)
    for (int x = 0; x < R; ++x)
      total += d[y * R + x] =
          PixelIntegral(-1 + x * px, -1 + (x + 1) * px, -1 + y * px, -1 + (y + 1) * px, false);
  for (int s = 0; s < 4; ++s)
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < R; ++x)
        total += d[R * R + (s * H + y) * R + x] =
            PixelIntegral(-1 + x * px, -1 + (x + 1) * px, y * px, (y + 1) * px, true);
  // The exact integrals sum to 1; renormalising removes the quadrature's
  // last digits so a closed scene's column sums to 1 to float precision.
  // Readback sums runs of one id along a row as a difference of prefix
  // sums: a run costs one subtraction instead of a dependent add per pixel.
  prefix_.resize(d.size() + d.size() / R);
  for (size_t row = 0, n = d.size() / R; row < n; ++row) {
    double* p = &prefix_[row * (R + 1)];
    p[0] = 0;
    for (int x = 0; x < R; ++x) p[x + 1] = p[x] + d[row * R + x] / total;
  }
  depth_.resize(d.size());
  item_.resize(d.size() + 1, -1);  // + a sentinel read past the last row
}

namespace {

// ceil(v) for |v| < 2^30 without a libm call (baseline x86-64 has no
// rounding instruction). Callers keep v in range: projected points are
// bounded by the near plane.
inline int Ceil(float v) {
  const int i = int(v);
  return i + (float(i) < v);
}

// 16.16 fixed point for edge crossings: rows then step by one integer add,
// and ceil is a shift. |v| is kept below 1e9 pixels.
inline int64_t Fixed(float v) {
  return int64_t(double(std::clamp(v, -1e9f, 1e9f)) * 65536.0);
}

// One chain of a convex polygon's edges, walked down the rows. Each edge is
// set up from its own endpoints, upper one first, and stepped from its own
// first row, so an edge shared by two neighbours gives both bit-identical
// crossings on every row.
struct Chain {
  const float (*pt)[2];
  int n, at, step, end;       // current upper vertex, direction, bottom vertex
  int r1 = INT32_MIN;         // first row below the current edge
  int64_t x = 0, dx = 0;      // crossing at the current row's centre; per row

  // Moves to the edge that crosses row `row`.
  void Seek(int row) {
    while (row >= r1 && at != end) {
      const float* p = pt[at];
      at += step;  // wrap without a division: this runs per edge
      if (at == n) at = 0;
      if (at < 0) at = n - 1;
      const float* q = pt[at];
      const float* u = p[1] < q[1] ? p : q;
      const float* l = p[1] < q[1] ? q : p;
      const int r0 = Ceil(u[1] - 0.5f);
      r1 = Ceil(l[1] - 0.5f);
      if (r0 >= r1 || row >= r1) continue;  // no row centre on this edge for us
      const float dxdy = (l[0] - u[0]) / (l[1] - u[1]);
      x = Fixed(u[0] + (float(r0) + 0.5f - u[1]) * dxdy);
      dx = Fixed(dxdy);
      x += int64_t(row - r0) * dx;  // rows above the face's top were clipped
    }
  }
};

// Pixel index of the first centre at or right of fixed-point x: ceil(x - 0.5).
inline int64_t FirstPixel(int64_t x) { return (x - 32768 + 65535) >> 16; }

}  // namespace

// Fills the convex polygon pt[0..n) (pixel coordinates) of face `face`
// with element `id`, depth 1/d = za*X + zb*Y + zc: pixel centres in
// [left, right) x [top, bottom), so shared edges give each pixel to one side.
void Hemicube::Scan(int face, const float (*pt)[2], int n, float za, float zb,
                    float zc, int32_t id) {
  const int R = res_, H = face == 0 ? R : R / 2;
  float* depth = depth_.data() + (face == 0 ? 0 : size_t(R) * R + size_t(face - 1) * H * R);
  int32_t* item = item_.data() + (depth - depth_.data());
  int top = 0, bottom = 0;
  for (int i = 1; i < n; ++i) {
    if (pt[i][1] < pt[top][1]) top = i;
    if (pt[i][1] > pt[bottom][1]) bottom = i;
  }
  const float lim = 1e9f;  // keeps Ceil in range; far outside any face
  const int ya = std::max(0, Ceil(std::max(pt[top][1], -lim) - 0.5f));
  const int yb = std::min(H, Ceil(std::min(pt[bottom][1], lim) - 0.5f));
  if (ya >= yb) return;
  Chain a{pt, n, top, 1, bottom}, b{pt, n, top, -1, bottom};
  for (int y = ya; y < yb; ++y, a.x += a.dx, b.x += b.dx) {
    a.Seek(y);
    b.Seek(y);
    const int64_t xl = std::min(a.x, b.x), xr = std::max(a.x, b.x);
    const int xa = int(std::clamp<int64_t>(FirstPixel(xl), 0, R));
    const int xb = int(std::clamp<int64_t>(FirstPixel(xr), 0, R));
    const float yc = y + 0.5f;
    float* drow = depth + size_t(y) * R;
    int32_t* irow = item + size_t(y) * R;
    const float zrow = zb * yc + zc + 0.5f * za;
    // Branch-free so that the compiler can vectorise the depth test.
    for (int x = xa; x < xb; ++x) {
      const float z = za * float(x) + zrow;
      const bool nearer = z > drow[x];
      drow[x] = nearer ? z : drow[x];
      irow[x] = nearer ? id : irow[x];
    }
  }
}

void Hemicube::Column(const Mesh& mesh, int shooter, double angle,
                      std::vector<FormFactor>* out, ColumnStats* stats) {
  const double t0 = MonotonicSeconds();
  const Patch& sp = mesh.patches[shooter];
  const MeshFace& sf = mesh.faces[sp.face];
  // A group's first member shoots for it all (groups.h), from the group's
  // centroid along its mean normal; its members receive nothing from it.
  const PatchGroup* group = GroupOf(mesh, shooter);
  const int32_t self = group ? mesh.group_of[shooter] : -1;
  const glm::dvec3 c = group ? group->center : sp.center;
  const glm::dvec3 n = group ? group->normal : sf.normal;
  // Any tangent will do; the face's first edge keeps it stable per face.
  const Element& e0 = mesh.elems[sp.elements[0]];
  glm::dvec3 t = mesh.verts[e0.v[1]] - mesh.verts[e0.v[0]];
  t = glm::normalize(t - n * glm::dot(t, n));
  glm::dvec3 b = glm::cross(n, t);
  const glm::dvec3 u = std::cos(angle) * t + std::sin(angle) * b;
  const glm::dvec3 v = glm::cross(n, u);

  const float near = float(1e-5 * mesh.scene_diagonal);
  const double coplanar = 1e-10 * (mesh.scene_diagonal + glm::length(c));
  if (local_.size() < 3 * mesh.verts.size()) {
    local_.resize(3 * mesh.verts.size());
    screen_.resize(10 * mesh.verts.size());
    code_.resize(mesh.verts.size());
  }
  const int R = res_;
  const float half = 0.5f * R;
  if (acc_.size() < mesh.elems.size()) acc_.resize(mesh.elems.size(), 0.0);

  // Pass 1: faces that face the shooter; their vertices into its frame.
  std::vector<int>& front = front_;
  front.clear();
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const MeshFace& mf = mesh.faces[f];
    double s = glm::dot(mf.normal, c) - mf.offset;  // shooter's height over the face
    if (!(s > coplanar)) continue;                  // seen from behind or edge-on
    front.push_back(int(f));
    auto transform = [&](int i) {
      glm::dvec3 d = mesh.verts[i] - c;
      float* p = &local_[3 * size_t(i)];
      p[0] = float(glm::dot(d, u));
      p[1] = float(glm::dot(d, v));
      p[2] = float(glm::dot(d, n));
      code_[i] = Outcodes(p[0], p[1], p[2], near);
      // Pixel coordinates on all five faces from three reciprocals (the
      // faces look along z, ±x, ±y). Used only where the vertex is past
      // the near plane, so a division by 0 elsewhere is harmless.
      const float iz = half / p[2], ix = half / p[0], iy = half / p[1];
      float* s = &screen_[10 * size_t(i)];
      s[0] = p[0] * iz + half;  s[1] = p[1] * iz + half;   // top
      s[2] = p[1] * ix + half;  s[3] = p[2] * ix;          // +x
      s[4] = -p[1] * ix + half; s[5] = -p[2] * ix;         // -x
      s[6] = p[0] * iy + half;  s[7] = p[2] * iy;          // +y
      s[8] = -p[0] * iy + half; s[9] = -p[2] * iy;         // -y
    };
    for (int i = mf.vbegin; i < mf.vend; ++i) transform(i);
    for (int i : mf.divide_verts) transform(i);
  }
  const double t1 = MonotonicSeconds();

  // Pass 2: every leaf element of those faces into the item buffers.
  std::fill(depth_.begin(), depth_.end(), 0.0f);
  std::fill(item_.begin(), item_.end() - 1, -1);
  long elements = 0;
  std::vector<int>& leaves = leaves_;
  for (int f : front) {
    const MeshFace& mf = mesh.faces[f];
    // Plane of the face in shooter coordinates: dot(nl, p) = k, k < 0.
    const glm::dvec3 nld(glm::dot(mf.normal, u), glm::dot(mf.normal, v), glm::dot(mf.normal, n));
    const float nl[3] = {float(nld.x), float(nld.y), float(nld.z)};
    const double k = mf.offset - glm::dot(mf.normal, c);
    // 1/d = (na*sa + nb*sb + nd)/k with sa = X/half - 1, sb = Y/half - boff,
    // per hemicube face: the same for every element of this face.
    float za[5], zb[5], zc[5];
    for (int h = 0; h < 5; ++h) {
      float nf[3];
      ToFace(h, nl, nf);
      const float boff = h == 0 ? 1.0f : 0.0f;
      za[h] = float(nf[0] / (half * k));
      zb[h] = float(nf[1] / (half * k));
      zc[h] = float((nf[2] - nf[0] - nf[1] * boff) / k);
    }
    for (int p : mf.patches) {
      if (self >= 0 && mesh.group_of[p] == self) continue;
      mesh.Leaves(p, &leaves);
      for (int id : leaves) {
        const Element& el = mesh.elems[id];
        // The outline: corners, and T-vertices where finer neighbours meet
        // this element, so that both sides scan the very same edges.
        int vid[8];
        const int nv = Outline(el, vid);
        ++elements;
        uint32_t all = ~0u, any = 0;
        for (int i = 0; i < nv; ++i) {
          all &= code_[vid[i]];
          any |= code_[vid[i]];
        }
        for (int h = 0; h < 5; ++h) {
          if ((all >> (5 * h)) & 31) continue;  // wholly outside one plane
          float pt[9][2];  // an 8-gon clipped by one plane
          if (!((any >> (5 * h)) & kNear)) {
            for (int i = 0; i < nv; ++i) {
              pt[i][0] = screen_[10 * size_t(vid[i]) + 2 * h];
              pt[i][1] = screen_[10 * size_t(vid[i]) + 2 * h + 1];
            }
            Scan(h, pt, nv, za[h], zb[h], zc[h], id);
            continue;
          }
          // Crosses the near plane: clip in this face's frame, then project.
          float in[8][3], poly[9][3];
          for (int i = 0; i < nv; ++i) ToFace(h, &local_[3 * size_t(vid[i])], in[i]);
          int m = 0;
          for (int i = 0; i < nv; ++i) {
            const int j = (i + 1) % nv;
            const float* a = in[i];
            const float* bq = in[j];
            if (a[2] >= near) std::copy(a, a + 3, poly[m++]);
            if ((a[2] >= near) != (bq[2] >= near)) {
              // Intersect from the lower vertex id: neighbours agree exactly.
              const float* lo = vid[i] < vid[j] ? a : bq;
              const float* hi = vid[i] < vid[j] ? bq : a;
              const float s = (near - lo[2]) / (hi[2] - lo[2]);
              poly[m][0] = lo[0] + s * (hi[0] - lo[0]);
              poly[m][1] = lo[1] + s * (hi[1] - lo[1]);
              poly[m][2] = near;
              ++m;
            }
          }
          if (m < 3) continue;
          // The same arithmetic as screen_, so unclipped corners match it bit
          // for bit and neighbours stay watertight.
          const float yoff = h == 0 ? half : 0.0f;
          for (int i = 0; i < m; ++i) {
            const float inv = half / poly[i][2];
            pt[i][0] = poly[i][0] * inv + half;
            pt[i][1] = poly[i][1] * inv + yoff;
          }
          Scan(h, pt, m, za[h], zb[h], zc[h], id);
        }
      }
    }
  }
  const double t2 = MonotonicSeconds();

  // Pass 3: sum delta form factors per element, a run of equal ids at a
  // time. Run ends are found as a bit mask per 64 pixels and visited by
  // their set bits: no branch per pixel to mispredict at every boundary.
  const size_t npix = size_t(3) * R * R;
  for (size_t row = 0, n = npix / R; row < n; ++row) {
    const int32_t* it = &item_[row * R];  // it[R] is readable: next row or sentinel
    const double* pre = &prefix_[row * (R + 1)];
    int x0 = 0;
    for (int base = 0; base < R; base += 64) {
      const int len = std::min(64, R - base);
      uint64_t ends = 0;  // bit k: a run ends after pixel base + k
      for (int k = 0; k < len; ++k)
        ends |= uint64_t(it[base + k + 1] != it[base + k]) << k;
      if (base + len == R) ends |= uint64_t(1) << (len - 1);
      while (ends) {
        const int x1 = base + __builtin_ctzll(ends) + 1;
        ends &= ends - 1;
        if (it[x0] >= 0) acc_[it[x0]] += pre[x1] - pre[x0];
        x0 = x1;
      }
    }
  }
  out->clear();
  for (size_t id = 0; id < mesh.elems.size(); ++id)
    if (acc_[id] > 0) {
      out->push_back({int32_t(id), float(acc_[id])});
      acc_[id] = 0;
    }
  const double t3 = MonotonicSeconds();
  if (stats) {
    stats->transform_s += t1 - t0;
    stats->raster_s += t2 - t1;
    stats->readback_s += t3 - t2;
    stats->elements += elements;
    stats->covered += long(out->size());
    stats->pixels += long(npix);
  }
}

double ShotAngle(unsigned seed, int patch, int k) {
  const uint64_t z =
      SplitMix64((uint64_t(seed) << 40) ^ (uint64_t(uint32_t(patch)) << 16) ^ uint64_t(k));
  return double(z >> 11) * 0x1.0p-53 * 2 * M_PI;
}

void ShotColumn(Hemicube* hemicube, const Mesh& mesh, int patch, int k, bool rotate,
                unsigned seed, std::vector<FormFactor>* out, ColumnStats* stats) {
  hemicube->Column(mesh, patch, rotate ? ShotAngle(seed, patch, k) : 0.0, out, stats);
}

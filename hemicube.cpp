#include "hemicube.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "check.h"

namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

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

inline uint32_t Outcode(int f, const float* q, float near) {
  uint32_t c = 0;
  if (q[0] > q[2]) c |= kAHi;
  if (q[0] < -q[2]) c |= kALo;
  if (q[1] > q[2]) c |= kBHi;
  if (q[1] < (f == 0 ? -q[2] : 0.0f)) c |= kBLo;
  if (q[2] < near) c |= kNear;
  return c;
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
  dff_.resize(3 * size_t(R) * R);
  std::vector<double> d(dff_.size());
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
  for (size_t i = 0; i < d.size(); ++i) dff_[i] = float(d[i] / total);
  depth_.resize(dff_.size());
  item_.resize(dff_.size());
}

struct Hemicube::Edge {
  float y0, y1, x0, dxdy;
};

// Fills the convex polygon pt[0..n) (pixel coordinates) of face `face`
// with element `id`, depth 1/d = za*X + zb*Y + zc, pixel centres in
// [left, right) x [top, bottom): shared edges give each pixel to one side.
void Hemicube::Scan(int face, const float (*pt)[2], int n, float za, float zb,
                    float zc, int32_t id) {
  const int R = res_, H = face == 0 ? R : R / 2;
  float* depth = depth_.data() + (face == 0 ? 0 : size_t(R) * R + size_t(face - 1) * H * R);
  int32_t* item = item_.data() + (depth - depth_.data());
  Edge e[8];
  int ne = 0;
  float ymin = pt[0][1], ymax = pt[0][1];
  for (int i = 0; i < n; ++i) {
    const float* p = pt[i];
    const float* q = pt[(i + 1) % n];
    ymin = std::min(ymin, p[1]);
    ymax = std::max(ymax, p[1]);
    if (p[1] == q[1]) continue;
    // The same edge of two neighbours must give bit-identical crossings,
    // so each edge is set up from its endpoints in a canonical order.
    if (p[1] > q[1]) std::swap(p, q);
    e[ne++] = {p[1], q[1], p[0], (q[0] - p[0]) / (q[1] - p[1])};
  }
  int ya = std::max(0, int(std::ceil(ymin - 0.5f)));
  int yb = std::min(H, int(std::ceil(ymax - 0.5f)));
  for (int y = ya; y < yb; ++y) {
    const float yc = y + 0.5f;
    float xl = 1e30f, xr = -1e30f;
    for (int k = 0; k < ne; ++k)
      if (yc >= e[k].y0 && yc < e[k].y1) {
        float x = e[k].x0 + (yc - e[k].y0) * e[k].dxdy;
        xl = std::min(xl, x);
        xr = std::max(xr, x);
      }
    int xa = std::max(0, int(std::ceil(xl - 0.5f)));
    int xb = std::min(R, int(std::ceil(xr - 0.5f)));
    float* drow = depth + size_t(y) * R;
    int32_t* irow = item + size_t(y) * R;
    const float zrow = zb * yc + zc;
    for (int x = xa; x < xb; ++x) {
      float z = za * (x + 0.5f) + zrow;
      if (z > drow[x]) {
        drow[x] = z;
        irow[x] = id;
      }
    }
  }
}

void Hemicube::Column(const Mesh& mesh, int shooter, double angle,
                      std::vector<FormFactor>* out, ColumnStats* stats) {
  auto t0 = Clock::now();
  const Patch& sp = mesh.patches[shooter];
  const MeshFace& sf = mesh.faces[sp.face];
  const glm::dvec3 c = sp.center, n = sf.normal;
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
    code_.resize(mesh.verts.size());
  }
  if (acc_.size() < mesh.elems.size()) acc_.resize(mesh.elems.size(), 0.0);

  // Pass 1: faces that face the shooter; their vertices into its frame.
  std::vector<int>& front = front_;
  front.clear();
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const MeshFace& mf = mesh.faces[f];
    double s = glm::dot(mf.normal, c) - mf.offset;  // shooter's height over the face
    if (!(s > coplanar)) continue;                  // seen from behind or edge-on
    front.push_back(int(f));
    for (int i = mf.vbegin; i < mf.vend; ++i) {
      glm::dvec3 d = mesh.verts[i] - c;
      float* p = &local_[3 * size_t(i)];
      p[0] = float(glm::dot(d, u));
      p[1] = float(glm::dot(d, v));
      p[2] = float(glm::dot(d, n));
      uint32_t code = 0;
      float q[3];
      for (int h = 0; h < 5; ++h) {
        ToFace(h, p, q);
        code |= Outcode(h, q, near) << (5 * h);
      }
      code_[i] = code;
    }
  }
  auto t1 = Clock::now();

  // Pass 2: every leaf element of those faces into the item buffers.
  std::fill(depth_.begin(), depth_.end(), 0.0f);
  std::fill(item_.begin(), item_.end(), -1);
  const int R = res_;
  const float half = 0.5f * R;
  long elements = 0;
  std::vector<int>& leaves = leaves_;
  for (int f : front) {
    const MeshFace& mf = mesh.faces[f];
    // Plane of the face in shooter coordinates: dot(nl, p) = k, k < 0.
    const glm::dvec3 nld(glm::dot(mf.normal, u), glm::dot(mf.normal, v), glm::dot(mf.normal, n));
    const float nl[3] = {float(nld.x), float(nld.y), float(nld.z)};
    const double k = mf.offset - glm::dot(mf.normal, c);
    for (int p : mf.patches) {
      mesh.Leaves(p, &leaves);
      for (int id : leaves) {
        const Element& el = mesh.elems[id];
        const int nv = el.IsTriangle() ? 3 : 4;
        ++elements;
        uint32_t all = ~0u, any = 0;
        for (int i = 0; i < nv; ++i) {
          all &= code_[el.v[i]];
          any |= code_[el.v[i]];
        }
        for (int h = 0; h < 5; ++h) {
          if ((all >> (5 * h)) & 31) continue;  // wholly outside one plane
          // Element in this face's frame; clipped at the near plane.
          float in[4][3], poly[8][3];
          for (int i = 0; i < nv; ++i) ToFace(h, &local_[3 * size_t(el.v[i])], in[i]);
          int m = 0;
          if ((any >> (5 * h)) & kNear) {
            for (int i = 0; i < nv; ++i) {
              int j = (i + 1) % nv;
              const float* a = in[i];
              const float* bq = in[j];
              if (a[2] >= near) std::copy(a, a + 3, poly[m++]);
              if ((a[2] >= near) != (bq[2] >= near)) {
                // Intersect from the lower vertex id: neighbours agree exactly.
                const float* lo = el.v[i] < el.v[j] ? a : bq;
                const float* hi = el.v[i] < el.v[j] ? bq : a;
                float s = (near - lo[2]) / (hi[2] - lo[2]);
                poly[m][0] = lo[0] + s * (hi[0] - lo[0]);
                poly[m][1] = lo[1] + s * (hi[1] - lo[1]);
                poly[m][2] = near;
                ++m;
              }
            }
            if (m < 3) continue;
          } else {
            for (int i = 0; i < nv; ++i) std::copy(in[i], in[i] + 3, poly[i]);
            m = nv;
          }
          float pt[8][2];
          const float boff = h == 0 ? 1.0f : 0.0f;
          for (int i = 0; i < m; ++i) {
            float inv = 1.0f / poly[i][2];
            pt[i][0] = (poly[i][0] * inv + 1.0f) * half;
            pt[i][1] = (poly[i][1] * inv + boff) * half;
          }
          float nf[3];
          ToFace(h, nl, nf);
          // 1/d = (na*sa + nb*sb + nd)/k with sa = X/half - 1, sb = Y/half - boff.
          const float za = float(nf[0] / (half * k));
          const float zb = float(nf[1] / (half * k));
          const float zc = float((nf[2] - nf[0] - nf[1] * boff) / k);
          Scan(h, pt, m, za, zb, zc, id);
        }
      }
    }
  }
  auto t2 = Clock::now();

  // Pass 3: sum delta form factors per element.
  const size_t npix = dff_.size();
  for (size_t i = 0; i < npix; ++i)
    if (item_[i] >= 0) acc_[item_[i]] += dff_[i];
  out->clear();
  for (size_t id = 0; id < mesh.elems.size(); ++id)
    if (acc_[id] > 0) {
      out->push_back({int32_t(id), float(acc_[id])});
      acc_[id] = 0;
    }
  auto t3 = Clock::now();
  if (stats) {
    stats->transform_s += Seconds(t0, t1);
    stats->raster_s += Seconds(t1, t2);
    stats->readback_s += Seconds(t2, t3);
    stats->elements += elements;
    stats->covered += long(out->size());
    stats->pixels += long(npix);
  }
}

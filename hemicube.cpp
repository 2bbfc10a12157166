#include "hemicube.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <tuple>
#include <type_traits>
#include <utility>

#include <emmintrin.h>  // SSE2: baseline x86-64

#include "check.h"
#include "clock.h"
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
  const size_t tw = (R + kTile - 1) / kTile, th = (H + kTile - 1) / kTile;
  tile_min_.resize(tw * tw + 4 * th * tw);
  dirty_.resize(tile_min_.size());
  for (int h = 0; h < 5; ++h) {
    pixel_at_[h] = h == 0 ? 0 : size_t(R) * R + size_t(h - 1) * H * R;
    tile_at_[h] = h == 0 ? 0 : tw * tw + size_t(h - 1) * th * tw;
  }
}

namespace {

// ceil(v) and floor(v), float or double, for |v| < 2^30 without a libm
// call (baseline x86-64 has no rounding instruction). Callers keep v in
// range: projected points are bounded by the near plane, Visible's clamped.
template <class T>
inline int Ceil(T v) {
  const int i = int(v);
  return i + (T(i) < v);
}
template <class T>
inline int Floor(T v) {
  const int i = int(v);
  return i - (v < T(i));
}

// The pixel rows a polygon spanning [y0, y1] in y covers on a hemicube
// face of H rows: those whose centre y + 1/2 lies within, [first, second)
// (empty when first >= second): those Scan draws.
inline std::pair<int, int> Rows(float y0, float y1, int H) {
  const float lim = 1e9f;  // keeps Ceil in range; far outside any face
  return {std::max(0, Ceil(std::max(y0, -lim) - 0.5f)), std::min(H, Ceil(std::min(y1, lim) - 0.5f))};
}

// Whether a polygon of fewer than 9 rows, its x in [x0, x1], holds no
// pixel centre across, 0 <= x < R. Scan's edge crossings lie in [x0, x1]
// but for float rounding (a few 2^-24 of |x| and of the width) and 16.16
// steps (under 2^-16 a row, 9 rows at most): m is far above both. No pixel
// centre i + 1/2 in [x0 - m, x1 + m], 0 <= i < R: no pixel lies between
// crossings. Monotone in the box (m only grows with it), so that what holds
// for a face's pixel box holds for each of its leaves' (DrawFace).
inline bool NoPixelCentre(float x0, float x1, int R) {
  const double m = 0x1p-10 + 0x1p-20 * (std::max(std::abs(x0), std::abs(x1)) + (x1 - x0));
  const double lo = std::clamp(double(x0) - m - 0.5, -2.0, R + 2.0);
  const double hi = std::clamp(double(x1) + m - 0.5, -2.0, R + 2.0);
  const int first = std::max(0, int(lo + 2) - 2 + (int(lo + 2) - 2 < lo));  // ceil(lo)
  const int last = std::min(R - 1, int(hi + 2) - 2);                         // floor(hi)
  return first > last;
}

// 16.16 fixed point for edge crossings: rows then step by one integer add,
// and ceil is a shift. |v| is kept below 1e9 pixels.
inline int64_t Fixed(float v) {
  return int64_t(double(std::clamp(v, -1e9f, 1e9f)) * 65536.0);
}

// One chain of a convex polygon's edges, walked down the rows. Each edge is
// set up from its own endpoints, upper one first, and stepped from its own
// first row, so an edge shared by two neighbours gives both bit-identical
// crossings on every row. Plain data that Scan keeps in registers: most
// polygons are a few pixels, and an out-of-line walk kept its state in
// memory and cost as much as their pixels.
struct Chain {
  int at, step, end;          // current upper vertex, direction, bottom vertex
  int r1 = INT32_MIN;         // first row below the current edge
  int64_t x = 0, dx = 0;      // crossing at the current row's centre; per row
};

// Moves chain c to the edge that crosses row `row` of polygon pt[0..n),
// whose vertex i has first row ry[i] = Ceil(pt[i][1] - 0.5f): a compare on
// most rows, the edge set-up only where one edge ends.
__attribute__((always_inline)) inline void Seek(Chain* c, const float (*pt)[2], const int* ry,
                                                int n, int row) {
  while (row >= c->r1 && c->at != c->end) {
    const int i = c->at;
    int j = i + c->step;  // wrap without a division: this runs per edge
    if (j == n) j = 0;
    if (j < 0) j = n - 1;
    c->at = j;
    const bool down = pt[i][1] < pt[j][1];
    const float* u = pt[down ? i : j];
    const float* l = pt[down ? j : i];
    const int r0 = ry[down ? i : j];
    c->r1 = ry[down ? j : i];
    if (r0 >= c->r1 || row >= c->r1) continue;  // no row centre on this edge for us
    const float dxdy = (l[0] - u[0]) / (l[1] - u[1]);
    c->x = Fixed(u[0] + (float(r0) + 0.5f - u[1]) * dxdy);
    c->dx = Fixed(dxdy);
    c->x += int64_t(row - r0) * c->dx;  // rows above the face's top were clipped
  }
}

// Pixel index of the first centre at or right of fixed-point x: ceil(x - 0.5).
inline int64_t FirstPixel(int64_t x) { return (x - 32768 + 65535) >> 16; }

}  // namespace

inline Hemicube::Extent Hemicube::Bounds(const float (*pt)[2], int n, int H) {
  if (n < 3) __builtin_unreachable();  // a polygon (and so pt[0] was set)
  Extent e;
  e.x0 = e.x1 = pt[0][0];
  for (int i = 1; i < n; ++i) {
    if (pt[i][1] < pt[e.top][1]) e.top = i;
    if (pt[i][1] > pt[e.bottom][1]) e.bottom = i;
    e.x0 = std::min(e.x0, pt[i][0]);
    e.x1 = std::max(e.x1, pt[i][0]);
  }
  std::tie(e.ya, e.yb) = Rows(pt[e.top][1], pt[e.bottom][1], H);
  return e;
}

// Fills the convex polygon pt[0..n) (pixel coordinates) of face `face`,
// its extent e holding some rows (Bounds), with leaf `rank`, depth 1/d =
// za*X + zb*Y + zc: pixel centres in [left, right) x [top, bottom), so
// shared edges give each pixel to one side. A tie in depth goes to the
// lower rank, the leaf first in face order, so that the buffer ends the
// same whatever order the leaves come in.
void Hemicube::Scan(int face, const float (*pt)[2], int n, const Extent& e, float za,
                    float zb, float zc, int32_t rank) {
  const int R = res_;
  const int top = e.top, bottom = e.bottom, ya = e.ya, yb = e.yb;
  float* depth = depth_.data() + pixel_at_[face];
  int32_t* item = item_.data() + pixel_at_[face];
  const int tw = (R + kTile - 1) / kTile;
  uint8_t* dirty = dirty_.data() + tile_at_[face];
  rows_[face][0] = std::min(rows_[face][0], ya);
  rows_[face][1] = std::max(rows_[face][1], yb);
  int ry[9];  // each vertex's first row, once rather than per edge end
  for (int i = 0; i < n; ++i) ry[i] = Ceil(pt[i][1] - 0.5f);
  Chain a{top, 1, bottom}, b{top, -1, bottom};
  // The columns it may have written, for the tiles to mark: empty rows'
  // bounds too (within the polygon's; no branch per row), a tile more at worst.
  int left = R, right = 0;
  for (int y = ya; y < yb; ++y, a.x += a.dx, b.x += b.dx) {
    Seek(&a, pt, ry, n, y);
    Seek(&b, pt, ry, n, y);
    const int64_t xl = std::min(a.x, b.x), xr = std::max(a.x, b.x);
    const int xa = int(std::clamp<int64_t>(FirstPixel(xl), 0, R));
    const int xb = int(std::clamp<int64_t>(FirstPixel(xr), 0, R));
    const float yc = y + 0.5f;
    float* drow = depth + size_t(y) * R;
    int32_t* irow = item + size_t(y) * R;
    left = std::min(left, xa);
    right = std::max(right, xb);
    const float zrow = zb * yc + zc + 0.5f * za;
    // Branch-free so that the compiler can vectorise the depth test.
    for (int x = xa; x < xb; ++x) {
      const float z = za * float(x) + zrow;
      const bool nearer = (z > drow[x]) | ((z == drow[x]) & (rank < irow[x]));
      drow[x] = nearer ? z : drow[x];
      irow[x] = nearer ? rank : irow[x];
    }
  }
  // The tiles of its bounding rectangle are marked, once: a few more than
  // it wrote at worst, each only recomputed when tested. Most polygons lie
  // within a tile or two across: the first and last are stored, a loop (a
  // memset call, costlier than a small polygon's rows) only for those between.
  if (left >= right) return;
  const int tl = left / kTile, tr = (right - 1) / kTile;
  for (int ty = ya / kTile; ty <= (yb - 1) / kTile; ++ty) {
    uint8_t* row = dirty + size_t(ty) * tw;
    row[tl] = row[tr] = 1;
    for (int t = tl + 1; t < tr; ++t) row[t] = 1;
  }
}

bool Hemicube::Open(int h, int xa, int xb, int ra, int rb, float zt) {
  const int R = res_, H = h == 0 ? R : R / 2, tw = (R + kTile - 1) / kTile;
  const float* depth = depth_.data() + pixel_at_[h];
  const int txa = xa / kTile, txb = (xb - 1) / kTile;
  for (int ty = ra / kTile; ty <= (rb - 1) / kTile; ++ty) {
    const int y0 = ty * kTile, y1 = std::min(H, y0 + kTile);
    const float* rows = depth + size_t(y0) * R;
    float* tmin = tile_min_.data() + tile_at_[h] + size_t(ty) * tw;
    uint8_t* dirty = dirty_.data() + tile_at_[h] + size_t(ty) * tw;
    for (int tx = txa; tx <= txb; ++tx) {
      const int x0 = tx * kTile, x1 = std::min(R, x0 + kTile);
      if (dirty[tx]) {
        // A tile's least depth, in any order (depths are 0 or positive,
        // never NaN or -0: the min is the same whichever is taken first);
        // a whole tile's rows 8 floats at a time in SSE2.
        const float* p = rows + x0;
        float m = *p;
        if (x1 - x0 == kTile) {
          __m128 m0 = _mm_loadu_ps(p), m1 = _mm_loadu_ps(p + 4);
          for (int y = y0 + 1; y < y1; ++y) {
            p += R;
            m0 = _mm_min_ps(m0, _mm_loadu_ps(p));
            m1 = _mm_min_ps(m1, _mm_loadu_ps(p + 4));
          }
          m0 = _mm_min_ps(m0, m1);
          m0 = _mm_min_ps(m0, _mm_movehl_ps(m0, m0));
          m = _mm_cvtss_f32(_mm_min_ss(m0, _mm_shuffle_ps(m0, m0, 1)));
        } else {
          for (int y = y0; y < y1; ++y, p += R)
            for (int x = 0; x < x1 - x0; ++x) m = std::min(m, p[x]);
        }
        tmin[tx] = m;
        dirty[tx] = 0;
      }
      if (tmin[tx] > zt) continue;
      for (int y = std::max(y0, ra); y < std::min(y1, rb); ++y)
        for (int x = std::max(x0, xa); x < std::min(x1, xb); ++x)
          if (depth[size_t(y) * R + x] <= zt) return true;
    }
  }
  return false;
}

// Whether a large leaf on face h (pixel bounding box [x0, x1] x [y0, y1]
// of kHiddenArea or more, holding some of the face's rows) could win no
// pixel, so that Scan need not draw it: wholly behind what face h holds,
// its nearest depth over that box (the plane's at a corner, in double,
// raised well past Scan's float rounding) against the tiles, as Visible
// tests boxes. A leaf left undrawn could not have written a pixel, so the
// buffer is as drawing it would have left it.
bool Hemicube::Hidden(int h, float x0, float x1, float y0, float y1, float za, float zb,
                      float zc) {
  const int R = res_, H = h == 0 ? R : R / 2;
  const int xa = std::max(0, int(std::floor(std::max(x0, -2.0f))) - 1);
  const int xb = std::min(R, int(std::ceil(std::min(x1, R + 2.0f))) + 1);
  const int ra = std::max(0, int(std::floor(std::max(y0, -2.0f))) - 1);
  const int rb = std::min(H, int(std::ceil(std::min(y1, H + 2.0f))) + 1);
  if (xa >= xb || ra >= rb) return false;  // Scan finds nothing to draw as cheaply
  // Scan's z at pixel (x, y) is za (x + 1/2) + zb (y + 1/2) + zc in float.
  const double a = za, b = zb, c = zc;
  const double X0 = xa, X1 = xb, Y0 = ra, Y1 = rb;
  const double zmax = std::max(std::max(a * X0 + b * Y0, a * X1 + b * Y0),
                               std::max(a * X0 + b * Y1, a * X1 + b * Y1)) + c;
  const double slack = 1e-4 * (std::abs(a) * X1 + std::abs(b) * Y1 + std::abs(c));
  return !Open(h, xa, xb, ra, rb, float(zmax + slack));
}

uint32_t Hemicube::Visible(const glm::dvec3& lo, const glm::dvec3& hi) {
  // The box in the shooter's frame, as a box again (it only grows), and by
  // a margin far above float rounding of the vertices: whatever is decided
  // here for the box holds for every outcode computed for its vertices.
  const glm::dvec3 mid = 0.5 * (lo + hi) - c_, ext = 0.5 * (hi - lo);
  auto range = [&](const glm::dvec3& axis, double* l, double* h) {
    const double m = glm::dot(mid, axis);
    const double e = glm::dot(ext, glm::abs(axis)) + margin_;
    *l = m - e;
    *h = m + e;
  };
  double x0, x1, y0, y1, z0, z1;
  range(u_, &x0, &x1);
  range(v_, &y0, &y1);
  range(n_, &z0, &z1);
  if (z1 < 0) return 0;  // wholly behind the shooter
  const int R = res_;
  const double half = 0.5 * R;
  uint32_t mask = 0;
  // Face h of (a, b, d) as ToFace orders them, d along the face's axis;
  // inline for each h, so that the faces' differences fold away (a loop
  // over h with a switch took a quarter more instructions).
  auto face = [&](auto hc, double a0, double a1, double b0, double b1, double d0,
                  double d1) __attribute__((always_inline)) {
    constexpr int h = decltype(hc)::value;
    if (d1 < near_ || a0 > d1 || a1 < -d1 || b0 > d1 || (h == 0 ? b1 < -d1 : b1 < 0)) return;
    if (d0 < near_) {  // reaches the near plane: no bound on its projection
      mask |= 1u << h;
      return;
    }
    // Pixels it may cover, a pixel wider all round than its projection,
    // and the nearest depth anything in it may have, a little nearer still.
    const double ya = h == 0 ? half : 0.0, rows = h == 0 ? R : R / 2;
    auto px = [&](double v, double off, double lim) {
      return std::clamp(v * half + off, -1.0, lim + 1.0);
    };
    const int xa = std::max(0, Floor(px(a0 / (a0 >= 0 ? d1 : d0), half, R)) - 1);
    const int xb = std::min(R, Ceil(px(a1 / (a1 >= 0 ? d0 : d1), half, R)) + 1);
    const int ra = std::max(0, Floor(px(b0 / (b0 >= 0 ? d1 : d0), ya, rows)) - 1);
    const int rb = std::min(int(rows), Ceil(px(b1 / (b1 >= 0 ? d0 : d1), ya, rows)) + 1);
    if (xa >= xb || ra >= rb) return;  // between pixel centres
    if (Open(h, xa, xb, ra, rb, float(1.001 / d0))) mask |= 1u << h;
  };
  face(std::integral_constant<int, 0>(), x0, x1, y0, y1, z0, z1);
  face(std::integral_constant<int, 1>(), y0, y1, z0, z1, x0, x1);
  face(std::integral_constant<int, 2>(), y0, y1, z0, z1, -x1, -x0);
  face(std::integral_constant<int, 3>(), x0, x1, z0, z1, y0, y1);
  face(std::integral_constant<int, 4>(), x0, x1, z0, z1, -y1, -y0);
  return mask;
}

void Hemicube::DrawFace(const Mesh& mesh, int f, uint32_t mask, double* clock) {
  const CacheFace& cf = faces_[f];
  const float half = 0.5f * res_;
  float *lx = lx_.data(), *ly = ly_.data(), *lz = lz_.data();
  int nv = 0;
  auto put = [&](const glm::dvec3& p) {
    const glm::dvec3 d = p - c_;
    lx[nv] = float(glm::dot(d, u_));
    ly[nv] = float(glm::dot(d, v_));
    lz[nv] = float(glm::dot(d, n_));
    ++nv;
  };
  // Two vertices at a time in SSE2, the same operations in the same order
  // as put's (glm::dot sums (x + y) + z; packed and scalar IEEE operations
  // round alike): the compiler's own vectorising of put, four vertices
  // at a time, spent about 60 instructions a face in setup and a
  // face has about six vertices.
  {
    __m128d f[12];
    for (int j = 0; j < 12; ++j) f[j] = _mm_load_pd(frame_[j]);
    static_assert(sizeof(glm::dvec3) == 3 * sizeof(double), "verts: x, y, z, x, ...");
    const double* p = &mesh.verts[cf.vb].x;
    for (; nv + 2 <= cf.ve - cf.vb; nv += 2, p += 6) {
      const __m128d dx = _mm_sub_pd(_mm_loadh_pd(_mm_load_sd(p), p + 3), f[0]);
      const __m128d dy = _mm_sub_pd(_mm_loadh_pd(_mm_load_sd(p + 1), p + 4), f[1]);
      const __m128d dz = _mm_sub_pd(_mm_loadh_pd(_mm_load_sd(p + 2), p + 5), f[2]);
      auto dot = [&](int a) {
        const __m128d s = _mm_add_pd(_mm_mul_pd(dx, f[a]), _mm_mul_pd(dy, f[a + 1]));
        return _mm_cvtpd_ps(_mm_add_pd(s, _mm_mul_pd(dz, f[a + 2])));
      };
      _mm_storel_pi(reinterpret_cast<__m64*>(lx + nv), dot(3));
      _mm_storel_pi(reinterpret_cast<__m64*>(ly + nv), dot(6));
      _mm_storel_pi(reinterpret_cast<__m64*>(lz + nv), dot(9));
    }
  }
  for (int i = cf.vb + nv; i < cf.ve; ++i) put(mesh.verts[i]);
  if (cf.nd)
    for (int i : mesh.DivideVerts(mesh.faces[cf.face])) put(mesh.verts[i]);
  uint32_t all = ~0u, any = 0;
  for (int i = 0; i < nv; ++i) {
    code_[i] = Outcodes(lx[i], ly[i], lz[i], near_);
    all &= code_[i];
    any |= code_[i];
  }
  // A hemicube face all its vertices lie outside one plane of gets none of
  // its leaves (each leaf's outline is of these vertices).
  for (uint32_t todo = mask; todo; todo &= todo - 1) {
    const int h = __builtin_ctz(todo);
    if ((all >> (5 * h)) & 31) mask &= ~(1u << h);
  }
  // Pixel coordinates on the faces it may reach, from one reciprocal per
  // face pair (the faces look along z, ±x, ±y). Used only where the vertex
  // is past the near plane, so a division by 0 elsewhere is harmless.
  if (mask & 1)
    for (int i = 0; i < nv; ++i) {
      const float iz = half / lz[i];
      sxy_[0][i][0] = lx[i] * iz + half;
      sxy_[0][i][1] = ly[i] * iz + half;
    }
  if (mask & 6)
    for (int i = 0; i < nv; ++i) {
      const float ix = half / lx[i];
      sxy_[1][i][0] = ly[i] * ix + half;
      sxy_[1][i][1] = lz[i] * ix;
      sxy_[2][i][0] = -ly[i] * ix + half;
      sxy_[2][i][1] = -lz[i] * ix;
    }
  if (mask & 24)
    for (int i = 0; i < nv; ++i) {
      const float iy = half / ly[i];
      sxy_[3][i][0] = lx[i] * iy + half;
      sxy_[3][i][1] = lz[i] * iy;
      sxy_[4][i][0] = -lx[i] * iy + half;
      sxy_[4][i][1] = -lz[i] * iy;
    }
  // Nor does one where the face's pixel box, all in front of the near
  // plane, holds no pixel centre: Scan finds none in any leaf's box, which
  // lies within it (Rows and NoPixelCentre only grow with the box). A
  // finely cut face smaller than a pixel or two costs its vertices only.
  if (culling_)
    for (uint32_t todo = mask; todo; todo &= todo - 1) {
      const int h = __builtin_ctz(todo);
      if ((any >> (5 * h)) & kNear) continue;
      const auto* s = sxy_[h].data();
      float x0 = s[0][0], x1 = x0, y0 = s[0][1], y1 = y0;
      for (int i = 1; i < nv; ++i) {
        x0 = std::min(x0, s[i][0]);
        x1 = std::max(x1, s[i][0]);
        y0 = std::min(y0, s[i][1]);
        y1 = std::max(y1, s[i][1]);
      }
      const auto [ya, yb] = Rows(y0, y1, h == 0 ? res_ : res_ / 2);
      if (ya >= yb || (y1 - y0 < 8 && NoPixelCentre(x0, x1, res_))) mask &= ~(1u << h);
    }
  if (clock) {  // culling and transform so far, the rest is raster
    const double now = MonotonicSeconds();
    clock[1] += now - clock[0];
    clock[0] = now;
  }
  // Plane of the face in shooter coordinates: dot(nl, p) = k, k < 0.
  const glm::dvec3 nld(glm::dot(cf.normal, u_), glm::dot(cf.normal, v_), glm::dot(cf.normal, n_));
  const float nl[3] = {float(nld.x), float(nld.y), float(nld.z)};
  const double k = cf.offset - glm::dot(cf.normal, c_);
  // 1/d = (na*sa + nb*sb + nd)/k with sa = X/half - 1, sb = Y/half - boff,
  // per hemicube face: the same for every element of this face.
  float za[5], zb[5], zc[5];
  for (int h = 0; h < 5; ++h) {
    if (!((mask >> h) & 1)) continue;
    float nf[3];
    ToFace(h, nl, nf);
    const float boff = h == 0 ? 1.0f : 0.0f;
    za[h] = float(nf[0] / (half * k));
    zb[h] = float(nf[1] / (half * k));
    zc[h] = float((nf[2] - nf[0] - nf[1] * boff) / k);
  }
  // Only a face holding one of the shooter's group members has leaves to
  // leave out: elsewhere no leaf's element is read from the mesh.
  const bool own = self_ && std::binary_search(self_faces_.begin(), self_faces_.end(), cf.face);
  // Its leaves, by their outlines (16-bit indices but on a huge face: BuildCache).
  auto leaves = [&](const auto* outline) {
    for (int r = cf.lb, at = cf.pb; r < cf.le; at += outline_n_[r], ++r) {
      if (own && std::binary_search(self_->members.begin(), self_->members.end(),
                                    mesh.elems[elem_[r]].patch))
        continue;
      const auto* vid = outline + at;
      const int n = outline_n_[r];
      uint32_t all = ~0u, any = 0;
      for (int i = 0; i < n; ++i) {
        all &= code_[vid[i]];
        any |= code_[vid[i]];
      }
      // The hemicube faces in mask (one or two for most faces), by its bits.
      for (uint32_t todo = mask; todo; todo &= todo - 1) {
        const int h = __builtin_ctz(todo);
        if ((all >> (5 * h)) & 31) continue;  // wholly outside one plane of face h
        float pt[9][2];  // an 8-gon clipped by one plane
        const int rows = h == 0 ? res_ : res_ / 2;
        if (!((any >> (5 * h)) & kNear)) {
          for (int i = 0; i < n; ++i) {
            pt[i][0] = sxy_[h][vid[i]][0];
            pt[i][1] = sxy_[h][vid[i]][1];
          }
          // Most leaves of a finely cut scene, smaller than a pixel, hold
          // no row centre or no pixel centre: tested here, without a call.
          // A leaf left undrawn could not have written a pixel.
          const Extent e = Bounds(pt, n, rows);
          if (e.ya >= e.yb) continue;
          const float y0 = pt[e.top][1], y1 = pt[e.bottom][1];
          if (culling_ && ((y1 - y0 < 8 && NoPixelCentre(e.x0, e.x1, res_)) ||
                           (double(e.x1 - e.x0) * double(y1 - y0) >= kHiddenArea &&
                            Hidden(h, e.x0, e.x1, y0, y1, za[h], zb[h], zc[h]))))
            continue;
          Scan(h, pt, n, e, za[h], zb[h], zc[h], r);
          continue;
        }
        // Crosses the near plane: clip in this face's frame, then project.
        float in[8][3], poly[9][3];
        for (int i = 0; i < n; ++i) {
          const float p[3] = {lx[vid[i]], ly[vid[i]], lz[vid[i]]};
          ToFace(h, p, in[i]);
        }
        int m = 0;
        for (int i = 0; i < n; ++i) {
          const int j = (i + 1) % n;
          const float* a = in[i];
          const float* bq = in[j];
          if (a[2] >= near_) std::copy(a, a + 3, poly[m++]);
          if ((a[2] >= near_) != (bq[2] >= near_)) {
            // Intersect from the lower vertex id: neighbours agree exactly.
            const float* lo = vid[i] < vid[j] ? a : bq;
            const float* hi = vid[i] < vid[j] ? bq : a;
            const float s = (near_ - lo[2]) / (hi[2] - lo[2]);
            poly[m][0] = lo[0] + s * (hi[0] - lo[0]);
            poly[m][1] = lo[1] + s * (hi[1] - lo[1]);
            poly[m][2] = near_;
            ++m;
          }
        }
        if (m < 3) continue;
        // The same arithmetic as sxy_, so unclipped corners match it bit
        // for bit and neighbours stay watertight.
        const float yoff = h == 0 ? half : 0.0f;
        for (int i = 0; i < m; ++i) {
          const float inv = half / poly[i][2];
          pt[i][0] = poly[i][0] * inv + half;
          pt[i][1] = poly[i][1] * inv + yoff;
        }
        const Extent e = Bounds(pt, m, rows);
        if (e.ya < e.yb) Scan(h, pt, m, e, za[h], zb[h], zc[h], r);
      }
    }
  };
  if (mask) {  // else none of its leaves reaches a pixel: nothing to draw
    if (wide_) leaves(outline_wide_.data());
    else leaves(outline_.data());
  }
  visited_ += cf.le - cf.lb;
  if (clock) {
    const double now = MonotonicSeconds();
    clock[2] += now - clock[0];
    clock[0] = now;
  }
}

void Hemicube::Prepare(const Mesh& mesh) {
  if (!(key_ == KeyOf(mesh))) BuildCache(mesh);
}

void Hemicube::Column(const Mesh& mesh, int shooter, const PatchGroup* group, double angle,
                      std::vector<FormFactor>* out, ColumnStats* stats) {
  const double t0 = MonotonicSeconds();
  const Patch& sp = mesh.patches[shooter];
  const MeshFace& sf = mesh.faces[sp.face];
  // A group's first member shoots for it all (groups.h), from the group's
  // centroid along its mean normal; its members receive nothing from it.
  self_ = group;
  self_faces_.clear();
  if (group) {
    for (int m : group->members) self_faces_.push_back(mesh.patches[m].face);
    std::sort(self_faces_.begin(), self_faces_.end());
  }
  const glm::dvec3 c = group ? group->center : mesh.Center(shooter);
  const glm::dvec3 n = group ? group->normal : sf.normal;
  // Any tangent will do; the face's first edge keeps it stable per face.
  const Element& e0 = mesh.elems[size_t(mesh.Tops(shooter)[0])];
  glm::dvec3 t = mesh.verts[e0.v[1]] - mesh.verts[e0.v[0]];
  t = glm::normalize(t - n * glm::dot(t, n));
  glm::dvec3 b = glm::cross(n, t);
  const glm::dvec3 u = std::cos(angle) * t + std::sin(angle) * b;
  c_ = c;
  u_ = u;
  v_ = glm::cross(n, u);
  n_ = n;
  near_ = float(1e-5 * mesh.scene_diagonal);
  coplanar_ = 1e-10 * (mesh.scene_diagonal + glm::length(c));
  margin_ = 1e-5 * mesh.scene_diagonal;
  Prepare(mesh);
  // depth_ and item_ are clear: the constructor, then each readback, clear
  // the rows a column wrote.
  std::fill(tile_min_.begin(), tile_min_.end(), 0.0f);
  std::fill(dirty_.begin(), dirty_.end(), 0);
  visited_ = 0;
  {  // the frame as DrawFace's transform reads it, two of each
    const double fr[12] = {c_.x, c_.y, c_.z, u_.x, u_.y, u_.z, v_.x, v_.y, v_.z, n_.x, n_.y, n_.z};
    for (int i = 0; i < 12; ++i) frame_[i][0] = frame_[i][1] = fr[i];
  }

  // Faces that face the shooter into the item buffers. With stats, the
  // clock is read twice a face: {last reading, transform, raster} (the
  // clear counts as raster, culling as transform).
  double clock[3] = {MonotonicSeconds(), 0, 0};
  clock[2] = clock[0] - t0;
  auto draw = [&](int f, uint32_t mask) {
    const CacheFace& cf = faces_[f];
    const double s = glm::dot(cf.normal, c_) - cf.offset;  // shooter's height over the face
    if (!(s > coplanar_)) return;                          // seen from behind or edge-on
    // `mask` is its node's; a face of a few leaves is drawn under that, as
    // testing it again would cost about what drawing it does.
    if (culling_ && cf.le - cf.lb > 4 && !(mask = Visible(boxes_[f].Lo(), boxes_[f].Hi()))) return;
    DrawFace(mesh, f, mask, stats ? clock : nullptr);
  };
  if (!culling_) {
    for (int f : by_face_) draw(f, 31);
  } else if (!nodes_.empty()) {
    // Front to back, so that what is near fills the buffers before what
    // it hides is tested.
    stack_.assign(1, 0);
    while (!stack_.empty()) {
      const Node& nd = nodes_[stack_.back()];
      const int at = stack_.back();
      stack_.pop_back();
      const uint32_t mask = Visible(nd.box.Lo(), nd.box.Hi());
      if (!mask) continue;
      if (nd.right < 0) {
        // The faces' vertices lie in mesh order, not the hierarchy's, and
        // the outlines in rank order: ask for all of them at once rather
        // than wait for each face's in turn.
        for (int i = nd.first; i < nd.first + nd.count; ++i) {
          const CacheFace& cf = faces_[i];
          if (cf.le - cf.lb > 4) __builtin_prefetch(&boxes_[i]);  // draw tests its box
          // By cache line, not by vertex: 64 bytes hold 2 2/3 vertices.
          const uintptr_t vb = reinterpret_cast<uintptr_t>(mesh.verts.data() + cf.vb) & ~uintptr_t(63);
          const uintptr_t ve = reinterpret_cast<uintptr_t>(mesh.verts.data() + cf.ve);
          for (uintptr_t a = vb; a < ve; a += 64) __builtin_prefetch(reinterpret_cast<const void*>(a));
          __builtin_prefetch(wide_ ? static_cast<const void*>(&outline_wide_[cf.pb])
                                   : static_cast<const void*>(&outline_[cf.pb]));
          __builtin_prefetch(&outline_n_[cf.lb]);
        }
        for (int i = nd.first; i < nd.first + nd.count; ++i) draw(i, mask);
        continue;
      }
      const Node &l = nodes_[at + 1], &r = nodes_[nd.right];
      auto dist = [&](const Node& x) { return glm::length(0.5 * (x.box.Lo() + x.box.Hi()) - c_); };
      const bool left_first = dist(l) <= dist(r);
      // Their children are read when they are popped (to order theirs),
      // and a leaf child's faces when it is drawn: ask for them now, a
      // hierarchy level ahead (right children lie far; at 10^6 elements
      // nodes and faces are far from the cache).
      if (l.right >= 0) __builtin_prefetch(&nodes_[l.right]);
      if (r.right >= 0) {
        __builtin_prefetch(&nodes_[nd.right + 1]);
        __builtin_prefetch(&nodes_[r.right]);
      }
      for (const Node* x : {&l, &r}) {
        if (x->right >= 0) continue;
        const char* a = reinterpret_cast<const char*>(&faces_[x->first]);
        const char* b = reinterpret_cast<const char*>(&faces_[x->first + x->count]);
        for (; a < b; a += 64) __builtin_prefetch(a);
      }
      stack_.push_back(left_first ? nd.right : at + 1);
      stack_.push_back(left_first ? at + 1 : nd.right);
    }
  }
  const double t2 = MonotonicSeconds();
  clock[1] += t2 - clock[0];  // culling after the last face drawn

  // Sum delta form factors per element, a run of equal ids at a time. Run
  // ends are found as a bit mask per 64 pixels and visited by their set
  // bits: no branch per pixel to mispredict at every boundary.
  // Only the rows Scan wrote, each cleared for the next column once read
  // (while in cache, instead of a pass over all buffers before drawing).
  const int R = res_;
  const size_t npix = size_t(3) * R * R;
  for (int h = 0; h < 5; ++h) {
    if (rows_[h][0] >= rows_[h][1]) continue;
    const size_t first = h == 0 ? 0 : R + size_t(h - 1) * (R / 2);  // its row 0
  for (size_t row = first + rows_[h][0]; row < first + rows_[h][1]; ++row) {
    int32_t* it = &item_[row * R];  // it[R] is readable: next row or sentinel
    const double* pre = &prefix_[row * (R + 1)];
    int x0 = 0;
    for (int base = 0; base < R; base += 64) {
      const int len = std::min(64, R - base);
      uint64_t ends = 0;  // bit k: a run ends after pixel base + k
      if (len == 64) {
        // A byte per pixel (a loop that vectorises), then 8 bytes of 0/1
        // into 8 bits by one multiply: byte k lands on bit 56 + k.
        uint8_t ne[64];
        for (int k = 0; k < 64; ++k) ne[k] = it[base + k + 1] != it[base + k];
        for (int j = 0; j < 8; ++j) {
          uint64_t x;
          std::memcpy(&x, ne + 8 * j, 8);
          ends |= ((x * 0x0102040810204080ull) >> 56) << (8 * j);
        }
      } else {
        for (int k = 0; k < len; ++k)
          ends |= uint64_t(it[base + k + 1] != it[base + k]) << k;
      }
      if (base + len == R) ends |= uint64_t(1) << (len - 1);
      // The elements' ids of the runs that start in this block are asked
      // for before the first is summed: ranks lie scattered over elem_.
      for (uint64_t e = ends; e; e &= e - 1)
        __builtin_prefetch(&elem_[std::max(it[base + __builtin_ctzll(e) + 1], 0)]);
      while (ends) {
        const int x1 = base + __builtin_ctzll(ends) + 1;
        ends &= ends - 1;
        if (it[x0] >= 0) {
          const uint32_t id = uint32_t(elem_[it[x0]]);  // unsigned: / and % are shifts
          int32_t& b = block_[id / kSumBlock];
          if (b < 0) {
            b = int32_t(acc_.size());
            acc_.resize(acc_.size() + kSumBlock, 0.0);
          }
          acc_[size_t(b) + id % kSumBlock] += pre[x1] - pre[x0];
          touched_[id >> 6] |= uint64_t(1) << (id & 63);
        }
        x0 = x1;
      }
    }
    std::fill(it, it + R, -1);
    std::fill(&depth_[row * R], &depth_[row * R] + R, 0.0f);
  }
  }
  for (auto& r : rows_) r[0] = INT32_MAX, r[1] = 0;
  // In increasing id by the touched bits: a word per 64 elements, not a
  // read of every element's sum.
  out->clear();
  for (size_t w = 0; w < touched_.size(); ++w) {
    uint64_t bits = touched_[w];
    if (!bits) continue;
    touched_[w] = 0;
    for (uint64_t left = bits; left; left &= left - 1) {
      const int32_t id = int32_t(64 * w + __builtin_ctzll(left));
      const double sum = acc_[size_t(block_[id / kSumBlock]) + id % kSumBlock];
      if (sum > 0) out->push_back({id, float(sum)});
    }
    for (; bits; bits &= bits - 1) block_[(64 * w + __builtin_ctzll(bits)) / kSumBlock] = -1;
  }
  acc_.clear();
  const double t3 = MonotonicSeconds();
  if (stats) {
    stats->transform_s += clock[1];
    stats->raster_s += clock[2];
    stats->readback_s += t3 - t2;
    stats->elements += visited_;
    stats->covered += long(out->size());
    stats->pixels += long(npix);
  }
}

double ShotAngle(unsigned seed, int patch, int k) {
  const uint64_t z =
      SplitMix64((uint64_t(seed) << 40) ^ (uint64_t(uint32_t(patch)) << 16) ^ uint64_t(k));
  return double(z >> 11) * 0x1.0p-53 * 2 * M_PI;
}

void ShotColumn(Hemicube* hemicube, const Mesh& mesh, int patch, const PatchGroup* group, int k,
                bool rotate, unsigned seed, std::vector<FormFactor>* out, ColumnStats* stats) {
  hemicube->Column(mesh, patch, group, rotate ? ShotAngle(seed, patch, k) : 0.0, out, stats);
}

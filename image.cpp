// Pictures of a solved mesh: a small software rasteriser (z-buffer,
// frustum clipping, back-face culling, perspective-correct Gouraud), the
// exposure rule, 8-bit sRGB encoding, the PNG, PPM and PLY writers, and
// the Radiance RGBE one (the OpenEXR one is exr.cpp's).
#include "image.h"

#include <stb_image_write.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <utility>

#include "check.h"
#include "coding.h"
#include "exr.h"
#include "files.h"
#include "radix_sort.h"
#include "textnum.h"

namespace {

// Vertices snap to 1/256 pixel, so coverage is decided by exact integer
// edge functions: shared edges are watertight, and a scene scaled by 1e±4
// (camera too) covers the same pixels despite rounding in the projection.
constexpr int64_t kSub = 256;

// Triangles are clipped to the frustum widened by this factor in x and y
// (a guard band): projected coordinates stay small enough for 64-bit edge
// functions, and the edges that clipping adds lie off screen.
constexpr double kGuard = 2.0;

// The near plane, relative to the eye–target distance, so that the picture
// does not depend on the scene's units.
constexpr double kNearFraction = 1e-4;

struct ClipVert {
  glm::dvec3 p;  // camera space: x right, y up, z forward (depth)
  glm::vec3 c;
};

// Not initialized: Render's per-polygon arrays of them, zeroed for every
// polygon, cost a tenth of it; each is written (project) before it is read.
struct ScreenVert {
  int64_t x, y;  // pixel coordinates × kSub, y down
  float w;       // near / depth: linear in screen space
  glm::vec3 c;
};

struct Frustum {
  double near, gx, gy;  // gx, gy: half-extents of the guard band at depth 1

  // Signed distance to clip plane PLANE (near, left, right, bottom, top),
  // >= 0 inside.
  double Dist(int plane, const glm::dvec3& p) const {
    switch (plane) {
      case 0: return p.z - near;
      case 1: return gx * p.z + p.x;
      case 2: return gx * p.z - p.x;
      case 3: return gy * p.z + p.y;
      default: return gy * p.z - p.y;
    }
  }
  static constexpr int kPlanes = 5;
};

// A triangle gains at most one vertex per plane.
constexpr int kMaxClipVerts = 3 + Frustum::kPlanes;

// Sutherland–Hodgman against one plane; returns the new vertex count.
int ClipPlane(const Frustum& f, int plane, const ClipVert* in, int n,
              ClipVert* out) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const ClipVert& a = in[i];
    const ClipVert& b = in[(i + 1) % n];
    const double da = f.Dist(plane, a.p), db = f.Dist(plane, b.p);
    if (da >= 0) out[m++] = a;
    if ((da >= 0) != (db >= 0)) {
      // Interpolate from the inside vertex: the neighbour sharing this edge
      // walks it the other way and must get the bit-identical point.
      const bool a_in = da >= 0;
      const ClipVert& vi = a_in ? a : b;
      const ClipVert& vo = a_in ? b : a;
      const double di = a_in ? da : db, dout = a_in ? db : da;
      const double t = di / (di - dout);
      out[m++] = {vi.p + t * (vo.p - vi.p), vi.c + float(t) * (vo.c - vi.c)};
    }
  }
  return m;
}

// std::llround inline: a call into the C library per coordinate was a
// tenth of a picture at 10^6 elements (8 million calls). Halves away from
// zero; exact for |x| < 2^52 (x less its integer part is then exact),
// which the guard band keeps projected points far within.
int64_t RoundHalfAway(double x) {
  const int64_t i = int64_t(x);  // toward zero
  const double frac = x - double(i);
  return i + (frac >= 0.5) - (frac <= -0.5);
}

int64_t FloorDiv(int64_t a, int64_t b) {  // b > 0
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

struct Target {
  int width, height;
  float* depth;  // near / depth of what is drawn; 0 = nothing
  glm::vec3* color;
};

// Pixel-centre sampling with the top-left fill rule.
void DrawTriangle(const ScreenVert& a, ScreenVert b, ScreenVert c,
                  const Target& t) {
  auto orient = [](const ScreenVert& p, const ScreenVert& q, int64_t x,
                   int64_t y) {
    return (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
  };
  int64_t area = orient(a, b, c.x, c.y);
  // y runs down the screen, so a triangle counter-clockwise seen from the
  // front has negative area; positive is a back face, zero a sliver.
  if (area >= 0) return;
  std::swap(b, c);
  area = -area;

  const int64_t half = kSub / 2;
  const int64_t min_x = std::min({a.x, b.x, c.x}), max_x = std::max({a.x, b.x, c.x});
  const int64_t min_y = std::min({a.y, b.y, c.y}), max_y = std::max({a.y, b.y, c.y});
  const int x0 = int(std::max<int64_t>(0, -FloorDiv(half - min_x, kSub)));
  const int y0 = int(std::max<int64_t>(0, -FloorDiv(half - min_y, kSub)));
  const int x1 = int(std::min<int64_t>(t.width - 1, FloorDiv(max_x - half, kSub)));
  const int y1 = int(std::min<int64_t>(t.height - 1, FloorDiv(max_y - half, kSub)));
  if (x0 > x1 || y0 > y1) return;

  // Edge k is opposite vertex k; its function is that vertex's barycentric
  // weight × area. A pixel centre on an edge belongs to the triangle only if
  // the edge is a top or left one (the neighbour walks it the other way),
  // folded in as a bias of -1 so that "inside" is all three >= 0.
  const ScreenVert* v[3] = {&a, &b, &c};
  int64_t row[3], step_x[3], step_y[3];
  const int64_t px = int64_t(x0) * kSub + half, py = int64_t(y0) * kSub + half;
  for (int k = 0; k < 3; ++k) {
    const ScreenVert& p = *v[(k + 1) % 3];
    const ScreenVert& q = *v[(k + 2) % 3];
    const int64_t dx = q.x - p.x, dy = q.y - p.y;
    const bool top_left = dy < 0 || (dy == 0 && dx > 0);
    row[k] = orient(p, q, px, py) - (top_left ? 0 : 1);
    step_x[k] = -dy * kSub;
    step_y[k] = dx * kSub;
  }
  // Perspective-correct: near/depth and colour·near/depth are linear in
  // screen space; the pixel's colour is their ratio.
  const float inv_area = 1.0f / float(area);
  const float w[3] = {a.w * inv_area, b.w * inv_area, c.w * inv_area};
  const glm::vec3 cw[3] = {a.c * w[0], b.c * w[1], c.c * w[2]};

  for (int y = y0; y <= y1; ++y) {
    int64_t e0 = row[0], e1 = row[1], e2 = row[2];
    float* depth = t.depth + size_t(y) * t.width;
    glm::vec3* color = t.color + size_t(y) * t.width;
    for (int x = x0; x <= x1; ++x) {
      if ((e0 | e1 | e2) >= 0) {
        const float f0 = float(e0), f1 = float(e1), f2 = float(e2);
        const float z = f0 * w[0] + f1 * w[1] + f2 * w[2];
        if (z > depth[x]) {
          depth[x] = z;
          color[x] = (f0 * cw[0] + f1 * cw[1] + f2 * cw[2]) / z;
        }
      }
      e0 += step_x[0];
      e1 += step_x[1];
      e2 += step_x[2];
    }
    row[0] += step_y[0];
    row[1] += step_y[1];
    row[2] += step_y[2];
  }
}

double PolyArea(const ShadedMesh& mesh, const std::array<int, 4>& q) {
  const glm::dvec3& p0 = mesh.positions()[q[0]];
  const glm::dvec3& p1 = mesh.positions()[q[1]];
  const glm::dvec3& p2 = mesh.positions()[q[2]];
  if (q[3] < 0) return 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
  // A planar quad's area is half the cross product of its diagonals.
  return 0.5 * glm::length(glm::cross(p2 - p0, mesh.positions()[q[3]] - p1));
}

int PolySize(const std::array<int, 4>& q) { return q[3] < 0 ? 3 : 4; }

void CheckPolys(const ShadedMesh& mesh) {
  CHECK(mesh.colors.size() == mesh.positions().size());
  const int n = int(mesh.positions().size());
  for (const auto& q : mesh.polys)
    for (int k = 0; k < PolySize(q); ++k) CHECK(q[k] >= 0 && q[k] < n);
}

// The exact sRGB transfer curve, 8 bits with rounding, for 0 < v < 1.
int CurveCode(double v) {
  const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
  return int(std::lround(s * 255));
}

// thresholds[k]: the least v in (0, 1) that CurveCode takes to k or more
// (k = 1..255; 0 for k = 0), found by bisection over the bits of v (a
// positive double's bits are in the order of its value). The curve rises
// with v, so a code is the number of thresholds at or below v: what
// CurveCode gives, bit for bit, without its pow, which result.ply paid
// three times a vertex (6.6 million at 10^6 elements).
const std::array<double, 256>& Thresholds() {
  static const std::array<double, 256> t = [] {
    std::array<double, 256> t{};
    for (int k = 1; k < 256; ++k) {
      uint64_t lo = DoubleBits(0.0), hi = DoubleBits(1.0);  // CurveCode(lo) < k <= CurveCode(hi)
      while (hi - lo > 1) {
        const uint64_t mid = lo + (hi - lo) / 2;
        (CurveCode(BitsDouble(mid)) >= k ? hi : lo) = mid;
      }
      t[size_t(k)] = BitsDouble(hi);
    }
    return t;
  }();
  return t;
}

void AppendBytes(void* context, void* data, int size) {
  static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
}

}  // namespace

uint8_t EncodeSrgb8(float linear, float exposure) {
  const double v = double(linear) * exposure;  // exact: a float times a float
  if (!(v > 0)) return 0;                      // also NaN
  if (v >= 1) return 255;
  const double* t = Thresholds().data();
  size_t k = 0;  // the last threshold at or below v, halving the range
  for (size_t step = 128; step > 0; step /= 2) k += t[k + step] <= v ? step : 0;
  return uint8_t(k);
}

std::string JsonString(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') out += '\\', out += char(c);
    else if (c < 0x20 || c == '<') {
      char u[8];
      std::snprintf(u, sizeof u, "\\u%04x", c);
      out += u;
    } else out += char(c);
  }
  return out;
}

Camera FrameBox(const glm::dvec3& lo, const glm::dvec3& hi) {
  constexpr double kFov = 45.0;
  constexpr double kMargin = 1.1;  // the box fills at most 1/1.1 of the view
  Camera cam;
  cam.fov_deg = kFov;
  cam.target = 0.5 * (lo + hi);
  // From the front (+z), raised about 20 degrees.
  const glm::dvec3 back = glm::normalize(glm::dvec3(0.0, 0.35, 1.0));
  const glm::dvec3 right(1.0, 0.0, 0.0);
  const glm::dvec3 up = glm::cross(back, right);
  // The nearest distance at which every corner fits the (square) view:
  // a corner at (x, y) off axis and z towards the eye is at depth d - z.
  const double t = std::tan(glm::radians(kFov / 2)) / kMargin;
  double d = 0;
  for (int i = 0; i < 8; ++i) {
    const glm::dvec3 corner(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    const glm::dvec3 r = corner - cam.target;
    const double off = std::max(std::abs(glm::dot(r, right)), std::abs(glm::dot(r, up)));
    d = std::max(d, glm::dot(r, back) + off / t);
  }
  if (!(d > 0) || !std::isfinite(d)) d = 1;  // a single point has no size
  cam.eye = cam.target + d * back;
  return cam;
}

void Render(const ShadedMesh& mesh, const Camera& cam, int width, int height,
            Image* out) {
  CHECK(width > 0 && height > 0);
  CHECK(cam.fov_deg > 0 && cam.fov_deg < 180);
  CheckPolys(mesh);
  out->width = width;
  out->height = height;
  out->pixels.assign(size_t(width) * height, glm::vec3(0.0f));

  glm::dvec3 fwd = cam.target - cam.eye;
  const double dist = glm::length(fwd);
  if (!(dist > 0) || !std::isfinite(dist)) return;  // no view direction
  fwd /= dist;
  glm::dvec3 right = glm::cross(fwd, glm::dvec3(0.0, 1.0, 0.0));
  if (glm::length(right) < 1e-6) {
    // Looking straight down (up): -z (+z) at the top of the picture, as for
    // a camera tilted there from the front.
    right = glm::cross(fwd, glm::dvec3(0.0, 0.0, fwd.y > 0 ? 1.0 : -1.0));
  }
  right = glm::normalize(right);
  const glm::dvec3 up = glm::cross(right, fwd);

  const double ty = std::tan(glm::radians(cam.fov_deg / 2));
  const double tx = ty * width / height;
  const Frustum frustum{kNearFraction * dist, kGuard * tx, kGuard * ty};

  // Both write their result in place: returned by value, it was built on
  // the stack 8 bytes at a time and read back 16 at a time, a store the
  // processor could not forward (a third of Render's time at 10^6
  // elements).
  auto project = [&](const ClipVert& v, ScreenVert* s) {
    const double sx = v.p.x / (v.p.z * tx), sy = v.p.y / (v.p.z * ty);
    s->x = RoundHalfAway((sx + 1) * 0.5 * width * kSub);
    s->y = RoundHalfAway((1 - sy) * 0.5 * height * kSub);
    s->w = float(frustum.near / v.p.z);
    s->c = v.c;
  };

  // Each polygon projects its own corners (the same numbers for a vertex
  // from every polygon around it): a vertex is projected about twice, and
  // no per-vertex arrays are made beside the mesh's (33 bytes a vertex,
  // 70 MB at 10^6 elements, at the master's peak).
  const std::vector<glm::dvec3>& pos = mesh.positions();
  auto camera = [&](int i, ClipVert* v) {
    const glm::dvec3 r = pos[size_t(i)] - cam.eye;
    v->p.x = glm::dot(r, right);
    v->p.y = glm::dot(r, up);
    v->p.z = glm::dot(r, fwd);
    v->c = mesh.colors[size_t(i)];
  };

  std::vector<float> depth(size_t(width) * height, 0.0f);
  const Target target{width, height, depth.data(), out->pixels.data()};
  for (const auto& q : mesh.polys) {
    ClipVert cv[4];
    ScreenVert sv[4];
    uint8_t state[4];  // 0 invalid, 1 needs clipping, 2 inside
    for (int k = 0; k < PolySize(q); ++k) {
      camera(q[k], &cv[k]);
      state[k] = 0;
      if (!std::isfinite(cv[k].p.x) || !std::isfinite(cv[k].p.y) || !std::isfinite(cv[k].p.z))
        continue;
      bool inside = true;
      for (int j = 0; j < Frustum::kPlanes; ++j) inside = inside && frustum.Dist(j, cv[k].p) >= 0;
      state[k] = inside ? 2 : 1;
      if (inside) project(cv[k], &sv[k]);
    }
    for (int k = 1; k + 1 < PolySize(q); ++k) {
      const int a = 0, b = k, c = k + 1;
      if (!state[a] || !state[b] || !state[c]) continue;
      if (state[a] == 2 && state[b] == 2 && state[c] == 2) {
        DrawTriangle(sv[a], sv[b], sv[c], target);
        continue;
      }
      ClipVert buf[2][kMaxClipVerts] = {{cv[a], cv[b], cv[c]}, {}};
      int n = 3, cur = 0;
      for (int plane = 0; plane < Frustum::kPlanes && n >= 3; ++plane) {
        n = ClipPlane(frustum, plane, buf[cur], n, buf[1 - cur]);
        cur = 1 - cur;
      }
      if (n < 3) continue;
      ScreenVert s[kMaxClipVerts];
      for (int i = 0; i < n; ++i) project(buf[cur][i], &s[i]);
      for (int i = 1; i + 1 < n; ++i) DrawTriangle(s[0], s[i], s[i + 1], target);
    }
  }
}

// Exposure rule: each vertex has a luminance (0.2126 R + 0.7152 G +
// 0.0722 B) and an equal share of the area of every polygon around it. The
// luminance below which 95% of the surface area lies is mapped to 0.8 of
// display white (before the sRGB curve), so small bright lights do not
// darken the picture and the units of Ke do not matter. If that is 0 (e.g.
// only the lights are lit yet) the brightest vertex is used; a black scene
// gets 1.
float AutoExposure(const ShadedMesh& mesh) {
  constexpr double kPercentile = 0.95;
  constexpr double kWhite = 0.8;
  CheckPolys(mesh);
  auto lum_of = [&mesh](size_t i) {
    const glm::dvec3 c(mesh.colors[i]);
    const double lum = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    return std::isfinite(lum) && lum > 0 ? lum : 0.0;
  };
  // A vertex's weight: its share of the polygons round it, summed in the
  // polygons' order. Kept for every vertex while this runs, 8 bytes each:
  // made again for a quarter of the vertices at each walk below (d8ab6ac,
  // to keep 6 of them out of the master's peak) they cost a pass over the
  // polygons a walk, and the picture of a wave is made while the workers
  // wait (app.cpp): 95-130 ms for 210,000 vertices, 27 with them kept
  // (the master's dividing peak about 10 bytes an element higher:
  // memory.h).
  const size_t nv = mesh.positions().size();
  std::vector<double> w(nv, 0.0);
  for (const auto& q : mesh.polys) {
    const double a = PolyArea(mesh, q);
    if (!std::isfinite(a)) continue;
    for (int k = 0; k < PolySize(q); ++k) w[size_t(q[k])] += a / PolySize(q);
  }
  // Bins of luminance by the top 16 bits of the double (sign, exponent, 4
  // bits of mantissa: in the order of the values, as they are >= 0), of
  // the vertices of some weight.
  auto bin_of = [](double lum) { return size_t(DoubleBits(lum) >> 48); };
  std::vector<uint32_t> count(size_t(1) << 15, 0);
  double total = 0, brightest = 0;
  size_t weighted = 0;
  for (size_t i = 0; i < nv; ++i) {
    if (!(w[i] > 0)) continue;
    const double lum = lum_of(i);
    total += w[i];
    brightest = std::max(brightest, lum);
    ++count[bin_of(lum)];
    ++weighted;
  }
  // The weights summed in increasing (luminance, weight) up to the
  // percentile, a run of bins at a time (about 1/16 of the vertices each,
  // or one bin), sorted: the same sums in the same order as a sort of all
  // of them, for a run's (luminance, weight) pairs, 16 bytes each, or,
  // for one bin larger than that of one luminance (those still dark early
  // in a run, all of luminance 0), its weights, 8.
  const size_t run = std::max<size_t>(weighted / 16, 1);
  struct Run {
    size_t end, vertices;  // its last bin + 1, its vertices
  };
  std::vector<Run> runs;
  for (size_t hi = 0; hi < count.size();) {
    size_t m = 0;
    while (hi < count.size() && (m == 0 || m + count[hi] <= run)) m += count[hi++];
    if (m == 0) break;  // empty bins to the end
    runs.push_back({hi, m});
  }
  std::vector<std::pair<double, double>> lw;
  std::vector<double> ws;
  double level = 0, sum = 0;
  bool reached = false;
  auto add = [&](double lum, double weight) {
    sum += weight;
    level = lum;
    return reached = sum >= kPercentile * total;
  };
  for (size_t r = 0, lo = 0; r < runs.size() && !reached; lo = runs[r++].end) {
    const size_t hi = runs[r].end;
    // fn(i) for each vertex i of the run, in the order of i.
    auto walk = [&](auto&& fn) {
      for (size_t i = 0; i < nv; ++i)
        if (w[i] > 0 && bin_of(lum_of(i)) - lo < hi - lo) fn(i);
    };
    // One bin of one luminance (the dark vertices' 0): its weights alone.
    double least = HUGE_VAL, most = 0;
    if (runs[r].vertices > run)
      walk([&](size_t i) {
        least = std::min(least, lum_of(i));
        most = std::max(most, lum_of(i));
      });
    lw.clear();
    ws.clear();
    if (least == most) {
      ws.reserve(runs[r].vertices);
      walk([&](size_t i) { ws.push_back(w[i]); });
      RadixSort(&ws, [](double x) { return DoubleBits(x); });
      for (double weight : ws)
        if (add(least, weight)) break;
    } else {
      lw.reserve(runs[r].vertices);
      walk([&](size_t i) { lw.emplace_back(lum_of(i), w[i]); });
      // By weight, then (stably) by luminance: std::sort's order of pairs.
      RadixSort(&lw, [&](const std::pair<double, double>& x) { return DoubleBits(x.second); });
      RadixSort(&lw, [&](const std::pair<double, double>& x) { return DoubleBits(x.first); });
      for (const auto& [lum, weight] : lw)
        if (add(lum, weight)) break;
    }
  }
  if (!(level > 0)) level = brightest;
  if (!(level > 0)) return 1.0f;
  return float(std::clamp(kWhite / level, double(std::numeric_limits<float>::min()),
                          double(std::numeric_limits<float>::max())));
}

bool WriteImage(const Image& img, float exposure, const std::vector<std::string>& paths,
                const std::string& format, std::string* err) {
  CHECK(img.width > 0 && img.height > 0 &&
        img.pixels.size() == size_t(img.width) * img.height);
  if (format == "exr") {  // linear: no exposure
    for (const std::string& path : paths)
      if (!WriteOpenExr(img, path, err)) return false;
    return true;
  }
  if (format != "png" && format != "ppm") {
    *err = (paths.empty() ? std::string() : paths[0] + ": ") + "unknown image format \"" + format +
           "\" (png, ppm or exr)";
    return false;
  }
  std::vector<uint8_t> rgb(img.pixels.size() * 3);
  for (size_t i = 0; i < img.pixels.size(); ++i)
    for (int k = 0; k < 3; ++k) rgb[3 * i + k] = EncodeSrgb8(img.pixels[i][k], exposure);

  // PNG is encoded in memory, because stbi_write_png ignores write errors.
  std::string bytes;
  if (format == "png") {
    if (!stbi_write_png_to_func(AppendBytes, &bytes, img.width, img.height, 3,
                                rgb.data(), img.width * 3)) {
      *err = (paths.empty() ? std::string() : paths[0] + ": ") + "cannot encode PNG";
      return false;
    }
  } else {
    bytes = "P6\n" + std::to_string(img.width) + " " + std::to_string(img.height) + "\n255\n";
    bytes.append(reinterpret_cast<const char*>(rgb.data()), rgb.size());
  }
  for (const std::string& path : paths)
    if (!WriteFileAtomic(path, bytes, err)) return false;
  return true;
}

bool WriteRadianceHdr(const Image& img, const std::string& path, std::string* err) {
  CHECK(img.width > 0 && img.height > 0 &&
        img.pixels.size() == size_t(img.width) * img.height);
  static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "pixels are packed RGB floats");
  // In memory, as the PNG, then written atomically.
  std::string bytes;
  if (!stbi_write_hdr_to_func(AppendBytes, &bytes, img.width, img.height, 3, &img.pixels[0].x)) {
    *err = path + ": cannot encode Radiance HDR";
    return false;
  }
  return WriteFileAtomic(path, bytes, err);
}

bool WritePly(const ShadedMesh& mesh, float exposure, const std::string& path,
              std::string* err) {
  CheckPolys(mesh);
  return WriteFileAtomic(path, [&](const FileSink& put) {
    std::string s = "ply\nformat ascii 1.0\n"
                    "comment radiosity: vertex colours are exposed, sRGB-encoded radiosity\n";
    s += "element vertex " + std::to_string(mesh.positions().size()) + "\n";
    s += "property float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    s += "element face " + std::to_string(mesh.polys.size()) + "\n";
    s += "property list uchar int vertex_indices\nend_header\n";
    // Written out a megabyte at a time: the whole text is some 100 bytes
    // an element.
    auto flush = [&](size_t at_least) {
      if (s.size() < at_least) return true;
      const bool ok = put(s.data(), s.size());
      s.clear();
      return ok;
    };
    for (size_t i = 0; i < mesh.positions().size(); ++i) {
      const glm::dvec3& p = mesh.positions()[i];
      const glm::vec3& c = mesh.colors[i];
      // Each coordinate as the float it reads back as, then the colour.
      for (int k = 0; k < 3; ++k) {
        AppendFloat(&s, float(p[k]));
        s += ' ';
      }
      for (int k = 0; k < 3; ++k) {
        AppendInt(&s, EncodeSrgb8(c[k], exposure));
        s += k < 2 ? ' ' : '\n';
      }
      if (!flush(1 << 20)) return false;
    }
    for (const auto& q : mesh.polys) {
      const int n = q[3] < 0 ? 3 : 4;
      AppendInt(&s, n);
      for (int k = 0; k < n; ++k) {
        s += ' ';
        AppendInt(&s, q[k]);
      }
      s += '\n';
      if (!flush(1 << 20)) return false;
    }
    return flush(0);
  }, err);
}

bool WriteGltf(const ShadedMesh& mesh, float exposure, const std::string& gltf_path,
               const std::string& bin_path, std::string* err) {
  CheckPolys(mesh);
  const size_t n = mesh.positions().size();
  float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF}, hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const float p = float(mesh.positions()[i][k]);
      lo[k] = std::min(lo[k], p);
      hi[k] = std::max(hi[k], p);
    }
  if (n == 0) lo[0] = lo[1] = lo[2] = hi[0] = hi[1] = hi[2] = 0;
  size_t nidx = 0;
  for (const auto& q : mesh.polys) nidx += q[3] >= 0 ? 6 : 3;
  const size_t pos_bytes = 12 * n, col_bytes = 12 * n, idx_bytes = 4 * nidx;
  const size_t bin_size = pos_bytes + col_bytes + idx_bytes;
  // The buffer goes out in pieces of a few thousand values (it is some 60
  // bytes an element): positions, colours, then indices. glTF buffers are
  // little-endian, as is every machine this builds on (x86-64, arm64); the
  // values are copied as they lie in memory.
  const bool bin_ok = WriteFileAtomic(bin_path, [&](const FileSink& put) {
    std::vector<float> f;
    std::vector<uint32_t> u;
    constexpr size_t kPiece = 1 << 16;
    auto send = [&](auto* v) {
      const bool ok = v->empty() || put(reinterpret_cast<const char*>(v->data()), 4 * v->size());
      v->clear();
      return ok;
    };
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) f.push_back(float(mesh.positions()[i][k]));
      if (f.size() >= kPiece && !send(&f)) return false;
    }
    if (!send(&f)) return false;
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        const float c = mesh.colors[i][k] * exposure;
        f.push_back(c > 0 ? std::min(c, 1.0f) : 0.0f);  // also NaN to 0
      }
      if (f.size() >= kPiece && !send(&f)) return false;
    }
    if (!send(&f)) return false;
    for (const auto& q : mesh.polys) {
      u.insert(u.end(), {uint32_t(q[0]), uint32_t(q[1]), uint32_t(q[2])});
      if (q[3] >= 0) u.insert(u.end(), {uint32_t(q[0]), uint32_t(q[2]), uint32_t(q[3])});
      if (u.size() >= kPiece && !send(&u)) return false;
    }
    return send(&u);
  }, err);
  if (!bin_ok) return false;

  const size_t slash = bin_path.rfind('/');
  const std::string uri = slash == std::string::npos ? bin_path : bin_path.substr(slash + 1);
  char buf[2048];
  std::snprintf(
      buf, sizeof buf,
      "{\n"
      "  \"asset\": {\"version\": \"2.0\", \"generator\": \"radiosity\"},\n"
      "  \"extensionsUsed\": [\"KHR_materials_unlit\"],\n"
      "  \"scene\": 0,\n"
      "  \"scenes\": [{\"nodes\": [0]}],\n"
      "  \"nodes\": [{\"mesh\": 0, \"name\": \"radiosity\"}],\n"
      "  \"materials\": [{\"name\": \"radiosity\", \"pbrMetallicRoughness\": "
      "{\"baseColorFactor\": [1, 1, 1, 1], \"metallicFactor\": 0, \"roughnessFactor\": 1}, "
      "\"extensions\": {\"KHR_materials_unlit\": {}}}],\n"
      "  \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"COLOR_0\": 1}, "
      "\"indices\": 2, \"material\": 0, \"mode\": 4}]}],\n"
      "  \"buffers\": [{\"uri\": \"%s\", \"byteLength\": %zu}],\n"
      "  \"bufferViews\": [\n"
      "    {\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": %zu, \"target\": 34962},\n"
      "    {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu, \"target\": 34962},\n"
      "    {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu, \"target\": 34963}\n"
      "  ],\n"
      "  \"accessors\": [\n"
      "    {\"bufferView\": 0, \"componentType\": 5126, \"count\": %zu, \"type\": \"VEC3\", "
      "\"min\": [%.9g, %.9g, %.9g], \"max\": [%.9g, %.9g, %.9g]},\n"
      "    {\"bufferView\": 1, \"componentType\": 5126, \"count\": %zu, \"type\": \"VEC3\"},\n"
      "    {\"bufferView\": 2, \"componentType\": 5125, \"count\": %zu, \"type\": \"SCALAR\"}\n"
      "  ]\n"
      "}\n",
      JsonString(uri).c_str(), bin_size, pos_bytes, pos_bytes, col_bytes, pos_bytes + col_bytes,
      idx_bytes, n, double(lo[0]), double(lo[1]), double(lo[2]), double(hi[0]), double(hi[1]),
      double(hi[2]), n, nidx);
  const std::string json = buf;
  return WriteFileAtomic(gltf_path, json, err);
}

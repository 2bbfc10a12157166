#include "results.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <sstream>
#include <unordered_map>

#include "check.h"
#include "files.h"
#include "surface.h"
#include "textnum.h"

namespace {

// Radiosity times area, and area, of the parts of leaves under element
// `e` that lie inside input face `clip` (in the surface's plane frame).
void Cover(const Mesh& mesh, const ElemB& elem_b, const PlaneFrame& frame,
           const std::vector<glm::dvec2>& clip, int e, glm::dvec3* sum, double* area) {
  const Element& el = mesh.elems[e];
  std::vector<glm::dvec2> poly;
  for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) poly.push_back(frame.At(mesh.verts[el.v[k]]));
  const double whole = Area2(poly), part = OverlapArea(poly, clip);
  if (!(part > 0) || !(whole > 0)) return;
  if (el.IsLeaf() || part >= whole * (1 - 1e-12)) {
    std::vector<int> leaves;
    mesh.LeavesUnder(e, &leaves);
    const double share = el.IsLeaf() ? part / whole : 1.0;
    for (int l : leaves) {
      *sum += elem_b[l] * (mesh.elem_area[size_t(l)] * share);
      *area += mesh.elem_area[size_t(l)] * share;
    }
    return;
  }
  for (int k = 0; k < kChildren; ++k) Cover(mesh, elem_b, frame, clip, el.first_child + k, sum, area);
}

}  // namespace

std::vector<glm::dvec3> FaceRadiosity(const Mesh& mesh, const ElemB& elem_b) {
  std::vector<glm::dvec3> out(mesh.corner_begin.size() - 1, glm::dvec3(0.0));
  std::vector<int> leaves;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const MeshFace& mf = mesh.faces[f];
    const IdSpan scene_faces = mesh.SceneFaces(f);
    if (scene_faces.size() == 1) {  // all its leaves, in patch order
      glm::dvec3 sum(0.0);
      double area = 0;
      mesh.FaceLeaves(mf, &leaves);
      for (int e : leaves) {
        sum += elem_b[e] * mesh.elem_area[size_t(e)];
        area += mesh.elem_area[size_t(e)];
      }
      if (area > 0) out[scene_faces[0]] = glm::max(sum / area, glm::dvec3(0.0));
      continue;
    }
    // A joined surface: each face gets the leaves' overlap with it, found
    // top down from the built elements whose bounds meet the face's.
    const PlaneFrame frame(mesh.verts[mf.vbegin], mf.normal);
    struct Top {
      int elem;
      glm::dvec2 lo, hi;
    };
    std::vector<Top> tops;
    for (int p : mesh.FacePatches(mf))
      for (int e : mesh.Tops(p)) {
        const Element& el = mesh.elems[e];
        Top t{e, glm::dvec2(HUGE_VAL), glm::dvec2(-HUGE_VAL)};
        for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) {
          const glm::dvec2 q = frame.At(mesh.verts[el.v[k]]);
          t.lo = glm::min(t.lo, q);
          t.hi = glm::max(t.hi, q);
        }
        tops.push_back(t);
      }
    std::vector<glm::dvec2> clip;
    for (int f : scene_faces) {
      clip.clear();
      glm::dvec2 lo(HUGE_VAL), hi(-HUGE_VAL);
      for (int c = mesh.corner_begin[f]; c < mesh.corner_begin[f + 1]; ++c) {
        clip.push_back(frame.At(mesh.face_corners[c]));
        lo = glm::min(lo, clip.back());
        hi = glm::max(hi, clip.back());
      }
      if (Area2(clip) < 0) std::reverse(clip.begin(), clip.end());
      glm::dvec3 sum(0.0);
      double area = 0;
      for (const Top& t : tops)
        if (t.lo.x <= hi.x && t.hi.x >= lo.x && t.lo.y <= hi.y && t.hi.y >= lo.y)
          Cover(mesh, elem_b, frame, clip, t.elem, &sum, &area);
      if (area > 0) out[f] = glm::max(sum / area, glm::dvec3(0.0));
    }
  }
  return out;
}

namespace {

// RFC 4180: a field with a comma, quote or line break is quoted, quotes doubled.
std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// Splits one CSV line; false on an unterminated quote.
bool CsvSplit(const std::string& line, std::vector<std::string>* cols) {
  cols->assign(1, "");
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c != '"') cols->back() += c;
      else if (i + 1 < line.size() && line[i + 1] == '"') cols->back() += line[++i];
      else quoted = false;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cols->emplace_back();
    } else {
      cols->back() += c;
    }
  }
  return !quoted;
}

}  // namespace

bool WriteResultCsv(const std::string& path, const Scene& scene,
                    const std::vector<glm::dvec3>& face_b, std::string* err) {
  std::string text = "face,object,area,B_r,B_g,B_b\n";
  for (size_t i = 0; i < scene.faces.size(); ++i) {
    const Face& fc = scene.faces[i];
    AppendInt(&text, fc.index);
    text += ',';
    text += CsvField(scene.objects[fc.object]);
    for (double v : {fc.area, face_b[i].r, face_b[i].g, face_b[i].b}) {
      text += ',';
      AppendG9(&text, v);
    }
    text += '\n';
  }
  return WriteFileAtomic(path, text, err);
}

bool ReadReference(const std::string& path, const Scene& scene,
                   std::vector<glm::dvec3>* ref, std::string* err) {
  std::string text;
  if (!ReadInput(path, kMaxReferenceBytes, &text, err)) return false;
  std::istringstream in(text);
  ref->assign(scene.faces.size(), glm::dvec3(0.0));
  std::string line;
  int lineno = 0;
  size_t row = 0;
  auto fail = [&](const std::string& what) {
    *err = path + ":" + std::to_string(lineno) + ": " + what;
    return false;
  };
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (lineno == 1) {
      if (line != "face,object,area,B_r,B_g,B_b") return fail("not a result.csv header");
      continue;
    }
    if (line.empty()) continue;
    std::vector<std::string> col;
    if (!CsvSplit(line, &col)) return fail("unterminated quote");
    if (col.size() != 6) return fail("expected 6 columns");
    if (row >= scene.faces.size()) return fail("more rows than the scene has faces");
    double v[4];
    for (int k = 0; k < 4; ++k) {
      const std::string& s = col[2 + k];
      char* end = nullptr;
      errno = 0;
      v[k] = std::strtod(s.c_str(), &end);
      if (s.empty() || *end || errno || !std::isfinite(v[k]) || v[k] < 0)
        return fail("bad number '" + s + "'");
    }
    if (col[0] != std::to_string(scene.faces[row].index))
      return fail("face " + col[0] + " is not the scene's face " +
                  std::to_string(scene.faces[row].index) + " (another scene?)");
    if (std::abs(v[0] - scene.faces[row].area) > 1e-6 * (v[0] + scene.faces[row].area))
      return fail("face area differs from the scene's (another scene?)");
    (*ref)[row++] = glm::dvec3(v[1], v[2], v[3]);
  }
  if (row != scene.faces.size()) {
    ++lineno;
    return fail("has " + std::to_string(row) + " rows, the scene " +
                std::to_string(scene.faces.size()) + " faces");
  }
  return true;
}

void RmsError(const Scene& scene, const std::vector<glm::dvec3>& face_b,
              const std::vector<glm::dvec3>& ref, double* rms, double* rel_rms) {
  double se = 0, area = 0, mean = 0;
  for (size_t i = 0; i < scene.faces.size(); ++i) {
    const double a = scene.faces[i].area;
    const glm::dvec3 d = ref[i] - face_b[i];
    se += a * glm::dot(d, d) / 3;
    mean += a * (ref[i].r + ref[i].g + ref[i].b) / 3;
    area += a;
  }
  *rms = area > 0 ? std::sqrt(se / area) : 0;
  *rel_rms = mean > 0 ? *rms / (mean / area) : 0;
}

LogCsv::~LogCsv() {
  if (f_) std::fclose(f_);
}

bool LogCsv::Open(const std::string& path, std::string* err) {
  path_ = path;
  // A new file (in the run's own directory, Staging): never one planted there.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  f_ = fd < 0 ? nullptr : ::fdopen(fd, "w");
  if (!f_) {
    if (fd >= 0) ::close(fd);
    *err = path + ": " + std::strerror(errno);
    return false;
  }
  std::fprintf(f_, "time_s,shots,wave,elements,unshot_fraction,rms,rel_rms\n");
  return true;
}

void LogCsv::Row(const Sample& s, const double* rms, const double* rel_rms) {
  char buf[256];
  int n = std::snprintf(buf, sizeof buf, "%.6f,%ld,%d,%ld,%.6g,", s.seconds, s.shots, s.wave,
                        s.elements, s.unshot);
  if (rms) std::snprintf(buf + n, sizeof buf - size_t(n), "%.6g,%.6g\n", *rms, *rel_rms);
  else std::snprintf(buf + n, sizeof buf - size_t(n), ",\n");
  std::fputs(buf, f_);
  text_ += buf;
}

void LogCsv::Restore(const std::string& text) {
  std::fputs(text.c_str(), f_);
  text_ = text;
}

std::vector<LogRow> LogCsv::rows() const {
  // Rows this program wrote (or a checkpoint's checksum vouches for).
  std::vector<LogRow> rows;
  std::istringstream in(text_);
  for (std::string line; std::getline(in, line);) {
    LogRow r{0, 0, 0, 0, 0, NAN, NAN};
    std::istringstream f(line);
    std::string cell[7];
    for (std::string& c : cell) std::getline(f, c, ',');
    r.seconds = std::atof(cell[0].c_str());
    r.shots = std::atol(cell[1].c_str());
    r.wave = std::atoi(cell[2].c_str());
    r.elements = std::atol(cell[3].c_str());
    r.unshot = std::atof(cell[4].c_str());
    if (!cell[5].empty()) r.rms = std::atof(cell[5].c_str());
    if (!cell[6].empty()) r.rel_rms = std::atof(cell[6].c_str());
    rows.push_back(r);
  }
  return rows;
}

bool LogCsv::Close(std::string* err) {
  int rc = std::fclose(f_);
  f_ = nullptr;
  if (rc != 0) {
    *err = path_ + ": " + std::strerror(errno);
    return false;
  }
  return true;
}

ShadedMesh Shade(const Mesh& mesh, const ElemB& elem_b) {
  ShadedMesh s;
  s.lent = &mesh.verts;
  std::vector<int> t_leaves;  // leaves with T-vertices on their edges
  // Polygons counted first and reserved: grown by doubling they took up
  // to three times their 16 bytes an element while it grew.
  size_t npolys = 0;
  for (size_t e = 0; e < mesh.elems.size(); ++e) {
    const Element& el = mesh.elems[e];
    if (!el.IsLeaf()) continue;
    int out[8];
    const int m = Outline(mesh, int(e), out);
    npolys += m == (el.IsTriangle() ? 3 : 4) ? 1 : size_t(m - 2);
  }
  s.polys.reserve(npolys);
  for (size_t e = 0; e < mesh.elems.size(); ++e) {
    const Element& el = mesh.elems[e];
    if (!el.IsLeaf()) continue;
    // Drawn as a fan over its outline: where finer neighbours meet it,
    // it meets their edges exactly (no pixel cracks).
    int out[8];
    const int m = Outline(mesh, int(e), out);
    if (m == (el.IsTriangle() ? 3 : 4)) {
      s.polys.push_back(el.v);
    } else {
      t_leaves.push_back(int(e));
      for (int i = 1; i + 1 < m; ++i) s.polys.push_back({out[0], out[i], out[i + 1], -1});
    }
  }
  // Faces do not share vertices, but where two faces of one material lie in
  // one plane (a floor cut round a rug, a ceiling round a light) a seam
  // would show: their coincident vertices are averaged together.
  // Vertices join when point, material and normal (to 1e-6) agree: an
  // open-addressing table of one vertex per group (4 bytes a slot, the key
  // read from the vertex and its face), not a hash map of keys (90 bytes a
  // vertex, the largest thing the master held at 10^6 elements).
  std::vector<int> face_of(mesh.verts.size(), -1);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int v = mesh.faces[f].vbegin; v < mesh.faces[f].vend; ++v) face_of[v] = int(f);
    for (int v : mesh.DivideVerts(mesh.faces[f])) face_of[v] = int(f);
  }
  // A face's key: its normal to 1e-6 and its material, made once a face.
  struct FaceKey {
    long long n[3];
    int material;
    bool operator==(const FaceKey& o) const {
      return n[0] == o.n[0] && n[1] == o.n[1] && n[2] == o.n[2] && material == o.material;
    }
  };
  auto face_key = [&](int f) {
    const MeshFace& mf = mesh.faces[size_t(f)];
    return FaceKey{{std::llround(mf.normal[0] * 1e6), std::llround(mf.normal[1] * 1e6),
                    std::llround(mf.normal[2] * 1e6)},
                   mf.material};
  };
  auto hash = [&](int v, const FaceKey& k) {
    return PointHash()(mesh.verts[v]) ^ size_t(k.n[0] ^ k.n[1] ^ k.n[2]) ^ size_t(k.material) * 101;
  };
  // At most 3/4 full (the pair of 4-byte tables at the joining, face_of
  // and this, was the peak of the master's last picture at half full).
  size_t slots = 16;
  while (3 * slots < 4 * mesh.verts.size()) slots *= 2;
  std::vector<int> first(slots, -1);  // a group's first vertex
  std::vector<int> group(mesh.verts.size());
  int groups = 0;
  // Some 64 vertices at a time (whole faces, in order): their slots
  // fetched first, then the vertices found there, then each joined in
  // turn (the same order, so the same groups). One at a time, each waited
  // for its slot and then for the vertex in it, both anywhere in memory:
  // Shade of boxes20000 (529,260 elements) took 158-197 ms, now 79-90.
  struct Pending {
    int v;
    uint32_t key;  // in keys
    size_t slot;
  };
  std::vector<Pending> batch;
  std::vector<FaceKey> keys;
  auto join_batch = [&] {
    for (const Pending& x : batch)
      if (first[x.slot] >= 0) {
        __builtin_prefetch(&mesh.verts[size_t(first[x.slot])]);
        __builtin_prefetch(&face_of[size_t(first[x.slot])]);
      }
    for (const Pending& x : batch) {
      const FaceKey& key = keys[x.key];
      size_t i = x.slot;
      // The same point on a face of the same key (its own face's vertices
      // are not the same point).
      while (first[i] >= 0 && !(mesh.verts[first[i]] == mesh.verts[x.v] &&
                                face_key(face_of[first[i]]) == key))
        i = (i + 1) & (slots - 1);
      if (first[i] < 0) {
        first[i] = x.v;
        group[x.v] = groups++;
      } else {
        group[x.v] = group[first[i]];
      }
    }
    batch.clear();
    keys.clear();
  };
  for (size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const MeshFace& f = mesh.faces[fi];
    keys.push_back(face_key(int(fi)));
    const uint32_t k = uint32_t(keys.size() - 1);
    auto add = [&](int v) {
      batch.push_back({v, k, hash(v, keys[k]) & (slots - 1)});
      __builtin_prefetch(&first[batch.back().slot]);
    };
    for (int v = f.vbegin; v < f.vend; ++v) add(v);
    for (int v : mesh.DivideVerts(f)) add(v);
    if (batch.size() >= 64) join_batch();
  }
  join_batch();
  std::vector<int>().swap(first);
  std::vector<int>().swap(face_of);
  // Most groups are one vertex, whose sums are its own (0 + x is x): sums
  // per group only for those joined (a group's members, then the index of
  // its sums or -1), and their members' own sums kept (`at`, in vertex
  // order) until the groups' are summed; each member's group sums index
  // (`sums_of`) kept instead of the per-group table, freed before the
  // colours are made.
  std::vector<int> joined(static_cast<size_t>(groups), 0);
  for (int g : group) ++joined[g];
  size_t njoined = 0;
  for (int& j : joined) j = j > 1 ? int(njoined++) : -1;
  std::vector<int> at(mesh.verts.size(), -1), sums_of;
  for (size_t v = 0; v < at.size(); ++v)
    if (joined[group[v]] >= 0) {
      at[v] = int(sums_of.size());
      sums_of.push_back(joined[group[v]]);
    }
  std::vector<int>().swap(joined);
  const size_t nmembers = sums_of.size();
  std::vector<glm::dvec3> msum(nmembers, glm::dvec3(0.0));
  std::vector<double> mw(nmembers, 0.0);
  // Each vertex's area-weighted sum over the leaves around it, a face at a
  // time (its vertices are its own: 32 bytes for the face's vertices, not
  // for every vertex of the mesh), its leaves in increasing id as a walk
  // over all leaves would add them, so the sums are the same bits.
  s.colors.resize(mesh.verts.size(), glm::vec3(0.0f));
  std::vector<int> leaves;
  std::vector<glm::dvec3> sum;
  std::vector<double> w;
  for (const MeshFace& f : mesh.faces) {
    mesh.FaceLeaves(f, &leaves);
    std::sort(leaves.begin(), leaves.end());
    const int own = f.vend - f.vbegin;
    const std::vector<int>& dv = mesh.DivideVerts(f);
    auto local = [&](int v) {
      return v < f.vend ? v - f.vbegin : own + int(std::lower_bound(dv.begin(), dv.end(), v) - dv.begin());
    };
    const size_t n = size_t(own) + dv.size();
    sum.assign(n, glm::dvec3(0.0));
    w.assign(n, 0.0);
    for (int e : leaves) {
      const Element& el = mesh.elems[size_t(e)];
      const glm::dvec3 b = glm::max(elem_b[size_t(e)], glm::dvec3(0.0));
      for (int k = 0; k < (el.IsTriangle() ? 3 : 4); ++k) {
        const int l = local(el.v[k]);
        sum[size_t(l)] += b * mesh.elem_area[size_t(e)];
        w[size_t(l)] += mesh.elem_area[size_t(e)];
      }
    }
    auto put = [&](int v) {
      const size_t l = size_t(local(v));
      if (at[v] >= 0) {
        msum[size_t(at[v])] = sum[l];
        mw[size_t(at[v])] = w[l];
      } else if (w[l] > 0) {
        s.colors[v] = glm::vec3(sum[l] / w[l]);
      }
    };
    for (int v = f.vbegin; v < f.vend; ++v) put(v);
    for (int v : dv) put(v);
  }
  std::vector<glm::dvec3> gsum(njoined, glm::dvec3(0.0));
  std::vector<double> gw(njoined, 0.0);
  for (size_t v = 0; v < at.size(); ++v)
    if (at[v] >= 0) {
      const int j = sums_of[size_t(at[v])];
      gsum[j] += msum[size_t(at[v])];
      gw[j] += mw[size_t(at[v])];
    }
  for (size_t v = 0; v < at.size(); ++v)
    if (at[v] >= 0) {
      const int j = sums_of[size_t(at[v])];
      if (gw[j] > 0) s.colors[v] = glm::vec3(gsum[j] / gw[j]);
    }
  for (auto* x : {&sum, &gsum, &msum}) std::vector<glm::dvec3>().swap(*x);
  for (auto* x : {&w, &gw, &mw}) std::vector<double>().swap(*x);
  for (auto* x : {&at, &sums_of}) std::vector<int>().swap(*x);
  // A T-vertex takes the value interpolated along the coarser edge it lies
  // on, so both sides shade that edge alike (no seam); so do the vertices
  // joined with it across coplanar faces. Coarser first: a corner of a
  // finer element may itself be a T-vertex of a coarser one.
  std::stable_sort(t_leaves.begin(), t_leaves.end(),
                   [&](int a, int b) { return mesh.elems[a].level < mesh.elems[b].level; });
  // By group, the T-vertices' only: few, so not an array over all groups
  // (13 bytes a vertex, the peak of the master's last picture).
  std::unordered_map<int, glm::vec3> on_edge;
  auto color = [&](int v) {
    const auto it = on_edge.find(group[v]);
    return it != on_edge.end() ? it->second : s.colors[v];
  };
  for (int e : t_leaves) {
    const Element& el = mesh.elems[e];
    const std::array<int, 4> mids = mesh.Mids(e);
    const int n = el.IsTriangle() ? 3 : 4;
    for (int k = 0; k < n; ++k)
      if (mids[k] >= 0) {
        const glm::vec3 c = 0.5f * (color(el.v[k]) + color(el.v[(k + 1) % n]));
        on_edge[group[mids[k]]] = c;
      }
  }
  for (size_t v = 0; v < s.colors.size() && !on_edge.empty(); ++v)
    if (const auto it = on_edge.find(group[v]); it != on_edge.end()) s.colors[v] = it->second;
  return s;
}

namespace {

// Signed twice-area of (a, b, x) about the normal n.
double Side(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& x, const glm::dvec3& n) {
  return glm::dot(glm::cross(b - a, x - a), n);
}

// The radiosity as drawn at point x of leaf e: interpolated over the fan
// triangle of its outline that holds x best (all weights >= 0 but for
// rounding), as Render does.
glm::dvec3 Drawn(const Mesh& mesh, const ShadedMesh& shaded, int e, const glm::dvec3& x,
                 const glm::dvec3& n) {
  int out[8];
  const int m = Outline(mesh, e, out);
  glm::dvec3 value(0.0);
  double best = -HUGE_VAL;
  for (int i = 1; i + 1 < m; ++i) {
    const int t[3] = {out[0], out[i], out[i + 1]};
    double w[3];
    for (int k = 0; k < 3; ++k) w[k] = Side(mesh.verts[t[(k + 1) % 3]], mesh.verts[t[(k + 2) % 3]], x, n);
    const double sum = std::max(1e-300, w[0] + w[1] + w[2]);
    const double lo = std::min({w[0], w[1], w[2]}) / sum;
    if (lo <= best) continue;
    best = lo;
    value = glm::dvec3(0.0);
    for (int k = 0; k < 3; ++k) value += std::max(0.0, w[k]) * glm::dvec3(shaded.colors[t[k]]);
    value /= std::max(1e-300, std::max(0.0, w[0]) + std::max(0.0, w[1]) + std::max(0.0, w[2]));
  }
  return value;
}

}  // namespace

void FieldError(const Mesh& mesh, const ElemB& elem_b, const Mesh& ref,
                const ElemB& ref_b, double* rms, double* rel_rms) {
  CHECK(mesh.faces.size() == ref.faces.size());
  const ShadedMesh shaded = Shade(mesh, elem_b), ref_shaded = Shade(ref, ref_b);
  const double tol = 1e-12 * mesh.scene_diagonal * mesh.scene_diagonal;
  auto inside = [&](int e, const glm::dvec3& x, const glm::dvec3& n) {
    const Element& el = mesh.elems[e];
    const int c = el.IsTriangle() ? 3 : 4;
    for (int k = 0; k < c; ++k)
      if (Side(mesh.verts[el.v[k]], mesh.verts[el.v[(k + 1) % c]], x, n) < -tol) return false;
    return true;
  };
  double se = 0, area = 0, mean = 0;
  for (size_t r = 0; r < ref.elems.size(); ++r) {
    const Element& rel = ref.elems[r];
    if (!rel.IsLeaf()) continue;
    const glm::dvec3 x = ref.Centroid(int(r));
    const glm::dvec3 n = ref.FaceOf(int(r)).normal;
    // Faces are cut alike, so the point lies under a top element of the
    // same face here (patches may have been split, in either mesh).
    const MeshFace& face = mesh.faces[size_t(ref.patches[rel.patch].face)];
    int e = -1;
    for (int p : mesh.FacePatches(face)) {
      for (int top : mesh.Tops(p))
        if (inside(top, x, n)) { e = top; break; }
      if (e >= 0) break;
    }
    if (e < 0) e = mesh.Tops(mesh.FacePatches(face)[0])[0];  // rounding at an edge
    while (!mesh.elems[e].IsLeaf()) {
      int next = mesh.elems[e].first_child;
      for (int k = 0; k < kChildren; ++k)
        if (inside(mesh.elems[e].first_child + k, x, n)) { next = mesh.elems[e].first_child + k; break; }
      e = next;
    }
    const glm::dvec3 want = Drawn(ref, ref_shaded, int(r), x, n);
    const glm::dvec3 d = Drawn(mesh, shaded, e, x, n) - want;
    se += ref.elem_area[r] * glm::dot(d, d) / 3;
    mean += ref.elem_area[r] * (want.r + want.g + want.b) / 3;
    area += ref.elem_area[r];
  }
  *rms = area > 0 ? std::sqrt(se / area) : 0;
  *rel_rms = mean > 0 ? *rms / (mean / area) : 0;
}

// OBJ + MTL loader. One pass over the OBJ: statements take effect in file
// order, so `usemtl` must come after the `mtllib` that defines the material
// and a face may only use vertices defined above it.
//
// Error formats:
//   "FILE:LINE: what"       a problem on one line (LINE 1-based)
//   "FILE: what"            a problem with the whole file: cannot open or
//                           read it, or it has no (usable) faces
#include "scene.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <string_view>
#include <utility>

#include "files.h"

namespace {

constexpr double kMaxKe = 1e30;
constexpr size_t kMaxLine = size_t{256} << 20;

// Planarity: the largest distance of a vertex from the face's plane may be
// this fraction of the face's bounding-box diagonal, plus a term for
// coordinates printed with ~7 significant digits (their rounding grows
// with the coordinates' magnitude, not with the face's size).
constexpr double kPlanarRel = 1e-3;
constexpr double kPlanarDigits = 4e-6;
// A face whose area is below this times its diagonal squared is degenerate.
constexpr double kZeroArea = 1e-12;

std::string Where(const std::string& file, long line) {
  return file + ":" + std::to_string(line) + ": ";
}

// A token for an error message: quoted, and cut short if it is long (a
// number or a name of a megabyte would not make a line one can read).
// File names are never cut (QuoteFile).
std::string Quote(std::string_view tok) {
  constexpr size_t kShown = 40;
  if (tok.size() <= kShown) return "'" + std::string(tok) + "'";
  return "'" + std::string(tok.substr(0, kShown)) + "...'";
}

// A file name for an error message: quoted and whole, since its last part,
// the file's own name, is what the user must see. Control characters are
// escaped where the message is printed (Printable, app.h).
std::string QuoteFile(const std::string& path) { return "'" + path + "'"; }

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// Tokens into *out, which keeps its capacity from line to line.
void SplitInto(std::string_view s, std::vector<std::string_view>* out) {
  out->clear();
  const char *p = s.data(), *end = p + s.size();
  while (true) {
    while (p != end && (*p == ' ' || *p == '\t')) ++p;
    if (p == end) return;
    const char* q = p;
    while (q != end && *q != ' ' && *q != '\t') ++q;
    out->emplace_back(p, size_t(q - p));
    p = q;
  }
}

std::vector<std::string_view> Split(std::string_view s) {
  std::vector<std::string_view> out;
  SplitInto(s, &out);
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// The text after the first token, trimmed (names may contain spaces).
std::string_view Rest(std::string_view line, std::string_view keyword) {
  return Trim(line.substr(keyword.data() + keyword.size() - line.data()));
}

// Parses a whole token as a finite double. Returns "" or what is wrong.
// std::from_chars first (no copy, no locale; correctly rounded like
// strtod, so the same value); strtod for what it does not take whole
// (a '+', hex, out of range), with strtod's messages.
std::string ParseDouble(std::string_view tok, double* out) {
  double fast;
  const auto [stop, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), fast);
  if (ec == std::errc() && stop == tok.data() + tok.size() && std::isfinite(fast)) {
    *out = fast;
    return "";
  }
  std::string s(tok);  // strtod needs a terminator
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size()) return Quote(tok) + " is not a number";
  if (!std::isfinite(v)) {
    return Quote(tok) + (errno == ERANGE ? " is out of range" : " is not a finite number");
  }
  *out = v;  // an underflow to 0 or a subnormal is harmless
  return "";
}

// Parses a whole token as an integer. Returns "" or what is wrong.
std::string ParseLong(std::string_view tok, long long* out) {
  long long fast;
  const auto [stop, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), fast);
  if (ec == std::errc() && stop == tok.data() + tok.size()) {
    *out = fast;
    return "";
  }
  std::string s(tok);
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || end != s.c_str() + s.size()) return Quote(tok) + " is not an integer";
  if (errno == ERANGE) return Quote(tok) + " is out of range";
  *out = v;
  return "";
}

// Lines of a file without their "\n" or "\r\n", of any length. Stops early
// (returning what it has) at a control byte so that a binary file such as
// /dev/zero is rejected at once instead of being read as one endless line.
class LineReader {
 public:
  explicit LineReader(std::FILE* f) : f_(f), buf_(1 << 16) {}

  // False at the end of the file or on a read error (then error() is set).
  bool Next(std::string* line) {
    line->clear();
    bool any = false;
    while (true) {
      if (pos_ == len_) {
        pos_ = 0;
        len_ = std::fread(buf_.data(), 1, buf_.size(), f_);
        if (len_ == 0) {
          if (std::ferror(f_)) {
            error_ = std::strerror(errno);
            return false;
          }
          if (!any) return false;
          break;
        }
      }
      any = true;
      const char* s = buf_.data() + pos_;
      size_t n = len_ - pos_;
      const char* nl = static_cast<const char*>(std::memchr(s, '\n', n));
      size_t take = nl ? static_cast<size_t>(nl - s) : n;
      line->append(s, take);
      pos_ += nl ? take + 1 : take;
      if (nl || HasControl(s, take)) break;
      if (line->size() > kMaxLine) {
        error_ = "a line is longer than " + std::to_string(kMaxLine) + " bytes";
        return false;
      }
    }
    if (!line->empty() && line->back() == '\r') line->pop_back();
    return true;
  }

  const std::string& error() const { return error_; }

 private:
  // Branch-free, so that it vectorises: every byte of the file goes here.
  static bool HasControl(const char* s, size_t n) {
    bool any = false;
    for (size_t i = 0; i < n; ++i) {
      unsigned char c = static_cast<unsigned char>(s[i]);
      any |= ((c < 0x20) & (c != '\t') & (c != '\r')) | (c == 0x7f);
    }
    return any;
  }

  std::FILE* f_;
  std::vector<char> buf_;
  size_t pos_ = 0, len_ = 0;
  std::string error_;
};

// "" if the line is text, else what is wrong. Tabs are whitespace; a CR
// is only legal as part of a CRLF ending, which LineReader removed.
std::string CheckText(const std::string& line) {
  // The common case first, eight bytes at a time (a scalar loop a byte at
  // a time was a fifth of parsing at 10^6 faces): is any byte below 0x20
  // (a tab too, so a line with a tab takes the exact loop below) or 0x7f?
  // Bit tricks for "a byte below n" and "a zero byte", exact for the word.
  constexpr uint64_t kOnes = 0x0101010101010101ull, kHigh = 0x8080808080808080ull;
  bool any = false;
  size_t i = 0;
  for (; i + 8 <= line.size(); i += 8) {
    uint64_t x;
    std::memcpy(&x, line.data() + i, 8);
    const uint64_t del = x ^ (0x7f * kOnes);
    any |= ((((x - 0x20 * kOnes) & ~x) | ((del - kOnes) & ~del)) & kHigh) != 0;
  }
  for (; i < line.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(line[i]);
    any |= ((c < 0x20) & (c != '\t')) | (c == 0x7f);
  }
  if (!any) return "";
  for (unsigned char c : line) {
    if ((c < 0x20 && c != '\t') || c == 0x7f) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "control byte 0x%02x (not a text file?)", c);
      return buf;
    }
  }
  return "";
}

class Loader {
 public:
  explicit Loader(std::vector<std::string>* warnings) : warnings_(warnings) {
    s_.materials.push_back(Material{"default", glm::dvec3(0.5), glm::dvec3(0.0)});
    s_.objects.push_back("default");
  }

  bool LoadObj(const std::string& path);
  Scene& scene() { return s_; }
  const std::string& error() const { return err_; }

 private:
  bool Fail(const std::string& file, long line, const std::string& what) {
    err_ = Where(file, line) + what;
    return false;
  }
  bool FailFile(const std::string& file, const std::string& what) {
    err_ = file + ": " + what;
    return false;
  }
  // A face without area (the mesh cannot cut it, and it sends and takes
  // no light): skipped with a warning that says where, and counted.
  bool SkipFace(const std::string& file, long line, const std::string& why) {
    if (warnings_) warnings_->push_back(Where(file, line) + "zero-area face skipped" + why);
    ++skipped_;
    return true;
  }
  bool Statement(const std::string& path, long ln, const std::string& raw);
  bool Vertex(const std::vector<std::string_view>& t, std::string* what);
  bool FaceLine(const std::string& path, long ln, const std::vector<std::string_view>& t);
  bool Mtllib(const std::string& obj, long ln, const std::vector<std::string_view>& t);
  bool LoadMtl(const std::string& path, std::FILE* f, const std::string& obj, long obj_line);
  std::string MtlStatement(const std::string& raw, int* m);
  int ObjectIndex();

  Scene s_;
  std::string err_;
  std::vector<std::string>* warnings_;
  std::vector<glm::dvec3> verts_;
  std::vector<std::string_view> tokens_;  // of the current line
  std::map<std::string, int> materials_{{"default", 0}};  // name -> index into s_.materials
  std::map<std::string, int> objects_{{"default", 0}};    // name -> index into s_.objects
  std::set<std::string> mtl_loaded_;
  std::string o_name_, g_name_;
  int material_ = 0;
  long f_lines_ = 0;
  long corners_ = 0;
  long skipped_ = 0;
};

bool Loader::LoadObj(const std::string& path) {
  s_.path = path;
  s_.files.push_back(path);
  std::string why;
  std::FILE* f = OpenInputFile(path, kMaxSceneBytes, &why);
  if (!f) return FailFile(path, "cannot open: " + why);
  LineReader reader(f);
  std::string line;
  long ln = 0;
  bool ok = true;
  while (ok && reader.Next(&line)) {
    ++ln;
    if (ln == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // UTF-8 BOM
    ok = Statement(path, ln, line);
  }
  std::fclose(f);
  if (!ok) return false;
  if (!reader.error().empty()) return FailFile(path, "cannot read: " + reader.error());
  if (s_.faces.empty()) {
    if (skipped_ == 0) return FailFile(path, "no faces");
    return FailFile(path, "no faces left (" + std::to_string(skipped_) +
                              " zero-area faces skipped)");
  }
  return true;
}

bool Loader::Statement(const std::string& path, long ln, const std::string& raw) {
  std::string what = CheckText(raw);
  if (!what.empty()) return Fail(path, ln, what);
  std::string_view line(raw);
  size_t hash = line.find('#');
  if (hash != std::string_view::npos) {
    std::string_view comment = line.substr(hash + 1);
    std::vector<std::string_view> c = Split(comment);
    if (Trim(line.substr(0, hash)).empty() && !c.empty() && c[0] == "camera") {
      if (!ParseCamera(std::string(Rest(comment, c[0])), &s_.camera, &what)) {
        return Fail(path, ln, "camera: " + what);
      }
      s_.has_camera = true;
      return true;
    }
    line = line.substr(0, hash);
  }
  std::vector<std::string_view>& t = tokens_;
  SplitInto(line, &t);
  if (t.empty()) return true;
  const std::string_view kw = t[0];
  if (kw == "v") {
    if (!Vertex(t, &what)) return Fail(path, ln, "v: " + what);
  } else if (kw == "f") {
    return FaceLine(path, ln, t);
  } else if (kw == "o") {
    o_name_ = std::string(Rest(line, kw));
  } else if (kw == "g") {
    g_name_ = std::string(Rest(line, kw));
  } else if (kw == "usemtl") {
    std::string name(Rest(line, kw));
    if (name.empty()) return Fail(path, ln, "usemtl: missing material name");
    auto it = materials_.find(name);
    if (it == materials_.end()) {
      return Fail(path, ln, "usemtl: material " + Quote(name) + " is not defined" +
                                (mtl_loaded_.empty() ? " (no mtllib before it)" : ""));
    }
    material_ = it->second;
  } else if (kw == "mtllib") {
    return Mtllib(path, ln, t);
  }
  return true;  // anything else (vt, vn, s, l, ...) does not affect radiosity
}

bool Loader::Vertex(const std::vector<std::string_view>& t, std::string* what) {
  if (t.size() < 4 || t.size() > 5) {
    *what = "expected 3 coordinates (and an optional w), got " + std::to_string(t.size() - 1);
    return false;
  }
  if (static_cast<long>(verts_.size()) >= kMaxVertices) {
    *what = "too many vertices (the limit is " + std::to_string(kMaxVertices) + ")";
    return false;
  }
  double x[4];
  for (size_t i = 1; i < t.size(); ++i) {
    *what = ParseDouble(t[i], &x[i - 1]);
    if (!what->empty()) return false;
  }
  verts_.emplace_back(x[0], x[1], x[2]);
  return true;
}

// Index into Scene::objects of the current name: `o`, else `g`, else default.
int Loader::ObjectIndex() {
  const std::string& name = !o_name_.empty() ? o_name_ : !g_name_.empty() ? g_name_ : "default";
  auto it = objects_.find(name);
  if (it != objects_.end()) return it->second;
  int i = static_cast<int>(s_.objects.size());
  objects_.emplace(name, i);
  s_.objects.push_back(name);
  return i;
}

bool Loader::FaceLine(const std::string& path, long ln, const std::vector<std::string_view>& t) {
  const int index = static_cast<int>(f_lines_);
  if (++f_lines_ > kMaxFaces) {
    return Fail(path, ln, "f: too many faces (the limit is " + std::to_string(kMaxFaces) + ")");
  }
  corners_ += static_cast<long>(t.size()) - 1;
  if (corners_ > kMaxCorners) {
    return Fail(path, ln, "f: too many face vertices in all (the limit is " +
                              std::to_string(kMaxCorners) + ")");
  }
  if (t.size() - 1 > kMaxPolygon)
    return Fail(path, ln, "f: a polygon of " + std::to_string(t.size() - 1) +
                              " vertices (the limit is " + std::to_string(kMaxPolygon) + ")");
  // Fewer than 3 references is no polygon at all; 3 or more that name
  // fewer than 3 distinct points (f 5 5 6) is one without area, below.
  if (t.size() - 1 < 3)
    return Fail(path, ln, "f: a face needs at least 3 vertices, got " + std::to_string(t.size() - 1));
  Face face;
  face.verts.reserve(t.size() - 1);
  const long n = static_cast<long>(verts_.size());
  for (size_t i = 1; i < t.size(); ++i) {
    // v, v/vt, v/vt/vn or v//vn; vt and vn must be integers but are unused.
    const std::string_view ref = t[i];
    std::string_view parts[3];
    size_t count = 0;  // parts found; past 3 the reference is malformed
    for (size_t start = 0;;) {
      size_t slash = ref.find('/', start);
      if (count < 3) parts[count] = ref.substr(start, slash - start);
      ++count;
      if (slash == std::string_view::npos) break;
      start = slash + 1;
    }
    bool shape_ok = count <= 3 && !(count > 1 && parts[0].empty());
    for (size_t p = 1; shape_ok && p < count; ++p) {
      long long unused;
      shape_ok = parts[p].empty() ? p == 1 && count == 3 : ParseLong(parts[p], &unused).empty();
    }
    if (!shape_ok) return Fail(path, ln, "f: malformed vertex reference " + Quote(ref));
    long long k = 0;
    std::string what = ParseLong(parts[0], &k);
    if (!what.empty()) return Fail(path, ln, "f: vertex index " + what);
    if (k == 0) return Fail(path, ln, "f: vertex index 0 (indices start at 1)");
    long long at = k > 0 ? k - 1 : n + k;
    if (at < 0 || at >= n) {
      return Fail(path, ln, "f: vertex index " + std::to_string(k) + " is out of range (" +
                                std::to_string(n) + " vertices defined so far)");
    }
    // A vertex repeated in a row (f 1 2 2 3, also by position: two v
    // lines of one point) adds no corner: dropped, and the rest is the
    // polygon the user meant.
    const glm::dvec3& v = verts_[static_cast<size_t>(at)];
    if (face.verts.empty() || face.verts.back() != v) face.verts.push_back(v);
  }
  while (face.verts.size() > 1 && face.verts.back() == face.verts.front()) face.verts.pop_back();
  if (face.verts.size() < 3)  // a point or a segment: no area, as below
    return SkipFace(path, ln, face.verts.size() == 1 ? " (1 distinct vertex)" : " (2 distinct vertices)");

  glm::dvec3 lo = face.verts[0], hi = face.verts[0], centroid{0.0};
  for (const glm::dvec3& v : face.verts) {
    lo = glm::min(lo, v);
    hi = glm::max(hi, v);
    centroid += v;
  }
  centroid /= static_cast<double>(face.verts.size());
  const double extent = glm::length(hi - lo);
  const double magnitude = glm::length(glm::max(glm::abs(lo), glm::abs(hi)));
  FacePlane(&face);
  if (!std::isfinite(face.area) || !std::isfinite(extent * extent))
    return Fail(path, ln, "f: face too large: its area is not a finite number");
  if (!(face.area > kZeroArea * extent * extent)) return SkipFace(path, ln, "");
  double off = 0.0;
  for (const glm::dvec3& v : face.verts) {
    off = std::max(off, std::abs(glm::dot(v - centroid, face.normal)));
  }
  const double tol = kPlanarRel * extent + kPlanarDigits * magnitude;
  if (off > tol) {
    return Fail(path, ln, "f: face is not planar: a vertex is " + Num(off) +
                              " from its plane (tolerance " + Num(tol) + ")");
  }
  face.material = material_;
  face.object = ObjectIndex();
  face.index = index;
  face.line = static_cast<int>(ln);
  if (s_.faces.empty()) s_.lo = s_.hi = face.verts[0];
  s_.lo = glm::min(s_.lo, lo);
  s_.hi = glm::max(s_.hi, hi);
  s_.faces.push_back(std::move(face));
  return true;
}

bool Loader::Mtllib(const std::string& obj, long ln, const std::vector<std::string_view>& t) {
  if (t.size() < 2) return Fail(obj, ln, "mtllib: missing file name");
  const size_t slash = obj.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : obj.substr(0, slash + 1);
  for (size_t i = 1; i < t.size(); ++i) {
    std::string path = t[i][0] == '/' ? std::string(t[i]) : dir + std::string(t[i]);
    if (!mtl_loaded_.insert(path).second) continue;  // named twice: same materials
    std::string why;
    std::FILE* f = OpenInputFile(path, kMaxMtlBytes, &why);
    if (!f) return Fail(obj, ln, "mtllib: cannot open " + QuoteFile(path) + ": " + why);
    s_.files.push_back(path);
    bool ok = LoadMtl(path, f, obj, ln);
    std::fclose(f);
    if (!ok) return false;
  }
  return true;
}

// Problems with the file as a whole are reported at the OBJ's mtllib line.
bool Loader::LoadMtl(const std::string& path, std::FILE* f, const std::string& obj,
                     long obj_line) {
  LineReader reader(f);
  std::string line;
  long ln = 0;
  int m = -1;  // the latest newmtl
  while (reader.Next(&line)) {
    ++ln;
    if (ln == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    std::string what = MtlStatement(line, &m);
    if (!what.empty()) return Fail(path, ln, what);
  }
  if (!reader.error().empty()) {
    return Fail(obj, obj_line, "mtllib: cannot read " + QuoteFile(path) + ": " + reader.error());
  }
  return true;
}

// One MTL line: "" or what is wrong with it.
std::string Loader::MtlStatement(const std::string& raw, int* m) {
  std::string what = CheckText(raw);
  if (!what.empty()) return what;
  std::string_view line(raw);
  line = line.substr(0, line.find('#'));
  std::vector<std::string_view> t = Split(line);
  if (t.empty()) return "";
  const std::string kw(t[0]);
  if (kw == "newmtl") {
    std::string name(Rest(line, t[0]));
    if (name.empty()) return "newmtl: missing material name";
    if (materials_.count(name)) {
      return "newmtl: material " + Quote(name) + " is already defined" +
             (name == "default" ? " (it is the built-in material)" : "");
    }
    materials_.emplace(name, static_cast<int>(s_.materials.size()));
    s_.materials.push_back(Material{name, glm::dvec3(0.5), glm::dvec3(0.0)});
    *m = static_cast<int>(s_.materials.size()) - 1;
    return "";
  }
  if (kw != "Kd" && kw != "Ke") return "";  // Ns, Ka, Ks, illum, map_*, ...: unused
  if (*m < 0) return kw + " before any newmtl";
  if (t.size() != 2 && t.size() != 4) {
    return kw + ": expected 1 or 3 numbers, got " + std::to_string(t.size() - 1);
  }
  double c[3];
  for (size_t i = 1; i < t.size(); ++i) {
    what = ParseDouble(t[i], &c[i - 1]);
    if (!what.empty()) return kw + ": " + what;
    if (kw == "Kd" && (c[i - 1] < 0 || c[i - 1] > 1)) {
      return kw + ": " + Quote(t[i]) + " is outside [0, 1]";
    }
    if (kw == "Ke" && c[i - 1] < 0) return kw + ": " + Quote(t[i]) + " is negative";
    // Far above any light, and below where power (Ke x area) and its sums overflow.
    if (kw == "Ke" && c[i - 1] > kMaxKe)
      return kw + ": " + Quote(t[i]) + " is too large (at most " + Num(kMaxKe) + ")";
  }
  glm::dvec3 v = t.size() == 2 ? glm::dvec3(c[0]) : glm::dvec3(c[0], c[1], c[2]);
  Material& mat = s_.materials[static_cast<size_t>(*m)];
  (kw == "Kd" ? mat.kd : mat.ke) = v;
  return "";
}

}  // namespace

bool LoadScene(const std::string& path, Scene* scene, std::string* err,
               std::vector<std::string>* warnings) {
  Loader loader(warnings);
  if (!loader.LoadObj(path)) {
    *err = loader.error();
    return false;
  }
  *scene = std::move(loader.scene());
  return true;
}

bool ParseCamera(const std::string& text, Camera* cam, std::string* err) {
  std::vector<std::string_view> t = Split(text);
  if (t.size() != 7) {
    *err = "expected 7 numbers \"ex ey ez tx ty tz fov\", got " + std::to_string(t.size());
    return false;
  }
  double x[7];
  for (int i = 0; i < 7; ++i) {
    std::string what = ParseDouble(t[i], &x[i]);
    if (!what.empty()) {
      *err = what;
      return false;
    }
  }
  if (!(x[6] > 0 && x[6] < 180)) {
    *err = "fov must be between 0 and 180 degrees, exclusive, got " + Num(x[6]);
    return false;
  }
  Camera c;
  c.eye = glm::dvec3(x[0], x[1], x[2]);
  c.target = glm::dvec3(x[3], x[4], x[5]);
  c.fov_deg = x[6];
  if (c.eye == c.target) {
    *err = "eye and target are the same point";
    return false;
  }
  *cam = c;
  return true;
}

glm::dvec3 AreaVector(const glm::dvec3* poly, size_t size) {
  // Newell's method, about the centroid to avoid cancellation far from 0.
  glm::dvec3 centroid{0.0};
  for (size_t i = 0; i < size; ++i) centroid += poly[i];
  centroid /= static_cast<double>(size);
  glm::dvec3 n{0.0};
  for (size_t i = 0; i < size; ++i)
    n += glm::cross(poly[i] - centroid, poly[(i + 1) % size] - centroid);
  return 0.5 * n;
}

glm::dvec3 AreaVector(const std::vector<glm::dvec3>& poly) {
  return AreaVector(poly.data(), poly.size());
}

// Not inlined, so that LoadScene and the worker's DecodeScene run the very
// same instructions (no contraction or reordering that differs by call
// site): the two must agree bit for bit (doc/protocol.txt, scene).
__attribute__((noinline)) void FacePlane(Face* face) {
  const glm::dvec3 n = AreaVector(face->verts);
  face->area = glm::length(n);
  face->normal = face->area > 0 ? n / face->area : glm::dvec3(0.0);
}

void DropVertices(Scene* scene) {
  for (Face& f : scene->faces) std::vector<glm::dvec3>().swap(f.verts);
}

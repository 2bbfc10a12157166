#include "view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <openssl/evp.h>

#include "check.h"
#include "coding.h"
#include "files.h"

namespace {

// view/view.html and view/view.js as raw string literals (kViewHtml,
// kViewJs), made by the Makefile: the page stays two files one can edit
// and open as they are, and the program needs nothing beside it at run
// time. A generated header rather than `ld -r -b binary`: plain C++ that
// g++, clang (the fuzz build) and the sanitizer build take alike, with no
// object format or executable-stack note to get right.
#include "view_page.inc"

// Where view.html loads view.js; the served and the offline page put the
// script itself there.
constexpr char kScriptTag[] = "<script src=\"view.js\"></script>";

std::string Number(const char* format, double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string Vec(const glm::dvec3& v) {
  return "[" + Number("%.17g", v.x) + "," + Number("%.17g", v.y) + "," + Number("%.17g", v.z) + "]";
}

// view.html split at its script tag: what comes before and after the
// scripts put in its place.
std::pair<std::string, std::string> PageHalves() {
  const std::string html = kViewHtml;
  const size_t at = html.find(kScriptTag);
  CHECK(at != std::string::npos);
  return {html.substr(0, at), html.substr(at + sizeof kScriptTag - 1)};
}

// Base64 handed on a piece at a time: whole 3-byte groups are encoded as
// they come, the last one or two bytes held until more come or Finish.
class Base64Writer {
 public:
  explicit Base64Writer(const FileSink& put) : put_(put) {}
  bool Add(const char* data, size_t size) {
    while (size > 0 && ok_) {
      if (held_ == 0 && size >= 3) {
        // libcrypto's encoder (linked for crypto.cpp) takes an int length.
        const size_t n = std::min(size / 3 * 3, kPiece);
        const size_t len = n / 3 * 4;
        buf_.resize(len + 1);  // room for the NUL EVP_EncodeBlock ends with
        EVP_EncodeBlock(reinterpret_cast<unsigned char*>(&buf_[0]),
                        reinterpret_cast<const unsigned char*>(data), int(n));
        ok_ = put_(buf_.data(), len);
        data += n;
        size -= n;
      } else {
        hold_[held_++] = *data++;
        --size;
        if (held_ == 3) Flush();
      }
    }
    return ok_;
  }
  bool Finish() {
    if (held_ > 0 && ok_) Flush();
    return ok_;
  }

 private:
  static constexpr size_t kPiece = size_t(3) << 20;
  void Flush() {
    unsigned char out[5];
    EVP_EncodeBlock(out, reinterpret_cast<const unsigned char*>(hold_), int(held_));
    ok_ = put_(reinterpret_cast<const char*>(out), 4);
    held_ = 0;
  }
  const FileSink& put_;
  std::string buf_;
  char hold_[3];
  size_t held_ = 0;
  bool ok_ = true;
};

bool Put(const FileSink& put, const std::string& s) { return put(s.data(), s.size()); }

}  // namespace

std::string ViewStateJson(const ViewInfo& info, const ViewState& state,
                          const std::vector<LogRow>& rows, size_t first) {
  std::string s = "{\"scene\":\"" + JsonString(info.scene) + "\",\"status\":\"" +
                  JsonString(state.status) + "\",\"workers\":" + std::to_string(state.workers) +
                  ",\"epsilon\":" + Number("%.17g", info.epsilon) + ",\"camera\":{\"eye\":" +
                  Vec(info.camera.eye) + ",\"target\":" + Vec(info.camera.target) +
                  ",\"fov\":" + Number("%.17g", info.camera.fov_deg) +
                  ",\"width\":" + std::to_string(info.width) +
                  ",\"height\":" + std::to_string(info.height) + "},\"snapshot\":{\"id\":" +
                  std::to_string(state.snapshot) + ",\"shots\":" +
                  std::to_string(state.snapshot_shots) + "},\"first\":";
  s += std::to_string(first) + ",\"rows\":[";
  for (size_t i = 0; i < rows.size(); ++i) {
    const LogRow& r = rows[i];
    // The formats of log.csv (LogCsv::Row): the page shows what it holds.
    s += (i ? ",[" : "[") + Number("%.6f", r.seconds) + "," + std::to_string(r.shots) +
         "," + std::to_string(r.wave) + "," + std::to_string(r.elements) + "," +
         Number("%.6g", r.unshot) + "," + Number("%.6g", r.rms) + "," +
         Number("%.6g", r.rel_rms) + "]";
  }
  return s + "]}";
}

bool ViewMeshBlob(const ShadedMesh& mesh, float exposure, const FileSink& put) {
  const size_t n = mesh.positions().size();
  size_t tris = 0;
  for (const auto& q : mesh.polys) tris += q[3] < 0 ? 1 : 2;
  CHECK(n <= UINT32_MAX && tris <= UINT32_MAX);
  glm::dvec3 lo(HUGE_VAL), hi(-HUGE_VAL);
  for (const glm::dvec3& p : mesh.positions()) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 origin = n ? 0.5 * (lo + hi) : glm::dvec3(0.0);
  // Handed on about a megabyte at a time: at 10^6 elements the whole is
  // some 75 MB, and its Base64 in view.html a third more.
  constexpr size_t kPiece = size_t(1) << 20;
  std::string out;
  out.reserve(kPiece + 64);
  bool ok = true;
  auto flush = [&](size_t at_least) {
    if (ok && out.size() >= at_least) {
      ok = put(out.data(), out.size());
      out.clear();
    }
  };
  out += "RVW1";
  PutFixed32(&out, uint32_t(n));
  PutFixed32(&out, uint32_t(tris));
  PutF32(&out, exposure);
  PutVec(&out, origin);
  for (const glm::dvec3& p : mesh.positions()) {
    for (int k = 0; k < 3; ++k) PutF32(&out, float(p[k] - origin[k]));
    flush(kPiece);
  }
  for (const glm::vec3& c : mesh.colors) {
    for (int k = 0; k < 3; ++k) PutF32(&out, c[k] > 0 ? c[k] : 0.0f);  // also NaN to 0
    flush(kPiece);
  }
  for (const auto& q : mesh.polys) {
    for (int k : {0, 1, 2}) PutFixed32(&out, uint32_t(q[k]));
    if (q[3] >= 0)
      for (int k : {0, 2, 3}) PutFixed32(&out, uint32_t(q[k]));
    flush(kPiece);
  }
  flush(1);
  return ok;
}

std::string ViewMeshBlob(const ShadedMesh& mesh, float exposure) {
  std::string out;
  ViewMeshBlob(mesh, exposure, [&out](const char* data, size_t size) {
    out.append(data, size);
    return true;
  });
  return out;
}

std::string ViewPage() {
  const auto [head, tail] = PageHalves();
  return head + "<script>" + kViewJs + "</script>" + tail;
}

bool WriteOfflineViewPage(const std::string& state_json,
                          const std::function<bool(const FileSink&)>& mesh_blob,
                          const FileSink& put) {
  const auto [head, tail] = PageHalves();
  Base64Writer base64(put);
  return Put(put, head) &&
         Put(put, "<script id=\"radiosity-state\" type=\"application/json\">" + state_json +
                      "</script><script id=\"radiosity-mesh\" type=\"application/octet-stream\">") &&
         mesh_blob([&base64](const char* data, size_t size) { return base64.Add(data, size); }) &&
         base64.Finish() && Put(put, std::string("</script><script>") + kViewJs + "</script>") &&
         Put(put, tail);
}

std::string Base64(const std::string& bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  const FileSink put = [&out](const char* data, size_t size) {
    out.append(data, size);
    return true;
  };
  Base64Writer writer(put);
  writer.Add(bytes.data(), bytes.size());
  writer.Finish();
  return out;
}

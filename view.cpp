#include "view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <openssl/evp.h>

#include "check.h"
#include "coding.h"

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

// The page with `scripts` in place of its script tag.
std::string Page(const std::string& scripts) {
  std::string html = kViewHtml;
  const size_t at = html.find(kScriptTag);
  CHECK(at != std::string::npos);
  return html.replace(at, sizeof kScriptTag - 1, scripts);
}

std::string Script(const std::string& attributes, const std::string& body) {
  return "<script" + attributes + ">" + body + "</script>";
}

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

std::string ViewMeshBlob(const ShadedMesh& mesh, float exposure) {
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
  std::string out;
  out.reserve(40 + 24 * n + 12 * tris);
  out += "RVW1";
  PutFixed32(&out, uint32_t(n));
  PutFixed32(&out, uint32_t(tris));
  PutF32(&out, exposure);
  PutVec(&out, origin);
  for (const glm::dvec3& p : mesh.positions())
    for (int k = 0; k < 3; ++k) PutF32(&out, float(p[k] - origin[k]));
  for (const glm::vec3& c : mesh.colors)
    for (int k = 0; k < 3; ++k) PutF32(&out, c[k] > 0 ? c[k] : 0.0f);  // also NaN to 0
  for (const auto& q : mesh.polys) {
    for (int k : {0, 1, 2}) PutFixed32(&out, uint32_t(q[k]));
    if (q[3] >= 0)
      for (int k : {0, 2, 3}) PutFixed32(&out, uint32_t(q[k]));
  }
  return out;
}

std::string ViewPage() { return Page(Script("", kViewJs)); }

std::string OfflineViewPage(const std::string& state_json, const std::string& mesh_blob) {
  return Page(Script(" id=\"radiosity-state\" type=\"application/json\"", state_json) +
              Script(" id=\"radiosity-mesh\" type=\"application/octet-stream\"", Base64(mesh_blob)) +
              Script("", kViewJs));
}

std::string Base64(const std::string& bytes) {
  // libcrypto's encoder (linked for crypto.cpp); it takes an int length,
  // so whole 3-byte groups go through a piece at a time.
  constexpr size_t kPiece = size_t(3) << 20;
  const size_t total = (bytes.size() + 2) / 3 * 4;
  std::string out(total + 1, '\0');  // room for the NUL EVP_EncodeBlock ends with
  size_t o = 0;
  for (size_t i = 0; i < bytes.size(); i += kPiece) {
    const size_t n = std::min(kPiece, bytes.size() - i);
    o += size_t(EVP_EncodeBlock(reinterpret_cast<unsigned char*>(&out[o]),
                                reinterpret_cast<const unsigned char*>(bytes.data() + i), int(n)));
  }
  out.resize(total);
  return out;
}

#include "view.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

namespace {

ViewInfo Info() {
  ViewInfo info;
  info.scene = "a</script>\"b\".obj";
  info.camera.eye = {1, 2, 3};
  info.camera.target = {1, 2, 0};
  info.camera.fov_deg = 40;
  info.width = 320;
  info.height = 200;
  info.epsilon = 1e-3;
  return info;
}

uint32_t U32(const std::string& b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
float F32(const std::string& b, size_t at) {
  float v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
double F64(const std::string& b, size_t at) {
  double v;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}

TEST(View, StateJsonHasLogCsvsNumbersAndNullForNaN) {
  ViewState st;
  st.workers = 2;
  st.snapshot = 3;
  st.snapshot_shots = 40;
  const std::vector<LogRow> rows = {{0.5, 40, 1, 100, 0.25, NAN, NAN},
                                    {1.25, 46, 2, 120, 1.5e-05, 0.01, 0.002}};
  const std::string json = ViewStateJson(Info(), st, rows, 7);
  EXPECT_EQ(json,
            "{\"scene\":\"a\\u003c/script>\\\"b\\\".obj\",\"status\":\"running\",\"workers\":2,"
            "\"epsilon\":0.001,\"camera\":{\"eye\":[1,2,3],\"target\":[1,2,0],\"fov\":40,"
            "\"width\":320,\"height\":200},\"snapshot\":{\"id\":3,\"shots\":40},\"first\":7,"
            "\"rows\":[[0.500000,40,1,100,0.25,null,null],[1.250000,46,2,120,1.5e-05,0.01,0.002]]}");
}

TEST(View, MeshBlobIsTheDocumentedLayout) {
  ShadedMesh m;
  m.own = {{10, 0, 0}, {12, 0, 0}, {12, 2, 0}, {10, 2, 0}, {10, 0, 4}, {12, 0, 4}, {10, 2, 4}};
  m.colors = {{1, 2, 3}, {-1, 0, 0.5f}, {NAN, 1, 1}, {0, 0, 0}, {4, 4, 4}, {5, 5, 5}, {6, 6, 6}};
  m.polys = {{0, 1, 2, 3}, {4, 5, 6, -1}};
  const std::string b = ViewMeshBlob(m, 0.75f);
  const size_t n = 7, tris = 3;
  ASSERT_EQ(b.size(), 40 + 24 * n + 12 * tris);
  EXPECT_EQ(b.substr(0, 4), "RVW1");
  EXPECT_EQ(U32(b, 4), n);
  EXPECT_EQ(U32(b, 8), tris);
  EXPECT_EQ(F32(b, 12), 0.75f);
  EXPECT_EQ(F64(b, 16), 11.0);  // the middle of the box
  EXPECT_EQ(F64(b, 24), 1.0);
  EXPECT_EQ(F64(b, 32), 2.0);
  EXPECT_EQ(F32(b, 40), -1.0f);  // vertex 0 less the origin
  EXPECT_EQ(F32(b, 44), -1.0f);
  EXPECT_EQ(F32(b, 48), -2.0f);
  const size_t col = 40 + 12 * n;
  EXPECT_EQ(F32(b, col + 8), 3.0f);
  EXPECT_EQ(F32(b, col + 12), 0.0f);  // negative
  EXPECT_EQ(F32(b, col + 20), 0.5f);
  EXPECT_EQ(F32(b, col + 24), 0.0f);  // NaN
  const size_t idx = 40 + 24 * n;
  const uint32_t want[] = {0, 1, 2, 0, 2, 3, 4, 5, 6};  // the quad split as in result.gltf
  for (size_t i = 0; i < 9; ++i) EXPECT_EQ(U32(b, idx + 4 * i), want[i]) << i;
}

TEST(View, Base64) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64(std::string("\xff\x00\xfe", 3)), "/wD+");
}

TEST(View, PagesCarryTheScriptAndTheOfflineOneTheData) {
  const std::string live = ViewPage();
  EXPECT_EQ(live.find("src=\"view.js\""), std::string::npos);
  EXPECT_NE(live.find("getContext('webgl'"), std::string::npos);
  // The script must not end its own element.
  const size_t open = live.rfind("<script>");
  ASSERT_NE(open, std::string::npos);
  EXPECT_EQ(live.find("</script", open), live.rfind("</script"));

  std::string page;
  const FileSink to_page = [&page](const char* data, size_t size) {
    page.append(data, size);
    return true;
  };
  // The blob in uneven pieces: the Base64 across them is that of the whole.
  ASSERT_TRUE(WriteOfflineViewPage(
      "{\"x\":1}",
      [](const FileSink& put) { return put("a", 1) && put("bcd", 3) && put("efgh", 4); }, to_page));
  EXPECT_NE(page.find("<script id=\"radiosity-state\" type=\"application/json\">{\"x\":1}</script>"),
            std::string::npos);
  EXPECT_NE(page.find("<script id=\"radiosity-mesh\" type=\"application/octet-stream\">YWJjZGVmZ2g=</script>"),
            std::string::npos);
  // A write that fails stops the page there and says so.
  size_t calls = 0;
  EXPECT_FALSE(WriteOfflineViewPage(
      "{}", [](const FileSink& put) { return put("abc", 3) && put("def", 3); },
      [&calls](const char*, size_t) { return ++calls < 2; }));
  EXPECT_EQ(calls, 2u);
  // Nothing from the network.
  for (const char* net : {"http://", "https://", "src=\"//"}) EXPECT_EQ(page.find(net), std::string::npos) << net;
}

}  // namespace

// The build id (version.h): what it names, stable, printable.
#include "version.h"

#include <string>

#include <gtest/gtest.h>

namespace {

TEST(Version, BuildIdNamesVersionProtocolAndCompiler) {
  const std::string id = proto::BuildId();
  EXPECT_EQ(id.rfind("radiosity ", 0), 0u) << id;
  EXPECT_NE(id.find(" proto 7 "), std::string::npos) << id;
  EXPECT_NE(id.find(__VERSION__), std::string::npos) << id;
  EXPECT_NE(id.find("64-bit le"), std::string::npos) << id;  // what this test runs on
  EXPECT_LE(id.size(), 256u);
  for (char c : id) EXPECT_TRUE(c >= 0x20 && c <= 0x7e) << id;
  EXPECT_EQ(id, proto::BuildId());
  RecordProperty("build_id", id);
}

}  // namespace

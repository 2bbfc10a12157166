// Byte coding (coding.h): the layouts of the Put* writers, varints in
// their shortest form only, and a Reader that checks every length, stays
// failed after its first failure and reports that one.
#include "coding.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

namespace {

TEST(Coding, FixedAndF64AreLittleEndian) {
  std::string s;
  PutU8(&s, 0xab);
  PutFixed(&s, 0x030201, 3);
  PutFixed32(&s, 0x07060504);
  PutFixed64(&s, 0x0f0e0d0c0b0a0908ull);
  PutF64(&s, 1.0);  // 0x3ff0000000000000
  EXPECT_EQ(s, std::string("\xab\x01\x02\x03\x04\x05\x06\x07\x08\x09\x0a\x0b\x0c\x0d\x0e\x0f"
                           "\0\0\0\0\0\0\xf0\x3f", 24));
  EncodeFixed32(&s[1], 0xddccbbaa);
  EXPECT_EQ(s.substr(1, 4), "\xaa\xbb\xcc\xdd");
  std::string err;
  Reader r(s, &err);
  uint8_t b;
  uint64_t v;
  double d;
  ASSERT_TRUE(r.U8(&b, "b") && r.Fixed(4, &v, "v")) << err;
  EXPECT_EQ(b, 0xab);
  EXPECT_EQ(v, 0xddccbbaau);
  ASSERT_TRUE(r.Fixed(3, &v, "v") && r.Fixed(8, &v, "v") && r.Finite(&d, "d")) << err;
  EXPECT_EQ(v, 0x0f0e0d0c0b0a0908ull);
  EXPECT_EQ(d, 1.0);
  EXPECT_TRUE(r.End("record")) << err;
}

TEST(Coding, VarintsRoundTripInTheirShortestForm) {
  for (uint64_t v : {uint64_t(0), uint64_t(1), uint64_t(127), uint64_t(128), uint64_t(300),
                     uint64_t(INT32_MAX), UINT64_MAX}) {
    std::string s;
    PutVarint(&s, v);
    const uint8_t* p = reinterpret_cast<const uint8_t*>(s.data());
    const uint8_t* q = p;
    uint64_t got = 0;
    ASSERT_EQ(GetVarint(&q, p + s.size(), &got), VarintStatus::kOk) << v;
    EXPECT_EQ(got, v);
    EXPECT_EQ(q, p + s.size());
    q = p;
    EXPECT_EQ(GetCheckedVarint(&q), v);
    EXPECT_EQ(q, p + s.size());
  }
  auto status = [](const std::string& s) {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(s.data());
    const uint8_t* q = p;
    uint64_t v = 0;
    const VarintStatus st = GetVarint(&q, p + s.size(), &v);
    EXPECT_EQ(q == p, st != VarintStatus::kOk);  // left where it was on failure
    return st;
  };
  EXPECT_EQ(status(""), VarintStatus::kTruncated);
  EXPECT_EQ(status("\x80"), VarintStatus::kTruncated);
  EXPECT_EQ(status(std::string("\x80\x00", 2)), VarintStatus::kOverlong);
  EXPECT_EQ(status("\xff\xff\xff\xff\xff\xff\xff\xff\xff\x02"), VarintStatus::kTooBig);
  EXPECT_EQ(status("\xff\xff\xff\xff\xff\xff\xff\xff\xff\x01"), VarintStatus::kOk);
}

TEST(Coding, ReaderChecksLengthsAndStaysFailed) {
  std::string s;
  PutVarint(&s, 1000);  // a count of 8-byte items with 9 bytes left
  PutF64(&s, NAN);
  PutU8(&s, 7);
  std::string err;
  uint64_t n;
  {
    Reader r(s, &err);
    EXPECT_FALSE(r.Count(8, &n, "item count"));
    EXPECT_EQ(err, "item count 1000 needs at least 8 bytes each, 9 bytes left");
    uint8_t b = 42;
    EXPECT_FALSE(r.U8(&b, "later"));  // failed for good: the first error stays
    EXPECT_EQ(b, 42);
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(err, "item count 1000 needs at least 8 bytes each, 9 bytes left");
  }
  {
    Reader r(s, &err);
    double d;
    ASSERT_TRUE(r.Varint(1000, &n, "count"));
    EXPECT_TRUE(r.F64(&d, "raw"));  // bits as they are
    EXPECT_TRUE(std::isnan(d));
    r.Seek(2);
    EXPECT_FALSE(r.Finite(&d, "time"));
    EXPECT_EQ(err, "time at offset 2 is not finite");
  }
  {
    Reader r(s, &err);
    EXPECT_FALSE(r.Varint(999, &n, "count"));
    EXPECT_EQ(err, "count 1000 is out of range (max 999)");
  }
  {
    Reader r(s, &err);
    std::string b;
    EXPECT_FALSE(r.Bytes(12, &b, "text"));
    EXPECT_EQ(err, "truncated: text needs 12 bytes at offset 0, 11 left");
    EXPECT_EQ(r.left(), 11u);
  }
  {
    Reader r(s, &err);
    ASSERT_TRUE(r.Varint(1000, &n, "count"));
    EXPECT_FALSE(r.End("record"));
    EXPECT_EQ(err, "record: 9 bytes left over after offset 2");
  }
  {
    std::string c;
    PutFixed64(&c, 2);
    PutFixed(&c, 0, 7);
    Reader r(c, &err);
    EXPECT_FALSE(r.Count64(4, &n, "array"));  // 2 items of 4 bytes, 7 left
    EXPECT_EQ(err, "array 2 needs at least 4 bytes each, 7 bytes left");
  }
}

}  // namespace

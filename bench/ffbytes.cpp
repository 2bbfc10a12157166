// radiosity-ffbytes: bytes on the wire per non-zero form factor, and what
// they cost the worker to encode and the master to decode, for the
// column encoding the program sends and for candidates that might send
// fewer (issue 17, "Fewer bytes"), as Markdown table rows on stdout
// (bench/ffbytes.sh adds the header):
//   radiosity-ffbytes SCENE.obj SHOTS [R]
// The columns are the run's own (Select, ShotColumn, Shoot: -j 0's order,
// no subdivision), each encoded as the worker encodes it (EncodeColumn: a
// frame). Candidates:
//   now         the frame as sent (protocol 7: element ids as runs, 11-bit
//               codes as differences of 1 or 2 bytes)
//   16-bit codes  the frame of protocol 5 (the same runs, 16-bit codes of
//               2 bytes, 5 escaped): its size only, exact (it does not
//               depend on the codes' values)
//   + lz4       each frame compressed alone with LZ4 (liblz4), as a
//               worker would send it
//   + zstd -1   likewise with Zstandard level 1 (libzstd), and -3
//   codes H0    the runs as now, the codes at their order-0 entropy over
//               the run's columns (a bound for an entropy coder with one
//               static table: no coder, no times)
//   deltas H0   likewise for each code's difference from the one before it
//               in the column (a bound for a coder of differences, against
//               now's bytes for them); and for codes with 5 fraction bits
//               instead of 7 (what coarser codes would leave to send)
// Times are the quickest of 3 passes over all columns, per form factor,
// on the thread's CPU clock; decoding includes DecodeColumn after the
// decompression, as the master would do both.
#include <lz4.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench/load.h"
#include "bench/record.h"
#include "clock.h"
#include "ffcodec.h"
#include "protocol.h"

namespace {

// The quickest of 3 runs of f(), in seconds of the thread's CPU time.
template <class F>
double Quickest(const F& f) {
  double best = HUGE_VAL;
  for (int round = 0; round < 3; ++round) {
    const double t0 = ThreadCpuSeconds();
    f();
    best = std::min(best, ThreadCpuSeconds() - t0);
  }
  return best;
}

// Order-0 entropy, in bits per symbol, of the counts.
double Entropy(const std::map<long, long>& counts) {
  double total = 0, bits = 0;
  for (const auto& c : counts) total += double(c.second);
  for (const auto& c : counts) bits -= double(c.second) * std::log2(double(c.second) / total);
  return total > 0 ? bits / total : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: radiosity-ffbytes SCENE.obj SHOTS [R]\n");
    return 2;
  }
  const long shots = std::atol(argv[2]);
  const int res = argc > 3 ? std::atoi(argv[3]) : 256;
  Scene scene;
  Mesh mesh;
  LoadMeshOrDie("radiosity-ffbytes", argv[1], &scene, &mesh);
  std::string err;

  const std::vector<std::string> frames = RecordFrames("radiosity-ffbytes", mesh, shots, res, true);
  // The columns as the master decodes them: the values of their codes.
  std::vector<proto::Column> columns(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) DecodeFrame("radiosity-ffbytes", frames[i], &columns[i]);
  double ffs = 0, now_bytes = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    ffs += double(columns[i].ff.size());
    now_bytes += double(frames[i].size());
  }
  if (ffs == 0) {
    std::fprintf(stderr, "radiosity-ffbytes: no form factors in %zu columns\n", frames.size());
    return 1;
  }
  std::string name = argv[1];
  name = name.substr(name.find_last_of('/') + 1);
  name = name.substr(0, name.rfind(".obj"));
  auto row = [&](const char* what, double bytes, double enc_s, double dec_s) {
    std::printf("| %s | %d | %zu | %.0f | %s | %.3f | %.2f |", name.c_str(), res, frames.size(),
                ffs / double(frames.size()), what, bytes / ffs, bytes / now_bytes);
    if (enc_s >= 0) std::printf(" %.2f | %.2f |\n", 1e9 * enc_s / ffs, 1e9 * dec_s / ffs);
    else std::printf(" - | - |\n");
  };

  proto::Column got;
  std::string out;
  const double now_enc = Quickest([&] {
    for (const proto::Column& c : columns) proto::EncodeColumn(c, &out), out.clear();
  });
  const double now_dec = Quickest([&] {
    for (const std::string& f : frames)
      proto::DecodeColumn(std::string_view(f).substr(proto::kHeaderSize), &got, &err);
  });
  row("now", now_bytes, now_enc, now_dec);

  // Protocol 5: 2 bytes a code and 5 an escape where now has 1 or 2 bytes
  // a difference and 3 more an escape (SentCode: the 11-bit codes, -1 for
  // escaped form factors; diff_bytes: now's bytes for the differences of
  // the codes not escaped).
  double codes16 = 0, diff_bytes = 0, coded = 0;
  for (const proto::Column& c : columns) {
    long last = 0;
    for (const FormFactor& ff : c.ff) {
      const long code = proto::SentCode(ff.f);
      const long d = (code < 0 ? 0 : code) - last;
      const double b = d >= -120 && d < 120 ? 1 : 2;  // ffcodec.cpp, kShortBias
      codes16 += 2;
      if (code < 0) continue;  // escaped: 3 more bytes both ways
      diff_bytes += b;
      ++coded;
      last = code;
    }
  }
  row("16-bit codes (protocol 5)", now_bytes - diff_bytes - (ffs - coded) + codes16, -1, -1);

  // Compressed frames: each alone, then decompressed and decoded.
  std::vector<std::string> packed(frames.size());
  std::string back;
  auto compressor = [&](const char* what, const auto& pack, const auto& unpack) {
    const double enc = Quickest([&] {
      for (size_t i = 0; i < frames.size(); ++i) pack(frames[i], &packed[i]);
    });
    double bytes = 0;
    for (const std::string& p : packed) bytes += double(p.size());
    const double dec = Quickest([&] {
      for (size_t i = 0; i < frames.size(); ++i) {
        unpack(packed[i], frames[i].size(), &back);
        proto::DecodeColumn(std::string_view(back).substr(proto::kHeaderSize), &got, &err);
      }
    });
    for (size_t i = 0; i < frames.size(); ++i) {  // round trip: what was packed comes back
      unpack(packed[i], frames[i].size(), &back);
      if (back != frames[i]) {
        std::fprintf(stderr, "radiosity-ffbytes: %s: frame %zu does not come back\n", what, i);
        std::exit(1);
      }
    }
    row(what, bytes, now_enc + enc, dec);
  };
  compressor(
      "+ lz4",
      [](const std::string& in, std::string* o) {
        o->resize(size_t(LZ4_compressBound(int(in.size()))));
        o->resize(size_t(LZ4_compress_default(in.data(), o->data(), int(in.size()), int(o->size()))));
      },
      [](const std::string& in, size_t n, std::string* o) {
        o->resize(n);
        LZ4_decompress_safe(in.data(), o->data(), int(in.size()), int(n));
      });
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  for (int level : {1, 3}) {
    const std::string what = "+ zstd -" + std::to_string(level);
    compressor(
        what.c_str(),
        [&](const std::string& in, std::string* o) {
          o->resize(ZSTD_compressBound(in.size()));
          o->resize(ZSTD_compressCCtx(cctx, o->data(), o->size(), in.data(), in.size(), level));
        },
        [&](const std::string& in, size_t n, std::string* o) {
          o->resize(n);
          ZSTD_decompressDCtx(dctx, o->data(), n, in.data(), in.size());
        });
  }
  ZSTD_freeCCtx(cctx);
  ZSTD_freeDCtx(dctx);

  // Entropy bounds: the frames less now's bytes for the differences (what
  // the runs, header and escapes take), plus the codes at their entropy;
  // then the differences of coarser codes (the fraction cut to 5 of its 6
  // bits: what one bit fewer would leave to code, at a rounding of 2^-6
  // instead of 2^-7 a form factor, before error diffusion).
  auto entropy = [&](int drop, bool delta) {
    std::map<long, long> counts;
    for (const proto::Column& c : columns) {
      long last = 0;
      for (const FormFactor& ff : c.ff) {
        const long code = proto::SentCode(ff.f);
        if (code < 0) continue;
        const long k = code >> drop;
        ++counts[delta ? k - last : k];
        last = k;
      }
    }
    return Entropy(counts);
  };
  const double h_codes = entropy(0, false), h_deltas = entropy(0, true);
  const double rest = now_bytes - diff_bytes;
  row("codes H0", rest + coded * h_codes / 8, -1, -1);
  row("deltas H0", rest + coded * h_deltas / 8, -1, -1);
  row("deltas H0, 5-bit fraction", rest + coded * entropy(1, true) / 8, -1, -1);
  return 0;
}

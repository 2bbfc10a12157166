// The benchmarks' one way to record the columns a run shoots: its first
// `shots` columns in the order `-j 0` shoots them (Select, ShotColumn,
// Shoot, no subdivision), each as the frame a worker sends (EncodeColumn),
// and shot as the master shoots it, from the decoded frame (11-bit codes);
// and a recorded frame decoded again. Both exit with "PROG: why" on
// stderr if a frame does not decode.
#ifndef RADIOSITY_BENCH_RECORD_H
#define RADIOSITY_BENCH_RECORD_H

#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "groups.h"
#include "hemicube.h"
#include "mesh.h"
#include "protocol.h"
#include "solver.h"

// A recorded frame's column, decoded as the master decodes it, into *col.
inline void DecodeFrame(const char* prog, const std::string& frame, proto::Column* col) {
  std::string err;
  if (!proto::DecodeColumn(std::string_view(frame).substr(proto::kHeaderSize), col, &err)) {
    std::fprintf(stderr, "%s: %s\n", prog, err.c_str());
    std::exit(1);
  }
}

inline std::vector<std::string> RecordFrames(const char* prog, const Mesh& mesh, long shots, int res,
                                             bool overshoot) {
  std::vector<std::string> frames;
  Solver solver(mesh, overshoot);
  Hemicube h(res);
  proto::Column col, got;
  for (long i = 0; i < shots; ++i) {
    const int p = solver.Select();
    if (p < 0) break;
    col.patch = p;
    col.k = solver.TimesShot(p);
    ShotColumn(&h, mesh, p, GroupOf(mesh, p), col.k, true, 1, &col.ff);
    frames.emplace_back();
    proto::EncodeColumn(col, &frames.back());
    DecodeFrame(prog, frames.back(), &got);
    solver.Shoot(p, got.ff);
  }
  return frames;
}

#endif

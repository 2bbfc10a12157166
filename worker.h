// The worker: reads the protocol of doc/protocol.txt on one file
// descriptor and writes it on another (stdin and stdout under --worker).
// It builds the master's mesh from the scene it is sent, then computes
// one form-factor column per assigned patch, in the order assigned, and
// applies hierarchy edits where they fall in the stream.
#ifndef RADIOSITY_WORKER_H
#define RADIOSITY_WORKER_H

#include <functional>
#include <string>
#include <vector>

#include "hemicube.h"
#include "protocol.h"

// How a worker computes one assigned column: ShotColumn, coded by
// PutFormFactors, unless a benchmark feeds the master faster than
// hemicubes can (bench/feed.cpp). It sets *coded to the column's form
// factors as PutFormFactors codes them.
using ColumnFn = std::function<void(Hemicube*, const Mesh&, const proto::Assignment&,
                                    bool rotate, unsigned seed, std::string* coded)>;

// Returns the process exit status: 0 after Bye or end of stream, 1 on a
// protocol error (*err says what; the master was also sent an Error).
// `spin`: never sleep waiting for work (the benchmark's stand-in for many
// busy workers, whose sockets the master's sends never wake).
int RunWorker(int in_fd, int out_fd, std::string* err, ColumnFn column = nullptr,
              bool spin = false);

#endif

// The master's own process as the one worker (-j 0, and the scheduler's
// fallback when every worker is lost): each Poll computes the oldest
// assignment on the master's mesh.
#ifndef RADIOSITY_INPROCESS_H
#define RADIOSITY_INPROCESS_H

#include <string>
#include <vector>

#include "hemicube.h"
#include "mesh.h"
#include "transport.h"

class InProcessTransport : public Transport {
 public:
  InProcessTransport(const Mesh& mesh, int resolution, bool rotate, unsigned seed);
  int Workers() const override { return 1; }
  int Starting() const override { return 0; }
  std::string Name(int) const override { return "the master"; }
  Capabilities Caps() const override { return {true}; }
  void Assign(int w, const proto::Assignment& a) override;
  // Shares the master's mesh, so nothing to apply; the hemicube's copy of
  // it is stale now and goes at once (a wave's picture may come next).
  void Divide(const std::vector<int32_t>&) override { hemicube_.ReleaseCache(); }
  void Poll(double timeout, std::vector<WorkerEvent>* events) override;
  double Now() override;

 private:
  const Mesh& mesh_;
  Hemicube hemicube_;
  bool rotate_;
  unsigned seed_;
  bool joined_ = false;
  std::vector<proto::Assignment> todo_;
};

#endif

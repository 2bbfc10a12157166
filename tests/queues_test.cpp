// The queues' pacing on its own: queue sizes from measured times, what a
// column's times count for, which workers are deferred, and how far down
// the order a deferred patch comes from.
#include "queues.h"

#include <gtest/gtest.h>

#include "solver.h"
#include "test_util.h"

namespace {

Pace Measured(double column_s, double wire_s, double interval_s, int depth) {
  return Pace{depth, 3, 2, column_s, wire_s, interval_s};
}

// A worker's first column, here at 1, and its second: sent at 1.5,
// ready at 1.75, here at 2.
Pace TwoColumns() {
  Pace p;
  p.Measure(1.0, 0.0, 0.0, 0.1, true, 0);
  p.Measure(2.0, 1.5, 0.0, 0.25, false, 0);
  return p;
}

TEST(Queues, DepthIsTheRoundTripOverTheServiceTimeWithin2And32) {
  Pace p = Measured(0.01, 0.05, 0, 0);  // 60 ms a trip, 10 ms a column
  p.Size(1, 0);
  EXPECT_EQ(p.depth, 6);
  EXPECT_EQ(p.high, 12);
  EXPECT_EQ(p.low, 6);
  p = Measured(0.01, 0, 0, 0);  // the worker's own time only: 1, at least 2
  p.Size(1, 0);
  EXPECT_EQ(p.depth, 2);
  p = Measured(0.001, 1.0, 0, 0);  // 1001 in flight, at most 32
  p.Size(1, 0);
  EXPECT_EQ(p.depth, kMaxDepth);
  EXPECT_EQ(p.high, 2 * kMaxDepth);
}

TEST(Queues, ALinkSlowerThanTheWorkerAddsItsTransferToTheTrip) {
  // 10 ms between columns against 1 ms of CPU: the link paces it, and the
  // trip is column + wire + transfer = 31 ms, over 10 ms a column.
  Pace p = Measured(0.001, 0.02, 0.01, 0);
  p.Size(1, 0);
  EXPECT_EQ(p.depth, 4);
  // Within 1.25 times the CPU time: a busy core, not the link.
  p = Measured(0.008, 0.02, 0.01, 0);
  p.Size(1, 0);
  EXPECT_EQ(p.depth, 3);  // (8 + 20) / 10
}

TEST(Queues, HighIsTwiceTheDepthPlusOnePer32WorkersWithin3And64) {
  Pace p;  // not measured: the depth stays as it is
  p.Size(64, 0);
  EXPECT_EQ(p.depth, 2);
  EXPECT_EQ(p.high, 6);
  EXPECT_EQ(p.low, 3);
  p.depth = 1;  // as a sequential transport's
  p.Size(1, 0);
  EXPECT_EQ(p.high, 3);
  EXPECT_EQ(p.low, 2);
  p = Measured(0.001, 1.0, 0, 0);
  p.Size(1000, 0);
  EXPECT_EQ(p.high, kMaxHigh);
}

TEST(Queues, QueueOptionSetsHighAndBoundsDepth) {
  Pace p = Measured(0.001, 1.0, 0, 0);
  p.Size(1, 5);
  EXPECT_EQ(p.high, 5);
  EXPECT_EQ(p.depth, 5);
  EXPECT_EQ(p.low, 3);
}

TEST(Queues, TheFirstColumnIsNoSampleButMarksTheArrival) {
  Pace p;
  p.Measure(1.0, 0.0, 0.0, 0.1, true, 0);
  EXPECT_EQ(p.column_s, 0);
  EXPECT_EQ(p.wire_s, 0);
  EXPECT_EQ(p.last_arrival, 1.0);
  EXPECT_EQ(p.Turnaround(), 0);
  // A quarter of a second on the wire; not sent before the last arrival,
  // so no service time.
  p = TwoColumns();
  EXPECT_EQ(p.column_s, 0.25);
  EXPECT_EQ(p.wire_s, 0.25);
  EXPECT_EQ(p.interval_s, 0);
}

TEST(Queues, AColumnSeenAfterTheMasterWasBusyLongerIsNoWireSample) {
  Pace quiet = TwoColumns(), busy = TwoColumns();
  // Sent at 1.9 (before the last arrival: it held work), ready at 2.4.
  quiet.Measure(3.0, 1.9, 0.0, 0.5, false, 0.4);
  busy.Measure(3.0, 1.9, 0.0, 0.5, false, 0.6);
  // Its compute time counts either way, smoothed by a quarter.
  EXPECT_DOUBLE_EQ(quiet.column_s, 0.3125);
  EXPECT_DOUBLE_EQ(busy.column_s, 0.3125);
  EXPECT_DOUBLE_EQ(quiet.wire_s, 0.25 + (0.6 - 0.25) / 4);
  EXPECT_DOUBLE_EQ(quiet.interval_s, 1.0);
  EXPECT_EQ(busy.wire_s, 0.25);
  EXPECT_EQ(busy.interval_s, 0);
  EXPECT_EQ(busy.last_arrival, 3.0);
}

TEST(Queues, AColumnReadyBeforeTheLastArrivedWaitedForTheLink) {
  Pace p = TwoColumns();
  // Ready at 0.5 + 0.25, long before the one before arrived at 2: its
  // round trip is the link's backlog, not the wire; the 1 s between the
  // columns is.
  p.Measure(3.0, 0.5, 0.0, 0.25, false, 0);
  EXPECT_EQ(p.wire_s, 0.25);
  EXPECT_EQ(p.interval_s, 1.0);
}

// Times in powers of two: the skips come out exact.
TEST(Queues, DeferredOnlyWhenHeldAndServedMoreThanFourTimesAsLong) {
  const Pace fast = Measured(1, 0, 0, 2);     // turnaround 2, service 1
  const Pace slow = Measured(1, 16, 8, 2);    // turnaround 32, service 8
  const Pace far = Measured(1, 100, 0, 2);    // held 102, served in 1
  const Pace loaded = Measured(8, 0, 0, 1);   // served in 8, held 8
  const Pace unmeasured;
  std::vector<long> skip;
  Deferrals({&fast, &slow, nullptr, &far, &loaded, &unmeasured}, 1000, &skip);
  // Only `slow` both holds patches over 4 x 2 s and serves them over
  // 4 x 1 s; in the 30 s it holds them longer, the others (fast, far,
  // loaded) shoot 1 + 1 + 1/8 a second.
  EXPECT_EQ(skip, (std::vector<long>{0, 63, 0, 0, 0, 0}));
  Deferrals({&fast, &slow}, 10, &skip);
  EXPECT_EQ(skip[1], 10);  // at most `most`
  Deferrals({&fast, &slow}, 1000, &skip);
  EXPECT_EQ(skip[1], 30);  // the fast one shoots 1 a second for 30 s
  Deferrals({&fast, &fast}, 1000, &skip);
  EXPECT_EQ(skip, (std::vector<long>{0, 0}));
}

TEST(Queues, ReturnsAfterComparesTurnarounds) {
  const Pace slow = Measured(1, 16, 8, 2);  // turnaround 32
  EXPECT_TRUE(slow.ReturnsAfter(10, 20, 2));    // back at 42, against 22
  EXPECT_FALSE(slow.ReturnsAfter(10, 40, 2));   // back at 42, against 42
  EXPECT_TRUE(slow.ReturnsAfter(10, 50, 2));    // overdue: a service (8) more, against 2
  EXPECT_FALSE(slow.ReturnsAfter(10, 50, 9));   // ... against 9
}

TEST(Queues, PatchBelowSkipsThatManyAndTakesNone) {
  Mesh m = MakeMesh(Box(1.0, {glm::dvec3(0.5)},
                        {glm::dvec3(0), glm::dvec3(3), glm::dvec3(0), glm::dvec3(0),
                         glm::dvec3(0), glm::dvec3(0)}));
  Solver solver(m, true);
  std::vector<int> held;
  const int top = solver.Select();
  ASSERT_GE(top, 0);
  EXPECT_EQ(PatchBelow(&solver, 0, &held), top);
  const int second = PatchBelow(&solver, 1, &held);
  EXPECT_NE(second, top);
  solver.Take(top);
  EXPECT_EQ(solver.Select(), second);
  solver.Release(top);
  // Only the ceiling has power: past its patches there is none.
  long lit = 0;
  for (const Patch& p : m.patches) lit += p.face == 1;
  EXPECT_GE(PatchBelow(&solver, lit - 1, &held), 0);
  EXPECT_EQ(PatchBelow(&solver, lit, &held), -1);
  EXPECT_EQ(solver.Select(), top);  // nothing left taken
}

}  // namespace

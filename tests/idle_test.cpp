// The idle accounting on its own: workers' gaps classed by what the
// master was doing meanwhile, and when a worker is reckoned done.
#include "idle.h"

#include <gtest/gtest.h>

namespace {

TEST(Idle, GapsAreClassedByTheSpansTheyOverlap) {
  IdleAccount a;
  a.Busy(IdleAccount::kPicture, 1, 2);
  a.Busy(IdleAccount::kPass, 3, 4);
  a.Count(0, 5, 0);
  EXPECT_EQ(a.idle().picture, 1);
  EXPECT_EQ(a.idle().pass, 1);
  EXPECT_EQ(a.idle().dry, 0);
  EXPECT_EQ(a.idle().other, 3);
  // Only the part of a span inside the gap.
  a.Count(1.5, 3.5, 0);
  EXPECT_EQ(a.idle().picture, 1.5);
  EXPECT_EQ(a.idle().pass, 1.5);
  EXPECT_EQ(a.idle().other, 4);
}

TEST(Idle, DrySpansCountUntilTheyCloseAndOpenOnesToTheGapsEnd) {
  IdleAccount a;
  a.Dry(true, 1);
  a.Dry(true, 2);  // still dry: from 1
  a.Count(0, 5, 0);
  EXPECT_EQ(a.idle().dry, 4);
  EXPECT_EQ(a.idle().other, 1);
  a.Dry(false, 3);
  a.Count(2, 6, 0);
  EXPECT_EQ(a.idle().dry, 5);
  EXPECT_EQ(a.idle().other, 4);
}

TEST(Idle, AStepOfTheMastersCutsTheDrySpanAround) {
  IdleAccount a;
  a.Dry(true, 0);
  a.Busy(IdleAccount::kPicture, 2, 3);
  a.Dry(false, 5);
  a.Count(0, 5, 0);
  EXPECT_EQ(a.idle().picture, 1);
  EXPECT_EQ(a.idle().dry, 4);
  EXPECT_EQ(a.idle().other, 0);
  EXPECT_EQ(a.idle().Sum(), 5);
}

TEST(Idle, NoGapAndSpansBeforeTheOldestFreeWorker) {
  IdleAccount a;
  a.Busy(IdleAccount::kPass, 0, 1);
  a.Count(3, 2, 2);  // no gap; the pass, over by 2, is dropped
  EXPECT_EQ(a.idle().Sum(), 0);
  a.Count(0, 1, 0);
  EXPECT_EQ(a.idle().pass, 0);
  EXPECT_EQ(a.idle().other, 1);
  a.End(2.5);
  EXPECT_EQ(a.idle().end, 2.5);
  EXPECT_EQ(a.idle().Sum(), 3.5);
}

TEST(Idle, AWorkerIsDoneAfterItsComputeTimeWithinThePolls) {
  // Free at 0, its work out at 1: done at 1.5.
  EXPECT_EQ(DoneAt(0, 1, 0.5, 0, 10), 1.5);
  // Busy with the one before until 2: done at 2.5.
  EXPECT_EQ(DoneAt(2, 1, 0.5, 0, 10), 2.5);
  // Not after it arrived.
  EXPECT_EQ(DoneAt(0, 1, 20, 0, 10), 10);
  // Not before the Poll before the one that read it, which found nothing.
  EXPECT_EQ(DoneAt(0, 1, 0.5, 5, 10), 5);
  EXPECT_EQ(DoneAt(0, 1, 0.5, 12, 10), 10);
}

}  // namespace

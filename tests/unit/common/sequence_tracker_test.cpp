// SequenceTracker: gaps are drops, repeats are rejected, a publisher that starts over is accepted.
#include <gtest/gtest.h>

#include "common/process_context.hpp"

namespace polarslam {
namespace {

TEST(SequenceTracker, GapsAreDropsAndRepeatsAreRejected) {
  SequenceTracker t;
  EXPECT_TRUE(t.accept("LASER", 5));
  EXPECT_TRUE(t.accept("LASER", 6));
  EXPECT_TRUE(t.accept("LASER", 9));
  EXPECT_EQ(t.dropped(), 2);
  EXPECT_FALSE(t.accept("LASER", 9));  // duplicate
  EXPECT_FALSE(t.accept("LASER", 7));  // late
  EXPECT_TRUE(t.accept("ODOMETRY", 9));  // channels are independent
  EXPECT_EQ(t.restarts(), 0);
}

TEST(SequenceTracker, APublisherThatStartsOverIsAcceptedAndCounted) {
  SequenceTracker t;
  for (int64_t s = 10; s < 20; ++s) EXPECT_TRUE(t.accept("LASER", s));
  EXPECT_TRUE(t.accept("LASER", 0));  // restarted from 0
  EXPECT_TRUE(t.accept("LASER", 1));
  EXPECT_EQ(t.restarts(), 1);
  EXPECT_EQ(t.dropped(), 0);
  for (int64_t s = 2; s < 500; ++s) t.accept("LASER", s);
  EXPECT_TRUE(t.accept("LASER", 250));  // far back: another restart (e.g. a replayed log)
  EXPECT_EQ(t.restarts(), 2);
}

}  // namespace
}  // namespace polarslam

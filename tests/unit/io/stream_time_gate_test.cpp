// StreamTimeGate: a stamp far from the other input is rejected, never adopted as the clock; a
// real change of clock is adopted after a few consistent messages.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "io/stream_time_gate.hpp"

namespace polarslam {
namespace {

constexpr int64_t kSecond = 1'000'000;
constexpr int64_t kStart = 1'700'000'000 * kSecond;

TEST(StreamTimeGate, OneMessageAnHourAheadIsRejectedAndTheStreamsGoOn) {
  StreamTimeGate gate;
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(gate.admit("ODOMETRY", kStart + i * kSecond / 10), "");
    EXPECT_EQ(gate.admit("LASER", kStart + i * kSecond / 10 + 5000), "");
  }
  const std::string why = gate.admit("ODOMETRY", kStart + 3600 * kSecond);
  EXPECT_NE(why.find("ODOMETRY: time stamp jumps"), std::string::npos) << why;
  EXPECT_LT(gate.clock(), kStart + 2 * kSecond) << "the future stamp did not become the clock";
  for (int i = 10; i < 20; ++i) {
    EXPECT_EQ(gate.admit("ODOMETRY", kStart + i * kSecond / 10), "") << i;
    EXPECT_EQ(gate.admit("LASER", kStart + i * kSecond / 10 + 5000), "") << i;
  }
  EXPECT_EQ(gate.rejected(), 1);
  EXPECT_EQ(gate.adoptedJumps(), 0);
}

TEST(StreamTimeGate, AStreamThatStopsDoesNotHoldTheOthersBack) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("LASER", kStart), "");
  for (int i = 1; i <= 600; ++i) EXPECT_EQ(gate.admit("ODOMETRY", kStart + i * kSecond / 10), "") << i;
  EXPECT_EQ(gate.admit("LASER", kStart + 60 * kSecond), "") << "the laser comes back at the current time";
}

TEST(StreamTimeGate, ALogThatResumesAfterAPauseIsAdoptedAfterThreeMessages) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("ODOMETRY", kStart), "");
  const int64_t later = kStart + 2 * 3600 * kSecond;
  EXPECT_NE(gate.admit("ODOMETRY", later), "");
  EXPECT_NE(gate.admit("LASER", later + 1000), "") << "another stream does not confirm this one's jump";
  EXPECT_NE(gate.admit("ODOMETRY", later + kSecond / 10), "");
  EXPECT_EQ(gate.admit("ODOMETRY", later + 2 * kSecond / 10), "") << "the third consistent message adopts the jump";
  EXPECT_EQ(gate.adoptedJumps(), 1);
  EXPECT_EQ(gate.admit("LASER", later + 3 * kSecond / 10), "") << "the others follow the new clock at once";
}

TEST(StreamTimeGate, AFutureFirstMessageIsOutvotedByTheNormalOnes) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("ODOMETRY", kStart + 3600 * kSecond), "") << "nothing to compare the first one with";
  int rejected = 0;
  for (int i = 0; i < 10; ++i) rejected += gate.admit("LASER", kStart + i * kSecond / 10).empty() ? 0 : 1;
  EXPECT_EQ(rejected, 2);
  EXPECT_LT(gate.clock(), kStart + kSecond);
}

TEST(StreamTimeGate, InconsistentStampsNeverConfirmAJump) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("ODOMETRY", kStart), "");
  for (int i = 0; i < 50; ++i) {
    const int64_t wild = kStart + (i % 2 == 0 ? 1 : -1) * (100 + i) * 3600 * kSecond;
    EXPECT_NE(gate.admit("ODOMETRY", wild), "") << i;
  }
  EXPECT_EQ(gate.clock(), kStart);
}

TEST(StreamTimeGate, StampsAtTheEndsOfInt64DoNotOverflow) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("LASER", std::numeric_limits<int64_t>::max()), "");
  EXPECT_NE(gate.admit("ODOMETRY", std::numeric_limits<int64_t>::min()), "");
  EXPECT_NE(gate.admit("ODOMETRY", 0), "");
  EXPECT_EQ(gate.clock(), std::numeric_limits<int64_t>::max());
}

TEST(StreamTimeGate, ReorderedStampsWithinTheBoundPass) {
  StreamTimeGate gate;
  EXPECT_EQ(gate.admit("LASER", kStart + kSecond), "");
  EXPECT_EQ(gate.admit("SONAR", kStart), "") << "a second late is not a jump";
  EXPECT_EQ(gate.clock(), kStart + kSecond);
}

}  // namespace
}  // namespace polarslam

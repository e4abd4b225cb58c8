// Context: cancellation and deadlines. The earliest deadline set wins, whatever the order.

#include "rdmesh/context.h"

#include <gtest/gtest.h>

#include <chrono>

namespace rdmesh {
namespace {

using Clock = std::chrono::steady_clock;

TEST(ContextTest, NoDeadlineNeverStops) {
  Context context;
  context.SetTimeout(0);
  context.SetTimeout(-1);
  EXPECT_FALSE(context.ShouldStop());
  EXPECT_TRUE(context.StopStatus().ok());
}

TEST(ContextTest, LongerTimeoutKeepsAnEarlierDeadline) {
  Context context;
  context.SetDeadline(Clock::now() - std::chrono::seconds(1));
  context.SetTimeout(3600);
  EXPECT_TRUE(context.ShouldStop());
  EXPECT_EQ(context.StopStatus().code(), StatusCode::kDeadlineExceeded);
}

TEST(ContextTest, EarlierDeadlineReplacesALongerTimeout) {
  Context context;
  context.SetTimeout(3600);
  EXPECT_FALSE(context.ShouldStop());
  context.SetDeadline(Clock::now() - std::chrono::seconds(1));
  EXPECT_TRUE(context.ShouldStop());
  EXPECT_EQ(context.StopStatus().code(), StatusCode::kDeadlineExceeded);
}

TEST(ContextTest, LaterDeadlineIsIgnored) {
  Context context;
  context.SetDeadline(Clock::now() + std::chrono::hours(1));
  context.SetDeadline(Clock::now() + std::chrono::hours(2));
  context.SetTimeout(7200 + 60);
  EXPECT_FALSE(context.ShouldStop());
  context.SetDeadline(Clock::now() - std::chrono::milliseconds(1));
  EXPECT_TRUE(context.ShouldStop());
}

TEST(ContextTest, CancelWinsOverDeadline) {
  Context context;
  context.SetDeadline(Clock::now() - std::chrono::seconds(1));
  context.Cancel();
  EXPECT_EQ(context.StopStatus().code(), StatusCode::kCancelled);
}

}  // namespace
}  // namespace rdmesh

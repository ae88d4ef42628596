// common::RecentRateEta: the rest of a job at the rate of its last tenth.
#include "common/eta.hpp"

#include <gtest/gtest.h>

using papersim::common::RecentRateEta;

// A job of 1,000 steps whose last fifth costs ten times as much per step (1 s, then 10 s), as a
// crumple's crush does; a report after every step. The ETA after step k is the rest at the rate
// of the last 100 steps; the mean rate of the whole job would give far less.
TEST(RecentRateEta, FollowsAJobWhoseStepsGrowDearer) {
  RecentRateEta eta;
  double t = 0;
  double at_900 = -1, at_50 = -1, at_500 = -1;
  for (int k = 1; k <= 1000; ++k) {
    t += k <= 800 ? 1.0 : 10.0;
    const double e = eta.update(k / 1000.0, t);
    if (k == 50) at_50 = e;
    if (k == 500) at_500 = e;
    if (k == 900) at_900 = e;
  }
  EXPECT_NEAR(at_50, 950.0, 1e-6);   // before a tenth: the mean rate (1 s per step)
  EXPECT_NEAR(at_500, 500.0, 1e-6);  // steady: 500 steps at 1 s
  // At step 900 the last 100 steps took 10 s each: 100 steps left at 10 s. The whole job's mean
  // (1,800 s over 900 steps) would say 200 s, the true rest is 1,000 s.
  EXPECT_NEAR(at_900, 1000.0, 1e-6);
}

TEST(RecentRateEta, ZeroBeforeAnyProgressAndAtTheEnd) {
  RecentRateEta eta;
  EXPECT_EQ(eta.update(0.0, 3.0), 0.0);
  EXPECT_GT(eta.update(0.5, 10.0), 0.0);
  EXPECT_EQ(eta.update(1.0, 20.0), 0.0);
}

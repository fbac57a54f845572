// The verdict of a reference's convergence check, from known numbers.
#include <gtest/gtest.h>

#include "shimmer/experiments/runner.h"

namespace shimmer::experiments {
namespace {

ShotCheck Measured(double tv_ref, double tv_ref_check, double bias, double bias_check, double tv_err,
                   double tv_err_check) {
  ShotCheck c;
  c.tv_ref = tv_ref;
  c.tv_ref_check = tv_ref_check;
  c.energy_bias = bias;
  c.energy_bias_check = bias_check;
  c.tv_err = tv_err;
  c.tv_err_check = tv_err_check;
  c.tol_energy = 0.02;
  c.tol_tv = 0.10;
  return c;
}

TEST(ShotCheck, SmallChangesConvergeAndEachLargeOneDoesNot) {
  ShotCheck ok = Measured(1.0, 1.05, 0.10, 0.11, 0.5, 0.52);
  JudgeConvergence(ok);
  EXPECT_NEAR(ok.d_tv_ref, 0.05, 1e-12);
  EXPECT_NEAR(ok.d_energy_bias, 0.01, 1e-12);
  EXPECT_NEAR(ok.d_tv_err, 0.04, 1e-12);
  EXPECT_TRUE(ok.converged);

  ShotCheck tv_ref = Measured(1.0, 1.25, 0.10, 0.10, 0.5, 0.5);
  JudgeConvergence(tv_ref);
  EXPECT_FALSE(tv_ref.converged);
  ShotCheck energy = Measured(1.0, 1.0, 0.10, 0.13, 0.5, 0.5);
  JudgeConvergence(energy);
  EXPECT_FALSE(energy.converged);
  ShotCheck tv_err = Measured(1.0, 1.0, 0.10, 0.10, 0.5, 0.6);
  JudgeConvergence(tv_err);
  EXPECT_FALSE(tv_err.converged);
}

TEST(ShotCheck, ATvErrBelowTheFloorIsJudgedAgainstTheFloorNotItself) {
  // none matches the reference: tv_err is reference noise, a millionth of
  // tv_ref, and it drops by a sixth when the reference doubles its samples.
  ShotCheck tiny = Measured(1.6e-3, 1.6e-3, 0.0, 0.0, 3.0e-9, 2.5e-9);
  JudgeConvergence(tiny);
  EXPECT_NEAR(tiny.d_tv_err, 0.5e-9 / 1.6e-6, 1e-9);
  EXPECT_TRUE(tiny.converged);
  // Above the floor the same relative change is a change.
  ShotCheck large = Measured(1.6e-3, 1.6e-3, 0.0, 0.0, 3.0e-5, 2.5e-5);
  JudgeConvergence(large);
  EXPECT_NEAR(large.d_tv_err, 1.0 / 6.0, 1e-12);
  EXPECT_FALSE(large.converged);
  // A tv_err that appears from nothing is the largest change there is.
  ShotCheck from_zero = Measured(0.0, 0.0, 0.0, 0.0, 0.0, 1e-3);
  JudgeConvergence(from_zero);
  EXPECT_FALSE(from_zero.converged);
}

// A Monte Carlo reference's noise F is part of tv_err and shrinks when the
// reference doubles its samples; what is judged is tv_err less F.
TEST(ShotCheck, TheReferencesOwnNoiseIsTakenOutOfTvErr) {
  ShotCheck noisy = Measured(7.0, 7.0, 0.0, 0.0, 0.028, 0.021);
  JudgeConvergence(noisy);
  EXPECT_FALSE(noisy.converged);  // a 25 % drop, all of it noise, but the check cannot tell
  noisy.tv_err_noise = 0.0090;    // F at N, and a quarter of it at 2N
  noisy.tv_err_noise_check = 0.00225;
  JudgeConvergence(noisy);
  EXPECT_NEAR(noisy.d_tv_err, std::abs(0.01875 / 0.019 - 1), 1e-12);
  EXPECT_TRUE(noisy.converged);
  // Noise does not excuse a moving mean.
  ShotCheck biased = noisy;
  biased.tv_err_check = 0.034;
  JudgeConvergence(biased);
  EXPECT_FALSE(biased.converged);
  // A tv_err that holds still converges whatever the replicates' spread says
  // (standard spec, sphere-field at alpha 0.5: F ~ 0.4 tv_err at N, an
  // eighth of that at 2N, tv_err the same to 0.1 %).
  ShotCheck still = Measured(2.628e-5, 2.628e-5, 0.0, 0.0, 1.2487e-6, 1.2477e-6);
  still.tv_err_noise = 4.98e-7;
  still.tv_err_noise_check = 6.13e-8;
  JudgeConvergence(still);
  EXPECT_NEAR(still.d_tv_err, 1.0e-3 / 1.2487, 1e-4);
  EXPECT_TRUE(still.converged);
}

// The same noise is part of the reference's own temporal variance: a
// glint-plane reference (vr-jitter, 8 x 8 samples) whose tv_ref fell by 30 %
// at 16 x 16, all of it F, converges; a tv_ref that moves beyond its noise
// does not.
TEST(ShotCheck, TheReferencesOwnNoiseIsTakenOutOfTvRef) {
  ShotCheck sparkly = Measured(1.0, 0.695, 0.0, 0.0, 0.5, 0.5);
  JudgeConvergence(sparkly);
  EXPECT_FALSE(sparkly.converged);
  sparkly.tv_err_noise = 0.39;
  sparkly.tv_err_noise_check = 0.087;
  JudgeConvergence(sparkly);
  EXPECT_NEAR(sparkly.d_tv_ref, std::abs(0.608 / 0.61 - 1), 1e-12);
  EXPECT_TRUE(sparkly.converged);
  ShotCheck moving = sparkly;
  moving.tv_ref_check = 0.5;
  JudgeConvergence(moving);
  EXPECT_FALSE(moving.converged);
}

// A glint reference's sparkles per frame are part of what converges: the
// far rows' sparkles that a glint-plane reference's own noise makes at
// 8 x 8 samples (515 a frame, 493 at 16 x 16 over the whole frame, a 4 %
// change, passes; 1.7 times the far rows' alone would not). A check without
// sparkle statistics (both 0) passes as before.
TEST(ShotCheck, AGlintReferencesSparklesMustHoldStill) {
  ShotCheck still = Measured(1.0, 1.0, 0.0, 0.0, 0.5, 0.5);
  still.sparkle_count = 515.0;
  still.sparkle_count_check = 493.0;
  JudgeConvergence(still);
  EXPECT_NEAR(still.d_sparkle_count, 22.0 / 515.0, 1e-12);
  EXPECT_TRUE(still.converged);
  ShotCheck noisy = still;
  noisy.sparkle_count = 29.8;
  noisy.sparkle_count_check = 17.8;
  JudgeConvergence(noisy);
  EXPECT_FALSE(noisy.converged);
  ShotCheck appearing = still;
  appearing.sparkle_count = 0.0;
  appearing.sparkle_count_check = 3.0;
  JudgeConvergence(appearing);
  EXPECT_FALSE(appearing.converged);
  ShotCheck smooth = Measured(1.0, 1.0, 0.0, 0.0, 0.5, 0.5);
  JudgeConvergence(smooth);
  EXPECT_EQ(smooth.d_sparkle_count, 0.0);
  EXPECT_TRUE(smooth.converged);
}

}  // namespace
}  // namespace shimmer::experiments

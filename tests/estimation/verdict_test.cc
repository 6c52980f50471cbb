// The quality checks of verdict.h: each fails on a constructed bad case, passes on a good one,
// and says what to try.
#include "ctid/estimation/verdict.h"

#include <cmath>
#include <complex>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace ctid::verdict_test {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::VectorXcd values(std::initializer_list<std::complex<double>> list) {
  Eigen::VectorXcd v(static_cast<Eigen::Index>(list.size()));
  Eigen::Index k = 0;
  for (const auto& x : list) v(k++) = x;
  return v;
}

TEST(Verdict, StartsUsableAndSaysNothing) {
  const Verdict v;
  EXPECT_TRUE(v.usable);
  EXPECT_TRUE(v.reasons.empty());
  EXPECT_EQ(v.summary(), "");
}

TEST(Verdict, FailCollectsReasonsAndEachRemedyOnce) {
  Verdict v;
  v.fail("first", {verdict_advice::lower_order});
  v.fail("second", {verdict_advice::lower_order, verdict_advice::more_data});
  EXPECT_FALSE(v.usable);
  ASSERT_EQ(v.reasons.size(), 2u);
  EXPECT_EQ(v.advice, std::string(verdict_advice::lower_order) + "; " +
                          std::string(verdict_advice::more_data));
  EXPECT_EQ(v.summary(), "no usable model: first; second. Try: " + v.advice + ".");
}

TEST(Verdict, FiniteCheck) {
  Verdict good;
  check_finite(good, true, "a parameter");
  EXPECT_TRUE(good.usable);
  Verdict bad;
  check_finite(bad, false, "a parameter");
  EXPECT_FALSE(bad.usable);
  EXPECT_THAT(bad.reasons.at(0), HasSubstr("a parameter is not finite"));
}

TEST(Verdict, FitCheck) {
  Verdict good;
  check_fit(good, 92.0, 80.0);
  check_fit(good, 79.5, 80.0);  // within the tolerance of the start
  check_fit(good, 5.0, kNaN);   // no start known
  EXPECT_TRUE(good.usable);

  Verdict negative;
  check_fit(negative, -82.5, kNaN);
  EXPECT_FALSE(negative.usable);
  EXPECT_THAT(negative.reasons.at(0), HasSubstr("-82.5 % is negative"));
  EXPECT_THAT(negative.advice, HasSubstr(verdict_advice::lower_order));

  Verdict worse;
  check_fit(worse, 40.0, 60.0);
  EXPECT_FALSE(worse.usable);
  EXPECT_THAT(worse.reasons.at(0), HasSubstr("worse than the start's 60 %"));

  Verdict not_finite;
  check_fit(not_finite, kNaN, 60.0);
  EXPECT_FALSE(not_finite.usable);
}

TEST(Verdict, ClosedLoopFitCheck) {
  Verdict good;
  check_closed_loop_fit(good, 48.0, 44.0);
  check_closed_loop_fit(good, 28.4, 45.3);  // a consistent fit can fit worse than a good start
  check_closed_loop_fit(good, kNaN, 44.0);  // an unstable loop is another check's business
  check_closed_loop_fit(good, 20.0, kNaN);  // no start known
  check_closed_loop_fit(good, 5.0, -3.0);   // a start that explains nothing sets no bar
  EXPECT_TRUE(good.usable);

  // The true loop's fit from r is positive whatever the noise: a negative one is a wrong loop,
  // whatever its start's.
  for (const double start : {-3.0, 14.0, kNaN}) {
    Verdict negative;
    check_closed_loop_fit(negative, -5.0, start);
    EXPECT_FALSE(negative.usable) << start;
    ASSERT_EQ(negative.reasons.size(), 1U);
    EXPECT_THAT(negative.reasons[0], HasSubstr("closed-loop fit from the reference -5 % is "
                                               "negative"));
    EXPECT_THAT(negative.advice, HasSubstr(verdict_advice::lower_order));
  }

  Verdict astray;
  check_closed_loop_fit(astray, 0.0178, 14.03);
  EXPECT_FALSE(astray.usable);
  EXPECT_THAT(astray.reasons.at(0), HasSubstr("closed-loop fit from the reference 0.0178 % is "
                                              "less than half the start's 14.03 %"));
  EXPECT_THAT(astray.advice, HasSubstr(verdict_advice::better_start));
}

TEST(Verdict, StabilityCheckIgnoresIntegrators) {
  Verdict good;
  check_stable(good, values({{-1.0, 2.0}, {-1.0, -2.0}, {0.0, 0.0}}));
  EXPECT_TRUE(good.usable);
  Verdict bad;
  check_stable(bad, values({{-1.0, 0.0}, {0.5, 3.0}, {0.5, -3.0}}));
  EXPECT_FALSE(bad.usable);
  EXPECT_THAT(bad.reasons.at(0), HasSubstr("is not stable"));
  EXPECT_EQ(bad.reasons.size(), 1u);
}

TEST(Verdict, StandardErrorCheck) {
  Eigen::VectorXd v(2);
  v << 10.0, 3.0;
  Eigen::VectorXd se(2);
  se << 0.5, kNaN;  // NaN: no covariance, not a failure
  Verdict good;
  check_standard_errors(good, {"w1", "w2"}, v, se);
  EXPECT_TRUE(good.usable);
  se << 0.5, 4.0;
  Verdict bad;
  check_standard_errors(bad, {"w1", "w2"}, v, se);
  EXPECT_FALSE(bad.usable);
  ASSERT_EQ(bad.reasons.size(), 1u);
  EXPECT_THAT(bad.reasons[0], HasSubstr("of w2 3 is larger than its value"));
}

TEST(Verdict, CancellationCheck) {
  const Eigen::VectorXcd poles = values({{-0.1, 10.0}, {-0.1, -10.0}, {-2.0, 0.0}});
  Verdict good;  // an anti-resonance 2 % away from the resonance is a real feature
  check_cancellation(good, poles, values({{-0.1, 9.8}, {-0.1, -9.8}}));
  EXPECT_TRUE(good.usable);
  Verdict bad;
  check_cancellation(bad, poles, values({{-2.0005, 0.0}}));
  EXPECT_FALSE(bad.usable);
  EXPECT_THAT(bad.reasons.at(0), HasSubstr("a zero cancels the pole -2"));
  Verdict pair;
  check_cancellation(pair, poles, values({{-0.1, 10.001}, {-0.1, -10.001}}));
  EXPECT_FALSE(pair.usable);
  EXPECT_EQ(pair.reasons.size(), 1u);  // one report for the conjugate pair
}

TEST(Verdict, ConditioningCheck) {
  Verdict good;
  check_conditioning(good, 1e-6);
  check_conditioning(good, kNaN);  // never formed: nothing to say
  EXPECT_TRUE(good.usable);
  Verdict bad;
  check_conditioning(bad, 1e-15);
  EXPECT_FALSE(bad.usable);
  EXPECT_THAT(bad.reasons.at(0), HasSubstr("numerically singular"));
  EXPECT_THAT(bad.advice, HasSubstr(verdict_advice::more_data));
}

}  // namespace
}  // namespace ctid::verdict_test

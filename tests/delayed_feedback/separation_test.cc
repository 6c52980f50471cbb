// Step 2 separations with exact and perturbed α, β, γ.
#include "ctid/delayed_feedback/separation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/simulation/delayed_feedback.h"
#include "support/de_iuliis_systems.h"

namespace ctid::separation_test {
namespace {

DelayedFeedbackLoop paper_loop() { return test_support::paper_feedback_loop(); }

double coefficient_error(const TransferFunction& a, const TransferFunction& b) {
  const TransferFunction x = a.normalized();
  const TransferFunction y = b.normalized();
  const int dn = std::max(x.numerator().degree(), y.numerator().degree());
  const int dd = std::max(x.denominator().degree(), y.denominator().degree());
  double e = 0.0;
  for (int i = 0; i <= dn; ++i)
    e = std::max(e, std::abs(x.numerator().coefficient(i) - y.numerator().coefficient(i)));
  for (int i = 0; i <= dd; ++i)
    e = std::max(e, std::abs(x.denominator().coefficient(i) - y.denominator().coefficient(i)));
  return e;
}

TEST(FeedbackSeparation, GcdIsExactWithExactPolynomials) {
  const DelayedFeedbackLoop loop = paper_loop();
  const GcdSeparationResult r =
      separate_approximate_gcd(loop.alpha(), loop.beta(), loop.gamma(), 3, 3);
  EXPECT_LT(coefficient_error(r.forward, loop.forward), 1e-9);
  EXPECT_LT(coefficient_error(r.feedback, loop.feedback), 1e-9);
  // Exact common factors: the cancelled singular values vanish, the gap is huge.
  EXPECT_GT(r.forward_gap, 1e8);
  EXPECT_GT(r.feedback_gap, 1e8);
  EXPECT_EQ(r.forward_singular_values.size(), 6);
  EXPECT_EQ(r.feedback_singular_values.size(), 5);
  // What was cancelled is D_H in F̃ and the monic N_F in H̃.
  const Polynomial dh = loop.feedback.denominator().monic();
  for (int i = 0; i <= 3; ++i)
    EXPECT_NEAR(r.cancelled_forward.coefficient(i), dh.coefficient(i), 1e-8);
  const Polynomial nf = loop.forward.numerator().monic();
  for (int i = 0; i <= 2; ++i)
    EXPECT_NEAR(r.cancelled_feedback.coefficient(i), nf.coefficient(i), 1e-8);
}

TEST(FeedbackSeparation, KroneckerIsExactWithExactPolynomials) {
  const DelayedFeedbackLoop loop = paper_loop();
  const KroneckerSeparationResult r =
      separate_kronecker(loop.alpha(), loop.beta(), loop.gamma(), 3, 3);
  EXPECT_LT(r.cost, 1e-20);
  EXPECT_LT(coefficient_error(r.forward, loop.forward), 1e-8);
  EXPECT_LT(coefficient_error(r.feedback, loop.feedback), 1e-8);
  EXPECT_GT(r.starts, 1);
  EXPECT_NEAR(kronecker_cost(loop.alpha(), loop.beta(), loop.gamma(), loop.forward, loop.feedback),
              0.0, 1e-20);
}

TEST(FeedbackSeparation, UnequalOrdersAndRealRootsAreExact) {
  // Different orders (n = 2, m = 1) and real roots only.
  const DelayedFeedbackLoop loop{TransferFunction(Polynomial{1.0, 3.0}, Polynomial{2.0, 3.0, 1.0}),
                                 TransferFunction(Polynomial{4.0}, Polynomial{5.0, 1.0}), 0.2};
  const KroneckerSeparationResult r =
      separate_kronecker(loop.alpha(), loop.beta(), loop.gamma(), 2, 1);
  EXPECT_LT(r.cost, 1e-20);
  EXPECT_LT(coefficient_error(r.forward, loop.forward), 1e-8);
  EXPECT_LT(coefficient_error(r.feedback, loop.feedback), 1e-8);
}

TEST(FeedbackSeparation, SmallPerturbationGivesCloseModelsAndSmallerJThanGcd) {
  const DelayedFeedbackLoop loop = paper_loop();
  Eigen::VectorXd a = loop.alpha().coefficients();
  Eigen::VectorXd b = loop.beta().coefficients();
  Eigen::VectorXd g = loop.gamma().coefficients();
  a(1) += 1e-3;
  b(2) -= 2e-3;
  g(0) += 1e-3;
  const Polynomial ap(a), bp(b), gp(g);
  const KroneckerSeparationResult k = separate_kronecker(ap, bp, gp, 3, 3);
  const GcdSeparationResult d = separate_approximate_gcd(ap, bp, gp, 3, 3);
  EXPECT_LT(coefficient_error(k.forward, loop.forward), 0.05);
  EXPECT_LT(coefficient_error(d.forward, loop.forward), 0.05);
  // min J minimises J: it cannot do worse than its own GCD start.
  EXPECT_LE(k.cost, kronecker_cost(ap, bp, gp, d.forward, d.feedback) * (1 + 1e-9));
  EXPECT_GT(d.forward_gap, 10.0);
}

TEST(FeedbackSeparation, BadInputIsNamed) {
  const DelayedFeedbackLoop loop = paper_loop();
  EXPECT_THAT([&] { separate_approximate_gcd(loop.alpha(), loop.beta(), loop.gamma(), 0, 6); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("forward order n")));
  EXPECT_THAT([&] { separate_kronecker(loop.alpha(), loop.beta(), loop.gamma(), 2, 3); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr("degree n + m")));
}

}  // namespace
}  // namespace ctid::separation_test

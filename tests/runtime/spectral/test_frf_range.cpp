// Frequency responses at the ends of the range of double (issue 39 §1, "overflow flagged ok"):
// a point whose data or value leave the range is flagged `overflow` — never `ok` with inf, never
// `pole` when the system is not singular. References: the 1-DOF closed form 1/(K − Ω²M), evaluated
// in long double (range to 1e4932), and the scale-free rcond of the system scaled to unit size.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <vector>

#include "mbsgen/runtime/model/descriptor_model.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/spectral/descriptor_eigen.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"

namespace {

using mbsgen::FrfFlag;
using mbsgen::FrfMethod;

Eigen::MatrixXd one(double x) { return Eigen::MatrixXd::Constant(1, 1, x); }

const FrfMethod kMethods[] = {FrfMethod::direct, FrfMethod::hessenberg, FrfMethod::real, FrfMethod::banded};

// M = 1e308 kg, K = 1.5e308 N/m: at 1 Hz and 10 Hz, Ω²M = 3.9e309 and 3.9e311 exceed the range
// (before: `pole`, rcond 0, from direct and banded). Each method either finds the value (those
// that never assemble −Ω²M + K: 1/(K − Ω²M) within 1e-12 relative, a subnormal 2.6e-310 keeping
// 12 digits) or flags the point overflow; none says pole (the scaled system is far from singular)
// and none returns a non-finite value flagged ok.
TEST(FrfRange, HugeMassOverflowsRatherThanPoles) {
  const mbsgen::LinearModel m(one(1e308), one(0), one(1.5e308), one(1), one(1), Eigen::MatrixXd());
  Eigen::VectorXd w(3);
  w << 2 * M_PI * 0.1, 2 * M_PI * 1, 2 * M_PI * 10;
  for (FrfMethod meth : kMethods) {
    mbsgen::FrfOptions opt;
    opt.method = meth;
    mbsgen::FrequencyResponse f(m, opt);
    f.compute(w, 0);
    for (int k = 0; k < 3; ++k) {
      const FrfFlag flag = f.flags()[static_cast<std::size_t>(k)];
      const long double truth = 1.0L / (1.5e308L - static_cast<long double>(w[k]) * w[k] * 1e308L);
      EXPECT_NE(flag, FrfFlag::pole) << to_string(meth) << " " << k;
      if (flag == FrfFlag::overflow) {
        EXPECT_TRUE(std::isnan(f.response()(0, k).real()));
      } else {
        EXPECT_NEAR(f.response()(0, k).real(), static_cast<double>(truth), 1e-12 * std::abs(static_cast<double>(truth)))
            << to_string(meth) << " " << k;
      }
    }
    if (meth == FrfMethod::direct) {
      EXPECT_EQ(f.flags()[1], FrfFlag::overflow);  // was pole
    }
  }
}

// M = 1e-10, K = 1e-307, B = 1.7e308 at Ω ≈ 6e-150 rad/s: the value 1.7e308/1e-307 = 1.7e615 is
// beyond the range, the system (scaled) perfectly conditioned: overflow for every method (before:
// `pole` with rcond 1).
TEST(FrfRange, ValueBeyondTheRangeIsOverflow) {
  const mbsgen::LinearModel m(one(1e-10), one(0), one(1e-307), one(1.7e308), one(1), Eigen::MatrixXd());
  Eigen::VectorXd w(1);
  w << 2 * M_PI * 1e-150;
  for (FrfMethod meth : kMethods) {
    mbsgen::FrfOptions opt;
    opt.method = meth;
    mbsgen::FrequencyResponse f(m, opt);
    f.compute(w, 0);
    EXPECT_EQ(f.flags()[0], FrfFlag::overflow) << to_string(meth);
    EXPECT_TRUE(std::isnan(f.response()(0, 0).real())) << to_string(meth);
    opt.on_pole = mbsgen::PoleHandling::raise;
    mbsgen::FrequencyResponse g(m, opt);
    EXPECT_THROW(g.compute(w, 0), mbsgen::NonFiniteError) << to_string(meth);
  }
}

// A true pole stays a pole: M = K = 1e300 (scaled: 1 and 1) at Ω = 1 rad/s exactly.
TEST(FrfRange, PoleAtExtremeScaleIsStillAPole) {
  const mbsgen::LinearModel m(one(1e300), one(0), one(1e300), one(1), one(1), Eigen::MatrixXd());
  Eigen::VectorXd w(1);
  w << 1.0;
  mbsgen::FrequencyResponse f(m, {});
  f.compute(w, 0);
  EXPECT_EQ(f.flags()[0], FrfFlag::pole);
}

// The descriptor path: E = 1, A = −1e-307, B = 1.7e308 at Ω = 0: x = 1.7e615, overflow (before:
// pole, rcond 1).
TEST(FrfRange, DescriptorValueBeyondTheRangeIsOverflow) {
  const mbsgen::DescriptorModel d(one(1), one(-1e-307), one(1.7e308), one(1));
  Eigen::VectorXd w(2);
  w << 0.0, 1e-300;
  const mbsgen::DescriptorFrf r = mbsgen::descriptor_frequency_response(d, w, 0);
  for (int k = 0; k < 2; ++k) EXPECT_EQ(r.flags[static_cast<std::size_t>(k)], FrfFlag::overflow) << k;
  EXPECT_TRUE(std::isnan(r.response(0, 0).real()));
}

// Eigenvalues of data at the ends of the range (before: an error bound of inf and the verdict
// zero_within_bound for λ = 1.22i; `-` for λ = 1e300 i; "null_space: LAPACK dormqr rejected
// argument 7" for a 2×2 of 1e308s). Solved exactly scaled by powers of two: λ² = −K/M in closed
// form, to a few ulps, with a relative bound of rounding size.
TEST(ModesRange, ExtremeScalesKeepTheirEigenvaluesAndBounds) {
  struct Case {
    double m, k;
  };
  for (const Case& c : {Case{1e308, 1.5e308}, Case{1e-300, 1e300}, Case{1e-200, 1e-250}, Case{4e300, 1e-300}}) {
    mbsgen::QuadraticEigenSolver solver(1);
    solver.compute(one(c.m), one(0), one(c.k));
    ASSERT_EQ(solver.modes().size(), 2u);
    const double w = static_cast<double>(std::sqrt(static_cast<long double>(c.k) / c.m));
    for (const mbsgen::Mode& md : solver.modes()) {
      EXPECT_EQ(md.kind, mbsgen::EigenvalueKind::finite);
      EXPECT_FALSE(md.zero_within_bound) << c.m;
      EXPECT_NEAR(std::abs(md.lambda.imag()), w, 4e-16 * w) << c.m;
      EXPECT_LE(md.error_bound, 1e-12 * w) << c.m;
    }
    EXPECT_EQ(solver.stability(), mbsgen::Stability::marginal) << c.m;
  }
  Eigen::MatrixXd M(2, 2);
  M << 1e308, 1e308, 1e308, 1.7e308;  // K = M: λ = ±i twice
  mbsgen::QuadraticEigenSolver solver(2);
  solver.compute(M, Eigen::MatrixXd::Zero(2, 2), M);
  for (const mbsgen::Mode& md : solver.modes()) EXPECT_NEAR(std::abs(md.lambda.imag()), 1.0, 1e-12);
  // The descriptor solver: E = 1e-300, A = −1e300: λ = −1e600 is beyond the range... so A = −1e-10,
  // E = 1e-300: λ = −1e290.
  mbsgen::DescriptorEigenSolver d;
  d.compute(one(1e-300), one(-1e-10));
  ASSERT_EQ(d.modes().size(), 1u);
  EXPECT_NEAR(d.modes()[0].lambda.real(), -1e290, 4e-16 * 1e290);
  EXPECT_EQ(d.stability(), mbsgen::Stability::stable);
}

}  // namespace

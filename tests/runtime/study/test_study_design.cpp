// Designs of experiments and their statistics (study_design.hpp): quantiles against closed values
// and an independent CDF (std::erfc), determinism bitwise, the stratification of a Latin
// hypercube, the Saltelli layout, and Sobol' indices against analytic values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/study/study_design.hpp"

using mbsgen::Design;
using mbsgen::Distribution;
using mbsgen::ParameterDistribution;
using mbsgen::StudyDesign;

namespace {

const double pi = 3.14159265358979323846;

std::uint64_t bits(double x) {
  std::uint64_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

ParameterDistribution dist(const std::string& name, Distribution kind, double a, double b) {
  ParameterDistribution d;
  d.name = name, d.kind = kind, d.a = a, d.b = b;
  return d;
}

std::vector<ParameterDistribution> unit_cube(std::size_t d, double lo = 0, double hi = 1) {
  std::vector<ParameterDistribution> v;
  for (std::size_t k = 0; k < d; ++k) v.push_back(dist("x" + std::to_string(k), Distribution::uniform, lo, hi));
  return v;
}

// The CDF, independently of the library's quantile (std::erfc for Φ).
double cdf(const ParameterDistribution& d, double x) {
  switch (d.kind) {
    case Distribution::uniform: return (x - d.a) / (d.b - d.a);
    case Distribution::normal: return 0.5 * std::erfc(-(x - d.a) / (d.b * std::sqrt(2.0)));
    case Distribution::lognormal: return 0.5 * std::erfc(-std::log(x / d.a) / (std::log(d.b) * std::sqrt(2.0)));
  }
  return 0;
}

double pdf(const ParameterDistribution& d, double x) {
  const double s = std::sqrt(2 * pi);
  switch (d.kind) {
    case Distribution::uniform: return 1 / (d.b - d.a);
    case Distribution::normal: return std::exp(-0.5 * std::pow((x - d.a) / d.b, 2)) / (d.b * s);
    case Distribution::lognormal:
      return std::exp(-0.5 * std::pow(std::log(x / d.a) / std::log(d.b), 2)) / (x * std::log(d.b) * s);
  }
  return 0;
}

// f evaluated at every point of a design, in the design's order.
template <class F>
std::vector<double> evaluate(const StudyDesign& design, F f) {
  std::vector<double> values(design.size());
  for (std::size_t i = 0; i < design.size(); ++i) values[i] = f(design.point(i));
  return values;
}

}  // namespace

TEST(StudyDesign, SplitMix64MatchesItsReferenceOutputs) {
  // The generator seeded with 1234567 (Rosetta Code "Pseudo-random numbers/Splitmix64", Vigna's
  // splitmix64.c): the k-th output is splitmix64(seed + k·golden). Pins the hash bit for bit, on
  // which the cross-platform reproducibility of every design rests.
  const std::uint64_t expected[] = {6457827717110365317ULL, 3203168211198807973ULL, 9817491932198370423ULL,
                                    4593380528125082431ULL, 16408922859458223821ULL};
  for (std::uint64_t k = 0; k < 5; ++k)
    EXPECT_EQ(mbsgen::detail::splitmix64(1234567ULL + k * 0x9e3779b97f4a7c15ULL), expected[k]) << k;
}

TEST(StudyDesign, QuantilesAgainstClosedValues) {
  // Φ⁻¹(0.975) = 1.959963984540054 (16 digits, e.g. Abramowitz & Stegun 26.2 / any table); 1e-14
  // relative allows a few ulps of Boost's erfc_inv plus the 1e-17 rounding of 0.975 itself.
  const double z975 = 1.959963984540054;
  const auto std_normal = dist("z", Distribution::normal, 0, 1);
  EXPECT_NEAR(mbsgen::quantile(std_normal, 0.975), z975, 1e-14 * z975);
  EXPECT_NEAR(mbsgen::quantile(std_normal, 0.025), -z975, 1e-14 * z975);
  EXPECT_EQ(mbsgen::quantile(std_normal, 0.5), 0.0);
  const auto normal = dist("m", Distribution::normal, 10, 2);
  EXPECT_NEAR(mbsgen::quantile(normal, 0.975), 10 + 2 * z975, 1e-14 * (10 + 2 * z975));
  EXPECT_EQ(mbsgen::quantile(normal, 0.5), 10.0);
  // uniform: a + (b − a) u, exact in binary for these values
  const auto uniform = dist("u", Distribution::uniform, 2, 5);
  EXPECT_EQ(mbsgen::quantile(uniform, 0.25), 2.75);
  EXPECT_EQ(mbsgen::quantile(uniform, 0.5), 3.5);
  // lognormal: the median a exactly at ½, and a·b at Φ(1) = 0.8413447460685429 (one standard
  // deviation of ln X); Φ(1) is computed with erfc (error ~1e-16, amplified 1/φ(1)·ln b ≈ 1.7
  // times), so 1e-14 relative.
  const auto lognormal = dist("c", Distribution::lognormal, 3, 1.5);
  EXPECT_EQ(mbsgen::quantile(lognormal, 0.5), 3.0);
  const double phi1 = 0.5 * std::erfc(-1 / std::sqrt(2.0));
  EXPECT_NEAR(phi1, 0.8413447460685429, 1e-16);
  EXPECT_NEAR(mbsgen::quantile(lognormal, phi1), 4.5, 1e-14 * 4.5);
}

TEST(StudyDesign, QuantileRoundTripsThroughTheCdf) {
  // u → x = quantile(u) → CDF(x) with the CDF from std::erfc: 1e-14 relative in u, the error of
  // Φ⁻¹ (a few ulps) times the conditioning of the CDF (|x|φ(x)/Φ(x) ≲ 40 down to u = 1e-10),
  // plus what rounding x to a double alone can move the CDF, pdf(x)·|x|·ε (it dominates for
  // U(−1, 3) at u = 1e-10, where x = −1 + 4e-10 carries an absolute error of ~1e-16).
  const std::vector<ParameterDistribution> ds = {dist("u", Distribution::uniform, -1, 3),
                                                 dist("n", Distribution::normal, 5, 0.5),
                                                 dist("l", Distribution::lognormal, 0.2, 3)};
  const double us[] = {1e-10, 1e-3, 0.1, 0.3, 0.5, 0.7, 0.9, 0.999, 1 - 1e-6};
  for (const auto& d : ds)
    for (const double u : us) {
      const double x = mbsgen::quantile(d, u);
      const double eps = std::numeric_limits<double>::epsilon();
      EXPECT_NEAR(cdf(d, x), u, 1e-14 * u + pdf(d, x) * std::abs(x) * eps) << d.name << " at " << u;
    }
}

TEST(StudyDesign, QuantileRejectsUOutsideTheOpenInterval) {
  const auto d = dist("k", Distribution::normal, 0, 1);
  for (const double u : {0.0, 1.0, -0.5, 1.5, std::nan("")}) EXPECT_THROW(mbsgen::quantile(d, u), mbsgen::Error) << u;
}

TEST(StudyDesign, ParsesDistributions) {
  const auto u = mbsgen::parse_distribution("k_1=uniform:-3.5:1e3");
  EXPECT_EQ(u.name, "k_1");
  EXPECT_EQ(u.kind, Distribution::uniform);
  EXPECT_EQ(u.a, -3.5);
  EXPECT_EQ(u.b, 1000.0);
  const auto n = mbsgen::parse_distribution("m=normal:2.5:0.1");
  EXPECT_EQ(n.kind, Distribution::normal);
  EXPECT_EQ(n.a, 2.5);
  EXPECT_EQ(n.b, 0.1);
  const auto l = mbsgen::parse_distribution("c.damping=lognormal:0.02:1.5");
  EXPECT_EQ(l.name, "c.damping");
  EXPECT_EQ(l.kind, Distribution::lognormal);
  EXPECT_EQ(l.a, 0.02);
  EXPECT_EQ(l.b, 1.5);
  // format_distribution reads back bitwise (17 significant digits)
  for (const auto& d : {u, n, l, dist("x", Distribution::normal, 0.1 + 0.2, 1.0 / 3)}) {
    const auto back = mbsgen::parse_distribution(mbsgen::format_distribution(d));
    EXPECT_EQ(back.name, d.name);
    EXPECT_EQ(back.kind, d.kind);
    EXPECT_EQ(bits(back.a), bits(d.a));
    EXPECT_EQ(bits(back.b), bits(d.b));
  }
}

TEST(StudyDesign, RejectsBadDistributionTexts) {
  const char* bad[] = {
      "k=gauss:0:1",         // unknown kind
      "k=uniform:1",         // missing number
      "k=normal",            // missing numbers
      "k=uniform:1:2:3",     // one too many
      "k=normal:0:0",        // standard deviation 0
      "k=normal:0:-1",       // negative standard deviation
      "k=lognormal:1:1",     // factor 1
      "k=lognormal:1:0.5",   // factor < 1
      "k=lognormal:0:2",     // median 0
      "k=uniform:2:2",       // a = b
      "k=uniform:3:2",       // a > b
      "k=uniform:one:2",     // not a number
      "k=uniform:1:2x",      // trailing junk
      "k=uniform:1:2 ",      // trailing space
      "k=uniform::2",        // empty number
      "k=uniform:1:inf",     // not finite
      "k=normal:nan:1",      // not finite
      "=uniform:1:2",        // no name
      "k uniform:1:2",       // no '='
      "k x=uniform:1:2",     // space in the name
  };
  for (const char* text : bad) {
    try {
      mbsgen::parse_distribution(text);
      ADD_FAILURE() << "no exception for " << text;
    } catch (const mbsgen::Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(std::string("\"") + text + "\""), std::string::npos) << message;
      EXPECT_NE(message.find("NAME=uniform:LO:HI"), std::string::npos) << message;
    }
  }
}

TEST(StudyDesign, ParsesDesigns) {
  EXPECT_EQ(mbsgen::parse_design("mc"), Design::monte_carlo);
  EXPECT_EQ(mbsgen::parse_design("monte-carlo"), Design::monte_carlo);
  EXPECT_EQ(mbsgen::parse_design("lhs"), Design::latin_hypercube);
  EXPECT_EQ(mbsgen::parse_design("latin-hypercube"), Design::latin_hypercube);
  EXPECT_EQ(mbsgen::parse_design("saltelli"), Design::saltelli);
  for (const Design d : {Design::monte_carlo, Design::latin_hypercube, Design::saltelli})
    EXPECT_EQ(mbsgen::parse_design(mbsgen::design_name(d)), d);
  try {
    mbsgen::parse_design("sobol");
    ADD_FAILURE();
  } catch (const mbsgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("\"sobol\""), std::string::npos) << e.what();
  }
}

TEST(StudyDesign, RejectsBadDesigns) {
  EXPECT_THROW(StudyDesign(Design::monte_carlo, unit_cube(2), 0, 1), mbsgen::Error);
  EXPECT_THROW(StudyDesign(Design::monte_carlo, {}, 10, 1), mbsgen::Error);
  EXPECT_THROW(StudyDesign(Design::monte_carlo, {dist("a", Distribution::uniform, 1, 1)}, 10, 1), mbsgen::Error);
  EXPECT_THROW(StudyDesign(Design::monte_carlo, {dist("", Distribution::normal, 1, 1)}, 10, 1), mbsgen::Error);
  EXPECT_THROW(StudyDesign(Design::saltelli, {dist("a", Distribution::normal, 0, 1), dist("a", Distribution::normal, 0, 1)},
                           10, 1),
               mbsgen::Error);
  const StudyDesign s(Design::saltelli, unit_cube(3), 10, 1);
  EXPECT_EQ(s.size(), 50u);
  EXPECT_EQ(s.base_size(), 10u);
  EXPECT_EQ(s.dimension(), 3u);
  EXPECT_THROW(s.point(50), mbsgen::Error);
  EXPECT_NO_THROW(s.point(49));
}

TEST(StudyDesign, PointsDoNotDependOnTheOrderOfRequests) {
  // Threads and MPI ranks ask for their own indices: the points requested backwards (and by a
  // second, independently constructed design) equal those requested forwards, bit for bit.
  const std::vector<ParameterDistribution> ds = {dist("a", Distribution::uniform, -1, 2),
                                                 dist("b", Distribution::normal, 3, 0.5),
                                                 dist("c", Distribution::lognormal, 0.1, 2)};
  for (const Design design : {Design::monte_carlo, Design::latin_hypercube, Design::saltelli}) {
    const StudyDesign forward(design, ds, 200, 42);
    std::vector<std::vector<double>> points(forward.size());
    for (std::size_t i = 0; i < forward.size(); ++i) points[i] = forward.point(i);
    const StudyDesign backward(design, ds, 200, 42);
    for (std::size_t i = backward.size(); i-- > 0;) {
      const auto p = backward.point(i);
      for (std::size_t k = 0; k < 3; ++k) ASSERT_EQ(bits(p[k]), bits(points[i][k])) << mbsgen::design_name(design) << i;
    }
    // another seed: different points (all of them, for continuous distributions)
    const StudyDesign other(design, ds, 200, 43);
    std::size_t equal = 0;
    for (std::size_t i = 0; i < other.size(); ++i)
      for (std::size_t k = 0; k < 3; ++k) equal += other.point(i)[k] == points[i][k];
    EXPECT_EQ(equal, 0u) << mbsgen::design_name(design);
  }
}

TEST(StudyDesign, LatinHypercubeStratifiesEveryDimension) {
  // u recovered through the CDF of the uniform distribution (x − a)/(b − a) (exact for U(0, 1)):
  // ⌊u·n⌋ over all i is a permutation of 0..n−1 in every dimension.
  const std::size_t n = 1000, d = 5;
  const auto ds = unit_cube(d, 0, 1);
  const StudyDesign lhs(Design::latin_hypercube, ds, n, 7);
  std::vector<std::vector<std::size_t>> strata(d);
  for (std::size_t i = 0; i < n; ++i) {
    const auto x = lhs.point(i);
    for (std::size_t k = 0; k < d; ++k) {
      const double u = cdf(ds[k], x[k]);
      ASSERT_GT(u, 0.0);
      ASSERT_LT(u, 1.0);
      strata[k].push_back(static_cast<std::size_t>(std::floor(u * static_cast<double>(n))));
    }
  }
  for (std::size_t k = 0; k < d; ++k) {
    std::vector<std::size_t> sorted = strata[k];
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t m = 0; m < n; ++m) ASSERT_EQ(sorted[m], m) << "dimension " << k;
    // and the permutations of different dimensions differ
    if (k > 0) {
      EXPECT_NE(strata[k], strata[k - 1]);
    }
  }
  // A design of one sample is still a valid hypercube.
  const StudyDesign one(Design::latin_hypercube, ds, 1, 7);
  for (const double x : one.point(0)) EXPECT_TRUE(x > 0 && x < 1);
}

TEST(StudyDesign, MonteCarloUniformsHaveTheRightMoments) {
  // U(0,1): mean ½, variance 1/12. Over N = 10⁵ points the sample mean has standard error
  // √(1/12/N) ≈ 9.1e-4 and the sample variance √((μ₄ − σ⁴)/N) = √(1/180/N) ≈ 2.4e-4 (μ₄ = 1/80);
  // each is checked within 5 standard errors (a false alarm with probability ~6e-7 per check, and
  // the seed is fixed anyway). The Latin hypercube must satisfy the same.
  const std::size_t n = 100000, d = 3;
  for (const Design design : {Design::monte_carlo, Design::latin_hypercube}) {
    const StudyDesign mc(design, unit_cube(d), n, 2024);
    std::vector<double> sum(d, 0), sum2(d, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto x = mc.point(i);
      for (std::size_t k = 0; k < d; ++k) sum[k] += x[k], sum2[k] += x[k] * x[k];
    }
    const double N = static_cast<double>(n);
    for (std::size_t k = 0; k < d; ++k) {
      const double mean = sum[k] / N, var = (sum2[k] - N * mean * mean) / (N - 1);
      EXPECT_NEAR(mean, 0.5, 5 * std::sqrt(1.0 / 12 / N)) << mbsgen::design_name(design) << k;
      EXPECT_NEAR(var, 1.0 / 12, 5 * std::sqrt(1.0 / 180 / N)) << mbsgen::design_name(design) << k;
    }
  }
}

TEST(StudyDesign, SaltelliLayout) {
  // AB_j rows equal A rows except column j, which equals B's; A is the Monte Carlo design of the
  // same seed; A and B differ everywhere.
  const std::size_t n = 64, d = 4;
  const auto ds = unit_cube(d, -2, 5);
  const StudyDesign s(Design::saltelli, ds, n, 99);
  const StudyDesign mc(Design::monte_carlo, ds, n, 99);
  ASSERT_EQ(s.size(), n * (d + 2));
  for (std::size_t r = 0; r < n; ++r) {
    const auto a = s.point(r), b = s.point(n + r), m = mc.point(r);
    for (std::size_t k = 0; k < d; ++k) {
      EXPECT_EQ(bits(a[k]), bits(m[k]));
      EXPECT_NE(a[k], b[k]);
    }
    for (std::size_t j = 0; j < d; ++j) {
      const auto ab = s.point(n * (2 + j) + r);
      for (std::size_t k = 0; k < d; ++k) EXPECT_EQ(bits(ab[k]), bits(k == j ? b[k] : a[k])) << r << j << k;
    }
  }
}

TEST(StudyDesign, SobolIndicesOfAnAdditiveFunction) {
  // f = Σ c_k x_k, x_k ~ U(0,1) independent: V_k = c_k²/12, no interactions, so exactly
  // S_k = ST_k = c_k²/Σc². Tolerance: the estimators' sampling error, 4 bootstrap half-widths
  // (a 95 % half-width is ≈ 2σ, so ≈ 8σ) plus a floor of 1e-3 for a half-width that is itself
  // noisy; and the interval must be informative (< 0.1 wide) at n = 2¹⁴.
  const std::vector<double> c = {1, 2, 3};
  const std::size_t n = std::size_t{1} << 14, d = c.size();
  const StudyDesign s(Design::saltelli, unit_cube(d), n, 5);
  const auto f = evaluate(s, [&](const std::vector<double>& x) { return c[0] * x[0] + c[1] * x[1] + c[2] * x[2]; });
  const auto r = mbsgen::sobol_indices(f, n, d, 500, 11);
  EXPECT_EQ(r.rows_used, n);
  const double sum_c2 = 1 + 4 + 9;
  EXPECT_NEAR(r.variance, sum_c2 / 12, 0.05 * sum_c2 / 12);  // sampling error ≈ 1 % at 2n values
  for (std::size_t k = 0; k < d; ++k) {
    const double exact = c[k] * c[k] / sum_c2;
    const auto& x = r.indices[k];
    EXPECT_NEAR(x.first, exact, 4 * (x.first_high - x.first_low) / 2 + 1e-3) << k;
    EXPECT_NEAR(x.total, exact, 4 * (x.total_high - x.total_low) / 2 + 1e-3) << k;
    EXPECT_LE(x.first_low, x.first);
    EXPECT_GE(x.first_high, x.first);
    EXPECT_LE(x.total_low, x.total);
    EXPECT_GE(x.total_high, x.total);
    EXPECT_LT(x.first_high - x.first_low, 0.1) << k;
    EXPECT_LT(x.total_high - x.total_low, 0.1) << k;
  }
}

TEST(StudyDesign, SobolIndicesOfTheIshigamiFunction) {
  // f = sin x₁ + a sin² x₂ + b x₃⁴ sin x₁, x_k ~ U(−π, π), a = 7, b = 0.1 (Ishigami & Homma 1990,
  // Proc. ISUMA '90, 398), the standard test of Sobol' estimators (Saltelli et al. 2010, Comput.
  // Phys. Commun. 181:259). Its ANOVA terms in closed form (integrals of sin², x⁴ over (−π, π)):
  //   V = a²/8 + bπ⁴/5 + b²π⁸/18 + ½,  V₁ = bπ⁴/5 + b²π⁸/50 + ½,  V₂ = a²/8,  V₃ = 0,
  //   V₁₃ = b²π⁸/18 − b²π⁸/50 (the only interaction); ST₁ = (V₁ + V₁₃)/V, ST₂ = S₂, ST₃ = V₁₃/V.
  // Tolerance as for the additive function: 4 bootstrap half-widths + 1e-3 (S₃ = 0 exactly and
  // its estimate's half-width is small but not zero). Over 40 seeds the largest error was 1.3
  // half-widths; the half-widths at n = 2¹⁴ are ≈ 0.005–0.025.
  const double a = 7, b = 0.1, pi4 = std::pow(pi, 4), pi8 = std::pow(pi, 8);
  const double V = a * a / 8 + b * pi4 / 5 + b * b * pi8 / 18 + 0.5;
  const double V1 = b * pi4 / 5 + b * b * pi8 / 50 + 0.5, V2 = a * a / 8, V13 = b * b * pi8 / 18 - b * b * pi8 / 50;
  const double S[3] = {V1 / V, V2 / V, 0}, ST[3] = {(V1 + V13) / V, V2 / V, V13 / V};
  // the published rounded values, as a check of the closed forms above
  EXPECT_NEAR(S[0], 0.3139, 1e-4);
  EXPECT_NEAR(S[1], 0.4424, 1e-4);
  EXPECT_NEAR(ST[0], 0.5576, 1e-4);
  EXPECT_NEAR(ST[2], 0.2437, 1e-4);

  const std::size_t n = std::size_t{1} << 14, d = 3;
  const StudyDesign s(Design::saltelli, unit_cube(d, -pi, pi), n, 2010);
  const auto f = evaluate(s, [&](const std::vector<double>& x) {
    return std::sin(x[0]) + a * std::pow(std::sin(x[1]), 2) + b * std::pow(x[2], 4) * std::sin(x[0]);
  });
  const auto r = mbsgen::sobol_indices(f, n, d, 500, 3);
  EXPECT_EQ(r.rows_used, n);
  EXPECT_NEAR(r.variance, V, 0.05 * V);  // sampling error of a variance over 2n values: ~2 %
  for (std::size_t k = 0; k < d; ++k) {
    const auto& x = r.indices[k];
    EXPECT_NEAR(x.first, S[k], 4 * (x.first_high - x.first_low) / 2 + 1e-3) << k;
    EXPECT_NEAR(x.total, ST[k], 4 * (x.total_high - x.total_low) / 2 + 1e-3) << k;
    EXPECT_LT(x.first_high - x.first_low, 0.1) << k;
    EXPECT_LT(x.total_high - x.total_low, 0.1) << k;
    EXPECT_GT(x.first_high - x.first_low, 0.0) << k;
  }
}

TEST(StudyDesign, SobolIndicesDropNonFiniteRows) {
  // Failed evaluations (NaN, ∞) in A, B or some AB_j drop their whole row: the result equals,
  // bit for bit, that of the design without those rows (same kept rows in the same order).
  const std::size_t n = 256, d = 3;
  const StudyDesign s(Design::saltelli, unit_cube(d), n, 8);
  auto f = evaluate(s, [](const std::vector<double>& x) { return x[0] + 2 * x[1] * x[2]; });
  const double nan = std::nan(""), inf = HUGE_VAL;
  const std::size_t bad_rows[] = {3, 10, 20, 30};
  f[3] = nan;                 // A
  f[n + 10] = nan;            // B
  f[n * 3 + 20] = -inf;       // AB_1
  f[n * 4 + 30] = inf;        // AB_2
  std::vector<double> reduced;
  for (std::size_t block = 0; block < d + 2; ++block)
    for (std::size_t r = 0; r < n; ++r)
      if (std::find(std::begin(bad_rows), std::end(bad_rows), r) == std::end(bad_rows)) reduced.push_back(f[block * n + r]);
  const auto with = mbsgen::sobol_indices(f, n, d, 50, 1);
  const auto without = mbsgen::sobol_indices(reduced, n - 4, d, 50, 1);
  EXPECT_EQ(with.rows_used, n - 4);
  EXPECT_EQ(without.rows_used, n - 4);
  EXPECT_EQ(bits(with.variance), bits(without.variance));
  for (std::size_t k = 0; k < d; ++k) {
    const auto &x = with.indices[k], &y = without.indices[k];
    for (const auto m : {&mbsgen::SobolIndex::first, &mbsgen::SobolIndex::first_low, &mbsgen::SobolIndex::first_high,
                         &mbsgen::SobolIndex::total, &mbsgen::SobolIndex::total_low, &mbsgen::SobolIndex::total_high}) {
      EXPECT_TRUE(std::isfinite(x.*m));
      EXPECT_EQ(bits(x.*m), bits(y.*m)) << k;
    }
  }
  // the same seed gives the same intervals; another seed other ones
  const auto again = mbsgen::sobol_indices(f, n, d, 50, 1), other = mbsgen::sobol_indices(f, n, d, 50, 2);
  EXPECT_EQ(bits(again.indices[1].first_low), bits(with.indices[1].first_low));
  EXPECT_NE(other.indices[1].first_low, with.indices[1].first_low);
  // no bootstrap: NaN bounds; a constant function: NaN indices, V = 0
  const auto no_ci = mbsgen::sobol_indices(f, n, d, 0, 1);
  EXPECT_TRUE(std::isnan(no_ci.indices[0].first_low));
  EXPECT_EQ(bits(no_ci.indices[0].first), bits(with.indices[0].first));
  const auto constant = mbsgen::sobol_indices(std::vector<double>(n * (d + 2), 4.0), n, d, 10, 1);
  EXPECT_EQ(constant.variance, 0.0);
  EXPECT_TRUE(std::isnan(constant.indices[0].first));
  EXPECT_TRUE(std::isnan(constant.indices[0].total_high));
}

TEST(StudyDesign, SobolIndicesRejectWrongSizes) {
  const std::vector<double> f(10 * 5, 1.0);
  try {
    mbsgen::sobol_indices(f, 10, 4, 10, 1);  // needs 10·6 = 60 values, has 50
    ADD_FAILURE();
  } catch (const mbsgen::DimensionError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("sobol_indices"), std::string::npos) << message;
    EXPECT_NE(message.find("50"), std::string::npos) << message;
    EXPECT_NE(message.find("60"), std::string::npos) << message;
  }
  EXPECT_THROW(mbsgen::sobol_indices(f, 0, 3, 10, 1), mbsgen::DimensionError);
  EXPECT_THROW(mbsgen::sobol_indices(f, 10, 0, 10, 1), mbsgen::DimensionError);
  EXPECT_THROW(mbsgen::sobol_indices(f, 10, 3, 10, 1, 1.0), mbsgen::Error);
  // fewer than two finite rows
  std::vector<double> g(4 * 3, std::nan(""));
  g[0] = g[4] = g[8] = 1;  // row 0 finite only
  EXPECT_THROW(mbsgen::sobol_indices(g, 4, 1, 10, 1), mbsgen::Error);
}

TEST(StudyDesign, PercentileIsNumpysDefault) {
  // Hand-computed Hyndman–Fan type 7 (numpy.percentile's default "linear"): sorted
  // 1 1 2 3 4 5 6 9 (N = 8), h = 7q/100: q = 50 → h = 3.5 → 3 + 0.5·1 = 3.5; q = 25 → h = 1.75
  // → 1 + 0.75·1 = 1.75; q = 90 → h = 6.3 → 6 + 0.3·3 = 6.9; q = 10 → h = 0.7 → 1. Non-finite
  // values are ignored. EXPECT_DOUBLE_EQ (4 ulps): numpy's lerp rounds differently for t ≥ ½.
  const double nan = std::nan(""), inf = HUGE_VAL;
  const std::vector<double> x = {3, 1, 4, nan, 1, 5, inf, 9, 2, -inf, 6};
  EXPECT_EQ(mbsgen::percentile(x, 0), 1.0);
  EXPECT_EQ(mbsgen::percentile(x, 100), 9.0);
  EXPECT_DOUBLE_EQ(mbsgen::percentile(x, 50), 3.5);
  EXPECT_DOUBLE_EQ(mbsgen::percentile(x, 25), 1.75);
  EXPECT_DOUBLE_EQ(mbsgen::percentile(x, 90), 6.9);
  EXPECT_DOUBLE_EQ(mbsgen::percentile(x, 10), 1.0);
  EXPECT_EQ(mbsgen::percentile({7.5}, 30), 7.5);
  EXPECT_TRUE(std::isnan(mbsgen::percentile({}, 50)));
  EXPECT_TRUE(std::isnan(mbsgen::percentile({nan, inf}, 50)));
  EXPECT_THROW(mbsgen::percentile(x, -1), mbsgen::Error);
  EXPECT_THROW(mbsgen::percentile(x, 100.5), mbsgen::Error);
  EXPECT_THROW(mbsgen::percentile(x, nan), mbsgen::Error);
}

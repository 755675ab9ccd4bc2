// Kernels cut into parts (issue 17 §1, generator/src/codegen/emit_chunks.hpp) compute exactly what the
// whole kernels compute: the same statements in the same order, only some values pass through
// the workspace. The 6-link spatial chain is generated both ways (tests/generator/CMakeLists.txt:
// parts of 300 operations in 3 files, and no kernel cut) and every kernel is compared bit for
// bit, at pseudo-random states and at the operating point (where the exact zeros apply).
#include "spatial_chain_6_parts.hpp"
#include "spatial_chain_6_whole.hpp"
#include "rounding.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

// The first two parts of `linear` (their declarations as the generated file has them): the test
// links only when the kernel really was cut.
namespace spatial_chain_6_parts_kernel_parts {
void linear_0(const double* y0, const double* yd0, const double* p, double* M, double* Q, double* K, double* B,
              double* Cy, double* Cv, double* w);
void linear_1(const double* y0, const double* yd0, const double* p, double* M, double* Q, double* K, double* B,
              double* Cy, double* Cv, double* w);
}  // namespace spatial_chain_6_parts_kernel_parts

namespace {

constexpr int f = 12;  // 6 links, 2 coordinates each
constexpr int np = 11;

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

struct State {
  std::vector<double> y, yd, p;
};

std::vector<State> states() {
  std::vector<State> out;
  State op{std::vector<double>(f), std::vector<double>(f), std::vector<double>(spatial_chain_6_whole_parameter_defaults,
                                                                               spatial_chain_6_whole_parameter_defaults + np)};
  EXPECT_EQ(spatial_chain_6_whole_operating_point(op.p.data(), op.y.data(), op.yd.data()), 0);
  out.push_back(op);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> angle(-1.5, 1.5), rate(-3, 3), scale(0.5, 2);
  for (int k = 0; k < 4; ++k) {
    State s = op;
    for (auto& v : s.y) v = angle(rng);
    for (auto& v : s.yd) v = rate(rng);
    for (auto& v : s.p) v *= scale(rng);
    out.push_back(s);
  }
  return out;
}

}  // namespace

TEST(KernelParts, EveryKernelCutIntoPartsEqualsTheWholeKernelBitForBit) {
  ASSERT_NE(&spatial_chain_6_parts_kernel_parts::linear_1, nullptr);
  ASSERT_NE(&spatial_chain_6_parts_kernel_parts::linear_0, nullptr);
  for (const State& s : states()) {
    const double* y = s.y.data();
    const double* yd = s.yd.data();
    const double* p = s.p.data();
    std::vector<double> a(f * f), b(f * f);
    ASSERT_EQ(spatial_chain_6_parts_mass_matrix(y, p, a.data()), spatial_chain_6_whole_mass_matrix(y, p, b.data()));
    EXPECT_TRUE(same_bits(a, b)) << "mass_matrix";

    std::vector<double> u(1, 0.0), ra(f), rb(f);
    ASSERT_EQ(spatial_chain_6_parts_residual(y, yd, u.data(), p, ra.data()),
              spatial_chain_6_whole_residual(y, yd, u.data(), p, rb.data()));
    EXPECT_TRUE(same_bits(ra, rb)) << "residual";

    std::vector<double> da(f * f), db(f * f);
    ASSERT_EQ(spatial_chain_6_parts_dynamics(y, yd, u.data(), p, da.data(), ra.data()),
              spatial_chain_6_whole_dynamics(y, yd, u.data(), p, db.data(), rb.data()));
    EXPECT_TRUE(same_bits(da, db)) << "dynamics M";
    EXPECT_TRUE(same_bits(ra, rb)) << "dynamics r";

    std::vector<std::vector<double>> la(6, std::vector<double>(f * f)), lb = la;
    ASSERT_EQ(spatial_chain_6_parts_linear(y, yd, p, la[0].data(), la[1].data(), la[2].data(), la[3].data(),
                                           la[4].data(), la[5].data()),
              spatial_chain_6_whole_linear(y, yd, p, lb[0].data(), lb[1].data(), lb[2].data(), lb[3].data(),
                                           lb[4].data(), lb[5].data()));
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bits(la[static_cast<std::size_t>(k)], lb[static_cast<std::size_t>(k)])) << "linear " << k;

    ASSERT_EQ(spatial_chain_6_parts_linear_structured(y, yd, p, la[0].data(), la[1].data(), la[2].data(),
                                                      la[3].data(), la[4].data()),
              spatial_chain_6_whole_linear_structured(y, yd, p, lb[0].data(), lb[1].data(), lb[2].data(),
                                                      lb[3].data(), lb[4].data()));
    for (int k = 0; k < 5; ++k)
      EXPECT_TRUE(same_bits(la[static_cast<std::size_t>(k)], lb[static_cast<std::size_t>(k)])) << "linear_structured " << k;

    const int nb = 6;
    std::vector<std::vector<double>> ba = {std::vector<double>(3 * nb), std::vector<double>(9 * nb),
                                           std::vector<double>(3 * nb * f), std::vector<double>(3 * nb * f),
                                           std::vector<double>(nb), std::vector<double>(9 * nb)};
    auto bb = ba;
    ASSERT_EQ(spatial_chain_6_parts_bodies(y, p, ba[0].data(), ba[1].data(), ba[2].data(), ba[3].data(),
                                           ba[4].data(), ba[5].data()),
              spatial_chain_6_whole_bodies(y, p, bb[0].data(), bb[1].data(), bb[2].data(), bb[3].data(),
                                           bb[4].data(), bb[5].data()));
    for (std::size_t k = 0; k < ba.size(); ++k) EXPECT_TRUE(same_bits(ba[k], bb[k])) << "bodies " << k;
  }
}

// linear_structured splits linear's Q and K: D + G = Q and Ks + N = K to rounding (each entry of
// D and G is a half-sum or half-difference of two entries of Q, one rounding each: 2 units of
// u = 1.1e-16 of the larger of the two), D and Ks exactly symmetric, G and N exactly
// antisymmetric, and M passed through unchanged. An entry of N that the generator proved zero
// (this chain's K is symmetric for every y, but its N_zero flag is beyond the proof's budget,
// so only some entries are proved) is an exact 0, and Ks there the mean of K's two entries to
// one rounding; those two are then evaluations of one function by different operations, equal
// to their rounding: within 64 u of K's largest entry (an entry's rounding follows the terms it
// sums, of the matrix's scale, not its own size; the three programs of the engines bench agree
// on this chain's matrices to 3.3e-15 of the largest entry, 30 u).
TEST(KernelParts, StructuredKernelSplitsTheLinearKernelsMatrices) {
  for (const State& s : states()) {
    std::vector<double> M(f * f), Q(f * f), K(f * f), B(1), Cy(1), Cv(1), M2(f * f), D(f * f), G(f * f), Ks(f * f),
        N(f * f);
    ASSERT_EQ(spatial_chain_6_whole_linear(s.y.data(), s.yd.data(), s.p.data(), M.data(), Q.data(), K.data(), B.data(),
                                           Cy.data(), Cv.data()),
              0);
    ASSERT_EQ(spatial_chain_6_whole_linear_structured(s.y.data(), s.yd.data(), s.p.data(), M2.data(), D.data(),
                                                      G.data(), Ks.data(), N.data()),
              0);
    EXPECT_TRUE(same_bits(M, M2));
    const double k_max = mbsgen::test::max_abs(K);
    for (int i = 0; i < f; ++i)
      for (int j = 0; j < f; ++j) {
        const int ij = i + f * j, ji = j + f * i;
        EXPECT_EQ(D[ij], D[ji]);
        EXPECT_EQ(Ks[ij], Ks[ji]);
        EXPECT_EQ(G[ij], -G[ji]);
        EXPECT_EQ(N[ij], -N[ji]);
        const double q = std::max(std::abs(Q[ij]), std::abs(Q[ji])), k = std::max(std::abs(K[ij]), std::abs(K[ji]));
        EXPECT_LE(std::abs(D[ij] + G[ij] - Q[ij]), 2 * mbsgen::test::kUnitRoundoff * q) << i << ", " << j;
        if (N[ij] == 0.0 && K[ij] != K[ji]) {
          EXPECT_LE(std::abs(Ks[ij] - 0.5 * (K[ij] + K[ji])), mbsgen::test::kUnitRoundoff * k) << i << ", " << j;
          EXPECT_LE(std::abs(K[ij] - K[ji]), 64 * mbsgen::test::kUnitRoundoff * k_max) << i << ", " << j;
        } else {
          EXPECT_LE(std::abs(Ks[ij] + N[ij] - K[ij]), 2 * mbsgen::test::kUnitRoundoff * k) << i << ", " << j;
        }
      }
  }
}

// The dynamics kernel (EmitOptions::dynamics) computes M and k − q in one function, its
// statements merged by one CSE: what mass_matrix and residual compute, to rounding. The same
// values summed in another association differ by a few units of the scale of the terms summed
// (the matrix's or vector's largest entry): within 64 u, as for K's pair above.
TEST(KernelParts, DynamicsKernelEqualsMassMatrixAndResidual) {
  for (const State& s : states()) {
    std::vector<double> M(f * f), r(f), M2(f * f), r2(f), u(1, 0.0);
    ASSERT_EQ(spatial_chain_6_whole_mass_matrix(s.y.data(), s.p.data(), M.data()), 0);
    ASSERT_EQ(spatial_chain_6_whole_residual(s.y.data(), s.yd.data(), u.data(), s.p.data(), r.data()), 0);
    ASSERT_EQ(spatial_chain_6_whole_dynamics(s.y.data(), s.yd.data(), u.data(), s.p.data(), M2.data(), r2.data()), 0);
    EXPECT_LE(mbsgen::test::difference_in_units(M, M2), 64);
    EXPECT_LE(mbsgen::test::difference_in_units(r, r2), 64);
  }
}

// A kernel returns 1 exactly when one of its outputs is not finite (the generated all_finite,
// emit.cpp's kAllFinite, ORs the bits of x·0 instead of branching on std::isfinite): infinite or
// NaN arguments, and finite arguments whose outputs overflow, give 1; outputs near the largest
// double that are finite give 0. Parameters of the 6-link chain: g, l, m, Ixx, … (index 1 is the
// link length, 2 the mass).
TEST(KernelParts, StatusIsOneExactlyWhenAnOutputIsNotFinite) {
  const State s = states()[1];
  std::vector<double> M(f * f), r(f), u(1, 0.0);
  auto mass_matrix = [&](const std::vector<double>& y, const std::vector<double>& p) {
    return spatial_chain_6_whole_mass_matrix(y.data(), p.data(), M.data());
  };
  auto residual = [&](const std::vector<double>& y, const std::vector<double>& p) {
    return spatial_chain_6_whole_residual(y.data(), s.yd.data(), u.data(), p.data(), r.data());
  };
  EXPECT_EQ(mass_matrix(s.y, s.p), 0);
  EXPECT_EQ(residual(s.y, s.p), 0);
  for (double bad : {HUGE_VAL, -HUGE_VAL, std::nan("")}) {
    std::vector<double> y = s.y, p = s.p;
    y[f - 1] = bad;  // the last coordinate: the tip link's angle, in M's and r's last entries
    EXPECT_EQ(mass_matrix(y, s.p), 1) << bad;
    EXPECT_EQ(residual(y, s.p), 1) << bad;
    p[2] = bad;  // the mass
    EXPECT_EQ(mass_matrix(s.y, p), 1) << bad;
    EXPECT_EQ(residual(s.y, p), 1) << bad;
  }
  std::vector<double> p = s.p;
  p[1] = 1e3;    // l: M ~ m l² summed over links
  p[2] = 1e303;  // m: overflows to infinity from finite arguments
  EXPECT_EQ(mass_matrix(s.y, p), 1);
  EXPECT_TRUE(std::any_of(M.begin(), M.end(), [](double x) { return !std::isfinite(x); }));
  p[2] = 1e290;  // finite outputs near 1e297: no false alarm
  EXPECT_EQ(mass_matrix(s.y, p), 0);
  EXPECT_TRUE(std::all_of(M.begin(), M.end(), [](double x) { return std::isfinite(x); }));
  EXPECT_GT(*std::max_element(M.begin(), M.end()), 1e295);
}

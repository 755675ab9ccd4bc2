// Generate, compile, evaluate: the emitted kernels of every test model are checked against
// closed-form eigenvalues (docs/test-references.md §1–§9), SymPy's exact matrices
// (docs/test-references.md, "The three-link chain"), and two invariants that use routes
// independent of the generator's own: M = Σ J_Tᵀ m J_T + J_Rᵀ I J_R from the body Jacobians, and
// Q, K, B, C_y, C_v against central finite differences of the nonlinear kernels.
#include "kernel_harness.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>

namespace mbsgen::test {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using cplx = std::complex<double>;

const GeneratedModel& model(const std::string& name) {
  for (const auto& m : all_models())
    if (m.name == name) return m;
  throw std::runtime_error("no generated model " + name);
}

struct Linear {
  VectorXd p, y0, yd0;
  MatrixXd M, Q, K, B, Cy, Cv;
};

Linear linear_at_default(const GeneratedModel& g) {
  Linear L;
  L.p = Eigen::Map<const VectorXd>(g.defaults, g.np);
  L.y0.resize(g.n);
  L.yd0.resize(g.n);
  EXPECT_EQ(g.operating_point(L.p.data(), L.y0.data(), L.yd0.data()), 0);
  L.M.resize(g.n, g.n);
  L.Q.resize(g.n, g.n);
  L.K.resize(g.n, g.n);
  L.B.resize(g.n, g.nu);
  L.Cy.resize(g.nr, g.n);
  L.Cv.resize(g.nr, g.n);
  EXPECT_EQ(g.linear(L.y0.data(), L.yd0.data(), L.p.data(), L.M.data(), L.Q.data(), L.K.data(),
                     L.B.data(), L.Cy.data(), L.Cv.data()),
            0);
  return L;
}

std::vector<cplx> eigenvalues(const Linear& L) { return quadratic_eigenvalues(L.M, L.Q, L.K); }

double max_abs(const MatrixXd& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

// Each expected eigenvalue must have a computed one within tol·|λ| (relative, 1e-12: the
// companion matrices are small and well scaled, so LAPACK-quality solvers reach ~1e-14), and
// exactly `zeros` computed eigenvalues must be below 1e-6 of the largest (zero eigenvalues of
// cyclic coordinates form Jordan blocks, computed only to about √u).
void expect_eigenvalues(const std::string& name, const std::vector<cplx>& expected, int zeros = 0) {
  SCOPED_TRACE(name);
  std::vector<cplx> ev = eigenvalues(linear_at_default(model(name)));
  double scale = 0;
  for (const auto& l : ev) scale = std::max(scale, std::abs(l));
  int small = 0;
  for (const auto& l : ev) small += std::abs(l) < 1e-6 * scale;
  EXPECT_EQ(small, zeros);
  for (const auto& e : expected) {
    double best = 1e300;
    for (const auto& l : ev) best = std::min(best, std::abs(l - e));
    EXPECT_LE(best, 1e-12 * std::abs(e)) << "expected " << e;
  }
}

std::vector<cplx> conjugate_pairs(const std::vector<cplx>& upper) {
  std::vector<cplx> all;
  for (const auto& l : upper) {
    all.push_back(l);
    all.push_back(std::conj(l));
  }
  return all;
}
std::vector<cplx> imaginary_pairs(const std::vector<double>& omegas) {
  std::vector<cplx> up;
  for (double w : omegas) up.emplace_back(0.0, w);
  return conjugate_pairs(up);
}

TEST(ClosedForm, SimplePendulum) { expect_eigenvalues("simple_pendulum", imaginary_pairs({std::sqrt(9.81)})); }
TEST(ClosedForm, PhysicalPendulum) {
  expect_eigenvalues("physical_pendulum", imaginary_pairs({std::sqrt(1.5 * 9.81)}));
}
TEST(ClosedForm, DoublePendulumPointMasses) {
  expect_eigenvalues("double_pendulum",
                     imaginary_pairs({std::sqrt((2 - std::sqrt(2.0)) * 9.81), std::sqrt((2 + std::sqrt(2.0)) * 9.81)}));
}
TEST(ClosedForm, DoublePendulumRods) {
  const double s = 6 / std::sqrt(7.0);
  expect_eigenvalues("double_pendulum_rods",
                     imaginary_pairs({std::sqrt((3 - s) * 9.81), std::sqrt((3 + s) * 9.81)}));
}
std::vector<double> chain_omegas(int n, double k, double m, const std::string& ends) {
  std::vector<double> w;
  const double pi = std::acos(-1.0), s = 2 * std::sqrt(k / m);
  for (int j = 1; j <= n; ++j) {
    if (ends == "fixed_fixed") w.push_back(s * std::sin(j * pi / (2 * (n + 1))));
    if (ends == "fixed_free") w.push_back(s * std::sin((2 * j - 1) * pi / (2 * (2 * n + 1))));
    if (ends == "free_free" && j < n) w.push_back(s * std::sin(j * pi / (2 * n)));
  }
  return w;
}
TEST(ClosedForm, SpringChains) {
  expect_eigenvalues("spring_chain_fixed_fixed", imaginary_pairs(chain_omegas(5, 100, 1, "fixed_fixed")));
  expect_eigenvalues("spring_chain_fixed_free", imaginary_pairs(chain_omegas(5, 100, 1, "fixed_free")));
  expect_eigenvalues("spring_chain_free_free", imaginary_pairs(chain_omegas(5, 100, 1, "free_free")), 2);
}
TEST(ClosedForm, SphericalPendulumConical) {
  const double c = std::cos(std::acos(-1.0) / 6), phi2 = 9.81 / c;
  expect_eigenvalues("spherical_pendulum_conical", imaginary_pairs({std::sqrt(phi2 * (1 + 3 * c * c))}), 2);
  expect_eigenvalues("spherical_pendulum_conical", imaginary_pairs({6.06751513511722}), 2);
}
TEST(ClosedForm, RotorDiskGyroscopic) {
  const double Id = 0.1, Ip = 0.2, kt = 1000, W = 50, d = std::sqrt(Ip * Ip * W * W + 4 * Id * kt);
  expect_eigenvalues("rotor_disk", imaginary_pairs({(Ip * W + d) / (2 * Id), (d - Ip * W) / (2 * Id)}), 2);
}
TEST(ClosedForm, JeffcottRotorCirculatory) {
  // Roots of m s² + (c_n + c_r) s + k − i c_r Ω and their conjugates.
  const double m = 10, c = 60, k = 4e5, crW = 40 * 250;
  std::vector<cplx> up;
  for (double sign : {1.0, -1.0}) {
    cplx disc = std::sqrt(cplx(c * c - 4 * m * k, 4 * m * crW));
    up.push_back((-c + sign * disc) / (2 * m));
  }
  expect_eigenvalues("jeffcott_rotor", conjugate_pairs(up));
}
TEST(ClosedForm, SleepingTop) {
  const double I1 = 0.0003 + 0.01 * 0.04 * 0.04, I3 = 0.0004, w3 = 10, mgl = 0.01 * 9.81 * 0.04;
  const double d = std::sqrt(I3 * I3 * w3 * w3 - 4 * I1 * mgl);
  expect_eigenvalues("sleeping_top", imaginary_pairs({(I3 * w3 + d) / (2 * I1), (I3 * w3 - d) / (2 * I1)}), 2);
}
TEST(ClosedForm, ZieglerColumnBelowFlutter) {
  expect_eigenvalues("ziegler_column", imaginary_pairs({1 / std::sqrt(2.0), 1.0}));
}

// docs/test-references.md, "The three-link chain": exact M, C, K from SymPy 1.11 KanesMethod;
// 1e-14 relative allows a few roundings of the emitted arithmetic (each entry is a short sum of
// products).
TEST(SymPy, ThreeLinkChainMatricesAndEigenvalues) {
  Linear L = linear_at_default(model("chain3_sympy"));
  MatrixXd M(3, 3), C(3, 3), K(3, 3);
  M << 869.0 / 200, 111.0 / 50, 18.0 / 25, 111.0 / 50, 61.0 / 50, 21.0 / 50, 18.0 / 25, 21.0 / 50, 9.0 / 50;
  C << 0.1, 0, 0, 0, 0.2, 0, 0, 0, 0.3;
  K << 20677.0 / 400, 981.0 / 50, 2943.0 / 500, 981.0 / 50, 1981.0 / 50, 2943.0 / 500, 2943.0 / 500,
      2943.0 / 500, 17943.0 / 500;
  EXPECT_LE(max_abs(L.M - M), 1e-14 * max_abs(M));
  EXPECT_LE(max_abs(L.Q - C), 1e-14 * max_abs(C));
  EXPECT_LE(max_abs(L.K - K), 1e-14 * max_abs(K));
  expect_eigenvalues("chain3_sympy", conjugate_pairs({{-0.010096587831717660845, 3.3970879165417434992},
                                                      {-1.0214048046636475596, 17.214160736709374982},
                                                      {-6.7837763852824125573, 38.930803854513753330}}));
}

// The C++ API and the YAML reader give the same equations for the same chain: the API chain,
// evaluated at the SymPy parameters by name, reproduces the YAML model's linear matrices.
TEST(SymPy, ApiChainEqualsYamlChainAtSameParameters) {
  const GeneratedModel& api = model("planar_chain_3");
  const GeneratedModel& yaml = model("chain3_sympy");
  ASSERT_EQ(api.n, yaml.n);
  Linear ref = linear_at_default(yaml);
  std::map<std::string, double> by_name;
  for (int i = 0; i < yaml.np; ++i) by_name[yaml.parameter_names[i]] = yaml.defaults[i];
  VectorXd p(api.np);
  for (int i = 0; i < api.np; ++i) {
    ASSERT_TRUE(by_name.count(api.parameter_names[i])) << api.parameter_names[i];
    p[i] = by_name[api.parameter_names[i]];
  }
  VectorXd y0 = VectorXd::Zero(3), yd0 = VectorXd::Zero(3);
  MatrixXd M(3, 3), Q(3, 3), K(3, 3);
  ASSERT_EQ(api.linear(y0.data(), yd0.data(), p.data(), M.data(), Q.data(), K.data(), nullptr,
                       nullptr, nullptr),
            0);
  EXPECT_LE(max_abs(M - ref.M), 1e-14 * max_abs(ref.M));
  EXPECT_LE(max_abs(Q - ref.Q), 1e-14 * max_abs(ref.Q));
  EXPECT_LE(max_abs(K - ref.K), 1e-14 * max_abs(ref.K));
}

class Invariants : public ::testing::TestWithParam<std::string> {};

TEST_P(Invariants, MassMatrixEqualsProjectedBodyInertia) {
  const GeneratedModel& g = model(GetParam());
  Linear L = linear_at_default(g);
  // At the operating point and at a perturbed configuration.
  for (double shift : {0.0, 0.3}) {
    VectorXd y = L.y0;
    for (int i = 0; i < g.n; ++i) y[i] += shift * std::sin(1.0 + i);
    MatrixXd M(g.n, g.n);
    ASSERT_EQ(g.mass_matrix(y.data(), L.p.data(), M.data()), 0);
    std::vector<double> rc(3 * g.nb), S(9 * g.nb), JT(3 * g.n * g.nb), JR(3 * g.n * g.nb), m(g.nb),
        Ic(9 * g.nb);
    ASSERT_EQ(g.bodies(y.data(), L.p.data(), rc.data(), S.data(), JT.data(), JR.data(), m.data(), Ic.data()), 0);
    MatrixXd Mb = MatrixXd::Zero(g.n, g.n);
    for (int b = 0; b < g.nb; ++b) {
      Eigen::Map<MatrixXd> Jt(JT.data() + 3 * g.n * b, 3, g.n), Jr(JR.data() + 3 * g.n * b, 3, g.n);
      Eigen::Map<Eigen::Matrix3d> I(Ic.data() + 9 * b);
      Mb += m[static_cast<std::size_t>(b)] * Jt.transpose() * Jt + Jr.transpose() * I * Jr;
    }
    // Two summation orders of the same products: rounding only (1e-13 of the largest entry).
    EXPECT_LE(max_abs(M - Mb), 1e-13 * max_abs(M)) << "shift " << shift;
    EXPECT_LE(max_abs(M - M.transpose()), 1e-15 * max_abs(M));
  }
}

TEST_P(Invariants, BodyJacobiansMatchFiniteDifferencesOfPoses) {
  const GeneratedModel& g = model(GetParam());
  Linear L = linear_at_default(g);
  VectorXd y = L.y0;
  for (int i = 0; i < g.n; ++i) y[i] += 0.2 * std::cos(2.0 + i);
  auto poses = [&](const VectorXd& q, std::vector<double>& rc, std::vector<double>& S,
                   std::vector<double>& JT, std::vector<double>& JR) {
    std::vector<double> m(g.nb), Ic(9 * g.nb);
    rc.resize(3 * g.nb);
    S.resize(9 * g.nb);
    JT.resize(3 * g.n * g.nb);
    JR.resize(3 * g.n * g.nb);
    g.bodies(q.data(), L.p.data(), rc.data(), S.data(), JT.data(), JR.data(), m.data(), Ic.data());
  };
  std::vector<double> rc, S, JT, JR, rcp, Sp, rcm, Sm, dummy1, dummy2;
  poses(y, rc, S, JT, JR);
  // Central differences with h = 1e-6: truncation h²/6·|f'''| ≈ 2e-13 and rounding u/h ≈ 2e-10
  // for O(1) poses, so 1e-8 of the Jacobian's scale separates a right Jacobian from a wrong one.
  const double h = 1e-6;
  double scale = 1e-300;
  for (double v : JT) scale = std::max(scale, std::abs(v));
  for (double v : JR) scale = std::max(scale, std::abs(v));
  for (int k = 0; k < g.n; ++k) {
    VectorXd yp = y, ym = y;
    yp[k] += h;
    ym[k] -= h;
    poses(yp, rcp, Sp, dummy1, dummy2);
    poses(ym, rcm, Sm, dummy1, dummy2);
    for (int b = 0; b < g.nb; ++b) {
      for (int a = 0; a < 3; ++a) {
        double fd = (rcp[3 * b + a] - rcm[3 * b + a]) / (2 * h);
        EXPECT_NEAR(JT[static_cast<std::size_t>(3 * g.n * b + 3 * k + a)], fd, 1e-8 * scale);
      }
      Eigen::Map<Eigen::Matrix3d> S0(S.data() + 9 * b), Spl(Sp.data() + 9 * b), Smi(Sm.data() + 9 * b);
      Eigen::Matrix3d W = (Spl - Smi) / (2 * h) * S0.transpose();  // [ω]× per unit rate
      Eigen::Vector3d w(W(2, 1), W(0, 2), W(1, 0));
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(JR[static_cast<std::size_t>(3 * g.n * b + 3 * k + a)], w[a], 1e-8 * scale);
    }
  }
}

TEST_P(Invariants, LinearMatricesMatchFiniteDifferences) {
  const GeneratedModel& g = model(GetParam());
  Linear L = linear_at_default(g);
  VectorXd u0 = VectorXd::Zero(g.nu);
  auto residual = [&](const VectorXd& y, const VectorXd& yd, const VectorXd& u) {
    VectorXd r(g.n);
    g.residual(y.data(), yd.data(), u.data(), L.p.data(), r.data());
    return r;
  };
  auto outputs = [&](const VectorXd& y, const VectorXd& yd) {
    VectorXd z(g.nr);
    g.outputs(y.data(), yd.data(), L.p.data(), z.data());
    return z;
  };
  MatrixXd Kfd(g.n, g.n), Qfd(g.n, g.n), Bfd(g.n, g.nu), Cyfd(g.nr, g.n), Cvfd(g.nr, g.n);
  // Central differences, h = 1e-6 relative: truncation ≈ h² and rounding ≈ u·|terms|/h ≈ 2e-10
  // relative to the largest force term, so 1e-7 of the matrix scale is a safe, still sharp bar.
  for (int j = 0; j < g.n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(L.y0[j]));
    const double hv = 1e-6 * std::max(1.0, std::abs(L.yd0[j]));
    VectorXd yp = L.y0, ym = L.y0, vp = L.yd0, vm = L.yd0;
    yp[j] += h;
    ym[j] -= h;
    vp[j] += hv;
    vm[j] -= hv;
    Kfd.col(j) = (residual(yp, L.yd0, u0) - residual(ym, L.yd0, u0)) / (2 * h);
    Qfd.col(j) = (residual(L.y0, vp, u0) - residual(L.y0, vm, u0)) / (2 * hv);
    Cyfd.col(j) = (outputs(yp, L.yd0) - outputs(ym, L.yd0)) / (2 * h);
    Cvfd.col(j) = (outputs(L.y0, vp) - outputs(L.y0, vm)) / (2 * hv);
  }
  for (int j = 0; j < g.nu; ++j) {
    VectorXd up = u0, um = u0;
    up[j] += 1.0;
    um[j] -= 1.0;  // inputs enter linearly: exact up to rounding for any step
    Bfd.col(j) = -(residual(L.y0, L.yd0, up) - residual(L.y0, L.yd0, um)) / 2.0;
    // The residual kernel holds a moving support still in its reference place (it does not read
    // a motion input): its B column reaches the linear model only (prescribed_motion.hpp), and
    // the closed forms of tests/generated/base_excitation_test.cpp check it.
    if (std::string(g.input_kinds[j]) == "motion") {
      EXPECT_EQ(Bfd.col(j).cwiseAbs().maxCoeff(), 0.0) << g.input_names[j];
      Bfd.col(j) = L.B.col(j);
    }
  }
  const double scale = std::max({max_abs(L.K), max_abs(L.Q), max_abs(L.M), 1e-300});
  EXPECT_LE(max_abs(L.K - Kfd), 1e-7 * scale) << "K\n" << L.K << "\nFD\n" << Kfd;
  EXPECT_LE(max_abs(L.Q - Qfd), 1e-7 * scale) << "Q\n" << L.Q << "\nFD\n" << Qfd;
  if (g.nu) {
    EXPECT_LE(max_abs(L.B - Bfd), 1e-12 * std::max(max_abs(L.B), 1e-300)) << L.B << "\n" << Bfd;
  }
  if (g.nr) {
    const double cs = std::max({max_abs(L.Cy), max_abs(L.Cv), 1e-300});
    EXPECT_LE(max_abs(L.Cy - Cyfd), 1e-7 * cs);
    EXPECT_LE(max_abs(L.Cv - Cvfd), 1e-7 * cs);
  }
  // The operating point is an equilibrium (or a steady motion): k − q = 0 there, to rounding of
  // the force terms (≈ u·‖K‖·‖y0‖ … a bar of 1e-9 of the matrix scale). (An `equilibrium`
  // point's kernels give the solver's initial guess; the matrices above are the Jacobians there.)
  if (g.equilibrium) return;
  VectorXd r0 = residual(L.y0, L.yd0, u0);
  EXPECT_LE(r0.cwiseAbs().maxCoeff(), 1e-9 * scale * std::max(1.0, L.y0.cwiseAbs().maxCoeff()));
}

std::vector<std::string> model_names() {
  std::vector<std::string> names;
  for (const auto& m : all_models()) names.push_back(m.name);
  return names;
}
INSTANTIATE_TEST_SUITE_P(AllModels, Invariants, ::testing::ValuesIn(model_names()),
                         [](const auto& param_info) { return param_info.param; });

}  // namespace
}  // namespace mbsgen::test

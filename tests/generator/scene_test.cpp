// Scenes (docs/scenes.md): the kernels generated for a scene must give the results of the full
// model's kernels with the inactive effects' parameters set to zero, at the scene's operating
// point, for the inputs and outputs the scene keeps (pruning never changes a result the scene
// asks for); and the scenes with closed forms must reproduce them.
#include "kernel_harness.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <set>

namespace mbsgen::test {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using cplx = std::complex<double>;

const GeneratedModel& full_model(const std::string& name) {
  for (const auto& m : all_models())
    if (m.name == name) return m;
  throw std::runtime_error("no generated model " + name);
}

const GeneratedScene& scene(const std::string& name) {
  for (const auto& s : all_scenes())
    if (s.name == name) return s;
  throw std::runtime_error("no generated scene " + name);
}

double max_abs(const MatrixXd& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

int index_of(const char* const* names, int n, const std::string& name) {
  for (int i = 0; i < n; ++i)
    if (name == names[i]) return i;
  return -1;
}

struct Matrices {
  MatrixXd M, Q, K, B, Cy, Cv, D, G, Ks, N;
};

Matrices linear(const GeneratedModel& g, const VectorXd& y0, const VectorXd& yd0, const VectorXd& p) {
  Matrices L;
  L.M.resize(g.n, g.n);
  L.Q.resize(g.n, g.n);
  L.K.resize(g.n, g.n);
  L.B.resize(g.n, g.nu);
  L.Cy.resize(g.nr, g.n);
  L.Cv.resize(g.nr, g.n);
  EXPECT_EQ(g.linear(y0.data(), yd0.data(), p.data(), L.M.data(), L.Q.data(), L.K.data(), L.B.data(),
                     L.Cy.data(), L.Cv.data()),
            0);
  if (g.linear_structured) {
    MatrixXd M2(g.n, g.n);
    L.D.resize(g.n, g.n);
    L.G.resize(g.n, g.n);
    L.Ks.resize(g.n, g.n);
    L.N.resize(g.n, g.n);
    EXPECT_EQ(g.linear_structured(y0.data(), yd0.data(), p.data(), M2.data(), L.D.data(), L.G.data(),
                                  L.Ks.data(), L.N.data()),
              0);
    EXPECT_EQ(max_abs(M2 - L.M), 0.0) << "linear and linear_structured compute M alike";
  }
  return L;
}

// The two kernels evaluate the same sums: the scene's lack the inactive terms, the full
// model's have them multiplied by a zero parameter, and CSE may group the rest differently. The
// difference is rounding: a few units of u = 1.1e-16 per operation on terms no larger than
// about 10² times the largest entry (gravity against joint stiffness in the chains), so 1e-13
// of the largest entry of the reference matrix; an exactly zero reference must be matched
// exactly (a dropped term is a zero, not a small number).
void expect_same(const MatrixXd& scene_value, const MatrixXd& full_value, const char* what) {
  ASSERT_EQ(scene_value.rows(), full_value.rows()) << what;
  ASSERT_EQ(scene_value.cols(), full_value.cols()) << what;
  EXPECT_LE(max_abs(scene_value - full_value), 1e-13 * max_abs(full_value))
      << what << ", scene:\n" << scene_value << "\nfull model:\n" << full_value;
}

struct SceneCase {
  const char* scene;
  const char* full;
  std::vector<const char*> zeroed;  // parameters of the inactive effects
};

// rotor_disk's modes_at_rest is the disk at standstill (the operating point gives gamma' = 0,
// which both kernels receive); its gyroscopic terms have no parameter of their own.
const SceneCase kCases[] = {
    {"rotor_disk_modes_at_rest", "rotor_disk", {}},
    {"rotor_disk_spinning", "rotor_disk", {}},
    {"jeffcott_rotor_undamped", "jeffcott_rotor", {"c_n", "c_r"}},
    {"jeffcott_rotor_no_rotating_damping", "jeffcott_rotor", {"c_r"}},
    {"chain3_sympy_no_damping", "chain3_sympy", {"c1", "c2", "c3"}},
    {"chain3_sympy_frf", "chain3_sympy", {}},
    {"chain3_sympy_sag", "chain3_sympy", {"c1", "c2", "c3"}},
    {"base_excited_oscillator_shaker", "base_excited_oscillator", {}},
    {"planar_chain_3_no_gravity", "planar_chain_3", {"g"}},
    {"planar_chain_3_no_damping", "planar_chain_3", {"c1", "c2", "c3"}},
    {"spatial_chain_3_no_gravity", "spatial_chain_3", {"g"}},
};

class SceneEqualsZeroedFullModel : public ::testing::TestWithParam<SceneCase> {};

TEST_P(SceneEqualsZeroedFullModel, AtTheScenesOperatingPoint) {
  const SceneCase& c = GetParam();
  const GeneratedScene& s = scene(c.scene);
  const GeneratedModel& g = full_model(c.full);
  // The same parameters in the same order: a scene keeps every parameter.
  ASSERT_EQ(s.np, g.np);
  for (int i = 0; i < g.np; ++i) ASSERT_STREQ(s.parameter_names[i], g.parameter_names[i]);
  ASSERT_EQ(s.n, g.n);
  ASSERT_NE(s.operating_point, nullptr);
  ASSERT_NE(s.linear, nullptr);

  const VectorXd p = Eigen::Map<const VectorXd>(s.defaults, s.np);
  VectorXd p_zeroed = p;
  for (const char* name : c.zeroed) {
    const int i = index_of(g.parameter_names, g.np, name);
    ASSERT_GE(i, 0) << name;
    p_zeroed[i] = 0;
  }
  VectorXd y0(s.n), yd0(s.n);
  ASSERT_EQ(s.operating_point(p.data(), y0.data(), yd0.data()), 0);

  const Matrices a = linear(s, y0, yd0, p), b = linear(g, y0, yd0, p_zeroed);
  expect_same(a.M, b.M, "M");
  expect_same(a.Q, b.Q, "Q");
  expect_same(a.K, b.K, "K");
  // B's columns and C's rows for the scene's inputs and outputs, by name.
  ASSERT_LE(s.nu, g.nu);
  ASSERT_LE(s.nr, g.nr);
  MatrixXd B(g.n, s.nu), Cy(s.nr, g.n), Cv(s.nr, g.n);
  for (int j = 0; j < s.nu; ++j) {
    const int k = index_of(g.input_names, g.nu, s.input_names[j]);
    ASSERT_GE(k, 0) << s.input_names[j];
    B.col(j) = b.B.col(k);
  }
  for (int i = 0; i < s.nr; ++i) {
    const int k = index_of(g.output_names, g.nr, s.output_names[i]);
    ASSERT_GE(k, 0) << s.output_names[i];
    Cy.row(i) = b.Cy.row(k);
    Cv.row(i) = b.Cv.row(k);
  }
  expect_same(a.B, B, "B");
  expect_same(a.Cy, Cy, "Cy");
  expect_same(a.Cv, Cv, "Cv");
  if (s.linear_structured) {
    expect_same(a.D, b.D, "D");
    expect_same(a.G, b.G, "G");
    expect_same(a.Ks, b.Ks, "Ks");
    expect_same(a.N, b.N, "N");
  }

  if (s.residual) {
    // Static equilibrium uses the residual at ẏ = 0, anywhere in y and for any input.
    ASSERT_NE(g.residual, nullptr);
    for (int trial = 0; trial < 3; ++trial) {
      VectorXd y = y0, zero = VectorXd::Zero(s.n), u(s.nu), u_full = VectorXd::Zero(g.nu);
      for (int i = 0; i < s.n; ++i) y[i] += 0.3 * std::sin(1.7 * (i + 1) + trial);
      for (int j = 0; j < s.nu; ++j) {
        u[j] = 2.0 * std::cos(0.9 * (j + 1) + trial);
        u_full[index_of(g.input_names, g.nu, s.input_names[j])] = u[j];
      }
      VectorXd ra(s.n), rb(g.n);
      ASSERT_EQ(s.residual(y.data(), zero.data(), u.data(), p.data(), ra.data()), 0);
      ASSERT_EQ(g.residual(y.data(), zero.data(), u_full.data(), p_zeroed.data(), rb.data()), 0);
      // Terms of the residual are of the size of K times the displacement (or of the load):
      // rounding of 1e-13 of that, as for the matrices.
      const double scale = std::max({rb.cwiseAbs().maxCoeff(), max_abs(b.K) * y.cwiseAbs().maxCoeff(),
                                     u.size() ? max_abs(b.B) * u.cwiseAbs().maxCoeff() : 0.0});
      EXPECT_LE((ra - rb).cwiseAbs().maxCoeff(), 1e-13 * scale) << "trial " << trial;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, SceneEqualsZeroedFullModel, ::testing::ValuesIn(kCases),
                         [](const auto& param_info) { return std::string(param_info.param.scene); });

// Scenes that ask for simulate only (no linear kernel): M(y) and k − q(y, ẏ, u) equal the full
// model's with the scene's inactive parameters zero at any state, rates included (such a scene
// keeps the velocity-quadratic terms even when linearized at rest). Rounding bound as above, of
// the size of the terms: K y, the inputs' loads and the rates' inertia forces M ẏ².
const SceneCase kMotionCases[] = {
    {"rotor_disk_motion", "rotor_disk", {}},
};

TEST(Scenes, SimulateSceneEqualsTheFullModelAtAnyState) {
  for (const SceneCase& c : kMotionCases) {
    const GeneratedScene& s = scene(c.scene);
    const GeneratedModel& g = full_model(c.full);
    ASSERT_EQ(s.linear, nullptr) << c.scene;
    ASSERT_TRUE(s.mass_matrix && s.residual && g.mass_matrix && g.residual) << c.scene;
    ASSERT_EQ(s.n, g.n);
    const VectorXd p = Eigen::Map<const VectorXd>(s.defaults, s.np);
    VectorXd p_zeroed = p;
    for (const char* name : c.zeroed) p_zeroed[index_of(g.parameter_names, g.np, name)] = 0;
    for (int trial = 0; trial < 3; ++trial) {
      VectorXd y(s.n), yd(s.n), u(s.nu), u_full = VectorXd::Zero(g.nu);
      for (int i = 0; i < s.n; ++i) {
        y[i] = 0.4 * std::sin(1.3 * (i + 1) + trial);
        yd[i] = 20 * std::cos(0.7 * (i + 1) + 2 * trial);
      }
      for (int j = 0; j < s.nu; ++j) {
        u[j] = 2.0 * std::cos(0.9 * (j + 1) + trial);
        u_full[index_of(g.input_names, g.nu, s.input_names[j])] = u[j];
      }
      MatrixXd Ma(s.n, s.n), Mb(g.n, g.n);
      VectorXd ra(s.n), rb(g.n);
      ASSERT_EQ(s.mass_matrix(y.data(), p.data(), Ma.data()), 0);
      ASSERT_EQ(g.mass_matrix(y.data(), p_zeroed.data(), Mb.data()), 0);
      expect_same(Ma, Mb, "M");
      ASSERT_EQ(s.residual(y.data(), yd.data(), u.data(), p.data(), ra.data()), 0);
      ASSERT_EQ(g.residual(y.data(), yd.data(), u_full.data(), p_zeroed.data(), rb.data()), 0);
      const double scale = std::max(rb.cwiseAbs().maxCoeff(), max_abs(Mb) * yd.squaredNorm());
      EXPECT_LE((ra - rb).cwiseAbs().maxCoeff(), 1e-13 * scale) << c.scene << ", trial " << trial;
    }
  }
}

TEST(Scenes, EveryGeneratedSceneIsCompared) {
  std::set<std::string> compared;
  for (const auto& c : kCases) compared.insert(c.scene);
  for (const auto& c : kMotionCases) compared.insert(c.scene);
  for (const auto& s : all_scenes()) EXPECT_TRUE(compared.count(s.name)) << s.name;
}

// Only the kernels of the scene's analyses are emitted (docs/scenes.md): modes → linear,
// linear_structured; frf → linear; static → residual, linear; operating_point always.
TEST(Scenes, KernelsFollowTheAnalyses) {
  const GeneratedScene& modes = scene("rotor_disk_modes_at_rest");
  EXPECT_TRUE(modes.linear && modes.linear_structured && modes.operating_point);
  EXPECT_FALSE(modes.residual || modes.mass_matrix || modes.outputs || modes.bodies);
  const GeneratedScene& frf = scene("chain3_sympy_frf");
  EXPECT_TRUE(frf.linear && frf.operating_point);
  EXPECT_FALSE(frf.linear_structured || frf.residual || frf.mass_matrix || frf.outputs || frf.bodies);
  const GeneratedScene& sag = scene("chain3_sympy_sag");
  EXPECT_TRUE(sag.linear && sag.residual && sag.operating_point);
  EXPECT_FALSE(sag.linear_structured || sag.mass_matrix || sag.outputs || sag.bodies);
  // Inputs and outputs: only those named; a modes scene without any keeps none.
  EXPECT_EQ(frf.nu, 1);
  EXPECT_EQ(frf.nr, 1);
  EXPECT_STREQ(frf.output_names[0], "end_x");
  EXPECT_EQ(modes.nu, 0);
  EXPECT_EQ(modes.nr, 0);
  EXPECT_EQ(sag.nu, 1);  // static keeps the loads
  EXPECT_EQ(sag.nr, 0);
}

// Each expected eigenvalue has a computed one within 1e-12·|λ| and exactly `zeros` computed
// eigenvalues are below 1e-6 of the largest (as in kernel_test.cpp).
void expect_eigenvalues(const GeneratedScene& s, const std::vector<cplx>& expected, int zeros) {
  SCOPED_TRACE(s.name);
  const VectorXd p = Eigen::Map<const VectorXd>(s.defaults, s.np);
  VectorXd y0(s.n), yd0(s.n);
  ASSERT_EQ(s.operating_point(p.data(), y0.data(), yd0.data()), 0);
  const Matrices L = linear(s, y0, yd0, p);
  const std::vector<cplx> ev = quadratic_eigenvalues(L.M, L.Q, L.K);
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

// Closed forms (the models' header comments): the disk at standstill, ω = √(k_t/I_d) = 100
// twice; the undamped Jeffcott rotor, ω = √(k/m) = 200 twice; the undamped SymPy chain.
TEST(Scenes, ClosedFormEigenvalues) {
  expect_eigenvalues(scene("rotor_disk_modes_at_rest"), {{0, 100}, {0, -100}}, 2);
  expect_eigenvalues(scene("jeffcott_rotor_undamped"), {{0, 200}, {0, -200}}, 0);
  expect_eigenvalues(scene("chain3_sympy_no_damping"),
                     {{0, 3.3971025910970052442}, {0, 17.243279257034485702}, {0, 39.520084387625512806}},
                     0);
}

// Structure (manifest "structure", header <id>_D_zero …): what vanishes at the operating point.
TEST(Scenes, StructureFlags) {
  const GeneratedScene& rest = scene("rotor_disk_modes_at_rest");
  EXPECT_TRUE(rest.D_zero && rest.G_zero && rest.N_zero);
  const GeneratedScene& spin = scene("rotor_disk_spinning");
  EXPECT_TRUE(spin.D_zero && !spin.G_zero && spin.N_zero);
  const GeneratedScene& jeff = scene("jeffcott_rotor_no_rotating_damping");
  EXPECT_TRUE(!jeff.D_zero && jeff.G_zero && jeff.N_zero);
  const GeneratedScene& undamped = scene("jeffcott_rotor_undamped");
  EXPECT_TRUE(undamped.D_zero && undamped.G_zero && undamped.N_zero);
  // Exact zeros where the structure is identically zero: the undamped rotor's Q is 0.0 and its
  // K exactly symmetric (what the runtime's symmetric fast path needs).
  const VectorXd p = Eigen::Map<const VectorXd>(undamped.defaults, undamped.np);
  VectorXd y0(undamped.n), yd0(undamped.n);
  ASSERT_EQ(undamped.operating_point(p.data(), y0.data(), yd0.data()), 0);
  const Matrices L = linear(undamped, y0, yd0, p);
  EXPECT_EQ(max_abs(L.Q), 0.0);
  EXPECT_EQ(max_abs(L.K - L.K.transpose()), 0.0);
  const GeneratedScene& chain = scene("chain3_sympy_no_damping");
  const VectorXd pc = Eigen::Map<const VectorXd>(chain.defaults, chain.np);
  VectorXd yc(chain.n), ydc(chain.n);
  ASSERT_EQ(chain.operating_point(pc.data(), yc.data(), ydc.data()), 0);
  const Matrices C = linear(chain, yc + VectorXd::Constant(chain.n, 0.2), ydc, pc);
  EXPECT_EQ(max_abs(C.Q), 0.0);
  EXPECT_EQ(max_abs(C.K - C.K.transpose()), 0.0) << "symmetric anywhere, not only at rest";
}

}  // namespace
}  // namespace mbsgen::test

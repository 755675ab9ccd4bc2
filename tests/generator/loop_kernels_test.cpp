// Compiled kernels of models with closed loops, run through the runtime (issue 15 §2, §4): the
// loaded four-bar's equilibrium found by Newton's method on the reduced statics, and its
// frequency, against an independent derivation in one minimal coordinate
// (tests/reference/four_bar_linkage_reference.py, mpmath at 50 digits).
#include "four_bar.hpp"
#include "four_bar_given.hpp"
#include "four_bar_linkage.hpp"
#include "four_bar_parallelogram.hpp"
#include "pendulum_cartesian.hpp"
#include "ladder_3.hpp"
#include "slider_crank.hpp"
#include "rounding.hpp"

#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <string>
#include <vector>

namespace {

#define LOOP_KERNELS(id)                                                                                   \
  mbsgen::ModelKernels {                                                                                   \
    #id, #id, "full", id##_abi_version(), id##_n_coordinates, id##_n_inputs, id##_n_outputs,              \
        id##_n_parameters, id##_at_rest != 0, id##_equilibrium != 0, 0.0, 0.0, id##_coordinate_names,      \
        nullptr, id##_parameter_names, nullptr, id##_parameter_defaults, id##_input_names, nullptr,        \
        id##_output_names, nullptr, id##_operating_point, id##_linear, id##_residual, id##_mass_matrix     \
  }

// python3 tests/reference/four_bar_linkage_reference.py
constexpr double kTheta0 = 1.256311620944826482631333;       // crank angle th1 at the equilibrium
constexpr double kOmega2 = 115.2470787951297394601392;       // [1/s²]
constexpr double kOmega2Wrong = 171.0001009042161920595596;  // without the geometric stiffness
// Static loads by statics of the rocker and the coupler (moments about their pivots) [N].
constexpr double kPin[2] = {-0.3105781941863467975117627, 2.916876196288909572518942};
constexpr double kPivot[2] = {-0.6116646951934536065438293, -0.4089278602473552914115706};

mbsgen::ModelKernels four_bar_kernels() {
  mbsgen::ModelKernels k = LOOP_KERNELS(four_bar_linkage);
  k.output_terms = four_bar_linkage_output_terms;
  k.outputs = four_bar_linkage_outputs;
  return k;
}

TEST(FourBarLinkage, EquilibriumAndFrequencyMatchTheMinimalCoordinateDerivation) {
  const mbsgen::ModelKernels k = four_bar_kernels();
  mbsgen::GeneratedModel model(k);
  const mbsgen::OperatingPoint op = model.operating_point();
  ASSERT_TRUE(op.equilibrium);
  std::vector<double> y(four_bar_linkage_n_tree_coordinates);
  ASSERT_EQ(four_bar_linkage_assemble(op.y0.data(), model.parameters().data(), y.data()), 0);
  // Newton's method stops at a residual of rounding: the angle to ~1e-15 rad (a few ulps).
  EXPECT_NEAR(y[0], kTheta0, 1e-13);
  const mbsgen::LinearModel lin = model.linear_model(op);
  ASSERT_EQ(lin.size(), 1);
  const double omega2 = lin.K()(0, 0) / lin.M()(0, 0);
  // 1e-12 relative: K and M of the wrapped kernel at a point known to ~1e-15 (K is the exact
  // Jacobian of the reduced statics), both sides rounded a few times.
  EXPECT_NEAR(omega2 / kOmega2, 1, 1e-12);
  // The geometric stiffness of the loaded loop is a third of the answer here.
  EXPECT_GT(std::abs(kOmega2Wrong / omega2 - 1), 0.4);
}

// The static loads at the cut pin (the multipliers) and at the crank's pivot (a joint probe less
// the pin's share) against the statics of the rocker and coupler by hand.
TEST(FourBarLinkage, StaticLoadsMatchTheStaticsOfTheBars) {
  const mbsgen::ModelKernels k = four_bar_kernels();
  mbsgen::GeneratedModel model(k);
  const Eigen::VectorXd z = model.outputs(model.operating_point());
  ASSERT_EQ(z.size(), 4);
  // 1e-12 N of loads of ~3 N: the equilibrium angle known to ~1e-15, a few roundings.
  EXPECT_NEAR(z[0], kPin[0], 1e-12);
  EXPECT_NEAR(z[1], kPin[1], 1e-12);
  EXPECT_NEAR(z[2], kPivot[0], 1e-12);
  EXPECT_NEAR(z[3], kPivot[1], 1e-12);
}

// The frequency response of a load per crank torque against one built from finite differences
// of the nonlinear `outputs_general` kernel (C_y, C_a, D) and a direct complex solve of the
// reduced matrices: ẑ = (C_y − Ω² C_a) ŷ + D û.
TEST(FourBarLinkage, LoadTransferMatchesDifferencesOfTheNonlinearLoad) {
  const mbsgen::ModelKernels k = four_bar_kernels();
  mbsgen::GeneratedModel model(k);
  const mbsgen::OperatingPoint op = model.operating_point();
  const mbsgen::LinearModel lin = model.linear_model(op);
  const double* p = model.parameters().data();
  auto load = [&](double y, double ydd, double u) {
    double z[4], yd = 0;
    EXPECT_EQ(four_bar_linkage_outputs_general(&y, &yd, &ydd, &u, p, z), 0);
    return Eigen::Vector4d(z[0], z[1], z[2], z[3]);
  };
  const double y0 = op.y0[0], h = 1e-6;
  // Central differences in y (truncation ~h², rounding ~1e-16/h of loads ~3 N: ~1e-10); ÿ and u
  // enter linearly, so a unit step is exact to rounding.
  const Eigen::Vector4d Cy = (load(y0 + h, 0, 0) - load(y0 - h, 0, 0)) / (2 * h);
  const Eigen::Vector4d Ca = load(y0, 1, 0) - load(y0, 0, 0), D = load(y0, 0, 1) - load(y0, 0, 0);
  mbsgen::FrequencyResponse frf(lin);
  Eigen::VectorXd omega(4);
  omega << 0.0, 3.0, 10.0, 30.0;  // around ω_n = 10.7 rad/s
  for (Eigen::Index row = 0; row < 4; ++row) {
    frf.compute(omega, 0, {row});
    for (Eigen::Index i = 0; i < omega.size(); ++i) {
      const double w = omega[i];
      const double q = lin.has_damping() ? lin.Q()(0, 0) : 0.0;  // Q is stored empty when zero
      const std::complex<double> yhat = lin.B()(0, 0) / std::complex<double>(lin.K()(0, 0) - w * w * lin.M()(0, 0), w * q);
      const std::complex<double> expected = (Cy[row] - w * w * Ca[row]) * yhat + D[row];
      EXPECT_LE(std::abs(frf.response()(0, i) - expected), 1e-7 * std::max(1.0, std::abs(expected)))
          << k.output_names[row] << " at " << w << " rad/s";
    }
  }
}

// The loops close at every call: Φ(y) = 0 after assemble, from the operating point and from an
// independent coordinate moved by 0.1 rad.
TEST(FourBarLinkage, AssembleClosesTheLoop) {
  const double* p = four_bar_linkage_parameter_defaults;
  std::vector<double> yi(four_bar_linkage_n_coordinates), yd(yi.size()), y(four_bar_linkage_n_tree_coordinates),
      phi(four_bar_linkage_n_constraints);
  ASSERT_EQ(four_bar_linkage_operating_point(p, yi.data(), yd.data()), 0);
  for (double shift : {0.0, 0.1, -0.1}) {
    std::vector<double> moved = yi;
    moved[0] += shift;
    ASSERT_EQ(four_bar_linkage_assemble(moved.data(), p, y.data()), 0);
    ASSERT_EQ(four_bar_linkage_constraints(y.data(), p, phi.data()), 0);
    // Lengths of 0.1–0.4 m: closed to rounding (1e-16 of the size after the last Newton step).
    for (double r : phi) EXPECT_LE(std::abs(r), 1e-15) << shift;
  }
}

// With closed loops the dynamics kernel is wrapped like mass_matrix and residual (it takes the
// independent coordinates and closes the loops first): the same M and k − q, to rounding (64 u
// of each one's largest entry: kernel_parts_test.cpp), at the operating point and moved off it.
TEST(FourBarLinkage, DynamicsKernelEqualsMassMatrixAndResidual) {
  const double* p = four_bar_linkage_parameter_defaults;
  const std::size_t f = four_bar_linkage_n_coordinates;
  std::vector<double> yi(f), yd(f), u(four_bar_linkage_n_inputs + 1, 0.0);
  ASSERT_EQ(four_bar_linkage_operating_point(p, yi.data(), yd.data()), 0);
  for (double shift : {0.0, 0.1, -0.1}) {
    std::vector<double> y = yi, v(f, 0.7);
    y[0] += shift;
    std::vector<double> M(f * f), r(f), M2(f * f), r2(f);
    ASSERT_EQ(four_bar_linkage_mass_matrix(y.data(), p, M.data()), 0);
    ASSERT_EQ(four_bar_linkage_residual(y.data(), v.data(), u.data(), p, r.data()), 0);
    ASSERT_EQ(four_bar_linkage_dynamics(y.data(), v.data(), u.data(), p, M2.data(), r2.data()), 0);
    EXPECT_LE(mbsgen::test::difference_in_units(M, M2), 64) << shift;
    EXPECT_LE(mbsgen::test::difference_in_units(r, r2), 64) << shift;
  }
}

// A coupler too short to span the gap (0.05 m where the crank's tip is at least 0.3 m from the
// rocker's tip's circle): assemble returns 2, and the runtime names the failure.
TEST(FourBarLinkage, LoopThatCannotCloseIsReported) {
  const mbsgen::ModelKernels k = four_bar_kernels();
  mbsgen::GeneratedModel model(k);
  model.set("l2", 0.05);
  std::vector<double> yi(four_bar_linkage_n_coordinates), yd(yi.size()), y(four_bar_linkage_n_tree_coordinates);
  ASSERT_EQ(four_bar_linkage_operating_point(model.parameters().data(), yi.data(), yd.data()), 0);
  EXPECT_EQ(four_bar_linkage_assemble(yi.data(), model.parameters().data(), y.data()), 2);
  try {
    model.operating_point();
    ADD_FAILURE() << "no error";
  } catch (const mbsgen::Error& e) {
    EXPECT_NE(std::string(e.what()).find("could not close the kinematic loops"), std::string::npos) << e.what();
  }
}

// The ladder of 3 loops: 9 tree coordinates, 6 constraint equations, 3 degrees of freedom, its
// given hanging point an equilibrium (the runtime's residual check) with a positive definite
// stiffness (it hangs stably).
TEST(Ladder, HangingLadderIsAStableEquilibrium) {
  const mbsgen::ModelKernels k = LOOP_KERNELS(ladder_3);
  mbsgen::GeneratedModel model(k);
  EXPECT_EQ(ladder_3_n_tree_coordinates, 9);
  EXPECT_EQ(ladder_3_n_constraints, 6);
  ASSERT_EQ(model.size(), 3);
  const mbsgen::OperatingPoint op = model.operating_point();
  EXPECT_LE(op.residual_norm, 1e-12);
  const mbsgen::LinearModel lin = model.linear_model(op);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(lin.K(), lin.M());
  EXPECT_GT(es.eigenvalues().minCoeff(), 0);
}

// models/linkages/four_bar.yaml is the same linkage as the C++ API's four_bar_linkage, with the
// crank listed as the independent coordinate: the same equilibrium, frequency and loads.
TEST(FourBarYaml, MatchesTheReference) {
  mbsgen::ModelKernels k = LOOP_KERNELS(four_bar);
  k.output_terms = four_bar_output_terms;
  k.outputs = four_bar_outputs;
  mbsgen::GeneratedModel model(k);
  EXPECT_STREQ(four_bar_coordinate_names[0], "th1");
  const mbsgen::OperatingPoint op = model.operating_point();
  EXPECT_NEAR(op.y0[0], kTheta0, 1e-13);
  const mbsgen::LinearModel lin = model.linear_model(op);
  EXPECT_NEAR(lin.K()(0, 0) / lin.M()(0, 0) / kOmega2, 1, 1e-12);
  const Eigen::VectorXd z = model.outputs(op);
  EXPECT_NEAR(z[0], kPin[0], 1e-12);
  EXPECT_NEAR(z[1], kPin[1], 1e-12);
  EXPECT_NEAR(z[2], kPivot[0], 1e-12);
  EXPECT_NEAR(z[3], kPivot[1], 1e-12);
  EXPECT_NEAR(z[4], kTheta0, 1e-13);
}

// models/linkages/slider_crank.yaml against tests/reference/slider_crank_reference.py: the
// equilibrium, the frequency and the load at every joint (statics of each body by hand).
TEST(SliderCrank, EquilibriumFrequencyAndEveryJointLoad) {
  mbsgen::ModelKernels k = LOOP_KERNELS(slider_crank);
  k.outputs = slider_crank_outputs;
  mbsgen::GeneratedModel model(k);
  const mbsgen::OperatingPoint op = model.operating_point();
  std::vector<double> y(slider_crank_n_tree_coordinates);
  ASSERT_EQ(slider_crank_assemble(op.y0.data(), model.parameters().data(), y.data()), 0);
  EXPECT_NEAR(y[0], -1.237847263651808002856276, 1e-13);
  EXPECT_NEAR(y[1], 1.558332930743535407287844, 1e-13);
  EXPECT_NEAR(y[2], 0.3174079148399754307166147, 1e-14);
  const mbsgen::LinearModel lin = model.linear_model(op);
  EXPECT_NEAR(lin.K()(0, 0) / lin.M()(0, 0) / 32.69465570242052536678955, 1, 1e-12);
  const Eigen::VectorXd z = model.outputs(op);
  const double expected[9] = {-0.91296042580012284642, -2.2650375797343765187, 0, 7.1700375797343765187,
                              -0.91296042580012284642, 1.6589624202656234813, -0.91296042580012284642,
                              3.6209624202656234813, 0.91296042580012284642};
  // Loads of a few N: 1e-12 N is rounding through the loop's elimination.
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(z[i], expected[i], 1e-12) << slider_crank_output_names[i];
}

// The other linkage files against tests/data/reference/loops.json (tests/reference/
// loops_reference.py: SymPy and mpmath, every value by two independent routes): the
// parallelogram's ω² = 3g(m1+2m2+m3)/(2l(m1+3m2+m3)) = 36.7875 and its pin load (0, −2.4525) N, the
// Cartesian pendulum's ω² = g/L = 12.2625, the loaded four-bar at its given equilibrium.
TEST(LinkageFiles, MatchLoopsJson) {
  struct Case {
    mbsgen::ModelKernels k;
    double omega2;
    std::vector<double> loads;
  };
  mbsgen::ModelKernels parallelogram = LOOP_KERNELS(four_bar_parallelogram), pendulum = LOOP_KERNELS(pendulum_cartesian),
                       given = LOOP_KERNELS(four_bar_given);
  parallelogram.outputs = four_bar_parallelogram_outputs;
  given.outputs = four_bar_given_outputs;
  for (const Case& c : {Case{parallelogram, 36.7875, {0, -2.4525}}, Case{pendulum, 12.2625, {}},
                        Case{given, kOmega2, {kPin[0], kPin[1], kPivot[0], kPivot[1]}}}) {
    mbsgen::GeneratedModel model(c.k);
    const mbsgen::OperatingPoint op = model.operating_point();
    const mbsgen::LinearModel lin = model.linear_model(op);
    ASSERT_EQ(lin.size(), 1) << c.k.model;
    // 1e-12: the kernels at a point closed to rounding against 50-digit references.
    EXPECT_NEAR(lin.K()(0, 0) / lin.M()(0, 0) / c.omega2, 1, 1e-12) << c.k.model;
    const Eigen::VectorXd z = model.outputs(op);
    for (std::size_t i = 0; i < c.loads.size(); ++i)
      EXPECT_NEAR(z[static_cast<Eigen::Index>(i)], c.loads[i], 1e-12) << c.k.model << " output " << i;
  }
}

// Invariant on every model with loops: at the operating point (and 0.05 rad or m away in each
// independent coordinate) assemble closes every constraint equation to rounding.
struct LoopKernels {
  const char* name;
  int n, n_tree, n_constraints, n_parameters;
  const double* defaults;
  int (*operating_point)(const double*, double*, double*);
  int (*assemble)(const double*, const double*, double*);
  int (*constraints)(const double*, const double*, double*);
};
#define LOOP_ENTRY(id)                                                                                        \
  LoopKernels {                                                                                               \
    #id, id##_n_coordinates, id##_n_tree_coordinates, id##_n_constraints, id##_n_parameters,                   \
        id##_parameter_defaults, id##_operating_point, id##_assemble, id##_constraints                         \
  }

TEST(LoopInvariants, AssembleClosesEveryLoopModel) {
  for (const LoopKernels& k : {LOOP_ENTRY(four_bar_linkage), LOOP_ENTRY(ladder_3), LOOP_ENTRY(four_bar),
                               LOOP_ENTRY(slider_crank), LOOP_ENTRY(four_bar_given), LOOP_ENTRY(four_bar_parallelogram),
                               LOOP_ENTRY(pendulum_cartesian)}) {
    std::vector<double> yi(static_cast<std::size_t>(k.n)), yd(yi.size()), y(static_cast<std::size_t>(k.n_tree)),
        phi(static_cast<std::size_t>(k.n_constraints));
    ASSERT_EQ(k.operating_point(k.defaults, yi.data(), yd.data()), 0) << k.name;
    for (int j = -1; j < k.n; ++j) {
      std::vector<double> at = yi;
      if (j >= 0) at[static_cast<std::size_t>(j)] += 0.05;
      ASSERT_EQ(k.assemble(at.data(), k.defaults, y.data()), 0) << k.name << " " << j;
      ASSERT_EQ(k.constraints(y.data(), k.defaults, phi.data()), 0) << k.name;
      // Lengths of 0.1–0.6 m: a few ulps after the last Newton step.
      for (double r : phi) EXPECT_LE(std::abs(r), 1e-15) << k.name << " " << j;
    }
  }
}

}  // namespace

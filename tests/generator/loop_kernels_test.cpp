// Compiled kernels of models with closed loops, run through the runtime (issue 15 §2, §4): the
// loaded four-bar's equilibrium found by Newton's method on the reduced statics, and its
// frequency, against an independent derivation in one minimal coordinate
// (tests/reference/four_bar_linkage_reference.py, mpmath at 50 digits).
#include "four_bar_linkage.hpp"
#include "ladder_3.hpp"

#include "mbsgen/runtime/generated_model.hpp"
#include "mbsgen/runtime/linear_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
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

TEST(FourBarLinkage, EquilibriumAndFrequencyMatchTheMinimalCoordinateDerivation) {
  const mbsgen::ModelKernels k = LOOP_KERNELS(four_bar_linkage);
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

// A coupler too short to span the gap (0.05 m where the crank's tip is at least 0.3 m from the
// rocker's tip's circle): assemble returns 2, and the runtime names the failure.
TEST(FourBarLinkage, LoopThatCannotCloseIsReported) {
  const mbsgen::ModelKernels k = LOOP_KERNELS(four_bar_linkage);
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

}  // namespace

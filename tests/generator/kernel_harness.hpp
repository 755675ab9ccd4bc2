// The kernels of one generated model, gathered for the tests.
#pragma once

#include <Eigen/Dense>

#include <cmath>
#include <complex>
#include <string>
#include <vector>

namespace mbsgen::test {

struct GeneratedModel {
  std::string name;
  int n, nu, nr, np, nb;
  bool at_rest;
  const double* defaults;
  const char* const* coordinate_names;
  const char* const* parameter_names;
  const char* const* input_names;
  const char* const* output_names;
  const char* const* input_kinds;  ///< "force" or "motion" (prescribed_motion.hpp)
  int (*mass_matrix)(const double* y, const double* p, double* M);
  int (*residual)(const double* y, const double* yd, const double* u, const double* p, double* r);
  int (*linear)(const double* y0, const double* yd0, const double* p, double* M, double* Q,
                double* K, double* B, double* Cy, double* Cv);
  int (*linear_structured)(const double* y0, const double* yd0, const double* p, double* M,
                           double* D, double* G, double* Ks, double* N);
  int (*operating_point)(const double* p, double* y0, double* yd0);
  int (*outputs)(const double* y, const double* yd, const double* p, double* z);
  int (*bodies)(const double* y, const double* p, double* rc, double* S, double* JT, double* JR,
                double* m, double* Ic);
  bool equilibrium = false;  ///< operating_point gives an equilibrium's initial guess
};

/// The kernels of one scene (a model pruned by apply_scene): a kernel the scene does not emit
/// is null, as its header does not declare it (no <id>_HAS_<KERNEL>).
struct GeneratedScene : GeneratedModel {
  bool D_zero, G_zero, N_zero;
};

const std::vector<GeneratedModel>& all_models();
const std::vector<GeneratedScene>& all_scenes();

/// Eigenvalues of λ²M + λQ + K through the companion matrix of the problem scaled as Fan, Lin
/// & Van Dooren (2004) propose, λ = γμ with γ = √(‖K‖/‖M‖), so that the companion matrix is well
/// balanced (M is well conditioned in every textbook case; the runtime's QZ solver is tested
/// separately).
inline std::vector<std::complex<double>> quadratic_eigenvalues(const Eigen::MatrixXd& M,
                                                               const Eigen::MatrixXd& Q,
                                                               const Eigen::MatrixXd& K) {
  const Eigen::Index n = M.rows();
  const double nk = K.norm(), nm = M.norm();
  const double gamma = nk > 0 ? std::sqrt(nk / nm) : 1.0;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  A.topRightCorner(n, n).setIdentity();
  Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
  A.bottomLeftCorner(n, n) = -lu.solve(K) / (gamma * gamma);
  A.bottomRightCorner(n, n) = -lu.solve(Q) / gamma;
  Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  std::vector<std::complex<double>> ev;
  for (Eigen::Index i = 0; i < 2 * n; ++i) ev.push_back(gamma * es.eigenvalues()[i]);
  return ev;
}

}  // namespace mbsgen::test

#define MBSGEN_GENERATED_MODEL(id)                                                          \
  ::mbsgen::test::GeneratedModel {                                                          \
    #id, id##_n_coordinates, id##_n_inputs, id##_n_outputs, id##_n_parameters,              \
        id##_n_bodies, id##_at_rest != 0, id##_parameter_defaults, id##_coordinate_names,   \
        id##_parameter_names, id##_input_names, id##_output_names, id##_input_kinds,         \
        id##_mass_matrix,                                                                   \
        id##_residual, id##_linear, id##_linear_structured, id##_operating_point,           \
        id##_outputs, id##_bodies, id##_equilibrium != 0                                    \
  }

#define MBSGEN_GENERATED_SCENE(id)                                                          \
  ::mbsgen::test::GeneratedScene {                                                          \
    {#id, id##_n_coordinates, id##_n_inputs, id##_n_outputs, id##_n_parameters,             \
     id##_n_bodies, id##_at_rest != 0, id##_parameter_defaults, id##_coordinate_names,      \
     id##_parameter_names, id##_input_names, id##_output_names, id##_input_kinds, nullptr,  \
     nullptr, nullptr,                                                                      \
     nullptr, nullptr, nullptr, nullptr},                                                   \
        id##_D_zero != 0, id##_G_zero != 0, id##_N_zero != 0                               \
  }

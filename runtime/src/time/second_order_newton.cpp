// Newton's linear systems of a BDF step in n unknowns (second_order_newton.hpp).
#include "time/second_order_newton.hpp"

#include <Eigen/LU>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>

namespace mbsgen::detail {

namespace {

using Eigen::Index;
using Eigen::Map;
using Eigen::MatrixXd;
using Eigen::VectorXd;

SecondOrderMatrix& content(SUNMatrix A) { return *static_cast<SecondOrderMatrix*>(A->content); }

// ---- the matrix ----------------------------------------------------------------------------

SUNMatrix_ID matrix_id(SUNMatrix) { return SUNMATRIX_CUSTOM; }

void matrix_destroy(SUNMatrix A) {
  if (!A) return;
  delete static_cast<SecondOrderMatrix*>(A->content);
  A->content = nullptr;
  SUNMatFreeEmpty(A);
}

SUNMatrix matrix_clone(SUNMatrix A) { return new_second_order_matrix(content(A).M.rows(), A->sunctx); }

int matrix_zero(SUNMatrix A) {
  SecondOrderMatrix& a = content(A);
  a.c = a.d = 0;
  return 0;
}

int matrix_copy(SUNMatrix from, SUNMatrix to) {  // SUNMatCopy(A, B): B = A
  content(to) = content(from);  // same sizes: no allocation
  return 0;
}

int matrix_scale_add_identity(double s, SUNMatrix A) {  // A = s·A + I
  SecondOrderMatrix& a = content(A);
  a.c *= s;
  a.d = s * a.d + 1;
  return 0;
}

int matrix_space(SUNMatrix A, long* real_words, long* integer_words) {
  *real_words = static_cast<long>(3 * content(A).M.size() + 2);
  *integer_words = 1;
  return 0;
}

// ---- the linear solver ---------------------------------------------------------------------

struct Solver {
  Eigen::PartialPivLU<MatrixXd> lu;
  MatrixXd R;
  VectorXd rhs, dv, scale;
  double c = 0, d = 1;
  sunindextype last_flag = 0;
};

Solver& solver(SUNLinearSolver S) { return *static_cast<Solver*>(S->content); }

SUNLinearSolver_Type solver_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID solver_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
int solver_initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }

// R = d·M − c·K_v + (c²/d)·K_y, equilibrated as M is (S R S, S = diag(|M_ii|)^(-1/2): for small
// γ, R is M in its units, kg against kg m²) and factored; singular (a pivot below 2^-52·n of the
// largest): recoverable, CVODE retries with a smaller step.
int solver_setup(SUNLinearSolver S, SUNMatrix A) noexcept {
  Solver& s = solver(S);
  const SecondOrderMatrix& a = content(A);
  if (a.d == 0) return s.last_flag = SUNLS_ILL_INPUT;
  s.c = a.c;
  s.d = a.d;
  s.R = a.d * a.M - a.c * a.Kv + (a.c * a.c / a.d) * a.Ky;
  equilibrate(a.M, s.scale, s.R);
  s.lu.compute(s.R);
  const bool singular = !(pivot_ratio(s.lu) > static_cast<double>(a.M.rows()) * std::numeric_limits<double>::epsilon());
  return s.last_flag = singular ? SUNLS_LUFACT_FAIL : SUNLS_SUCCESS;
}

int solver_solve(SUNLinearSolver S, SUNMatrix A, N_Vector x, N_Vector b, double) noexcept {
  Solver& s = solver(S);
  const SecondOrderMatrix& a = content(A);
  const Index n = a.M.rows();
  const Map<const VectorXd> r1(N_VGetArrayPointer(b), n), r2(N_VGetArrayPointer(b) + n, n);
  s.rhs.noalias() = a.M * r2;
  s.rhs.noalias() += (s.c / s.d) * a.Ky * r1;
  s.rhs.array() *= s.scale.array();  // Δv = S (S R S)⁻¹ S rhs
  s.dv.noalias() = s.lu.solve(s.rhs);
  s.dv.array() *= s.scale.array();
  Map<VectorXd> dy(N_VGetArrayPointer(x), n), dv(N_VGetArrayPointer(x) + n, n);
  dy = (r1 - s.c * s.dv) / s.d;  // x and b may be the same vector: r1 is read before dv is written
  dv = s.dv;
  return s.last_flag = s.dv.allFinite() ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;
}

sunindextype solver_last_flag(SUNLinearSolver S) { return solver(S).last_flag; }

int solver_space(SUNLinearSolver S, long* real_words, long* integer_words) {
  *real_words = static_cast<long>(2 * solver(S).R.size());
  *integer_words = static_cast<long>(solver(S).R.rows());
  return SUNLS_SUCCESS;
}

int solver_free(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  delete static_cast<Solver*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

void mass_scale(const MatrixXd& M, VectorXd& scale) {
  for (Index i = 0; i < M.rows(); ++i) {
    const double m = std::abs(M(i, i));
    scale[i] = m > 0 && std::isfinite(m) ? 1 / std::sqrt(m) : 1.0;
  }
}

void equilibrate(const MatrixXd& M, VectorXd& scale, MatrixXd& A) {
  const Index n = M.rows();
  mass_scale(M, scale);
  for (Index j = 0; j < n; ++j)
    for (Index i = 0; i < n; ++i) A(i, j) = scale[i] * A(i, j) * scale[j];
}

double pivot_ratio(const Eigen::PartialPivLU<MatrixXd>& lu) {
  if (lu.rows() == 0) return 1.0;
  const auto pivots = lu.matrixLU().diagonal().cwiseAbs();
  return pivots.minCoeff() / pivots.maxCoeff();
}

SecondOrderMatrix& parts(SUNMatrix A) { return content(A); }

SUNMatrix new_second_order_matrix(Index n, SUNContext context) {
  SUNMatrix A = SUNMatNewEmpty(context);
  if (!A) return nullptr;
  auto* a = new (std::nothrow) SecondOrderMatrix;
  if (!a) {
    SUNMatFreeEmpty(A);
    return nullptr;
  }
  try {
    a->M.setZero(n, n);
    a->Ky.setZero(n, n);
    a->Kv.setZero(n, n);
  } catch (const std::bad_alloc&) {
    delete a;
    SUNMatFreeEmpty(A);
    return nullptr;
  }
  A->content = a;
  A->ops->getid = matrix_id;
  A->ops->clone = matrix_clone;
  A->ops->destroy = matrix_destroy;
  A->ops->zero = matrix_zero;
  A->ops->copy = matrix_copy;
  A->ops->scaleaddi = matrix_scale_add_identity;
  A->ops->space = matrix_space;
  return A;
}

SUNLinearSolver new_second_order_solver(Index n, SUNContext context) {
  SUNLinearSolver S = SUNLinSolNewEmpty(context);
  if (!S) return nullptr;
  auto* s = new (std::nothrow) Solver;
  if (!s) {
    SUNLinSolFreeEmpty(S);
    return nullptr;
  }
  try {
    s->R.setZero(n, n);
    s->lu = Eigen::PartialPivLU<MatrixXd>(n);
    s->rhs.setZero(n);
    s->dv.setZero(n);
    s->scale.setOnes(n);
  } catch (const std::bad_alloc&) {
    delete s;
    SUNLinSolFreeEmpty(S);
    return nullptr;
  }
  S->content = s;
  S->ops->gettype = solver_type;
  S->ops->getid = solver_id;
  S->ops->initialize = solver_initialize;
  S->ops->setup = solver_setup;
  S->ops->solve = solver_solve;
  S->ops->lastflag = solver_last_flag;
  S->ops->space = solver_space;
  S->ops->free = solver_free;
  return S;
}

}  // namespace mbsgen::detail

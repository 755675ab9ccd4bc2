// Matrices of program expressions (exact zeros skipped, each entry an intermediate) and their
// numbers at the operating point with the default parameter values (50 digits; the loops'
// dependent coordinates closed by close_loops). Internal to the generator: the nonholonomic
// constraints (mechanics/nonholonomic.cpp) and the linear model of a constrained steady motion
// (linear/constrained_linearization.cpp) share them.
#pragma once

#include "mbsgen/generator/mechanics/loop_closure.hpp"

#include <Eigen/Core>

#include <map>
#include <string>
#include <vector>

namespace mbsgen {
struct Equations;
}

namespace mbsgen::detail {

/// A rows × cols matrix of exact zeros.
ExMatrix zeros(std::size_t rows, std::size_t cols);
std::size_t columns_of(const ExMatrix& A);
/// A B, each entry defined as an intermediate of prog.
ExMatrix product(Program& prog, const ExMatrix& A, const ExMatrix& B);
ExMatrix transposed(const ExMatrix& A);
/// A + sign·B, the changed entries defined as intermediates of prog.
ExMatrix combination(Program& prog, const ExMatrix& A, const ExMatrix& B, int sign);

/// The independent coordinates of the loops (all coordinates without loops).
std::vector<std::size_t> independent_coordinates(const Equations& eq);
/// T = ∂y/∂y_i (n×f): unit rows for the independent coordinates, X for the dependent ones.
ExMatrix tangent_map(const Equations& eq);
/// The position of k in the ascending v (where it is, or would be inserted).
std::size_t position_in(const std::vector<std::size_t>& v, std::size_t k);
/// The names of the coordinates `which`, comma-separated.
std::string coordinate_names(const Model& model, const std::vector<std::size_t>& which);

/// The operating point's values with the default parameter values: parameters, coordinates
/// (closed loops at their closed values), rates.
GiNaC::exmap defaults_at_operating_point(const Model& model, const Equations& eq);
/// entries at the operating point with the default parameter values, in 50 digits; `shift` moves
/// coordinates away from it (index → amount). Throws ModelError when they cannot be evaluated.
std::vector<double> at_defaults(const Model& model, Equations& eq, const std::vector<GiNaC::ex>& entries,
                                const std::map<std::size_t, double>& shift = {});
/// A's entries at the operating point with the default parameter values.
Eigen::MatrixXd numbers(const Model& model, Equations& eq, const ExMatrix& A);
/// The largest steady rate with the default parameter values.
double rate_size(const Model& model, const Equations& eq);
/// v with 9 significant digits.
std::string format(double v);

}  // namespace mbsgen::detail

// Numerical checks of derived equations at the model's operating point (issue 8 §1), run by
// `mbsgen check`, `generate`, `info` and `run` after linearization and before any code is
// emitted, so that a model that cannot give a meaningful linear model fails with its location.
#pragma once

#include "mbsgen/generator/linear/linearize.hpp"

namespace mbsgen {

/// Evaluates the equations at the operating point (y0, ẏ0, u = 0) with the parameters' default
/// values, in 50-digit floating point, and throws ModelError when
///  - M(y0) is singular: a kinematic singularity (gimbal lock) or coordinates that move no mass;
///    the message names the coordinates of its null space. Criterion: the diagonally scaled
///    matrix D^{-1/2} M D^{-1/2} (D = diag M) has an eigenvalue below 1e-10, i.e. M is singular
///    to within 10 digits after equilibration, or a diagonal entry of M is zero;
///  - the operating point is `given` and is not an equilibrium (or a steady motion): some
///    |k − q|_i exceeds 1e-9·(‖K‖·max(1, ‖y0‖) + ‖Q‖·max(1, ‖ẏ0‖)) (max norms); the message lists
///    the largest residuals by coordinate;
///  - the equations cannot be evaluated there (a pole) or give a non-finite number.
/// An operating point of kind `equilibrium` holds only an initial guess: it is not checked here
/// (the runtime's Newton method reports when it cannot find an equilibrium).
void check_operating_point(const Equations& eq, const LinearEquations& lin);

}  // namespace mbsgen

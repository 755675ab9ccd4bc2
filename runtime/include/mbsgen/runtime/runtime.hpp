// Umbrella header of the mbsgen runtime (Eigen + LAPACK; never GiNaC).
#pragma once

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/frequency_response.hpp"
#include "mbsgen/runtime/linear_model.hpp"
#include "mbsgen/runtime/matrix_market.hpp"
#include "mbsgen/runtime/parameter_sweep.hpp"
#include "mbsgen/runtime/quadratic_eigen.hpp"
#include "mbsgen/runtime/simulation.hpp"
#include "mbsgen/runtime/static_equilibrium.hpp"
#include "mbsgen/runtime/version.hpp"

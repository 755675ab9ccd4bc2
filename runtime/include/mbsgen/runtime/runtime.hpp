// Umbrella header of the mbsgen runtime (Eigen + LAPACK; never GiNaC).
#pragma once

#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/linear_model.hpp"
#include "mbsgen/runtime/model/matrix_market.hpp"
#include "mbsgen/runtime/model/static_equilibrium.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/spectral/parameter_sweep.hpp"
#include "mbsgen/runtime/spectral/quadratic_eigen.hpp"
#include "mbsgen/runtime/time/simulation.hpp"
#include "mbsgen/runtime/version.hpp"

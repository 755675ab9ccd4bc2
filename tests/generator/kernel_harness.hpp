// The kernels of one generated model, gathered for the tests.
#pragma once

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
  int (*mass_matrix)(const double* y, const double* p, double* M);
  int (*residual)(const double* y, const double* yd, const double* u, const double* p, double* r);
  int (*linear)(const double* y0, const double* yd0, const double* p, double* M, double* Q,
                double* K, double* B, double* Cy, double* Cv);
  int (*operating_point)(const double* p, double* y0, double* yd0);
  int (*outputs)(const double* y, const double* yd, const double* p, double* z);
  int (*bodies)(const double* y, const double* p, double* rc, double* S, double* JT, double* JR,
                double* m, double* Ic);
};

const std::vector<GeneratedModel>& all_models();

}  // namespace mbsgen::test

#define MBSGEN_GENERATED_MODEL(id)                                                          \
  ::mbsgen::test::GeneratedModel {                                                          \
    #id, id##_n_coordinates, id##_n_inputs, id##_n_outputs, id##_n_parameters,              \
        id##_n_bodies, id##_at_rest != 0, id##_parameter_defaults, id##_coordinate_names,   \
        id##_parameter_names,                                                               \
        id##_mass_matrix, id##_residual, id##_linear, id##_operating_point, id##_outputs,   \
        id##_bodies                                                                         \
  }

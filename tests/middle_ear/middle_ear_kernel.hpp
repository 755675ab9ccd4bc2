// The generated kernels of models/middle_ear/middle_ear.yaml (generated at build time by
// tests/middle_ear/CMakeLists.txt), evaluated by parameter name.
#pragma once

#include "middle_ear.hpp"

#include <Eigen/Dense>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace middle_ear_test {

constexpr int kN = middle_ear_n_coordinates;   // 18
constexpr int kNu = middle_ear_n_inputs;       // 7 (P and the temporal bone's six motions)
constexpr int kNr = middle_ear_n_outputs;      // outputs, in the order of the model file
constexpr int kNp = middle_ear_n_parameters;

/// Parameters by name, SI values.
using Parameters = std::map<std::string, double>;

/// The model file's parameter defaults.
inline Parameters default_parameters() {
  Parameters p;
  for (int i = 0; i < kNp; ++i) p[middle_ear_parameter_names[i]] = middle_ear_parameter_defaults[i];
  return p;
}

inline int index_of(const char* const* names, int count, const std::string& name) {
  for (int i = 0; i < count; ++i)
    if (name == names[i]) return i;
  throw std::runtime_error("middle_ear: no entry named " + name);
}
inline int coordinate_index(const std::string& name) {
  return index_of(middle_ear_coordinate_names, kN, name);
}
inline int output_index(const std::string& name) {
  return index_of(middle_ear_output_names, kNr, name);
}

/// M, Q, K, B, C_y, C_v of the linear kernel at the operating point for parameters p (every
/// parameter of the model must be present in p).
struct Linear {
  Eigen::MatrixXd M, Q, K, B, Cy, Cv;
  Eigen::MatrixXd D, G, Ks, N;  // linear_structured: sym(Q), skew(Q), sym(K), skew(K)
};

inline Linear generated_linear(const Parameters& p) {
  Eigen::VectorXd pv(kNp);
  for (int i = 0; i < kNp; ++i) {
    const auto it = p.find(middle_ear_parameter_names[i]);
    if (it == p.end())
      throw std::runtime_error(std::string("middle_ear: parameter missing: ") +
                               middle_ear_parameter_names[i]);
    pv[i] = it->second;
  }
  Eigen::VectorXd y0(kN), yd0(kN);
  if (middle_ear_operating_point(pv.data(), y0.data(), yd0.data()) != 0)
    throw std::runtime_error("middle_ear_operating_point failed");
  Linear L;
  L.M.resize(kN, kN);
  L.Q.resize(kN, kN);
  L.K.resize(kN, kN);
  L.B.resize(kN, kNu);
  L.Cy.resize(kNr, kN);
  L.Cv.resize(kNr, kN);
  if (middle_ear_linear(y0.data(), yd0.data(), pv.data(), L.M.data(), L.Q.data(), L.K.data(),
                        L.B.data(), L.Cy.data(), L.Cv.data()) != 0)
    throw std::runtime_error("middle_ear_linear: non-finite output");
  L.D.resize(kN, kN);
  L.G.resize(kN, kN);
  L.Ks.resize(kN, kN);
  L.N.resize(kN, kN);
  Eigen::MatrixXd M2(kN, kN);
  if (middle_ear_linear_structured(y0.data(), yd0.data(), pv.data(), M2.data(), L.D.data(),
                                   L.G.data(), L.Ks.data(), L.N.data()) != 0)
    throw std::runtime_error("middle_ear_linear_structured: non-finite output");
  return L;
}

inline std::vector<std::string> coordinate_names() {
  return {middle_ear_coordinate_names, middle_ear_coordinate_names + kN};
}
inline std::vector<std::string> output_names() {
  return {middle_ear_output_names, middle_ear_output_names + kNr};
}

}  // namespace middle_ear_test

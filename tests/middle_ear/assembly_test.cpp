// The generated linear kernel of the middle-ear model against an independent, finite-element
// style assembly of the same 18-coordinate system, written here from the parameter tables of
// docs/middle-ear.md ("Parameters and sources": the notes' proposed parameter set, with the
// sources in docs/references.md) and not from the generator's route (frames, rotation matrices,
// Newton-Euler projection, symbolic differentiation).
//
// Small-displacement field: body b (0 malleus, 1 incus, 2 stapes) has the coordinates
// q_b = (t_b, θ_b) (translation of its point at the origin, small rotation about the global axes),
// and its point at rest position r moves by  δr = t_b + θ_b × r = [E, −[r]×] q_b.
//   - rigid-body mass matrix of a body about the origin, from m, centre of mass c and the inertia
//     I_c about c:  M_O = [[m E, −m[c]×], [m[c]×, I_c − m[c]×[c]×]]  (T = ½ q̇ᵀ M_O q̇);
//     the point masses (eardrum at the umbo, cochlear fluid at the footplate) are the same with
//     I_c = 0, scattered into their carrier body's block;
//   - a bushing at point r between bodies a and b (or the skull) measures the relative
//     displacement and rotation  T q = [[P_b(r) − P_a(r)], [R_b − R_a]]  (6×18) and adds
//     Tᵀ diag(k_t, k_r) T to K and Tᵀ diag(d_t, d_r) T to D, as an FE code assembles springs;
//   - B = P_malleus(umbo)ᵀ (0, 0, −A), and the output rows dᵀ P_b(r) (or unit rows for rates).
#include "middle_ear_kernel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <sstream>

namespace middle_ear_test {
namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;

// Both routes form the same sums of products of the same doubles in different orders and
// associations (the generator through composite inertias and subtree wrench sums, this file
// through 6×18 maps). Each entry of M, D and K is a sum of PSD element contributions, so by
// Cauchy-Schwarz the sum of the moduli of all its terms is at most sqrt(F_ii F_jj); the rounding
// difference is then at most about (number of terms, < 100)·u·sqrt(F_ii F_jj) ≈ 2e-14·sqrt(F_ii F_jj).
// 1e-12 leaves a factor 50 for the generator's intermediate sums, while a wrong, missing or
// misplaced term (a unit slip, a sign, a lever arm) changes an entry by far more. For B and C the
// same argument uses ‖J column‖·‖direction‖ as the bound of the terms.
constexpr double kTol = 1e-12;

enum Body { kGround = -1, kMalleus = 0, kIncus = 1, kStapes = 2 };

// The proposed parameter set, typed in the units of the notes and converted here.
Parameters reference_parameters() {
  constexpr double mm = 1e-3, mg = 1e-6, mg_mm2 = 1e-12;
  Parameters p;
  // Bodies: mass, centre of mass, principal inertia about the centre of mass.
  p["m_malleus"] = 25 * mg;
  p["com_malleus_x"] = 0.5 * mm;
  p["com_malleus_y"] = 0.3 * mm;
  p["com_malleus_z"] = 0.2 * mm;
  p["I_malleus_xx"] = 104 * mg_mm2;
  p["I_malleus_yy"] = 17.3 * mg_mm2;
  p["I_malleus_zz"] = 104 * mg_mm2;
  p["m_incus"] = 28 * mg;
  p["com_incus_x"] = -2.0 * mm;
  p["com_incus_y"] = 0.5 * mm;
  p["com_incus_z"] = -0.6 * mm;
  p["I_incus_xx"] = 70.6 * mg_mm2;
  p["I_incus_yy"] = 35.3 * mg_mm2;
  p["I_incus_zz"] = 70.6 * mg_mm2;
  p["m_stapes"] = 3.0 * mg;
  p["com_stapes_x"] = -2.5 * mm;
  p["com_stapes_y"] = -4.46 * mm;
  p["com_stapes_z"] = -3.0 * mm;
  p["I_stapes_xx"] = 2.9 * mg_mm2;
  p["I_stapes_yy"] = 2.9 * mg_mm2;
  p["I_stapes_zz"] = 2.2 * mg_mm2;
  p["m_eardrum"] = 12 * mg;
  p["m_cochlea"] = 10 * mg;
  // Points.
  const auto point = [&](const std::string& name, double x, double y, double z) {
    p[name + "_x"] = x * mm;
    p[name + "_y"] = y * mm;
    p[name + "_z"] = z * mm;
  };
  point("umbo", 0, -5.8, 0.5);
  point("aml", 2.0, 0, 0);
  point("pil", -4.0, 0, 0);
  point("imj", -1.0, 1.5, -0.5);
  point("isj", -2.5, -4.46, -1.0);
  point("fp", -2.5, -4.46, -4.2);
  // Bushings (N/m, N m/rad, N s/m).
  const auto xyz = [&](const std::string& name, double x, double y, double z) {
    p[name + "_x"] = x;
    p[name + "_y"] = y;
    p[name + "_z"] = z;
  };
  p["beta"] = 3e-5;
  xyz("k_eardrum", 500, 500, 200);
  xyz("d_eardrum", 0.01, 0.01, 0.02);
  xyz("k_aml", 5000, 5000, 5000);
  xyz("kr_aml", 2.0e-2, 1e-4, 1e-4);
  xyz("k_pil", 5000, 5000, 5000);
  xyz("kr_pil", 1e-4, 1e-4, 1e-4);
  xyz("k_imj", 25000, 25000, 25000);
  xyz("kr_imj", 0.2, 0.2, 0.2);
  xyz("d_imj", 1.0, 1.0, 1.0);
  xyz("k_isj", 2041, 2041, 2041);
  xyz("kr_isj", 1e-5, 1e-5, 1e-5);
  xyz("d_isj", 3.6, 3.6, 3.6);
  xyz("k_al", 4000, 4000, 891);
  xyz("kr_al", 1.7e-4, 8.2e-4, 4.4e-3);
  p["d_al_z"] = 0.018;
  p["d_cochlea_z"] = 0.216;
  p["A_tm"] = 60 * mm * mm;
  return p;
}

Matrix3d skew(const Vector3d& r) {
  Matrix3d S;
  S << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return S;  // S v = r × v
}

Vector3d vec(const Parameters& p, const std::string& name) {
  return {p.at(name + "_x"), p.at(name + "_y"), p.at(name + "_z")};
}

// δr of the body point at rest position r: 3×18, [E, −[r]×] in the body's columns.
MatrixXd point_map(int body, const Vector3d& r) {
  MatrixXd P = MatrixXd::Zero(3, kN);
  if (body == kGround) return P;
  P.block(0, 6 * body, 3, 3) = Matrix3d::Identity();
  P.block(0, 6 * body + 3, 3, 3) = -skew(r);
  return P;
}
// Small rotation θ of the body: 3×18.
MatrixXd rotation_map(int body) {
  MatrixXd R = MatrixXd::Zero(3, kN);
  if (body != kGround) R.block(0, 6 * body + 3, 3, 3) = Matrix3d::Identity();
  return R;
}

// Rigid-body mass matrix about the origin (coordinates (t, θ)).
MatrixXd rigid_mass(double m, const Vector3d& c, const Matrix3d& Ic) {
  MatrixXd Mo(6, 6);
  const Matrix3d C = skew(c);
  Mo << m * Matrix3d::Identity(), -m * C, m * C, Ic - m * C * C;
  return Mo;
}

struct Assembly {
  MatrixXd M = MatrixXd::Zero(kN, kN), D = MatrixXd::Zero(kN, kN), K = MatrixXd::Zero(kN, kN);
  MatrixXd B, Cy, Cv, B_scale, Cy_scale, Cv_scale;
};

Assembly assemble(const Parameters& p) {
  Assembly A;
  // Mass: each body's element matrix, plus the two point masses on their carrier bodies.
  const char* names[] = {"malleus", "incus", "stapes"};
  for (int b = 0; b < 3; ++b) {
    const std::string n = names[b];
    const Matrix3d Ic =
        Vector3d(p.at("I_" + n + "_xx"), p.at("I_" + n + "_yy"), p.at("I_" + n + "_zz")).asDiagonal();
    A.M.block(6 * b, 6 * b, 6, 6) += rigid_mass(p.at("m_" + n), vec(p, "com_" + n), Ic);
  }
  A.M.block(6 * kMalleus, 6 * kMalleus, 6, 6) += rigid_mass(p.at("m_eardrum"), vec(p, "umbo"), Matrix3d::Zero());
  A.M.block(6 * kStapes, 6 * kStapes, 6, 6) += rigid_mass(p.at("m_cochlea"), vec(p, "fp"), Matrix3d::Zero());

  // Bushings: relative displacement/rotation map T, element stiffness and damping.
  const double beta = p.at("beta");
  const auto bushing = [&](int a, int b, const Vector3d& r, const Vector3d& kt, const Vector3d& kr,
                           const Vector3d& dt, const Vector3d& dr) {
    MatrixXd T(6, kN);
    T << point_map(b, r) - point_map(a, r), rotation_map(b) - rotation_map(a);
    Eigen::VectorXd k(6), d(6);
    k << kt, kr;
    d << dt, dr;
    A.K += T.transpose() * k.asDiagonal() * T;
    A.D += T.transpose() * d.asDiagonal() * T;
  };
  const Vector3d zero = Vector3d::Zero();
  // eardrum (lumped): malleus-ground at the umbo, translational only, damping given.
  bushing(kGround, kMalleus, vec(p, "umbo"), vec(p, "k_eardrum"), zero, vec(p, "d_eardrum"), zero);
  // AML: malleus-ground, damping beta*k.
  bushing(kGround, kMalleus, vec(p, "aml"), vec(p, "k_aml"), vec(p, "kr_aml"), beta * vec(p, "k_aml"),
          beta * vec(p, "kr_aml"));
  // PIL: incus-ground, damping beta*k.
  bushing(kGround, kIncus, vec(p, "pil"), vec(p, "k_pil"), vec(p, "kr_pil"), beta * vec(p, "k_pil"),
          beta * vec(p, "kr_pil"));
  // incudomallear joint: translational damping given, rotational beta*k.
  bushing(kMalleus, kIncus, vec(p, "imj"), vec(p, "k_imj"), vec(p, "kr_imj"), vec(p, "d_imj"),
          beta * vec(p, "kr_imj"));
  // incudostapedial joint: translational damping given, rotational beta*k.
  bushing(kIncus, kStapes, vec(p, "isj"), vec(p, "k_isj"), vec(p, "kr_isj"), vec(p, "d_isj"),
          beta * vec(p, "kr_isj"));
  // annular ligament + cochlea: x, y beta*k, z = annular ligament + cochlear resistance.
  const Vector3d k_al = vec(p, "k_al");
  bushing(kGround, kStapes, vec(p, "fp"), k_al, vec(p, "kr_al"),
          Vector3d(beta * k_al.x(), beta * k_al.y(), p.at("d_al_z") + p.at("d_cochlea_z")),
          beta * vec(p, "kr_al"));

  // Input: force (0, 0, −A P) at the umbo.
  const Vector3d f(0, 0, -p.at("A_tm"));
  const MatrixXd Pu = point_map(kMalleus, vec(p, "umbo"));
  // The temporal bone's motion inputs (bone conduction) reach the chain through its inertia
  // only (B2); every bushing measures relative motion, so their columns of B are exactly zero.
  const int pressure = index_of(middle_ear_input_names, kNu, "P");
  A.B = A.B_scale = MatrixXd::Zero(kN, kNu);
  A.B.col(pressure) = Pu.transpose() * f;
  A.B_scale.col(pressure) = Pu.colwise().norm().transpose() * f.norm();

  // Outputs, by name.
  A.Cy = A.Cv = A.Cy_scale = A.Cv_scale = MatrixXd::Zero(kNr, kN);
  const Vector3d medial(0, 0, -1), superior(0, 1, 0);
  const auto point_output = [&](const std::string& name, MatrixXd& C, MatrixXd& S, int body,
                                const Vector3d& r, const Vector3d& dir) {
    const MatrixXd P = point_map(body, r);
    C.row(output_index(name)) = dir.transpose() * P;
    S.row(output_index(name)) = P.colwise().norm() * dir.norm();
  };
  point_output("v_stapes", A.Cv, A.Cv_scale, kStapes, vec(p, "fp"), medial);
  point_output("v_umbo", A.Cv, A.Cv_scale, kMalleus, vec(p, "umbo"), medial);
  point_output("v_incus_isj", A.Cv, A.Cv_scale, kIncus, vec(p, "isj"), medial);
  point_output("x_stapes", A.Cy, A.Cy_scale, kStapes, vec(p, "fp"), medial);
  point_output("x_umbo", A.Cy, A.Cy_scale, kMalleus, vec(p, "umbo"), medial);
  point_output("v_stapes_y", A.Cv, A.Cv_scale, kStapes, vec(p, "fp"), superior);
  // Relative to the oval window on the temporal bone, which is still in the linear model's
  // states (its motion enters through the inputs): the same rows as the absolute ones.
  point_output("v_stapes_rel", A.Cv, A.Cv_scale, kStapes, vec(p, "fp"), medial);
  point_output("x_stapes_rel", A.Cy, A.Cy_scale, kStapes, vec(p, "fp"), medial);
  // F_cochlea: minus the annular ligament's load on the footplate along z, the world-fixed
  // bushing's k_z Δz + d_z Δż (d_z with the cochlear load), = k_z x_stapes + d_z v_stapes medial.
  point_output("F_cochlea", A.Cy, A.Cy_scale, kStapes, vec(p, "fp"), medial * p.at("k_al_z"));
  point_output("F_cochlea", A.Cv, A.Cv_scale, kStapes, vec(p, "fp"), medial * (p.at("d_al_z") + p.at("d_cochlea_z")));
  for (const auto& [output, coordinate] :
       {std::pair<std::string, std::string>{"omega_malleus_x", "malleus_rx"},
        {"omega_stapes_x", "stapes_rx"},
        {"omega_stapes_y", "stapes_ry"}}) {
    A.Cv(output_index(output), coordinate_index(coordinate)) = 1;
    A.Cv_scale(output_index(output), coordinate_index(coordinate)) = 1;
  }
  return A;
}

// |G_ij − F_ij| ≤ kTol·sqrt(|S_ii S_jj|) for a symmetric positive semidefinite S (see kTol).
void expect_close_symmetric(const char* what, const MatrixXd& G, const MatrixXd& F, const MatrixXd& S) {
  const auto names = coordinate_names();
  int bad = 0;
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const double bound = kTol * std::sqrt(std::abs(S(i, i) * S(j, j)));
      if (!(std::abs(G(i, j) - F(i, j)) <= bound) && bad++ < 10)
        ADD_FAILURE() << what << "(" << names[static_cast<std::size_t>(i)] << ", "
                      << names[static_cast<std::size_t>(j)] << "): generated " << G(i, j)
                      << ", assembled " << F(i, j) << ", bound " << bound;
    }
  EXPECT_EQ(bad, 0) << what;
}
// |G_ij − F_ij| ≤ kTol·S_ij with S a bound of the moduli of the terms (exact zero where S = 0).
void expect_close_scaled(const char* what, const MatrixXd& G, const MatrixXd& F, const MatrixXd& S) {
  ASSERT_EQ(G.rows(), F.rows());
  ASSERT_EQ(G.cols(), F.cols());
  int bad = 0;
  for (Eigen::Index i = 0; i < G.rows(); ++i)
    for (Eigen::Index j = 0; j < G.cols(); ++j)
      if (!(std::abs(G(i, j) - F(i, j)) <= kTol * S(i, j)) && bad++ < 10)
        ADD_FAILURE() << what << "(" << i << ", " << j << "): generated " << G(i, j)
                      << ", assembled " << F(i, j) << ", bound " << kTol * S(i, j);
  EXPECT_EQ(bad, 0) << what;
}

// The generated kernel at parameters p_kernel against the assembly at p_assembly (the same
// values, or the notes' values typed in their own units).
void expect_kernel_equals_assembly(const Parameters& p_kernel, const Parameters& p_assembly) {
  const Linear L = generated_linear(p_kernel);
  const Assembly A = assemble(p_assembly);
  // Every coordinate carries mass, stiffness and damping: the scales are positive.
  ASSERT_GT(A.M.diagonal().minCoeff(), 0);
  ASSERT_GT(A.K.diagonal().minCoeff(), 0);
  ASSERT_GT(A.D.diagonal().minCoeff(), 0);
  expect_close_symmetric("M", L.M, A.M, A.M);
  expect_close_symmetric("Q", L.Q, A.D, A.D);
  expect_close_symmetric("K", L.K, A.K, A.K);
  // At rest there is no gyroscopic or circulatory term: Q = D, K = K_s, G = N = 0.
  expect_close_symmetric("D", L.D, A.D, A.D);
  expect_close_symmetric("G", L.G, MatrixXd::Zero(kN, kN), A.D);
  expect_close_symmetric("K_s", L.Ks, A.K, A.K);
  expect_close_symmetric("N", L.N, MatrixXd::Zero(kN, kN), A.K);
  expect_close_scaled("B", L.B, A.B, A.B_scale);
  expect_close_scaled("C_y", L.Cy, A.Cy, A.Cy_scale);
  expect_close_scaled("C_v", L.Cv, A.Cv, A.Cv_scale);
}

// The model file holds exactly the proposed parameter set, converted to SI: each value is the
// nearest double to the same decimal, computed once by the YAML reader and once here as a
// product (e.g. 25·1e-6), so they agree to a few units in the last place (4u).
TEST(MiddleEarParameters, ModelFileHoldsTheReferenceParameterSetInSI) {
  const Parameters file = default_parameters(), ref = reference_parameters();
  std::set<std::string> file_names, ref_names;
  for (const auto& [name, value] : file) file_names.insert(name);
  for (const auto& [name, value] : ref) ref_names.insert(name);
  EXPECT_EQ(file_names, ref_names);
  for (const auto& [name, value] : ref) {
    if (!file.count(name)) continue;
    EXPECT_LE(std::abs(file.at(name) - value), 4 * 1.1102230246251565e-16 * std::abs(value))
        << name << ": file " << file.at(name) << ", notes " << value;
  }
}

// The generated kernel at the file's defaults against the assembly from the notes' values.
TEST(MiddleEarAssembly, LinearKernelEqualsAssemblyAtTheReferenceParameters) {
  // Defaults and notes differ by a few ulp (test above), i.e. ~1e-15 relative: inside kTol.
  expect_kernel_equals_assembly(default_parameters(), reference_parameters());
}

// Every parameter perturbed by name (zero-valued point coordinates get an offset): each one is
// wired to the right place in the generated code.
TEST(MiddleEarAssembly, LinearKernelEqualsAssemblyAtPerturbedParameters) {
  Parameters p = default_parameters();
  int i = 0;
  for (auto& [name, value] : p) {
    ++i;
    value = value == 0 ? 0.4e-3 * std::sin(1.3 * i) : value * (1 + 0.3 * std::sin(1.7 * i + 1));
  }
  expect_kernel_equals_assembly(p, p);
}

// The variations of the notes as parameter overrides: stapes fixation (annular ligament × 100)
// and a disarticulated incudostapedial joint (stiffness and damping 0).
TEST(MiddleEarAssembly, VariationsAreParameterOverrides) {
  Parameters fixed = default_parameters();
  for (const char* k : {"k_al_x", "k_al_y", "k_al_z", "kr_al_x", "kr_al_y", "kr_al_z"}) fixed[k] *= 100;
  expect_kernel_equals_assembly(fixed, fixed);
  Parameters loose = default_parameters();
  for (const char* k : {"k_isj_x", "k_isj_y", "k_isj_z", "kr_isj_x", "kr_isj_y", "kr_isj_z",
                        "d_isj_x", "d_isj_y", "d_isj_z"})
    loose[k] = 0;
  expect_kernel_equals_assembly(loose, loose);
  // Disarticulated: no coupling between the incus and the stapes coordinates.
  const Linear L = generated_linear(loose);
  EXPECT_EQ(L.K.block(6, 12, 6, 6).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(L.Q.block(6, 12, 6, 6).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace middle_ear_test

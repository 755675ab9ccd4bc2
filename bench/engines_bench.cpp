// Per-call speed against numeric engines (issue 17 §2; docs/accuracy-vs-time.md, run by
// bench/engines.sh): our generated `mass_matrix` and `residual` kernels against MuJoCo and Orocos
// KDL on the N-link spatial chains (mbsgen::spatial_chain: universal joints, full inertia tensors,
// 2N coordinates) and on the PUMA 560 (models/robots/puma560.yaml), in the same process, on the
// same random states.
//
// What is timed, from the state (q, q̇) to the result:
//   M      ours: <id>_mass_matrix; MuJoCo: mj_kinematics, mj_comPos, mj_crb, mj_fullM (the
//          position stages mj_forward runs that M needs; collision and constraints left out);
//          KDL: ChainDynParam::JntToMass
//   bias   k − q = c(q, q̇) + g(q) (springs and dampers set to zero): ours: <id>_residual;
//          MuJoCo: mj_kinematics, mj_comPos, mj_comVel, mj_rne (qfrc_bias); KDL:
//          ChainDynParam::JntToCoriolis + JntToGravity ("kdl"), or one ChainIdSolver_RNE pass
//          with q̈ = 0 ("kdl_rne")
//   M+bias both: ours: <id>_dynamics (M and k − q in one kernel, EmitOptions::dynamics, sharing
//          the sines, cosines and transforms); MuJoCo sharing its position stages; KDL both calls
// Before timing, M and the bias of every engine are compared on every state: the largest
// difference over the largest entry must be below 1e-12, else the run stops (exit 1).
// Repetitions (51; 21 with --quick) of batches of about 2 ms of all engines of a model are
// interleaved (round robin) and timed in thread CPU time, so that the load of the shared machine
// weighs on all alike and little; medians are reported, with the spread (bench/harness.hpp).
//
//   engines_bench OUT_DIR [--quick] [--reps N] [--only MODEL]
// writes OUT_DIR/engines.csv, OUT_DIR/engines_agreement.csv and the MJCF files it loaded
// (OUT_DIR/engines_mjcf/*.xml).
#include "harness.hpp"
#include "mujoco_engine.hpp"
#include "puma560.hpp"
#include "spatial_chain_12.hpp"
#include "spatial_chain_3.hpp"
#include "spatial_chain_30.hpp"
#include "spatial_chain_6.hpp"

#include <Eigen/Dense>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#ifndef MBSGEN_ENGINES_GENERATED_DIR
#define MBSGEN_ENGINES_GENERATED_DIR ""
#endif

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// Agreement required of the three before anything is timed: all compute in double through
// different sequences of operations (composite inertias, recursive Newton–Euler, CSE'd
// closed forms), so they differ by rounding, a few hundred ulps of the largest entry at most.
constexpr double kAgreement = 1e-12;

// ---- the models, as all three are given them ----------------------------------------------------

/// One rigid link of a serial chain: its frame F_i = F_(i-1) · Trans(p) · R · Rot(axes[0], q_j) ·
/// Rot(axes[1], q_(j+1)) …, each rotation about an axis (0 = x, 1 = y, 2 = z) of the current frame,
/// and its mass m [kg], centre of mass c [m] and inertia I about c [kg m²], both in F_i.
struct Link {
  Vec3 p = Vec3::Zero();
  Mat3 R = Mat3::Identity();
  std::vector<int> axes;
  double m = 0;
  Vec3 c = Vec3::Zero();
  Mat3 I = Mat3::Zero();
};

struct ChainModel {
  std::vector<Link> links;
  Vec3 gravity = Vec3::Zero();  ///< [m/s²], world frame
  int dof() const {
    int n = 0;
    for (const Link& l : links) n += static_cast<int>(l.axes.size());
    return n;
  }
};

/// Our generated kernels of one model (<id>.hpp).
struct Kernels {
  std::string id;
  int n = 0, n_parameters = 0;
  int (*mass_matrix)(const double*, const double*, double*) = nullptr;
  int (*residual)(const double*, const double*, const double*, const double*, double*) = nullptr;
  int (*dynamics)(const double*, const double*, const double*, const double*, double*, double*) = nullptr;
  const char* const* parameter_names = nullptr;
  const double* parameter_defaults = nullptr;
};

#define MBSGEN_KERNELS(ID) \
  Kernels { #ID, ID##_n_coordinates, ID##_n_parameters, ID##_mass_matrix, ID##_residual, ID##_dynamics, ID##_parameter_names, ID##_parameter_defaults }

/// A model of the benchmark: our kernels, their parameter vector and the same model for the
/// engines, built from that parameter vector.
struct Case {
  std::string name;
  int links = 0;  ///< N
  Kernels k;
  std::vector<double> p;
  ChainModel model;
};

double parameter(const Kernels& k, const std::vector<double>& p, const std::string& name) {
  for (int i = 0; i < k.n_parameters; ++i)
    if (name == k.parameter_names[i]) return p[static_cast<std::size_t>(i)];
  throw std::runtime_error(k.id + " has no parameter " + name);
}

void set_parameter(const Kernels& k, std::vector<double>& p, const std::string& name, double v) {
  for (int i = 0; i < k.n_parameters; ++i)
    if (name == k.parameter_names[i]) {
      p[static_cast<std::size_t>(i)] = v;
      return;
    }
  throw std::runtime_error(k.id + " has no parameter " + name);
}

// The sizes of the chains, those bench/CMakeLists.txt generates.
Case spatial_chain_case(int n, const Kernels& k) {
  Case c{"spatial_chain", n, k, {k.parameter_defaults, k.parameter_defaults + k.n_parameters}, {}};
  // No springs or dampers: k − q is then the engines' bias c(q, q̇) + g(q).
  set_parameter(k, c.p, "k", 0.0);
  set_parameter(k, c.p, "c", 0.0);
  auto P = [&](const char* name) { return parameter(k, c.p, name); };
  const double l = P("l");
  Mat3 I;
  I << P("Ixx"), P("Ixy"), P("Ixz"), P("Ixy"), P("Iyy"), P("Iyz"), P("Ixz"), P("Iyz"), P("Izz");
  for (int i = 0; i < n; ++i) {
    Link link;
    if (i > 0) link.p = Vec3(0, 0, -l);
    link.axes = {0, 1};  // about x (a_i), then about the new y (b_i)
    link.m = P("m");
    link.c = Vec3(0, 0, -l / 2);
    link.I = I;
    c.model.links.push_back(link);
  }
  c.model.gravity = Vec3(0, 0, -P("g"));
  return c;
}

// models/robots/puma560.yaml: modified Denavit–Hartenberg frames
// S_i = S_(i-1) Tx(a_i) Rx(alpha_i) Tz(d_i) Rz(q_i), twists alpha = 0, −π/2, 0, π/2, −π/2, π/2
// (their sines and cosines written exactly, as the model's exact Pi/2 gives them).
Case puma_case(const Kernels& k) {
  Case c{"puma560", 6, k, {k.parameter_defaults, k.parameter_defaults + k.n_parameters}, {}};
  auto P = [&](const std::string& name) { return parameter(k, c.p, name); };
  const double sin_alpha[6] = {0, -1, 0, 1, -1, 1}, cos_alpha[6] = {1, 0, 1, 0, 0, 0};
  const double a[6] = {0, 0, P("a3"), P("a4"), 0, 0}, d[6] = {0, P("d2"), P("d3"), P("d4"), 0, 0};
  const Vec3 com[6] = {Vec3::Zero(), Vec3(P("c2x"), P("c2y"), P("c2z")), Vec3(0, P("c3y"), P("c3z")),
                       Vec3(0, 0, P("c4z")), Vec3::Zero(), Vec3(0, 0, P("c6z"))};
  for (int i = 0; i < 6; ++i) {
    const std::string s = std::to_string(i + 1);
    Link link;
    link.p = Vec3(a[i], -sin_alpha[i] * d[i], cos_alpha[i] * d[i]);
    link.R << 1, 0, 0, 0, cos_alpha[i], -sin_alpha[i], 0, sin_alpha[i], cos_alpha[i];
    link.axes = {2};
    link.m = P("m" + s);
    link.c = com[i];
    // Link 1's moments about x and y equal its I1zz (the model file says why).
    link.I.diagonal() = i == 0 ? Vec3(P("I1zz"), P("I1zz"), P("I1zz"))
                               : Vec3(P("I" + s + "xx"), P("I" + s + "yy"), P("I" + s + "zz"));
    c.model.links.push_back(link);
  }
  c.model.gravity = Vec3(0, 0, -P("g"));
  return c;
}

// ---- MuJoCo -------------------------------------------------------------------------------------

std::string num17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::string vec_attr(const double* v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += (i ? " " : "") + num17(v[i]);
  return s;
}

/// The chain as MJCF: one body per link at pos p, quat R; its hinges in the order of `axes`
/// (MuJoCo composes a body's joints in the order written, each about its axis in the frame the
/// joints before it produced); the inertia in principal axes (quat, diaginertia), computed here
/// in double rather than by MuJoCo's compiler.
std::string mjcf(const ChainModel& model, const std::string& name) {
  std::ostringstream x;
  x << "<mujoco model=\"" << name << "\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
    << "  <option gravity=\"" << vec_attr(model.gravity.data(), 3) << "\"/>\n"
    << "  <worldbody>\n";
  std::string indent = "    ";
  int j = 0;
  for (std::size_t i = 0; i < model.links.size(); ++i) {
    const Link& l = model.links[i];
    const Eigen::Quaterniond q(l.R);
    const double quat[4] = {q.w(), q.x(), q.y(), q.z()};
    x << indent << "<body name=\"link" << i + 1 << "\" pos=\"" << vec_attr(l.p.data(), 3) << "\" quat=\""
      << vec_attr(quat, 4) << "\">\n";
    for (int axis : l.axes) {
      const double v[3] = {axis == 0 ? 1.0 : 0.0, axis == 1 ? 1.0 : 0.0, axis == 2 ? 1.0 : 0.0};
      x << indent << "  <joint name=\"j" << ++j << "\" type=\"hinge\" axis=\"" << vec_attr(v, 3) << "\"/>\n";
    }
    Mat3 V = Mat3::Identity();
    Vec3 moments = l.I.diagonal();
    if (!l.I.isDiagonal(0.0)) {
      const Eigen::SelfAdjointEigenSolver<Mat3> es(l.I);
      V = es.eigenvectors();
      if (V.determinant() < 0) V.col(2) = -V.col(2);
      moments = es.eigenvalues();
    }
    const Eigen::Quaterniond qi(V);
    const double iquat[4] = {qi.w(), qi.x(), qi.y(), qi.z()};
    x << indent << "  <inertial pos=\"" << vec_attr(l.c.data(), 3) << "\" quat=\"" << vec_attr(iquat, 4)
      << "\" mass=\"" << num17(l.m) << "\" diaginertia=\"" << vec_attr(moments.data(), 3) << "\"/>\n";
    indent += "  ";
  }
  for (std::size_t i = model.links.size(); i > 0; --i) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

using bench::MuJoCo;

// ---- Orocos KDL ---------------------------------------------------------------------------------

KDL::Frame kdl_frame(const Vec3& p, const Mat3& R) {
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)),
                    KDL::Vector(p.x(), p.y(), p.z()));
}

/// The chain as KDL segments: a segment's joint turns at its root and its frame is the joint's
/// pose times f_tip; its inertia is expressed in that tip frame. So each link's last joint
/// carries, as f_tip, the next link's Trans(p) · R, and the link's inertia transformed into that
/// frame; its other joints are massless segments. A fixed first segment places the first link.
KDL::Chain kdl_chain(const ChainModel& model) {
  KDL::Chain chain;
  const Link& first = model.links.front();
  if (!first.p.isZero(0.0) || !first.R.isIdentity(0.0))
    chain.addSegment(KDL::Segment(KDL::Joint(KDL::Joint::Fixed), kdl_frame(first.p, first.R)));
  const KDL::Joint::JointType types[3] = {KDL::Joint::RotX, KDL::Joint::RotY, KDL::Joint::RotZ};
  for (std::size_t i = 0; i < model.links.size(); ++i) {
    const Link& l = model.links[i];
    for (std::size_t j = 0; j < l.axes.size(); ++j) {
      const KDL::Joint joint(types[l.axes[j]]);
      if (j + 1 < l.axes.size()) {
        chain.addSegment(KDL::Segment(joint));
        continue;
      }
      Vec3 p = Vec3::Zero();
      Mat3 R = Mat3::Identity();
      if (i + 1 < model.links.size()) {
        p = model.links[i + 1].p;
        R = model.links[i + 1].R;
      }
      const Vec3 c = R.transpose() * (l.c - p);
      const Mat3 I = R.transpose() * l.I * R;
      const KDL::RigidBodyInertia inertia(l.m, KDL::Vector(c.x(), c.y(), c.z()),
                                          KDL::RotationalInertia(I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2)));
      chain.addSegment(KDL::Segment(joint, kdl_frame(p, R), inertia));
    }
  }
  return chain;
}

struct Kdl {
  KDL::Chain chain;
  KDL::ChainDynParam dyn;
  KDL::ChainIdSolver_RNE rne;
  KDL::JntArray q, qd, qdd, coriolis, gravity, tau;
  KDL::JntSpaceInertiaMatrix H;
  KDL::Wrenches f_ext;
  std::vector<double> bias_sum;

  Kdl(const ChainModel& model)
      : chain(kdl_chain(model)),
        dyn(chain, KDL::Vector(model.gravity.x(), model.gravity.y(), model.gravity.z())),
        rne(chain, KDL::Vector(model.gravity.x(), model.gravity.y(), model.gravity.z())),
        q(chain.getNrOfJoints()), qd(chain.getNrOfJoints()), qdd(chain.getNrOfJoints()),
        coriolis(chain.getNrOfJoints()), gravity(chain.getNrOfJoints()), tau(chain.getNrOfJoints()),
        H(chain.getNrOfJoints()), f_ext(chain.getNrOfSegments(), KDL::Wrench::Zero()),
        bias_sum(chain.getNrOfJoints()) {}

  void set(const double* q_in, const double* qd_in) {
    const Eigen::Index n = q.data.size();
    q.data = Eigen::Map<const Eigen::VectorXd>(q_in, n);
    if (qd_in) qd.data = Eigen::Map<const Eigen::VectorXd>(qd_in, n);
  }
  int mass_matrix(const double* q_in) {
    set(q_in, nullptr);
    return dyn.JntToMass(q, H);
  }
  int bias(const double* q_in, const double* qd_in) {
    set(q_in, qd_in);
    const int s = dyn.JntToCoriolis(q, qd, coriolis) | dyn.JntToGravity(q, gravity);
    Eigen::Map<Eigen::VectorXd>(bias_sum.data(), q.data.size()) = coriolis.data + gravity.data;
    return s;
  }
  int bias_rne(const double* q_in, const double* qd_in) {
    set(q_in, qd_in);
    return rne.CartToJnt(q, qd, qdd, f_ext, tau);
  }
};

// ---- agreement ----------------------------------------------------------------------------------

/// max |a − b| / max(max |a|, max |b|).
double relative_difference(const double* a, const double* b, std::size_t n) {
  double diff = 0, scale = 0;
  for (std::size_t i = 0; i < n; ++i) {
    diff = std::max(diff, std::abs(a[i] - b[i]));
    scale = std::max({scale, std::abs(a[i]), std::abs(b[i])});
  }
  return scale > 0 ? diff / scale : diff;
}

/// The random states (q, q̇) of a model: angles uniform in [−π, π], rates in [−2, 2] rad/s, from a
/// fixed seed, so every run and every engine sees the same ones.
struct States {
  int n = 0, count = 0;
  std::vector<double> q, qd;
  const double* q_at(int s) const { return q.data() + static_cast<std::size_t>(s * n); }
  const double* qd_at(int s) const { return qd.data() + static_cast<std::size_t>(s * n); }
};

States random_states(int n, int count, unsigned seed) {
  States st;
  st.n = n;
  st.count = count;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), rate(-2.0, 2.0);
  for (int i = 0; i < n * count; ++i) {
    st.q.push_back(angle(rng));
    st.qd.push_back(rate(rng));
  }
  return st;
}

struct Engines {
  Case c;
  States states;
  std::unique_ptr<MuJoCo> mujoco;
  std::unique_ptr<Kdl> kdl;
  std::vector<double> M, r, u, M2, r2;  // ours (M2, r2: the dynamics kernel's)
  /// (engine, quantity) → the largest relative difference to the other engines over the states.
  std::map<std::pair<std::string, std::string>, double> agreement;
};

/// Rows of engines_agreement.csv: for each quantity and engine pair, the largest relative
/// difference over the states; fills e.agreement. Returns the largest of all.
double check_agreement(Engines& e, bench::Csv& csv) {
  const std::size_t n = static_cast<std::size_t>(e.c.k.n);
  double mm = 0, mk = 0, km = 0, mb = 0, kb = 0, rb = 0, kr = 0, dm = 0, dk = 0;
  e.M2.resize(n * n);
  e.r2.resize(n);
  for (int s = 0; s < e.states.count; ++s) {
    const double *q = e.states.q_at(s), *qd = e.states.qd_at(s);
    e.c.k.mass_matrix(q, e.c.p.data(), e.M.data());
    e.c.k.residual(q, qd, e.u.data(), e.c.p.data(), e.r.data());
    e.c.k.dynamics(q, qd, e.u.data(), e.c.p.data(), e.M2.data(), e.r2.data());
    e.mujoco->mass_matrix(q);
    e.mujoco->bias(q, qd);
    e.kdl->mass_matrix(q);
    e.kdl->bias(q, qd);
    e.kdl->bias_rne(q, qd);
    mm = std::max(mm, relative_difference(e.M.data(), e.mujoco->M.data(), n * n));
    mk = std::max(mk, relative_difference(e.M.data(), e.kdl->H.data.data(), n * n));
    km = std::max(km, relative_difference(e.kdl->H.data.data(), e.mujoco->M.data(), n * n));
    mb = std::max(mb, relative_difference(e.r.data(), e.mujoco->d->qfrc_bias, n));
    kb = std::max(kb, relative_difference(e.r.data(), e.kdl->bias_sum.data(), n));
    rb = std::max(rb, relative_difference(e.r.data(), e.kdl->tau.data.data(), n));
    kr = std::max(kr, relative_difference(e.kdl->bias_sum.data(), e.mujoco->d->qfrc_bias, n));
    dm = std::max({dm, relative_difference(e.M2.data(), e.mujoco->M.data(), n * n),
                   relative_difference(e.r2.data(), e.mujoco->d->qfrc_bias, n)});
    dk = std::max({dk, relative_difference(e.M2.data(), e.kdl->H.data.data(), n * n),
                   relative_difference(e.r2.data(), e.kdl->tau.data.data(), n)});
  }
  const std::string N = std::to_string(e.c.links), f = std::to_string(n);
  auto row = [&](const char* quantity, const char* a, const char* b, double v) {
    csv.row({e.c.name, N, f, quantity, a, b, num17(v)});
    std::fprintf(stderr, "  %-8s %-7s vs %-7s %.3g%s\n", quantity, a, b, v, v > kAgreement ? "  DISAGREE" : "");
  };
  row("M", "ours", "mujoco", mm);
  row("M", "ours", "kdl", mk);
  row("M", "kdl", "mujoco", km);
  row("bias", "ours", "mujoco", mb);
  row("bias", "ours", "kdl", kb);
  row("bias", "ours", "kdl_rne", rb);
  row("bias", "kdl", "mujoco", kr);
  row("M+bias", "ours", "mujoco", dm);  // ours: the dynamics kernel
  row("M+bias", "ours", "kdl_rne", dk);
  auto& a = e.agreement;
  a[{"ours", "M"}] = std::max(mm, mk);
  a[{"mujoco", "M"}] = std::max(mm, km);
  a[{"kdl", "M"}] = std::max(mk, km);
  a[{"ours", "bias"}] = std::max({mb, kb, rb});
  a[{"mujoco", "bias"}] = std::max(mb, kr);
  a[{"kdl", "bias"}] = std::max(kb, kr);
  a[{"kdl_rne", "bias"}] = rb;
  for (const char* engine : {"mujoco", "kdl"})
    a[{engine, "M+bias"}] = std::max(a[{engine, "M"}], a[{engine, "bias"}]);
  a[{"ours", "M+bias"}] = std::max(dm, dk);
  a[{"kdl_rne", "M+bias"}] = std::max(a[{"kdl", "M"}], rb);
  return std::max({mm, mk, km, mb, kb, rb, kr, dm, dk});
}

// ---- timing -------------------------------------------------------------------------------------

using bench::Timed;
using bench::time_interleaved;

/// The operation count of one of our kernels, from the manifest <dir>/<id>.json (0 when absent).
std::size_t kernel_operations(const std::string& id, const std::string& kernel) {
  std::ifstream f(std::string(MBSGEN_ENGINES_GENERATED_DIR) + "/" + id + ".json");
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  const std::string key = "\"name\": \"" + kernel + "\", \"operations\": ";
  const std::size_t at = text.find(key);
  return at == std::string::npos ? 0 : std::stoul(text.substr(at + key.size()));
}

std::vector<Timed> timed_quantities(Engines& e) {
  const Kernels& k = e.c.k;
  const double* p = e.c.p.data();
  const States& st = e.states;
  MuJoCo& mj = *e.mujoco;
  Kdl& kdl = *e.kdl;
  double *M = e.M.data(), *r = e.r.data(), *u = e.u.data();
  // Each runs `calls` calls, state s = 0, 1, …, count − 1, 0, …
  auto cycle = [&st](auto&& f) {
    return [&st, f](long calls) {
      int s = 0;
      for (long i = 0; i < calls; ++i) {
        f(st.q_at(s), st.qd_at(s));
        if (++s == st.count) s = 0;
      }
    };
  };
  std::vector<Timed> v;
  auto add = [&v](const char* engine, const char* quantity, std::function<void(long)> run, std::size_t ops) {
    Timed x;
    x.engine = engine;
    x.quantity = quantity;
    x.run = std::move(run);
    x.ops = ops;
    v.push_back(std::move(x));
  };
  const std::size_t ops_M = kernel_operations(k.id, "mass_matrix"), ops_r = kernel_operations(k.id, "residual"),
                    ops_d = kernel_operations(k.id, "dynamics");
  add("ours", "M", cycle([=](const double* q, const double*) { k.mass_matrix(q, p, M); }), ops_M);
  add("ours", "bias", cycle([=](const double* q, const double* qd) { k.residual(q, qd, u, p, r); }), ops_r);
  add("ours", "M+bias", cycle([=](const double* q, const double* qd) { k.dynamics(q, qd, u, p, M, r); }), ops_d);
  add("mujoco", "M", cycle([&mj](const double* q, const double*) { mj.mass_matrix(q); }), 0);
  add("mujoco", "bias", cycle([&mj](const double* q, const double* qd) { mj.bias(q, qd); }), 0);
  add("mujoco", "M+bias", cycle([&mj](const double* q, const double* qd) { mj.both(q, qd); }), 0);
  add("kdl", "M", cycle([&kdl](const double* q, const double*) { kdl.mass_matrix(q); }), 0);
  add("kdl", "bias", cycle([&kdl](const double* q, const double* qd) { kdl.bias(q, qd); }), 0);
  add("kdl", "M+bias", cycle([&kdl](const double* q, const double* qd) {
        kdl.mass_matrix(q);
        kdl.bias(q, qd);
      }),
      0);
  add("kdl_rne", "bias", cycle([&kdl](const double* q, const double* qd) { kdl.bias_rne(q, qd); }), 0);
  add("kdl_rne", "M+bias", cycle([&kdl](const double* q, const double* qd) {
        kdl.mass_matrix(q);
        kdl.bias_rne(q, qd);
      }),
      0);
  return v;
}

struct Options {
  std::string out;
  bool quick = false;
  int repetitions = 51;
  std::string only;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      o.quick = true;
      o.repetitions = 21;
    } else if (a == "--reps" && i + 1 < argc) {
      o.repetitions = std::stoi(argv[++i]);
    } else if (a == "--only" && i + 1 < argc) {
      o.only = argv[++i];
    } else if (o.out.empty() && a[0] != '-') {
      o.out = a;
    } else {
      throw std::invalid_argument("usage: engines_bench OUT_DIR [--quick] [--reps N] [--only MODEL]");
    }
  }
  if (o.out.empty()) throw std::invalid_argument("usage: engines_bench OUT_DIR [--quick] [--reps N] [--only MODEL]");
  return o;
}

std::vector<Case> cases() {
  std::vector<Case> v;
  v.push_back(spatial_chain_case(3, MBSGEN_KERNELS(spatial_chain_3)));
  v.push_back(spatial_chain_case(6, MBSGEN_KERNELS(spatial_chain_6)));
  v.push_back(spatial_chain_case(12, MBSGEN_KERNELS(spatial_chain_12)));
  v.push_back(spatial_chain_case(30, MBSGEN_KERNELS(spatial_chain_30)));
  v.push_back(puma_case(MBSGEN_KERNELS(puma560)));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  try {
    opt = parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  const std::string mjcf_dir = opt.out + "/engines_mjcf";
  std::error_code ec;
  std::filesystem::create_directories(mjcf_dir, ec);
  bench::Csv agreement(opt.out + "/engines_agreement.csv", "model,N,coords,quantity,a,b,max_rel_diff");
  bench::Csv csv(opt.out + "/engines.csv",
                 "model,N,coords,engine,quantity,median_ns,min_ns,max_ns,repetitions,calls_per_repetition,agreement,ops");
  if (!agreement.ok() || !csv.ok()) {
    std::fprintf(stderr, "engines_bench: cannot write into %s\n", opt.out.c_str());
    return 1;
  }
  std::fprintf(stderr, "MuJoCo %d, KDL (orocos-kdl), %d repetitions\n", mj_version(), opt.repetitions);

  // All models first, checked; then timed.
  std::vector<std::unique_ptr<Engines>> all;
  double worst = 0;
  try {
    for (Case& c : cases()) {
      const std::string label = c.name == "spatial_chain" ? c.name + "_" + std::to_string(c.links) : c.name;
      if (!opt.only.empty() && opt.only != label && opt.only != c.name) continue;
      auto e = std::make_unique<Engines>();
      e->c = c;
      const std::string path = mjcf_dir + "/" + label + ".xml";
      std::ofstream(path) << mjcf(c.model, label);
      e->mujoco = std::make_unique<MuJoCo>(path);
      e->kdl = std::make_unique<Kdl>(c.model);
      const int n = c.k.n;
      if (e->mujoco->m->nv != n || static_cast<int>(e->kdl->chain.getNrOfJoints()) != n || c.model.dof() != n)
        throw std::runtime_error(label + ": the engines' models have " + std::to_string(e->mujoco->m->nv) + " and " +
                                 std::to_string(e->kdl->chain.getNrOfJoints()) + " coordinates, ours " +
                                 std::to_string(n));
      e->states = random_states(n, 16, 17u + static_cast<unsigned>(n));
      e->M.resize(static_cast<std::size_t>(n * n));
      e->r.resize(static_cast<std::size_t>(n));
      e->u.resize(1);
      std::fprintf(stderr, "%s (%d coordinates): agreement over %d random states\n", label.c_str(), n,
                   e->states.count);
      worst = std::max(worst, check_agreement(*e, agreement));
      all.push_back(std::move(e));
    }
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "engines_bench: %s\n", ex.what());
    return 1;
  }
  if (worst > kAgreement) {
    std::fprintf(stderr, "engines_bench: the engines disagree (%.3g > %.0e, engines_agreement.csv); nothing timed\n",
                 worst, kAgreement);
    return 1;
  }

  // Short batches, many of them: on a shared machine a batch of a few milliseconds often runs
  // without being preempted, and the median picks those.
  const double min_batch = 0.002;
  for (auto& e : all) {
    std::vector<Timed> timed = timed_quantities(*e);
    time_interleaved(timed, opt.repetitions, min_batch);
    const std::string N = std::to_string(e->c.links), f = std::to_string(e->c.k.n);
    for (const Timed& x : timed) {
      csv.row({e->c.name, N, f, x.engine, x.quantity, bench::num(x.t.median * 1e9), bench::num(x.t.min * 1e9),
               bench::num(x.t.max * 1e9), std::to_string(x.t.repetitions), std::to_string(x.t.calls_per_repetition),
               bench::num(e->agreement[{x.engine, x.quantity}]), x.ops ? std::to_string(x.ops) : ""});
      std::fprintf(stderr, "  %s N=%s %-8s %-7s %10.1f ns\n", e->c.name.c_str(), N.c_str(), x.engine.c_str(),
                   x.quantity.c_str(), x.t.median * 1e9);
    }
  }
  return 0;
}

// Reference dynamics of a URDF robot from two independent engines (tests/data/urdf/<robot>.engines.csv):
// the joint-space mass matrix M(q), the bias c(q, q̇) + g(q) and the gravity forces g(q) on random
// states, as MuJoCo computes them (mj_loadXML reads the URDF itself), checked against Orocos KDL
// (kdl_parser::treeFromFile, KDL::TreeIdSolver_RNE) before anything is written.
//
//   urdf_engines OUT.csv FILE.urdf [--samples N] [--seed S] [--tolerance T] [--time]
//
// The recorded numbers are MuJoCo's; KDL's only enter the agreement check, and the file is
// written (OUT.csv.tmp, then renamed) only when, on every state, max |X_mujoco − X_kdl| over the
// largest |X_mujoco| of that state (floor 1e-300) is at most T (default 1e-10) for X = M, bias
// and gravity; else exit 1 and nothing is written.
//
// How each engine computes them:
//   MuJoCo  M: mj_kinematics, mj_comPos, mj_crb, mj_fullM. bias: mj_comVel, then
//           mj_rne(flg_acc = 0) → the qfrc_bias of the state (q, q̇). gravity: the same at q̇ = 0.
//           Joint armature would be added to M by mj_crb; it is zero in a URDF import, and set to
//           zero after loading anyway, as are the URDF's damping and friction (MuJoCo keeps
//           <dynamics damping> as dof_damping: a passive force, qfrc_passive, never in
//           qfrc_bias, but zeroed all the same). Notes on stderr say what was found.
//   KDL     the tree's recursive Newton–Euler (treeidsolver_recursive_newton_euler.hpp, also for
//           a tree such as a biped): column j of M = ID(q, 0, e_j) with zero gravity; bias =
//           ID(q, q̇, 0) and gravity = ID(q, 0, 0) with MuJoCo's gravity vector (m->opt.gravity,
//           (0, 0, −9.81) by default). When the tree is a single chain, KDL::ChainDynParam
//           (composite inertias) is compared as well.
// Joints are matched by their URDF names (MuJoCo keeps them; kdl_parser names each segment's
// joint after them); only 1-dof joints (revolute, continuous, prismatic; MuJoCo hinge and slide)
// are accepted, and the two sets must be equal. Fixed joints are no coordinates in either (MuJoCo
// fuses a fixed-jointed link into its parent, KDL keeps it as a segment with Joint::Fixed). A
// <mimic> joint is recorded as an independent coordinate (M and the bias are those of the
// unconstrained tree); a note says whether MuJoCo made an equality constraint of it (m->neq;
// MuJoCo 2.2.2 makes none: it ignores <mimic>).
//
// Mass properties. MuJoCo's import must not change them: the sum of its body masses must equal the
// sum of the URDF masses of the links that move (the root link, and links fixed to it, are fused
// into MuJoCo's world body and dropped by kdl_parser; they carry no dynamics), and each body's
// mass, centre of mass and inertia must match those computed here from the URDF (the link and the
// links fused into it); a link without an <inertial> but with a <collision>, which MuJoCo would
// weigh from its geometry (inertiafromgeom="auto") and KDL not, stops the run. Two corrections,
// both written into the loaded mjModel and stated in OUT.csv's notes: (1) MuJoCo's compiler
// diagonalizes full inertias only to about 1e-7 relative (see run), so every body's mass
// properties are replaced by the URDF's, diagonalized in double; (2) MuJoCo 2.2 refuses to load a
// moving body without mass or inertia, so such links are given placeholder inertials in a
// temporary copy it loads, and the URDF's zeros are put back after loading. The kinematics (body
// frames, joint axes) and the algorithms stay MuJoCo's.

// States: std::mt19937_64(seed); per sample, q_i for each joint in MuJoCo's qpos order, uniform in
// the joint's limits when MuJoCo has them finite (jnt_limited, jnt_range from the URDF's <limit>),
// else in [−π, π] (hinge) or [−0.5, 0.5] m (slide); then q̇_i uniform in [−2, 2] rad/s or m/s.
//
// OUT.csv: '#' lines (provenance: the URDF's path, size and SHA-256, the engines' versions, seed,
// gravity, the worst disagreements), then a header and one row per sample: q:<joint>…,
// qd:<joint>…, M:<joint_i>:<joint_j> for i ≤ j (upper triangle, row by row, qpos order),
// bias:<joint>… (the generalized force the actuators must supply for zero acceleration, MuJoCo's
// qfrc_bias sign: M q̈ + bias = τ), gravity:<joint>… (g(q)); values %.17g.
//
// --time: after the check, the median time per call (thread CPU time; --reps repetitions, 21 by
// default, of batches of about 2 ms, the engines interleaved round robin, as in
// bench/engines_bench.cpp) of M, of the bias and of both (M+bias) for each engine, written to
// stdout as engine,quantity,ns_per_call,min_ns,max_ns,calls_per_repetition,agreement (min and max:
// the spread of the repetitions; agreement: the engine's worst relative difference to MuJoCo,
// KDL's from the check on the sampled states above, ours' from its own check below, empty for
// MuJoCo itself). MuJoCo's M+bias shares its position stages (mj_kinematics,
// mj_comPos, mj_crb, mj_fullM, mj_comVel, mj_rne). KDL's M is n tree RNE passes (KDL has no
// composite-inertia solver for trees), its bias one pass; "kdl_chain" is ChainDynParam
// (JntToMass; JntToCoriolis + JntToGravity) when the robot is a chain.
//
// Ours (issue 43), in --time mode only: built with -DMBSGEN_URDF_KERNELS and the kernels of
// `mbsgen generate ROBOT.urdf --id ROBOT_urdf --dynamics` on the include path (and linked), the
// kernels of the robot (the URDF's <robot name> + "_urdf"; a robot whose header was not found is
// not compiled in, and then only MuJoCo and KDL are timed) are a third engine: <id>_mass_matrix
// (M), <id>_residual with u = 0 and every parameter `<joint>_damping` (URDF <dynamics damping>,
// a passive force MuJoCo's qfrc_bias leaves out) set to 0 (k − q = c + g: the bias), and
// <id>_dynamics (both in one kernel). Their coordinates are matched with MuJoCo's joints by name.
// Before timing, on every state, ours' M, bias, gravity forces (the residual at q̇ = 0) and the
// dynamics kernel's M and bias must agree with MuJoCo's to T (max |difference| over max |MuJoCo|
// per state, as tests/generator/model/urdf_import_test.cpp's AgainstEngines), else exit 1 and
// nothing is timed. A <mimic> joint is a constraint in ours (an expression constraint; MuJoCo
// 2.2.2 and KDL ignore <mimic>): the kernels take the independent coordinates, so ours are
// compared with MuJoCo's tree projected onto them, Tᵀ M T and Tᵀ bias (q = T q_ours + offset,
// q_mimic = multiplier q_joint + offset: linear, so no T-dot term), on states where the mimic
// holds (the sampled q and q̇ of the other joints, the mimic joint's from them), and then all
// engines are timed on those states. Our public kernels of such a model first close the loop
// (<id>_assemble: Newton from the operating point), and that is timed; MuJoCo and KDL are timed on
// their unconstrained tree, without the projection they would need on top.
//
// Built with the benchmarks (bench/CMakeLists.txt) when MuJoCo, KDL, kdl_parser, urdfdom and
// tinyxml2 are found (Debian libmujoco-dev, liborocos-kdl-dev, libkdl-parser-dev); with ours when
// the generator (the `mbsgen` target, with its URDF import) is built too. By hand, one line:
//   g++ -O2 -std=c++17 -isystem /usr/include/eigen3 bench/urdf_engines.cpp -o /tmp/urdf_engines
//       -lmujoco -lkdl_parser -lorocos-kdl -lurdfdom_model -ltinyxml2
// and with ours, the kernels generated into DIR and compiled at -O2 into DIR/liburdf_kernels.a:
//   g++ -O2 -std=c++17 -isystem /usr/include/eigen3 -DMBSGEN_URDF_KERNELS -I DIR bench/urdf_engines.cpp
//       -o /tmp/urdf_engines DIR/liburdf_kernels.a -lmujoco -lkdl_parser -lorocos-kdl -lurdfdom_model -ltinyxml2
// bench/urdf_speed.sh runs --time over the five robots of models/robots/urdf and tabulates it.
#include "harness.hpp"
#include "mujoco_engine.hpp"

#include <Eigen/Dense>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/config.h>
#include <kdl/tree.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <tinyxml2.h>
#include <unistd.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

// Our generated kernels (see "Ours" above): each robot whose header is on the include path.
#ifdef MBSGEN_URDF_KERNELS
#if __has_include("puma560_urdf.hpp")
#include "puma560_urdf.hpp"
#endif
#if __has_include("ur5_urdf.hpp")
#include "ur5_urdf.hpp"
#endif
#if __has_include("panda_urdf.hpp")
#include "panda_urdf.hpp"
#endif
#if __has_include("biped_urdf.hpp")
#include "biped_urdf.hpp"
#endif
#if __has_include("gripper_urdf.hpp")
#include "gripper_urdf.hpp"
#endif
#endif

namespace {

// ---- provenance ---------------------------------------------------------------------------------

/// SHA-256 (FIPS 180-4) of `data`, as 64 hex digits.
std::string sha256(const std::string& data) {
  static const std::uint32_t k[64] = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
      0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
      0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
      0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
      0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
      0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
      0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};
  std::uint32_t h[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                        0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  std::string msg = data;
  const std::uint64_t bits = static_cast<std::uint64_t>(data.size()) * 8;
  msg += static_cast<char>(0x80);
  while (msg.size() % 64 != 56) msg += '\0';
  for (int i = 7; i >= 0; --i) msg += static_cast<char>((bits >> (8 * i)) & 0xff);
  auto rotr = [](std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); };
  for (std::size_t block = 0; block < msg.size(); block += 64) {
    std::uint32_t w[64];
    for (int i = 0; i < 16; ++i) {
      w[i] = 0;
      for (int b = 0; b < 4; ++b)
        w[i] = (w[i] << 8) | static_cast<unsigned char>(msg[block + static_cast<std::size_t>(4 * i + b)]);
    }
    for (int i = 16; i < 64; ++i) {
      const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int i = 0; i < 64; ++i) {
      const std::uint32_t t1 = hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const std::uint32_t t2 = (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      hh = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    const std::uint32_t add[8] = {a, b, c, d, e, f, g, hh};
    for (int i = 0; i < 8; ++i) h[i] += add[i];
  }
  char hex[65];
  for (int i = 0; i < 8; ++i) std::snprintf(hex + 8 * i, 9, "%08x", h[i]);
  return std::string(hex, 64);
}

std::string num17(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::string num3(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

// ---- the URDF as written (urdfdom): masses, inertias, mimic joints ------------------------------

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

struct UrdfFacts {
  urdf::ModelInterfaceSharedPtr model;
  std::string robot;
  double total_mass = 0;   ///< [kg] all links
  double moving_mass = 0;  ///< [kg] links below at least one non-fixed joint
  std::vector<std::string> massless_moving;  ///< moving links without <inertial> or with mass 0
  std::map<std::string, std::string> mimic;  ///< joint → "mimics <joint> x multiplier + offset"
};

UrdfFacts urdf_facts(const std::string& text) {
  UrdfFacts f;
  f.model = urdf::parseURDF(text);
  if (!f.model) throw std::runtime_error("urdfdom cannot parse the URDF");
  f.robot = f.model->getName();
  for (const auto& [name, link] : f.model->links_) {
    const double mass = link->inertial ? link->inertial->mass : 0.0;
    f.total_mass += mass;
    bool moving = false;
    for (urdf::LinkConstSharedPtr l = link; l && l->parent_joint; l = l->getParent())
      if (l->parent_joint->type != urdf::Joint::FIXED) moving = true;
    if (moving) {
      f.moving_mass += mass;
      if (mass == 0) f.massless_moving.push_back(name);
    }
  }
  for (const auto& [name, joint] : f.model->joints_) {
    if (joint->type == urdf::Joint::FLOATING || joint->type == urdf::Joint::PLANAR)
      throw std::runtime_error("joint " + name + " is floating or planar; only 1-dof joints are compared");
    if (joint->mimic)
      f.mimic[name] = "mimics " + joint->mimic->joint_name + " x " + num17(joint->mimic->multiplier) + " + " +
                      num17(joint->mimic->offset);
  }
  return f;
}

/// A URDF <origin> as a rigid transform (urdfdom's quaternion of the rpy, normalized).
Eigen::Isometry3d transform(const urdf::Pose& p) {
  double x, y, z, w;
  p.rotation.getQuaternion(x, y, z, w);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
  T.translation() = Vec3(p.position.x, p.position.y, p.position.z);
  return T;
}

/// Mass m [kg], centre of mass c [m] and inertia I about c [kg m²], c and I in a link's frame.
struct MassProperties {
  double m = 0;
  Vec3 c = Vec3::Zero();
  Mat3 I = Mat3::Zero();
};

/// The mass properties of MuJoCo's body `link`: the link's <inertial> and those of the links fixed
/// to it by fixed joints, recursively (MuJoCo's URDF import fuses them, fusestatic), in the link's
/// frame, computed in double from the URDF's numbers.
MassProperties fused_mass_properties(const urdf::ModelInterface& model, const std::string& link) {
  std::vector<MassProperties> parts;  // each about its own centre of mass, in the link's frame
  std::function<void(const urdf::LinkConstSharedPtr&, const Eigen::Isometry3d&)> add =
      [&](const urdf::LinkConstSharedPtr& l, const Eigen::Isometry3d& T) {
        if (l->inertial) {
          const urdf::Inertial& in = *l->inertial;
          const Eigen::Isometry3d Ti = T * transform(in.origin);
          Mat3 I;
          I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
          parts.push_back({in.mass, Ti.translation(), Ti.linear() * I * Ti.linear().transpose()});
        }
        for (const urdf::JointSharedPtr& j : l->child_joints)
          if (j->type == urdf::Joint::FIXED)
            add(model.getLink(j->child_link_name), T * transform(j->parent_to_joint_origin_transform));
      };
  const urdf::LinkConstSharedPtr root = model.getLink(link);
  if (!root) throw std::runtime_error("MuJoCo body " + link + " is no URDF link");
  add(root, Eigen::Isometry3d::Identity());
  MassProperties r;
  for (const MassProperties& p : parts) {
    r.m += p.m;
    r.c += p.m * p.c;
  }
  if (r.m > 0) r.c /= r.m;
  for (const MassProperties& p : parts) {
    const Vec3 d = p.c - r.c;
    r.I += p.I + p.m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  return r;
}

/// MuJoCo 2.2 refuses a body with a joint whose mass or moments of inertia are below mjMINVAL
/// ("mass and inertia of moving bodies must be larger than mjMINVAL"), though M stays positive
/// definite when the link's children carry mass. Such links (a moving parent joint, and no
/// <inertial>, or mass 0, or zero moments) get a placeholder <inertial> (1 kg, 1 kg m² about the
/// link's origin) in a copy that MuJoCo loads; the URDF's own mass properties replace it after
/// loading (see run). Returns the copy's text, "" when no link needs it; `patched`: their names.
std::string with_placeholder_inertials(const std::string& text, const urdf::ModelInterface& model,
                                       std::vector<std::string>& patched) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.c_str(), text.size()) != tinyxml2::XML_SUCCESS) throw std::runtime_error("tinyxml2 cannot parse the URDF");
  tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw std::runtime_error("the URDF has no <robot>");
  for (tinyxml2::XMLElement* e = robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const char* name = e->Attribute("name");
    const urdf::LinkConstSharedPtr link = name ? model.getLink(name) : nullptr;
    if (!link || !link->parent_joint || link->parent_joint->type == urdf::Joint::FIXED) continue;
    const urdf::InertialSharedPtr& in = link->inertial;
    if (in && in->mass > 0 && in->ixx > 0 && in->iyy > 0 && in->izz > 0) continue;
    while (tinyxml2::XMLElement* old = e->FirstChildElement("inertial")) e->DeleteChild(old);
    tinyxml2::XMLElement* inertial = doc.NewElement("inertial");
    tinyxml2::XMLElement* mass = doc.NewElement("mass");
    mass->SetAttribute("value", "1");
    tinyxml2::XMLElement* inertia = doc.NewElement("inertia");
    for (const char* a : {"ixx", "iyy", "izz"}) inertia->SetAttribute(a, "1");
    for (const char* a : {"ixy", "ixz", "iyz"}) inertia->SetAttribute(a, "0");
    inertial->InsertEndChild(mass);
    inertial->InsertEndChild(inertia);
    e->InsertEndChild(inertial);
    patched.push_back(name);
  }
  if (patched.empty()) return "";
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  return printer.CStr();
}

// ---- MuJoCo -------------------------------------------------------------------------------------

using bench::MuJoCo;

// ---- Orocos KDL ---------------------------------------------------------------------------------

struct Kdl {
  KDL::Tree tree;
  std::unique_ptr<KDL::TreeIdSolver_RNE> rne, rne_no_gravity;
  KDL::JntArray q, qd, qdd, zero, tau;
  KDL::WrenchMap f_ext;  // empty: no external forces
  Eigen::MatrixXd M;     // n × n, KDL's joint order
  Eigen::VectorXd bias, gravity;
  // When the tree is a single chain: the chain from the root to its leaf, and chain_index[k] = the
  // tree's number of the chain's k-th joint.
  std::unique_ptr<KDL::Chain> chain;
  std::unique_ptr<KDL::ChainDynParam> dyn;
  std::vector<unsigned> chain_index;
  KDL::JntArray cq, cqd, ccoriolis, cgravity;
  KDL::JntSpaceInertiaMatrix cH;
  Eigen::MatrixXd chain_M;
  Eigen::VectorXd chain_bias, chain_gravity;

  Kdl(const std::string& path, const KDL::Vector& g) {
    if (!kdl_parser::treeFromFile(path, tree)) throw std::runtime_error("kdl_parser cannot read " + path);
    const unsigned n = tree.getNrOfJoints();
    rne = std::make_unique<KDL::TreeIdSolver_RNE>(tree, g);
    rne_no_gravity = std::make_unique<KDL::TreeIdSolver_RNE>(tree, KDL::Vector::Zero());
    for (KDL::JntArray* a : {&q, &qd, &qdd, &zero, &tau}) a->resize(n);
    M.resize(n, n);
    bias.resize(n);
    gravity.resize(n);

    // A chain when no segment has two children.
    const KDL::SegmentMap& segments = tree.getSegments();
    std::string leaf = tree.getRootSegment()->first;
    bool is_chain = true;
    for (KDL::SegmentMap::const_iterator s = tree.getRootSegment();;) {
      const auto& children = GetTreeElementChildren(s->second);
      if (children.size() > 1) {
        is_chain = false;
        break;
      }
      if (children.empty()) break;
      s = children.front();
      leaf = s->first;
    }
    if (!is_chain || segments.empty()) return;
    chain = std::make_unique<KDL::Chain>();
    if (!tree.getChain(tree.getRootSegment()->first, leaf, *chain) || chain->getNrOfJoints() != n) {
      chain.reset();
      return;
    }
    for (unsigned k = 0; k < chain->getNrOfSegments(); ++k) {
      const KDL::Joint& joint = chain->getSegment(k).getJoint();
      if (joint.getType() == KDL::Joint::Fixed) continue;
      for (const auto& [name, element] : segments)
        if (GetTreeElementSegment(element).getJoint().getName() == joint.getName() &&
            GetTreeElementSegment(element).getJoint().getType() != KDL::Joint::Fixed)
          chain_index.push_back(GetTreeElementQNr(element));
    }
    if (chain_index.size() != n) {
      chain.reset();
      return;
    }
    dyn = std::make_unique<KDL::ChainDynParam>(*chain, g);
    for (KDL::JntArray* a : {&cq, &cqd, &ccoriolis, &cgravity}) a->resize(n);
    cH.resize(n);
    chain_M.resize(n, n);
    chain_bias.resize(n);
    chain_gravity.resize(n);
  }
  Kdl(const Kdl&) = delete;
  Kdl& operator=(const Kdl&) = delete;

  /// Joint name → the tree's joint number, 1-dof joints only.
  std::map<std::string, unsigned> joint_numbers() const {
    std::map<std::string, unsigned> v;
    for (const auto& [name, element] : tree.getSegments()) {
      const KDL::Joint& joint = GetTreeElementSegment(element).getJoint();
      if (joint.getType() != KDL::Joint::Fixed) v[joint.getName()] = GetTreeElementQNr(element);
    }
    return v;
  }

  // The inputs in KDL's order; each throws when a solver reports an error.
  void check(int status, const char* what) const {
    if (status < 0) throw std::runtime_error(std::string("KDL ") + what + " failed, status " + std::to_string(status));
  }
  void mass_matrix() {
    const Eigen::Index n = q.data.size();
    zero.data.setZero();
    for (Eigen::Index j = 0; j < n; ++j) {
      qdd.data.setZero();
      qdd(static_cast<unsigned>(j)) = 1.0;
      check(rne_no_gravity->CartToJnt(q, zero, qdd, f_ext, tau), "TreeIdSolver_RNE (M)");
      M.col(j) = tau.data;
    }
  }
  void bias_and_gravity(bool with_bias = true, bool with_gravity = true) {
    zero.data.setZero();
    if (with_bias) {
      check(rne->CartToJnt(q, qd, zero, f_ext, tau), "TreeIdSolver_RNE (bias)");
      bias = tau.data;
    }
    if (with_gravity) {
      check(rne->CartToJnt(q, zero, zero, f_ext, tau), "TreeIdSolver_RNE (gravity)");
      gravity = tau.data;
    }
  }
  void chain_set() {
    for (std::size_t k = 0; k < chain_index.size(); ++k) {
      cq(static_cast<unsigned>(k)) = q(chain_index[k]);
      cqd(static_cast<unsigned>(k)) = qd(chain_index[k]);
    }
  }
  void chain_mass_matrix() {
    chain_set();
    check(dyn->JntToMass(cq, cH), "ChainDynParam::JntToMass");
  }
  void chain_bias_and_gravity() {
    chain_set();
    check(dyn->JntToCoriolis(cq, cqd, ccoriolis), "ChainDynParam::JntToCoriolis");
    check(dyn->JntToGravity(cq, cgravity), "ChainDynParam::JntToGravity");
  }
  void chain_both() {
    chain_set();
    check(dyn->JntToMass(cq, cH), "ChainDynParam::JntToMass");
    check(dyn->JntToCoriolis(cq, cqd, ccoriolis), "ChainDynParam::JntToCoriolis");
    check(dyn->JntToGravity(cq, cgravity), "ChainDynParam::JntToGravity");
  }
  /// The chain's results in the tree's order.
  void chain_all() {
    chain_mass_matrix();
    chain_bias_and_gravity();
    const std::size_t n = chain_index.size();
    for (std::size_t a = 0; a < n; ++a) {
      const auto ia = static_cast<Eigen::Index>(chain_index[a]);
      chain_bias(ia) = ccoriolis.data(static_cast<Eigen::Index>(a)) + cgravity.data(static_cast<Eigen::Index>(a));
      chain_gravity(ia) = cgravity.data(static_cast<Eigen::Index>(a));
      for (std::size_t b = 0; b < n; ++b)
        chain_M(ia, static_cast<Eigen::Index>(chain_index[b])) =
            cH(static_cast<unsigned>(a), static_cast<unsigned>(b));
    }
  }
};

// ---- agreement ----------------------------------------------------------------------------------

/// max |ref − x| / max(max |ref|, 1e-300): the disagreement relative to the recorded numbers.
double relative_difference(const double* ref, const double* x, std::size_t n) {
  double diff = 0, scale = 1e-300;
  for (std::size_t i = 0; i < n; ++i) {
    diff = std::max(diff, std::abs(ref[i] - x[i]));
    scale = std::max(scale, std::abs(ref[i]));
  }
  return diff / scale;
}

// ---- ours: mbsgen's generated kernels -----------------------------------------------------------

/// One robot's generated kernels (<id>.hpp; docs/generated-abi.md).
struct Kernels {
  std::string id;
  int n = 0, n_inputs = 0, n_parameters = 0;
  int (*mass_matrix)(const double*, const double*, double*) = nullptr;
  int (*residual)(const double*, const double*, const double*, const double*, double*) = nullptr;
  int (*dynamics)(const double*, const double*, const double*, const double*, double*, double*) = nullptr;
  const char* const* coordinate_names = nullptr;
  const char* const* parameter_names = nullptr;
  const double* parameter_defaults = nullptr;
  int n_tree = 0;  ///< with constraints: the tree's coordinates, which the kernels reduce; else 0
  const char* const* tree_coordinate_names = nullptr;
};

#define MBSGEN_URDF_KERNELS_OF(ID)                                                                       \
  Kernels {                                                                                             \
    #ID, ID##_n_coordinates, ID##_n_inputs, ID##_n_parameters, ID##_mass_matrix, ID##_residual,         \
        ID##_dynamics, ID##_coordinate_names, ID##_parameter_names, ID##_parameter_defaults, 0, nullptr \
  }

/// The kernels compiled in (none without MBSGEN_URDF_KERNELS).
std::vector<Kernels> compiled_kernels() {
  std::vector<Kernels> v;
#ifdef MBSGEN_URDF_KERNELS
#if __has_include("puma560_urdf.hpp")
  v.push_back(MBSGEN_URDF_KERNELS_OF(puma560_urdf));
#ifdef puma560_urdf_HAS_CONSTRAINTS
  v.back().n_tree = puma560_urdf_n_tree_coordinates;
  v.back().tree_coordinate_names = puma560_urdf_tree_coordinate_names;
#endif
#endif
#if __has_include("ur5_urdf.hpp")
  v.push_back(MBSGEN_URDF_KERNELS_OF(ur5_urdf));
#ifdef ur5_urdf_HAS_CONSTRAINTS
  v.back().n_tree = ur5_urdf_n_tree_coordinates;
  v.back().tree_coordinate_names = ur5_urdf_tree_coordinate_names;
#endif
#endif
#if __has_include("panda_urdf.hpp")
  v.push_back(MBSGEN_URDF_KERNELS_OF(panda_urdf));
#ifdef panda_urdf_HAS_CONSTRAINTS
  v.back().n_tree = panda_urdf_n_tree_coordinates;
  v.back().tree_coordinate_names = panda_urdf_tree_coordinate_names;
#endif
#endif
#if __has_include("biped_urdf.hpp")
  v.push_back(MBSGEN_URDF_KERNELS_OF(biped_urdf));
#ifdef biped_urdf_HAS_CONSTRAINTS
  v.back().n_tree = biped_urdf_n_tree_coordinates;
  v.back().tree_coordinate_names = biped_urdf_tree_coordinate_names;
#endif
#endif
#if __has_include("gripper_urdf.hpp")
  v.push_back(MBSGEN_URDF_KERNELS_OF(gripper_urdf));
#ifdef gripper_urdf_HAS_CONSTRAINTS
  v.back().n_tree = gripper_urdf_n_tree_coordinates;
  v.back().tree_coordinate_names = gripper_urdf_tree_coordinate_names;
#endif
#endif
#endif
  return v;
}

/// Ours on one robot: the kernels, their parameters and inputs, and how their coordinates map to
/// MuJoCo's: q_mujoco = T q_ours + offset, q̇_mujoco = T q̇_ours (T: n × f; the identity, up to
/// the order, without <mimic>).
struct Ours {
  Kernels k;
  std::size_t n = 0, f = 0;
  bool reduced = false;  ///< f < n: <mimic> joints are constraints in ours
  Eigen::MatrixXd T;
  Eigen::VectorXd offset;
  std::vector<std::size_t> at;  ///< ours' coordinate j → MuJoCo's qpos index of the same joint
  std::vector<double> p, u, zero_rates, M, r, rg, M2, r2;
  std::vector<std::string> zeroed;  ///< the damping parameters set to 0
  // The states: ours' coordinates (S × f) and MuJoCo's (S × n) where the mimics hold.
  std::vector<double> Qo, QDo, Qt, QDt;
};

/// Matches the kernels' coordinates with MuJoCo's joints (`names`, qpos order) by name; a joint
/// that is none of ours must be a <mimic> of one (followed through mimics of mimics).
std::unique_ptr<Ours> make_ours(const Kernels& k, const std::vector<std::string>& names,
                                const urdf::ModelInterface& model) {
  auto o = std::make_unique<Ours>();
  o->k = k;
  o->n = names.size();
  o->f = static_cast<std::size_t>(k.n);
  const std::size_t n = o->n, f = o->f;
  std::map<std::string, std::size_t> ours;
  for (std::size_t j = 0; j < f; ++j)
    if (!ours.emplace(k.coordinate_names[j], j).second)
      throw std::runtime_error(k.id + " names two coordinates " + k.coordinate_names[j]);
  o->T = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(f));
  o->offset = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  o->at.assign(f, n);
  for (std::size_t i = 0; i < n; ++i) {
    std::string joint = names[i];
    if (ours.count(joint)) o->at[ours.at(joint)] = i;
    double a = 1, b = 0;  // q_(names[i]) = a q_joint + b
    for (std::size_t depth = 0; !ours.count(joint); ++depth) {
      const urdf::JointConstSharedPtr j = model.getJoint(joint);
      if (!j || !j->mimic || depth > n)
        throw std::runtime_error("MuJoCo's joint " + names[i] + " is none of " + k.id +
                                 "'s coordinates, nor a <mimic> of one");
      b += a * j->mimic->offset;
      a *= j->mimic->multiplier;
      joint = j->mimic->joint_name;
    }
    const auto ia = static_cast<Eigen::Index>(i);
    o->T(ia, static_cast<Eigen::Index>(ours.at(joint))) = a;
    o->offset(ia) = b;
    if (joint != names[i]) o->reduced = true;
  }
  for (const auto& [name, j] : ours)
    if (o->at[j] == n) throw std::runtime_error(k.id + "'s coordinate " + name + " is no joint of MuJoCo's");
  if (o->reduced != (k.n_tree > 0))
    throw std::runtime_error(k.id + (o->reduced ? " has no constraints, but MuJoCo has more joints (mimics)"
                                                : " has constraints other than the URDF's <mimic> joints"));
  if (o->reduced) {
    std::set<std::string> tree(k.tree_coordinate_names, k.tree_coordinate_names + k.n_tree);
    if (tree != std::set<std::string>(names.begin(), names.end()) || static_cast<std::size_t>(k.n_tree) != n)
      throw std::runtime_error(k.id + "'s tree coordinates are not MuJoCo's joints");
  }
  o->p.assign(k.parameter_defaults, k.parameter_defaults + k.n_parameters);
  for (int i = 0; i < k.n_parameters; ++i) {
    const std::string name = k.parameter_names[i];
    if (name.size() > 8 && name.compare(name.size() - 8, 8, "_damping") == 0) {
      o->p[static_cast<std::size_t>(i)] = 0;
      o->zeroed.push_back(name);
    }
  }
  o->u.assign(static_cast<std::size_t>(std::max(1, k.n_inputs)), 0.0);
  o->zero_rates.assign(f, 0.0);
  o->M.resize(f * f);
  o->M2.resize(f * f);
  o->r.resize(f);
  o->rg.resize(f);
  o->r2.resize(f);
  return o;
}

/// Ours' states from the sampled ones (S × n, qpos order): the independent coordinates taken as
/// sampled, the mimic joints' from them.
void ours_states(Ours& o, const std::vector<double>& Q, const std::vector<double>& QD, std::size_t S) {
  const std::size_t n = o.n, f = o.f;
  o.Qo.resize(S * f);
  o.QDo.resize(S * f);
  o.Qt = Q;
  o.QDt = QD;
  for (std::size_t s = 0; s < S; ++s)
    for (std::size_t j = 0; j < f; ++j) {
      o.Qo[s * f + j] = Q[s * n + o.at[j]];
      o.QDo[s * f + j] = QD[s * n + o.at[j]];
    }
  if (!o.reduced) return;
  for (std::size_t s = 0; s < S; ++s) {
    const Eigen::Map<const Eigen::VectorXd> q(&o.Qo[s * f], static_cast<Eigen::Index>(f)),
        qd(&o.QDo[s * f], static_cast<Eigen::Index>(f));
    Eigen::Map<Eigen::VectorXd>(&o.Qt[s * n], static_cast<Eigen::Index>(n)) = o.T * q + o.offset;
    Eigen::Map<Eigen::VectorXd>(&o.QDt[s * n], static_cast<Eigen::Index>(n)) = o.T * qd;
  }
}

/// Ours against MuJoCo on every state: the worst relative differences (max |MuJoCo − ours| over
/// max |MuJoCo| per state), MuJoCo's projected onto ours' coordinates (Tᵀ M T, Tᵀ bias).
struct OursAgreement {
  double M = 0, bias = 0, gravity = 0, dynamics = 0;
};

OursAgreement check_ours(Ours& o, MuJoCo& mj, std::size_t S) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const auto n = static_cast<Eigen::Index>(o.n), f = static_cast<Eigen::Index>(o.f);
  const std::size_t ff = o.f * o.f;
  const Kernels& k = o.k;
  OursAgreement w;
  RowMajor ref_M(f, f), ours_M(f, f), ours_M2(f, f);
  Eigen::VectorXd ref_b(f), ref_g(f);
  for (std::size_t s = 0; s < S; ++s) {
    const double *qo = &o.Qo[s * o.f], *qdo = &o.QDo[s * o.f], *qt = &o.Qt[s * o.n], *qdt = &o.QDt[s * o.n];
    auto ok = [&](int status, const char* kernel) {
      if (status != 0)
        throw std::runtime_error(k.id + "_" + kernel + " returned status " + std::to_string(status) + " at state " +
                                 std::to_string(s));
    };
    ok(k.mass_matrix(qo, o.p.data(), o.M.data()), "mass_matrix");
    ok(k.residual(qo, qdo, o.u.data(), o.p.data(), o.r.data()), "residual");
    ok(k.residual(qo, o.zero_rates.data(), o.u.data(), o.p.data(), o.rg.data()), "residual (at rest)");
    ok(k.dynamics(qo, qdo, o.u.data(), o.p.data(), o.M2.data(), o.r2.data()), "dynamics");
    ours_M = Eigen::Map<const Eigen::MatrixXd>(o.M.data(), f, f);  // the kernels' M is column-major
    ours_M2 = Eigen::Map<const Eigen::MatrixXd>(o.M2.data(), f, f);
    mj.mass_matrix(qt);
    ref_M = o.T.transpose() * Eigen::Map<const RowMajor>(mj.M.data(), n, n) * o.T;
    mj.bias(qt, qdt);
    ref_b = o.T.transpose() * Eigen::Map<const Eigen::VectorXd>(mj.d->qfrc_bias, n);
    mj.bias(qt, nullptr);
    ref_g = o.T.transpose() * Eigen::Map<const Eigen::VectorXd>(mj.d->qfrc_bias, n);
    w.M = std::max(w.M, relative_difference(ref_M.data(), ours_M.data(), ff));
    w.bias = std::max(w.bias, relative_difference(ref_b.data(), o.r.data(), o.f));
    w.gravity = std::max(w.gravity, relative_difference(ref_g.data(), o.rg.data(), o.f));
    w.dynamics = std::max({w.dynamics, relative_difference(ref_M.data(), ours_M2.data(), ff),
                           relative_difference(ref_b.data(), o.r2.data(), o.f)});
  }
  return w;
}

// ---- timing (as bench/engines_bench.cpp) --------------------------------------------------------

using bench::Timed;
using bench::time_interleaved;

// ---- command line -------------------------------------------------------------------------------

struct Options {
  std::string out, urdf;
  int samples = 100;
  std::uint64_t seed = 20261129;
  double tolerance = 1e-10;
  bool time = false;
  int repetitions = 21;  ///< --time
};

const char* const kUsage =
    "usage: urdf_engines OUT.csv FILE.urdf [--samples N (100)] [--seed S (20261129)] [--tolerance T (1e-10)] "
    "[--time] [--reps R (21)]";

Options parse(int argc, char** argv) {
  Options o;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--samples" && has_value) {
      o.samples = std::stoi(argv[++i]);
    } else if (a == "--seed" && has_value) {
      o.seed = std::stoull(argv[++i]);
    } else if (a == "--tolerance" && has_value) {
      o.tolerance = std::stod(argv[++i]);
    } else if (a == "--time") {
      o.time = true;
    } else if (a == "--reps" && has_value) {
      o.repetitions = std::stoi(argv[++i]);
    } else if (!a.empty() && a[0] != '-') {
      positional.push_back(a);
    } else {
      throw std::invalid_argument(kUsage);
    }
  }
  if (positional.size() != 2 || o.samples < 1 || !(o.tolerance >= 0) || o.repetitions < 1) throw std::invalid_argument(kUsage);
  o.out = positional[0];
  o.urdf = positional[1];
  return o;
}

/// The notes of a run: kept for the CSV's header and said on stderr as they come.
struct Notes {
  std::vector<std::string> lines;
  void operator()(const std::string& s) {
    lines.push_back(s);
    std::fprintf(stderr, "urdf_engines: note: %s\n", s.c_str());
  }
};

/// MuJoCo with the URDF: the file itself, or a copy with placeholder inertials for the massless
/// moving links MuJoCo 2.2 refuses (with_placeholder_inertials), written to a file created
/// exclusively with an unpredictable name and removed once loaded. `loaded`: what it was given.
std::unique_ptr<MuJoCo> load_mujoco(const Options& opt, const std::string& text, const UrdfFacts& facts,
                                    std::vector<std::string>& patched, UrdfFacts& loaded, Notes& note) {
  const std::string patched_text = with_placeholder_inertials(text, *facts.model, patched);
  if (patched.empty()) {
    loaded = facts;
    return std::make_unique<MuJoCo>(opt.urdf);
  }
  std::string s;
  for (const auto& l : patched) s += (s.empty() ? "" : " ") + l;
  note("MuJoCo 2.2 refuses moving bodies without mass or inertia; placeholder inertials given to it for " + s +
       ", replaced by the URDF's after loading");
  std::string path = (std::filesystem::temp_directory_path() / "urdf_engines_XXXXXX.urdf").string();
  const int fd = mkstemps(path.data(), 5);
  if (fd < 0) throw std::runtime_error("cannot create a temporary file for MuJoCo's copy of " + opt.urdf);
  const bool written = ::write(fd, patched_text.data(), patched_text.size()) == static_cast<ssize_t>(patched_text.size());
  ::close(fd);
  std::unique_ptr<MuJoCo> mj;
  try {
    if (!written) throw std::runtime_error("cannot write MuJoCo's copy of " + opt.urdf);
    mj = std::make_unique<MuJoCo>(path);
  } catch (...) {
    std::filesystem::remove(path);
    throw;
  }
  std::filesystem::remove(path);
  loaded = urdf_facts(patched_text);
  return mj;
}

/// MuJoCo's joints in qpos order (names, joint ids), each a hinge or slide; armature, damping,
/// friction loss and stiffness set to zero (none is in M or qfrc_bias, armature aside), said.
void joints_of_mujoco(MuJoCo& mj, const UrdfFacts& facts, std::vector<std::string>& names, std::vector<int>& joint_of,
                      Notes& note) {
  mjModel* m = mj.m;
  const int n = m->nq;
  names.assign(static_cast<std::size_t>(n), "");
  joint_of.assign(static_cast<std::size_t>(n), 0);
  if (m->nv != n || m->njnt != n)
    throw std::runtime_error("MuJoCo made " + std::to_string(m->njnt) + " joints, " + std::to_string(m->nq) +
                             " positions, " + std::to_string(m->nv) + " velocities: not all joints are 1-dof");
  for (int j = 0; j < m->njnt; ++j) {
    const char* name = mj_id2name(m, mjOBJ_JOINT, j);
    if (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE)
      throw std::runtime_error(std::string("MuJoCo joint ") + (name ? name : "(unnamed)") + " is not a hinge or slide");
    if (!name) throw std::runtime_error("MuJoCo has an unnamed joint");
    const std::string s = name;
    if (s.find_first_of(",\":\n\r") != std::string::npos)
      throw std::runtime_error("joint name '" + s + "' holds one of , \" : or a line break (CSV columns)");
    names[static_cast<std::size_t>(m->jnt_qposadr[j])] = s;
    joint_of[static_cast<std::size_t>(m->jnt_qposadr[j])] = j;
  }
  auto zero_out = [&](mjtNum* v, int count, const char* what) {
    double largest = 0;
    for (int i = 0; i < count; ++i) largest = std::max(largest, std::abs(v[i]));
    if (largest > 0) note(std::string("MuJoCo had ") + what + " up to " + num3(largest) + "; set to 0");
    mju_zero(v, count);
  };
  zero_out(m->dof_armature, m->nv, "dof_armature (added to M by mj_crb)");
  zero_out(m->dof_damping, m->nv, "dof_damping (URDF <dynamics damping>; passive, not in qfrc_bias)");
  zero_out(m->dof_frictionloss, m->nv, "dof_frictionloss (URDF <dynamics friction>; a constraint, not in qfrc_bias)");
  zero_out(m->jnt_stiffness, m->njnt, "jnt_stiffness (passive, not in qfrc_bias)");
  note("MuJoCo " + std::to_string(m->neq) + " equality constraint(s) (m->neq) after loading");
  for (const auto& [joint, what] : facts.mimic)
    note("mimic joint " + joint + " (" + what + "): " +
         (m->neq > 0 ? "MuJoCo has equality constraints (neq > 0); " : "MuJoCo made no equality constraint; ") +
         "recorded as an independent coordinate, M and bias of the unconstrained tree");
  if (!facts.massless_moving.empty()) {
    std::string s;
    for (const auto& l : facts.massless_moving) s += (s.empty() ? "" : " ") + l;
    note("links without mass below a moving joint: " + s);
  }

}

/// Each MuJoCo body's mass properties recomputed from the URDF, compared and written back.
void restore_mass_properties(MuJoCo& mj, const UrdfFacts& facts, const UrdfFacts& loaded,
                             const std::vector<std::string>& patched, Notes& note) {
  mjModel* m = mj.m;
  // Masses: MuJoCo's bodies against the URDF's moving links, in total and body by body. MuJoCo's
  // compiler diagonalizes each body's inertia (a URDF's off-diagonal terms, and the sum of fused
  // links) with a Jacobi iteration, mju_eig3, that stops when the next rotation's cosine is within
  // eigEPS = 1000 mjMINVAL = 1e-12 of 1 (an angle of about 1.4e-6 rad) or the largest off-diagonal
  // term is below 1e-12 kg m²: its principal axes are off by up to about a microradian, and the
  // inertia it represents by up to about 1e-7 of its largest entry (seen: 6e-8). So each body's mass
  // properties are recomputed here in double from the URDF (fused_mass_properties), compared with
  // MuJoCo's (a real change, such as inertia from geometry, stops the run), and written into the
  // mjModel: body_mass, body_ipos, and body_iquat and body_inertia from Eigen's eigensolver; the
  // kinematics (body frames, joint axes) and the algorithms stay MuJoCo's.
  double mj_mass = 0;
  for (int b = 1; b < m->nbody; ++b) mj_mass += m->body_mass[b];
  note("mass [kg]: URDF all links " + num17(facts.total_mass) + ", URDF moving links " + num17(facts.moving_mass) +
       ", MuJoCo bodies as loaded " + num17(mj_mass) + (patched.empty() ? "" : " (with the placeholders)") +
       "; the root link and links fixed to it are fused into MuJoCo's world body and are no KDL segment");
  if (std::abs(mj_mass - loaded.moving_mass) > 1e-12 * std::max(1.0, loaded.moving_mass))
    throw std::runtime_error("MuJoCo's bodies weigh " + num17(mj_mass) + " kg, the moving links it was given " +
                             num17(loaded.moving_mass) + " kg: MuJoCo's import changed the masses");
  double worst_inertia = 0, worst_com = 0;
  std::string worst_inertia_body;
  for (int b = 1; b < m->nbody; ++b) {
    const char* name = mj_id2name(m, mjOBJ_BODY, b);
    if (!name) throw std::runtime_error("MuJoCo has an unnamed body");
    const MassProperties u = fused_mass_properties(*loaded.model, name);  // as MuJoCo was given it
    const Eigen::Quaterniond mq(m->body_iquat[4 * b], m->body_iquat[4 * b + 1], m->body_iquat[4 * b + 2],
                                m->body_iquat[4 * b + 3]);
    const Mat3 R = mq.normalized().toRotationMatrix();
    const Mat3 I_mj = R * Vec3(m->body_inertia[3 * b], m->body_inertia[3 * b + 1], m->body_inertia[3 * b + 2]).asDiagonal() *
                      R.transpose();
    const double dI = (I_mj - u.I).cwiseAbs().maxCoeff(), scale_I = u.I.cwiseAbs().maxCoeff();
    const double dc = (Vec3(m->body_ipos[3 * b], m->body_ipos[3 * b + 1], m->body_ipos[3 * b + 2]) - u.c).cwiseAbs().maxCoeff();
    if (std::abs(m->body_mass[b] - u.m) > 1e-12 * std::max(1.0, u.m) || dc > 1e-9 || dI > 1e-5 * scale_I + 1e-10)
      throw std::runtime_error("MuJoCo's body " + std::string(name) + " has mass " + num17(m->body_mass[b]) +
                               " kg, the URDF " + num17(u.m) + " kg; its centre of mass differs by " + num3(dc) +
                               " m, its inertia by " + num3(dI) + " kg m^2: MuJoCo's import changed it");
    if (scale_I > 0 && dI / scale_I > worst_inertia) {
      worst_inertia = dI / scale_I;
      worst_inertia_body = name;
    }
    worst_com = std::max(worst_com, dc);
    const MassProperties t = patched.empty() ? u : fused_mass_properties(*facts.model, name);  // the URDF's own
    Mat3 V = Mat3::Identity();
    Vec3 moments = t.I.diagonal();
    if (!t.I.isDiagonal(0.0)) {
      const Eigen::SelfAdjointEigenSolver<Mat3> es(t.I);
      V = es.eigenvectors();
      if (V.determinant() < 0) V.col(2) = -V.col(2);
      moments = es.eigenvalues();
    }
    const Eigen::Quaterniond qi(V);
    const double quat[4] = {qi.w(), qi.x(), qi.y(), qi.z()};
    m->body_mass[b] = t.m;
    mju_copy(m->body_ipos + 3 * b, t.c.data(), 3);
    mju_copy(m->body_iquat + 4 * b, quat, 4);
    mju_normalize4(m->body_iquat + 4 * b);
    mju_copy(m->body_inertia + 3 * b, moments.data(), 3);
  }
  for (int b = 0; b < m->nbody; ++b) m->body_subtreemass[b] = m->body_mass[b];
  for (int b = m->nbody - 1; b > 0; --b) m->body_subtreemass[m->body_parentid[b]] += m->body_subtreemass[b];
  note("MuJoCo's compiled inertias differed from the URDF's by up to " + num3(worst_inertia) +
       " of the body's largest entry (" + (worst_inertia_body.empty() ? "-" : worst_inertia_body) +
       "), its centres of mass by up to " + num3(worst_com) +
       " m; replaced by the URDF's, diagonalized in double (Eigen)");

}

/// KDL's joint numbers of MuJoCo's qpos order (the sets must be equal).
std::vector<unsigned> match_kdl(Kdl& kdl, const std::vector<std::string>& names, Notes& note) {
  const int n = static_cast<int>(names.size());
  const std::map<std::string, unsigned> kdl_numbers = kdl.joint_numbers();
  std::vector<unsigned> kdl_index(static_cast<std::size_t>(n));  // qpos index → KDL joint number
  {
    std::set<std::string> mj_set(names.begin(), names.end()), kdl_set;
    for (const auto& [name, number] : kdl_numbers) kdl_set.insert(name);
    if (mj_set != kdl_set || kdl.tree.getNrOfJoints() != static_cast<unsigned>(n) ||
        static_cast<int>(mj_set.size()) != n) {
      std::string only_mj, only_kdl;
      for (const auto& s : mj_set)
        if (!kdl_set.count(s)) only_mj += " " + s;
      for (const auto& s : kdl_set)
        if (!mj_set.count(s)) only_kdl += " " + s;
      throw std::runtime_error("the engines' joints differ: MuJoCo " + std::to_string(n) + ", KDL " +
                               std::to_string(kdl.tree.getNrOfJoints()) + "; only in MuJoCo:" +
                               (only_mj.empty() ? " -" : only_mj) + "; only in KDL:" +
                               (only_kdl.empty() ? " -" : only_kdl));
    }
    for (int i = 0; i < n; ++i) kdl_index[static_cast<std::size_t>(i)] = kdl_numbers.at(names[static_cast<std::size_t>(i)]);
    bool same_order = true;
    for (int i = 0; i < n; ++i) same_order = same_order && kdl_index[static_cast<std::size_t>(i)] == static_cast<unsigned>(i);
    if (!same_order) note("KDL numbers the joints in another order than MuJoCo's qpos; matched by name");
  }
  note(std::string("KDL tree: ") + std::to_string(kdl.tree.getNrOfSegments()) + " segments, " +
       (kdl.chain ? "a single chain: ChainDynParam compared too" : "branched: TreeIdSolver_RNE only"));

  return kdl_index;
}

/// The sampled states, q within each joint's limits (or its default range) and q̇ in [−2, 2],
/// and a line per joint saying which range it was.
void sample_states(const mjModel* m, const std::vector<int>& joint_of, const Options& opt, std::vector<double>& Q,
                   std::vector<double>& QD, std::vector<std::string>& ranges) {
  const std::size_t N = joint_of.size(), S = static_cast<std::size_t>(opt.samples);
  Q.assign(S * N, 0.0);
  QD.assign(S * N, 0.0);
  ranges.assign(N, "");
  {
    std::mt19937_64 rng(opt.seed);
    std::vector<std::uniform_real_distribution<double>> position;
    for (std::size_t i = 0; i < N; ++i) {
      const int j = joint_of[i];
      const bool hinge = m->jnt_type[j] == mjJNT_HINGE;
      double lo = hinge ? -M_PI : -0.5, hi = hinge ? M_PI : 0.5;
      std::string how = hinge ? "hinge, no limits: [-pi, pi]" : "slide, no limits: [-0.5, 0.5] m";
      if (m->jnt_limited[j]) {
        const double a = m->jnt_range[2 * j], b = m->jnt_range[2 * j + 1];
        if (std::isfinite(a) && std::isfinite(b) && a < b) {
          lo = a;
          hi = b;
          how = std::string(hinge ? "hinge" : "slide") + ", limits [" + num17(a) + ", " + num17(b) + "]";
        } else {
          how += " (its range [" + num17(a) + ", " + num17(b) + "] is empty or infinite)";
        }
      }
      ranges[i] = how;
      position.emplace_back(lo, hi);
    }
    std::uniform_real_distribution<double> rate(-2.0, 2.0);
    for (std::size_t s = 0; s < S; ++s) {
      for (std::size_t i = 0; i < N; ++i) Q[s * N + i] = position[i](rng);
      for (std::size_t i = 0; i < N; ++i) QD[s * N + i] = rate(rng);
    }
  }
}

/// What MuJoCo recorded and how far KDL is from it.
struct Recorded {
  std::vector<double> M, bias, gravity;
  double worst_M = 0, worst_bias = 0, worst_gravity = 0, worst_chain = 0;
};

/// Both engines on every state; MuJoCo's numbers kept.
Recorded record(MuJoCo& mj, Kdl& kdl, const std::vector<unsigned>& kdl_index, const std::vector<double>& Q,
                const std::vector<double>& QD, std::size_t S) {
  const std::size_t N = kdl_index.size();
  Recorded rec;
  rec.M.assign(S * N * N, 0.0);
  rec.bias.assign(S * N, 0.0);
  rec.gravity.assign(S * N, 0.0);
  std::vector<double> &rec_M = rec.M, &rec_bias = rec.bias, &rec_gravity = rec.gravity;
  double &worst_M = rec.worst_M, &worst_bias = rec.worst_bias, &worst_gravity = rec.worst_gravity,
         &worst_chain = rec.worst_chain;
  std::vector<double> kM(N * N), kv(N);
  auto to_kdl = [&](std::size_t s) {
    for (std::size_t i = 0; i < N; ++i) {
      kdl.q(kdl_index[i]) = Q[s * N + i];
      kdl.qd(kdl_index[i]) = QD[s * N + i];
    }
  };
  for (std::size_t s = 0; s < S; ++s) {
    const double *q = &Q[s * N], *qd = &QD[s * N];
    mj.mass_matrix(q);
    std::copy(mj.M.begin(), mj.M.end(), rec_M.begin() + static_cast<std::ptrdiff_t>(s * N * N));
    mj.bias(q, qd);
    std::copy(mj.d->qfrc_bias, mj.d->qfrc_bias + N, rec_bias.begin() + static_cast<std::ptrdiff_t>(s * N));
    mj.bias(q, nullptr);
    std::copy(mj.d->qfrc_bias, mj.d->qfrc_bias + N, rec_gravity.begin() + static_cast<std::ptrdiff_t>(s * N));

    to_kdl(s);
    kdl.mass_matrix();
    kdl.bias_and_gravity();
    auto compare = [&](const Eigen::MatrixXd& KM, const Eigen::VectorXd& kb, const Eigen::VectorXd& kg, double& wM,
                       double& wb, double& wg) {
      for (std::size_t a = 0; a < N; ++a)
        for (std::size_t b = 0; b < N; ++b)
          kM[a * N + b] = KM(static_cast<Eigen::Index>(kdl_index[a]), static_cast<Eigen::Index>(kdl_index[b]));
      wM = std::max(wM, relative_difference(&rec_M[s * N * N], kM.data(), N * N));
      for (std::size_t a = 0; a < N; ++a) kv[a] = kb(static_cast<Eigen::Index>(kdl_index[a]));
      wb = std::max(wb, relative_difference(&rec_bias[s * N], kv.data(), N));
      for (std::size_t a = 0; a < N; ++a) kv[a] = kg(static_cast<Eigen::Index>(kdl_index[a]));
      wg = std::max(wg, relative_difference(&rec_gravity[s * N], kv.data(), N));
    };
    compare(kdl.M, kdl.bias, kdl.gravity, worst_M, worst_bias, worst_gravity);
    if (kdl.chain) {
      kdl.chain_all();
      double cM = 0, cb = 0, cg = 0;
      compare(kdl.chain_M, kdl.chain_bias, kdl.chain_gravity, cM, cb, cg);
      worst_chain = std::max({worst_chain, cM, cb, cg});
    }
  }
  return rec;
}

/// OUT.csv, all or nothing.
void write_csv(const Options& opt, const std::string& text, const UrdfFacts& facts, const mjModel* m, const Kdl& kdl,
               const std::vector<std::string>& names, const std::vector<std::string>& ranges, const Notes& notes,
               const std::vector<double>& Q, const std::vector<double>& QD, const Recorded& rec) {
  const std::size_t N = names.size(), S = static_cast<std::size_t>(opt.samples);
  const std::vector<double> &rec_M = rec.M, &rec_bias = rec.bias, &rec_gravity = rec.gravity;
  const double worst_M = rec.worst_M, worst_bias = rec.worst_bias, worst_gravity = rec.worst_gravity,
               worst_chain = rec.worst_chain;
  const std::string tmp = opt.out + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw std::runtime_error("cannot write " + tmp);
    f << "# Reference dynamics of a URDF robot, written by bench/urdf_engines.cpp; do not edit by hand.\n"
      << "# urdf: " << opt.urdf << "\n"
      << "# urdf_bytes: " << text.size() << "\n"
      << "# urdf_sha256: " << sha256(text) << "\n"
      << "# robot: " << facts.robot << "\n"
      << "# recorded: MuJoCo " << mj_version()
      << " (mj_loadXML of the URDF, its bodies' mass properties then set to the URDF's in double;"
         " M: mj_crb + mj_fullM; bias and gravity: mj_rne, flg_acc = 0, qfrc_bias; armature, damping, friction,"
         " stiffness zero)\n"
      << "# checked against: Orocos KDL " << KDL_VERSION_STRING
      << " (Debian liborocos-kdl 1.5.1; kdl_parser::treeFromFile; KDL::TreeIdSolver_RNE"
      << (kdl.chain ? "; and KDL::ChainDynParam, the tree being a chain" : "") << ")\n"
      << "# samples: " << opt.samples << ", seed: " << opt.seed
      << " (std::mt19937_64; per sample q for each joint, then qd for each joint, std::uniform_real_distribution)\n"
      << "# qd: uniform in [-2, 2] rad/s or m/s\n"
      << "# gravity: " << num17(m->opt.gravity[0]) << " " << num17(m->opt.gravity[1]) << " "
      << num17(m->opt.gravity[2]) << " m/s^2 (world frame; MuJoCo's default, given to KDL)\n";
    for (std::size_t i = 0; i < N; ++i) f << "# joint " << i << ": " << names[i] << ", q: " << ranges[i] << "\n";
    for (const std::string& s : notes.lines) f << "# note: " << s << "\n";
    f << "# worst relative disagreement KDL vs MuJoCo over the samples (max |difference| / max |MuJoCo| per sample): M "
      << num3(worst_M) << ", bias " << num3(worst_bias) << ", gravity " << num3(worst_gravity);
    if (kdl.chain) f << "; ChainDynParam " << num3(worst_chain);
    f << " (tolerance " << num3(opt.tolerance) << ")\n"
      << "# bias = c(q, qd) + g(q), the force for zero acceleration (M qdd + bias = tau); gravity = g(q); SI units\n";
    std::string header;
    auto col = [&header](const std::string& c) { header += (header.empty() ? "" : ",") + c; };
    for (const auto& s : names) col("q:" + s);
    for (const auto& s : names) col("qd:" + s);
    for (std::size_t a = 0; a < N; ++a)
      for (std::size_t b = a; b < N; ++b) col("M:" + names[a] + ":" + names[b]);
    for (const auto& s : names) col("bias:" + s);
    for (const auto& s : names) col("gravity:" + s);
    f << header << "\n";
    for (std::size_t s = 0; s < S; ++s) {
      std::string row;
      auto put = [&row](double v) { row += (row.empty() ? "" : ",") + num17(v); };
      for (std::size_t i = 0; i < N; ++i) put(Q[s * N + i]);
      for (std::size_t i = 0; i < N; ++i) put(QD[s * N + i]);
      for (std::size_t a = 0; a < N; ++a)
        for (std::size_t b = a; b < N; ++b) put(rec_M[s * N * N + a * N + b]);
      for (std::size_t i = 0; i < N; ++i) put(rec_bias[s * N + i]);
      for (std::size_t i = 0; i < N; ++i) put(rec_gravity[s * N + i]);
      f << row << "\n";
    }
    f.flush();
    if (!f) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, opt.out);
  std::fprintf(stderr, "urdf_engines: wrote %s\n", opt.out.c_str());

}

/// --time: ours (when compiled in), MuJoCo and KDL, checked and then timed on the same states.
int time_engines(const Options& opt, const UrdfFacts& facts, MuJoCo& mj, Kdl& kdl, const std::vector<std::string>& names,
                 const std::vector<unsigned>& kdl_index, const std::vector<double>& Q, const std::vector<double>& QD,
                 const Recorded& rec) {
  const std::size_t N = names.size(), S = static_cast<std::size_t>(opt.samples);
  const double worst_M = rec.worst_M, worst_bias = rec.worst_bias, worst_gravity = rec.worst_gravity,
               worst_chain = rec.worst_chain;
  // Ours, when the robot's kernels are compiled in (see the head of the file).
  std::unique_ptr<Ours> ours;
  {
    std::string ids;
    for (const Kernels& k : compiled_kernels()) {
      ids += (ids.empty() ? "" : " ") + k.id;
      if (k.id == facts.robot + "_urdf") ours = make_ours(k, names, *facts.model);
    }
    if (!ours)
      std::fprintf(stderr, "urdf_engines: no kernels of ours for %s compiled in (%s); MuJoCo and KDL only\n",
                   facts.robot.c_str(),
                   ids.empty() ? "built without -DMBSGEN_URDF_KERNELS, or no header found" : ("only " + ids).c_str());
  }
  // The timed states: the sampled ones, or, when ours reduce <mimic> joints, those where the
  // mimics hold (for all engines alike).
  const std::vector<double>* TQ = &Q;
  const std::vector<double>* TQD = &QD;
  std::map<std::pair<std::string, std::string>, double> agreement;  // (engine, quantity) → vs MuJoCo
  agreement[{"kdl", "M"}] = worst_M;
  agreement[{"kdl", "bias"}] = std::max(worst_bias, worst_gravity);
  agreement[{"kdl", "M+bias"}] = std::max({worst_M, worst_bias, worst_gravity});
  if (kdl.chain)
    for (const char* quantity : {"M", "bias", "M+bias"}) agreement[{"kdl_chain", quantity}] = worst_chain;
  if (ours) {
    ours_states(*ours, Q, QD, S);
    std::string zeroed;
    for (const auto& z : ours->zeroed) zeroed += " " + z;
    std::fprintf(stderr, "urdf_engines: ours: %s, %zu coordinates; parameters set to 0:%s\n", ours->k.id.c_str(),
                 ours->f, zeroed.empty() ? " none" : zeroed.c_str());
    if (ours->reduced) {
      std::string how;
      for (const auto& [joint, what] : facts.mimic) how += "; " + joint + " " + what;
      std::fprintf(stderr,
                   "urdf_engines: ours take the %zu independent coordinates of %zu (<mimic> as a constraint%s): "
                   "compared with MuJoCo's T^T M T and T^T bias, all engines checked and timed at the states where "
                   "the mimics hold; MuJoCo and KDL timed on their unconstrained %zu-joint tree without the "
                   "projection, ours with closing the loop (%s_assemble)\n",
                   ours->f, ours->n, how.c_str(), ours->n, ours->k.id.c_str());
      TQ = &ours->Qt;
      TQD = &ours->QDt;
    }
    const OursAgreement w = check_ours(*ours, mj, S);
    std::fprintf(stderr,
                 "urdf_engines: %s, %d samples: worst relative disagreement ours (%s) vs MuJoCo: M %.3g, bias %.3g, "
                 "gravity %.3g, dynamics kernel (M and bias) %.3g (tolerance %.3g)\n",
                 facts.robot.c_str(), opt.samples, ours->k.id.c_str(), w.M, w.bias, w.gravity, w.dynamics,
                 opt.tolerance);
    if (std::max({w.M, w.bias, w.gravity, w.dynamics}) > opt.tolerance) {
      std::fprintf(stderr, "urdf_engines: ours disagree with MuJoCo beyond the tolerance; nothing timed\n");
      return 1;
    }
    agreement[{"ours", "M"}] = w.M;
    agreement[{"ours", "bias"}] = std::max(w.bias, w.gravity);
    agreement[{"ours", "M+bias"}] = w.dynamics;
  }
  const double *tq = TQ->data(), *tqd = TQD->data();
  auto kdl_at = [&](std::size_t s) {
    for (std::size_t i = 0; i < N; ++i) {
      kdl.q(kdl_index[i]) = tq[s * N + i];
      kdl.qd(kdl_index[i]) = tqd[s * N + i];
    }
  };

  // Each runs `calls` calls, state s = 0, 1, …, S − 1, 0, …
  auto cycle = [S](std::function<void(std::size_t)> f) {
    return [S, f](long calls) {
      std::size_t s = 0;
      for (long c = 0; c < calls; ++c) {
        f(s);
        if (++s == S) s = 0;
      }
    };
  };
  std::vector<Timed> timed;
  auto add = [&timed](const char* engine, const char* quantity, std::function<void(long)> f) {
    Timed x;
    x.engine = engine;
    x.quantity = quantity;
    x.run = std::move(f);
    timed.push_back(std::move(x));
  };
  if (ours) {
    Ours& o = *ours;
    const Kernels& k = o.k;
    const std::size_t F = o.f;
    const double *qo = o.Qo.data(), *qdo = o.QDo.data(), *p = o.p.data(), *u = o.u.data();
    double *M = o.M.data(), *r = o.r.data();
    add("ours", "M", cycle([=](std::size_t s) { k.mass_matrix(qo + s * F, p, M); }));
    add("ours", "bias", cycle([=](std::size_t s) { k.residual(qo + s * F, qdo + s * F, u, p, r); }));
    add("ours", "M+bias", cycle([=](std::size_t s) { k.dynamics(qo + s * F, qdo + s * F, u, p, M, r); }));
  }
  add("mujoco", "M", cycle([&](std::size_t s) { mj.mass_matrix(tq + s * N); }));
  add("mujoco", "bias", cycle([&](std::size_t s) { mj.bias(tq + s * N, tqd + s * N); }));
  add("mujoco", "M+bias", cycle([&](std::size_t s) { mj.both(tq + s * N, tqd + s * N); }));
  add("kdl", "M", cycle([&](std::size_t s) {
        kdl_at(s);
        kdl.mass_matrix();
      }));
  add("kdl", "bias", cycle([&](std::size_t s) {
        kdl_at(s);
        kdl.bias_and_gravity(true, false);
      }));
  add("kdl", "M+bias", cycle([&](std::size_t s) {
        kdl_at(s);
        kdl.mass_matrix();
        kdl.bias_and_gravity(true, false);
      }));
  if (kdl.chain) {
    add("kdl_chain", "M", cycle([&](std::size_t s) {
          kdl_at(s);
          kdl.chain_mass_matrix();
        }));
    add("kdl_chain", "bias", cycle([&](std::size_t s) {
          kdl_at(s);
          kdl.chain_bias_and_gravity();
        }));
    add("kdl_chain", "M+bias", cycle([&](std::size_t s) {
          kdl_at(s);
          kdl.chain_both();
        }));
  }
  time_interleaved(timed, opt.repetitions, 0.002);
  std::printf("engine,quantity,ns_per_call,min_ns,max_ns,calls_per_repetition,agreement\n");
  for (const Timed& x : timed) {
    const auto a = agreement.find({x.engine, x.quantity});
    std::printf("%s,%s,%.4g,%.4g,%.4g,%ld,%s\n", x.engine.c_str(), x.quantity.c_str(), x.t.median * 1e9,
                x.t.min * 1e9, x.t.max * 1e9, x.t.calls_per_repetition,
                a == agreement.end() ? "" : num3(a->second).c_str());
  }
  return 0;
}

int run(const Options& opt) {
  std::ifstream in(opt.urdf, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + opt.urdf);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const UrdfFacts facts = urdf_facts(text);
  Notes note;
  std::vector<std::string> patched;
  UrdfFacts loaded;
  const std::unique_ptr<MuJoCo> mj = load_mujoco(opt, text, facts, patched, loaded, note);
  std::vector<std::string> names;
  std::vector<int> joint_of;  // qpos index → joint id
  joints_of_mujoco(*mj, facts, names, joint_of, note);
  restore_mass_properties(*mj, facts, loaded, patched, note);
  const mjModel* m = mj->m;
  const int n = m->nq;

  // KDL, with MuJoCo's gravity; joints matched by name.
  const KDL::Vector g(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]);
  Kdl kdl(opt.urdf, g);
  const std::vector<unsigned> kdl_index = match_kdl(kdl, names, note);

  std::vector<double> Q, QD;
  std::vector<std::string> ranges;
  sample_states(m, joint_of, opt, Q, QD, ranges);
  const Recorded rec = record(*mj, kdl, kdl_index, Q, QD, static_cast<std::size_t>(opt.samples));
  std::fprintf(stderr,
               "urdf_engines: %s, %d joints, %d samples: worst relative disagreement KDL (TreeIdSolver_RNE) vs "
               "MuJoCo: M %.3g, bias %.3g, gravity %.3g",
               facts.robot.c_str(), n, opt.samples, rec.worst_M, rec.worst_bias, rec.worst_gravity);
  if (kdl.chain) std::fprintf(stderr, "; KDL ChainDynParam vs MuJoCo (M, bias, gravity) %.3g", rec.worst_chain);
  std::fprintf(stderr, " (tolerance %.3g)\n", opt.tolerance);
  if (std::max({rec.worst_M, rec.worst_bias, rec.worst_gravity, rec.worst_chain}) > opt.tolerance) {
    std::fprintf(stderr, "urdf_engines: the engines disagree beyond the tolerance; %s not written\n",
                 opt.out.c_str());
    return 1;
  }
  // The three readers (urdfdom here, MuJoCo, kdl_parser) read the file separately, so it must not
  // have changed meanwhile.
  {
    std::ifstream again(opt.urdf, std::ios::binary);
    const std::string now((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>());
    if (now != text) throw std::runtime_error("the URDF changed while it was read; run again");
  }
  write_csv(opt, text, facts, m, kdl, names, ranges, note, Q, QD, rec);
  if (!opt.time) return 0;
  return time_engines(opt, facts, *mj, kdl, names, kdl_index, Q, QD, rec);
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
  try {
    return run(opt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urdf_engines: %s: %s\n", opt.urdf.c_str(), e.what());
    std::error_code ec;
    std::filesystem::remove(opt.out + ".tmp", ec);
    return 1;
  }
}

// MuJoCo as a peer of our kernels (bench/engines_bench.cpp, bench/urdf_engines.cpp): a model
// loaded from MJCF or URDF, and the stages of mj_forward that the mass matrix and the bias forces
// need (collision and constraints left out).
//   M      mj_kinematics, mj_comPos, mj_crb, mj_fullM (dense, nv × nv, row-major)
//   bias   mj_kinematics, mj_comPos, mj_comVel, mj_rne(flg_acc = 0) → qfrc_bias = c(q, q̇) + g(q)
//   both   the position stages shared
#pragma once

#include <mujoco/mujoco.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace bench {

struct MuJoCo {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::vector<double> M;  // dense, nv × nv, row-major

  explicit MuJoCo(const std::string& path) {
    char error[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
    if (!m) throw std::runtime_error("MuJoCo cannot load " + path + ": " + error);
    d = mj_makeData(m);
    M.resize(static_cast<std::size_t>(m->nv * m->nv));
  }
  ~MuJoCo() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
  MuJoCo(const MuJoCo&) = delete;
  MuJoCo& operator=(const MuJoCo&) = delete;

  void mass_matrix(const double* q) {
    mju_copy(d->qpos, q, m->nq);
    mj_kinematics(m, d);
    mj_comPos(m, d);
    mj_crb(m, d);
    mj_fullM(m, M.data(), d->qM);
  }
  /// qfrc_bias at (q, q̇); q̇ = nullptr: at rest, the gravity forces.
  void bias(const double* q, const double* qd) {
    mju_copy(d->qpos, q, m->nq);
    if (qd)
      mju_copy(d->qvel, qd, m->nv);
    else
      mju_zero(d->qvel, m->nv);
    mj_kinematics(m, d);
    mj_comPos(m, d);
    mj_comVel(m, d);
    mj_rne(m, d, 0, d->qfrc_bias);
  }
  /// M and qfrc_bias at (q, q̇), the position stages shared.
  void both(const double* q, const double* qd) {
    mju_copy(d->qpos, q, m->nq);
    mju_copy(d->qvel, qd, m->nv);
    mj_kinematics(m, d);
    mj_comPos(m, d);
    mj_crb(m, d);
    mj_fullM(m, M.data(), d->qM);
    mj_comVel(m, d);
    mj_rne(m, d, 0, d->qfrc_bias);
  }
};

}  // namespace bench

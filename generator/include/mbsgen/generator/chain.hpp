// Parametric models built through the C++ API, for tests and benchmarks.
#pragma once

#include "mbsgen/generator/model.hpp"

namespace mbsgen {

/// N-link planar pendulum: point masses m_i at the ends of massless rods l_i, revolute joints
/// about z with relative angles q_i (q_1 from the downward vertical), a torsional spring k_i and
/// damper c_i in each joint (generalized forces joint_spring<i>, joint_damper<i> of the
/// categories springs and dampers), gravity g along −y. The model of the SymPy baseline
/// (../shared/reference/sympy_chain3.md for N = 3). Scenes: no_damping (modes without the
/// dampers) and no_gravity (modes and statics without gravity).
Model planar_chain(int n);

/// N-link spatial chain: rigid links of length l with full inertia tensors, joined by universal
/// joints (rotations about x then y, two coordinates per joint), a torsional spring and damper
/// on every joint angle (spring_<q>, damper_<q>), gravity along −z. 2N coordinates. The same
/// scenes as planar_chain.
Model spatial_chain(int n);

}  // namespace mbsgen

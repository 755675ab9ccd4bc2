// Parametric models built through the C++ API, for tests and benchmarks.
#pragma once

#include "mbsgen/generator/model/model.hpp"

namespace mbsgen {

/// N-link planar pendulum: point masses m_i at the ends of massless rods l_i, revolute joints
/// about z with relative angles q_i (q_1 from the downward vertical), a torsional spring k_i and
/// damper c_i in each joint (generalized forces joint_spring<i>, joint_damper<i> of the
/// categories springs and dampers), gravity g along −y. The model of the SymPy baseline (for
/// N = 3: docs/test-references.md, "The three-link chain"). Scenes: no_damping (modes without the
/// dampers) and no_gravity (modes and statics without gravity).
Model planar_chain(int n);

/// N-link spatial chain: rigid links of length l with full inertia tensors, joined by universal
/// joints (rotations about x then y, two coordinates per joint), a torsional spring and damper
/// on every joint angle (spring_<q>, damper_<q>), gravity along −z. 2N coordinates. The same
/// scenes as planar_chain.
Model spatial_chain(int n);

/// A four-bar in the x–y plane (ground a = 0.4 m, crank l1 = 0.1 m, coupler l2 = 0.35 m, rocker
/// l3 = 0.25 m, uniform bars of 0.3 kg): crank (th1) and rocker (th3) pivoted on the world, the
/// coupler (th2, relative to the crank) joined to the rocker's tip by the revolute constraint
/// `pin`; gravity −y and a spring from a world anchor to the coupler's middle load the loop.
/// Input: a torque T on the crank. Outputs: the pin's load on the rocker (pin_fx, pin_fy) and the
/// world's load on the crank at its pivot (pivot_fx, pivot_fy), type reaction.
/// Operating point: the equilibrium near th1 = 1 rad (guess closed elbow up).
Model four_bar_linkage();

/// A planar ladder of N closed loops hanging under gravity: two rails of N bars (a_i, b_i, length
/// h, relative angles, a joint spring on each, relaxed when hanging) from pivots w apart, and N rungs (r_i, length w)
/// each a child of rail a's i-th bar and joined to rail b's i-th bar by a revolute constraint.
/// 3N coordinates, 2N constraint equations, N degrees of freedom; given operating point hanging
/// straight (exact).
Model ladder(int n);

}  // namespace mbsgen

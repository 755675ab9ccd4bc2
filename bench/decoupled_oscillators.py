#!/usr/bin/env python3
"""Writes the model of issue 14 §4: n bodies, each on its own coordinate and its own spring to
the ground (n decoupled oscillators). Usage: decoupled_oscillators.py N > model.yaml

Body i (mass m_i = 1 + i/n kg) moves along x by x_i; a spring of stiffness k_i = 100 i N/m and
rest length L0 = 1 m joins it to a world marker at x = i - L0, so that x_i = i (the operating
point) is its rest position. Closed form: M = diag(m_i), K = diag(k_i), Q = 0,
omega_i = sqrt(k_i/m_i)."""
import sys


def model(n: int) -> str:
    out = [f"# {n} decoupled oscillators (issue 14 §4), written by bench/decoupled_oscillators.py",
           f"model: oscillators_{n}", "", "parameters:", "  L0: {value: 1, unit: m}", "",
           "coordinates:"]
    out += [f"  - {{name: x{i}, unit: m}}" for i in range(1, n + 1)]
    out += ["", "bodies:"]
    for i in range(1, n + 1):
        out += [f"  - {{name: b{i}, translation: [x{i}, 0, 0], mass: 1 + {i}/{n}, "
                f"markers: [{{name: p{i}}}]}}"]
    out += ["", "markers:"]
    out += [f"  - {{name: a{i}, position: [{i} - L0, 0, 0]}}" for i in range(1, n + 1)]
    out += ["", "forces:"]
    out += [f"  - {{type: spring, between: [a{i}, p{i}], stiffness: {100 * i}, rest_length: L0}}"
            for i in range(1, n + 1)]
    out += ["", "operating_point:", "  position: {" +
            ", ".join(f"x{i}: {i}" for i in range(1, n + 1)) + "}"]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    if len(sys.argv) != 2 or not sys.argv[1].isdigit() or int(sys.argv[1]) < 1:
        sys.exit("usage: decoupled_oscillators.py N (a positive integer) > model.yaml")
    sys.stdout.write(model(int(sys.argv[1])))

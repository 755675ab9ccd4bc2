"""The Python package against the command line and against closed forms (issue 41 §3).

Run by ctest (tests/python/CMakeLists.txt) with PYTHONPATH at the build tree's package, MBSGEN at
the build's mbsgen command and MBSGEN_SOURCE_DIR at the repository. The package and `mbsgen run`
evaluate the same tape with the same runtime code, so their numbers must be equal bit for bit: the
command line prints 17 significant digits, which read back to the same double.
"""

import json
import os
import resource
import subprocess

import numpy as np
import pytest

import mbsgen

SOURCE = os.environ["MBSGEN_SOURCE_DIR"]
TOOL = os.environ["MBSGEN"]


def shipped_models():
    """(model file, scene) of generated/models.txt, each once."""
    seen = []
    with open(os.path.join(SOURCE, "generated", "models.txt"), encoding="utf-8") as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            _, path, scene = line.split()[:3]
            if (path, scene) not in seen:
                seen.append((path, scene))
    return seen


# Closed loops have no tape (their kernels close the loops by Newton in compiled code only): the
# package loads their kernels compiled into a shared library (`mbsgen kernels`).
CLOSED_LOOPS = {"models/linkages/four_bar.yaml", "models/bicycle/whipple_benchmark.yaml"}
# A scene for simulation only, without the linear kernel.
NO_LINEAR = {("models/textbook/rotor_disk.yaml", "motion")}
# The bicycle's compiled solver (for `mbsgen run`) would cost the suite another 10 s of compiling;
# its compiled kernels are checked against [Meijaard2007] (test_the_bicycles_stability_boundaries)
# and the four-bar stands for closed loops against the command line.
NOT_AGAINST_THE_CLI = {("models/bicycle/whipple_benchmark.yaml", "full")}
TAPED = [m for m in shipped_models() if m not in NO_LINEAR and m not in NOT_AGAINST_THE_CLI]


def cli(path, scene, *args):
    done = subprocess.run([TOOL, "run", os.path.join(SOURCE, path), "--scene", scene, "--", *args],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


_models = {}


def model(path, scene):
    key = (path, scene)
    if key not in _models:
        _models[key] = mbsgen.Model(os.path.join(SOURCE, path), scene=scene)
    return _models[key]


def one_changed_parameter(m):
    """A parameter set 10 % above its default (the first nonzero one), as keyword and as --set."""
    for p in m.parameters:
        if p.default != 0:
            value = p.default * 1.1
            return {p.name: value}, ["--set", f"{p.name}={value!r}"]
    return {}, []


@pytest.mark.parametrize("path,scene", TAPED, ids=[f"{os.path.basename(p)}:{s}" for p, s in TAPED])
class TestAgainstTheCommandLine:
    def test_names(self, path, scene):
        m = model(path, scene)
        j = cli(path, scene, "matrices", "--format", "json")
        assert m.inputs == j["inputs"] and m.outputs == j["outputs"]
        assert (m.coordinates == j["coordinates"]) if "coordinates" in j else True

    def test_matrices(self, path, scene):
        m = model(path, scene)
        params, set_args = one_changed_parameter(m)
        for kwargs, extra in (({}, []), (params, set_args)):
            j = cli(path, scene, "matrices", "--format", "json", *extra)
            lin = m.linear(**kwargs)
            names = ["E", "A", "B", "C"] if lin.descriptor else ["M", "Q", "K", "B", "C_y", "C_v"]
            for name in names:
                expected = np.array(j[name], dtype=float).reshape(getattr(lin, name).shape)
                assert np.array_equal(getattr(lin, name), expected), name

    def test_modes(self, path, scene):
        m = model(path, scene)
        params, set_args = one_changed_parameter(m)
        for kwargs, extra in (({}, []), (params, set_args)):
            j = cli(path, scene, "modes", "--format", "json", *extra)
            r = m.modes(**kwargs)
            assert r.stability == j["stability"]
            assert len(r.eigenvalues) == len(j["modes"])
            for k, mode in enumerate(j["modes"]):
                lam = complex(float(mode["lambda_re"]), float(mode["lambda_im"]))
                assert r.eigenvalues[k] == lam or (np.isinf(lam.real) and np.isinf(r.eigenvalues[k].real))
                assert r.error_bound[k] == float(mode["error_bound"])
                assert r.kinds[k] == mode["kind"]

    def test_frf(self, path, scene):
        m = model(path, scene)
        if not m.inputs or not m.outputs:
            pytest.skip("no input or no output")
        j = cli(path, scene, "frf", "--input", m.inputs[0], "--output", m.outputs[-1], "--from", "0.5", "--to",
                "2000", "--points", "7", "--format", "json")
        hz = np.array([float(p["frequency_hz"]) for p in j["points"]])
        r = m.frf(m.inputs[0], m.outputs[-1], hz)
        expected = np.array([complex(float(p["re"]), float(p["im"])) for p in j["points"]])
        assert np.array_equal(r.values, expected)
        assert r.flags == [p["flag"] for p in j["points"]]


class TestClosedForms:
    def test_two_masses_on_springs(self):
        # m1 = 1, m2 = 2, k1 = 3 (to the ground), k2 = 4 (between): ω² are the roots of
        # m1 m2 ω⁴ − (m1 k2 + m2 (k1 + k2)) ω² + k1 k2 = 0.
        M = np.diag([1.0, 2.0])
        K = np.array([[7.0, -4.0], [-4.0, 4.0]])
        w2 = np.sort(np.roots([2.0, -(1.0 * 4.0 + 2.0 * 7.0), 12.0]).real)
        r = mbsgen.linear.modes(M, None, K)
        assert np.allclose(np.sort(np.abs(r.eigenvalues)), np.sqrt(w2), rtol=1e-14, atol=0)
        # the bound the solver states holds for the closed form
        assert np.all(np.abs(np.sort(np.abs(r.eigenvalues)) - np.sqrt(w2)) <= r.error_bound + 1e-15)
        assert r.stability == "marginal"

    def test_damped_oscillator_response(self):
        # m ÿ + c ẏ + k y = u: H(Ω) = 1 / (k − mΩ² + icΩ), rounding of a few operations.
        m, c, k = 2.0, 0.3, 50.0
        hz = np.array([0.0, 0.5, 0.8, 10.0])
        r = mbsgen.linear.frf([[m]], [[c]], [[k]], [[1.0]], [[1.0]], hz)
        w = 2 * np.pi * hz
        assert np.allclose(r.values, 1 / (k - m * w**2 + 1j * c * w), rtol=1e-14, atol=0)
        assert r.flags == ["ok"] * 4


class TestErrors:
    def test_unknown_parameter(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        with pytest.raises(ValueError, match="no parameter 'mass'.*m1, m2"):
            m.modes(mass=1.0)

    def test_unphysical_and_non_finite_values(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        with pytest.raises(ValueError, match="mass -1 kg"):
            m.linear(m1=-1.0)
        with pytest.raises(ValueError, match="non-finite"):
            m.linear(m1=float("nan"))

    def test_unknown_input_and_bad_frequencies(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        with pytest.raises(ValueError, match="force"):
            m.frf("force", "tip_x", [1.0])
        with pytest.raises(ValueError, match="frequencies"):
            m.frf("F", "tip_x", [[1.0, 2.0]])
        with pytest.raises(ValueError, match="frequencies"):
            m.frf("F", "tip_x", [-1.0])

    def test_shapes_of_matrices(self):
        with pytest.raises(ValueError, match=r"K: shape \(3, 3\), expected \(2, 2\)"):
            mbsgen.linear.modes(np.eye(2), None, np.eye(3))
        with pytest.raises(ValueError, match="input: 1 is not a column of B"):
            mbsgen.linear.frf(np.eye(2), None, np.eye(2), np.ones((2, 1)), np.eye(2), [1.0], input=1)

    def test_bad_model_file(self, tmp_path):
        bad = tmp_path / "bad.yaml"
        bad.write_text("model: m\nbodies:\n  - name: [\n")
        with pytest.raises(mbsgen.ModelError, match=r"bad\.yaml:\d+:\d+"):
            mbsgen.Model(bad)

    def test_a_scene_without_linear_analyses(self):
        m = model("models/textbook/rotor_disk.yaml", "motion")
        with pytest.raises(mbsgen.Error, match="no linear kernel"):
            m.modes()

    def test_closed_loops_have_no_tape(self):
        with pytest.raises(mbsgen.ModelError, match="closed loops"):
            mbsgen.Model(os.path.join(SOURCE, "models/linkages/four_bar.yaml"), compiled=False)


def test_closed_loops_are_compiled():
    for path in CLOSED_LOOPS:
        assert model(path, "full").evaluation == "compiled"
    # The bicycle's linear model at v = 5 m/s against [Meijaard2007]'s eigenvalues (Table 2,
    # recomputed at 40 digits: docs/test-references.md), 1e-12 as the C++ tests.
    r = model("models/bicycle/whipple_benchmark.yaml", "full").modes(all=True, v=5.0)
    finite = np.array([lam for lam, kind in zip(r.eigenvalues, r.kinds) if kind == "finite"])
    for expected in (-14.07838969279825, -0.3228664290040871, -0.7753418821958419 + 4.464867713788225j,
                     -0.7753418821958419 - 4.464867713788225j):
        assert np.min(np.abs(finite - expected)) <= 1e-12 * max(1.0, abs(expected))


def test_compiled_kernels_give_the_tapes_numbers():
    # A tape runs the compiled kernel's operations in the same order: the same numbers, bit for bit.
    path = os.path.join(SOURCE, "models/textbook/jeffcott_rotor.yaml")
    taped, compiled = mbsgen.Model(path), mbsgen.Model(path, compiled=True)
    assert (taped.evaluation, compiled.evaluation) == ("tape", "compiled")
    p = taped.parameters[0]
    a, b = taped.linear(**{p.name: 1.3 * p.default}), compiled.linear(**{p.name: 1.3 * p.default})
    for name in ("M", "Q", "K", "B", "C_y", "C_v"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert np.array_equal(taped.modes().eigenvalues, compiled.modes().eigenvalues)


def test_a_tape_file_directly(tmp_path):
    out = tmp_path / "gen"
    subprocess.run([TOOL, "generate", os.path.join(SOURCE, "models/textbook/simple_pendulum.yaml"), "--tape",
                    "--out", str(out)], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    tapes = list(out.glob("*.tape"))
    assert len(tapes) == 1
    direct = mbsgen.Model(tapes[0])
    cached = model("models/textbook/simple_pendulum.yaml", "full")
    assert np.array_equal(direct.modes().eigenvalues, cached.modes().eigenvalues)


def test_a_robot_from_its_urdf(tmp_path):
    """A .urdf is a model file too (docs/urdf.md): the Panda's seven joints in the file's order; the
    import with elastic joints gives seven oscillatory modes (one of each pair listed), stable, and the same
    numbers as the command line's `modes` of the same imported file."""
    arm = mbsgen.Model(os.path.join(SOURCE, "models/robots/urdf/panda.urdf"))
    assert arm.coordinates == ["panda_joint%d" % k for k in range(1, 8)]
    assert arm.evaluation == "tape"
    yaml = tmp_path / "panda_elastic.yaml"
    subprocess.run([TOOL, "import", os.path.join(SOURCE, "models/robots/urdf/panda.urdf"), "--elastic", "all",
                    "--pose", "panda_joint4=-1.8", "--out", str(yaml)], check=True, stderr=subprocess.DEVNULL)
    modes = mbsgen.Model(yaml).modes()
    assert modes.stability == "stable"
    assert len(modes.eigenvalues) == 7 and np.all(modes.eigenvalues.imag > 0)  # one of each pair
    cli = json.loads(subprocess.run([TOOL, "run", str(yaml), "--", "modes", "--format", "json"], check=True,
                                    capture_output=True, text=True).stdout)
    ours = sorted((z for z in modes.eigenvalues if z.imag > 0), key=lambda z: z.imag)
    theirs = sorted((complex(m["lambda_re"], m["lambda_im"]) for m in cli["modes"] if m["lambda_im"] > 0),
                    key=lambda z: z.imag)
    assert np.array_equal(np.array(ours), np.array(theirs))


def resident_kib():
    with open("/proc/self/statm", encoding="ascii") as f:
        return int(f.read().split()[1]) * resource.getpagesize() // 1024


def test_no_memory_is_kept_per_call():
    # 10⁵ calls after 10⁴ to warm up: a leak of 50 bytes a call would keep 5 MB.
    m = model("models/textbook/double_pendulum.yaml", "full")
    for _ in range(10_000):
        m.linear(m1=1.5)
    before = resident_kib()
    for _ in range(100_000):
        m.linear(m1=1.5)
    assert resident_kib() - before < 4096


class TestBatch:
    def test_rows_are_the_single_responses_on_any_number_of_threads(self):
        m = model("models/middle_ear/middle_ear.yaml", "full")
        hz = np.logspace(2, 4, 40)
        rng = np.random.default_rng(7)
        names = ["m_stapes", "k_al_z"]
        defaults = m.parameter_values()
        columns = {n: defaults[[p.name for p in m.parameters].index(n)] * rng.uniform(0.8, 1.2, 12) for n in names}
        columns["m_stapes"][3] = -1e-6  # a negative mass: refused for this set only
        one = m.frf("P", "v_stapes", hz, params=columns, threads=1)
        two = m.frf("P", "v_stapes", hz, params=columns, threads=2)
        assert np.array_equal(one.values, two.values, equal_nan=True)
        assert [k for k, _ in one.failures] == [3] and names[0] in one.failures[0][1]
        assert np.all(np.isnan(one.values[3]))
        for k in (0, 5, 11):
            single = m.frf("P", "v_stapes", hz, **{n: columns[n][k] for n in names})
            assert np.array_equal(one.values[k], single.values)

    def test_bad_sets(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        with pytest.raises(ValueError, match=r"params: shape \(3, 4\), expected \(n_sets, 5\)"):
            m.frf("F", "tip_x", [1.0], params=np.ones((3, 4)))
        with pytest.raises(ValueError, match="as many values"):
            m.frf("F", "tip_x", [1.0], params={"m1": [1.0, 2.0], "m2": [1.0]})
        with pytest.raises(ValueError, match="force"):
            m.frf("force", "tip_x", [1.0], params={"m1": [1.0]})

    def test_ctrl_c_stops_a_long_batch(self):
        # 20,000 sets of the middle ear at 300 frequencies take about a minute on 2 cores; SIGINT
        # after 0.5 s must end the call with KeyboardInterrupt within a few sets.
        import signal
        import threading
        import time

        m = model("models/middle_ear/middle_ear.yaml", "full")
        sets = np.tile(m.parameter_values(), (20_000, 1))
        timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
        t0 = time.perf_counter()
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            m.frf("P", "v_stapes", np.logspace(2, 4, 300), params=sets)
        timer.join()
        assert time.perf_counter() - t0 < 10


SENSITIVITY_CASES = [("models/textbook/double_pendulum.yaml", ["m1", "l2"]),
                     ("models/textbook/rotor_disk.yaml", None),
                     ("models/middle_ear/middle_ear.yaml", ["k_al_z", "m_stapes", "d_al_z"])]


@pytest.mark.parametrize("path,names", SENSITIVITY_CASES, ids=[os.path.basename(p) for p, _ in SENSITIVITY_CASES])
class TestSensitivities:
    def test_modes_equal_the_command_line(self, path, names):
        m = model(path, "full")
        s = m.modes_sensitivity(names)
        j = cli(path, "full", "modes", "--all", "--format", "json", "--sensitivity", *(names or []))
        assert len(j["modes"]) == len(s.modes.eigenvalues)
        for k, mode in enumerate(j["modes"]):
            for q, e in enumerate(mode["sensitivities"]):
                assert e["parameter"] == s.parameters[q]
                if e["defined"]:
                    assert s.dlambda[k, q] == complex(float(e["dlambda"][0]), float(e["dlambda"][1]))
                else:
                    assert np.isnan(s.dlambda[k, q]) and s.notes[k] == e["note"]

    def test_frf_equals_the_command_line(self, path, names):
        m = model(path, "full")
        if not m.inputs or not m.outputs:
            pytest.skip("no input or no output")
        j = cli(path, "full", "frf", "--input", m.inputs[0], "--output", m.outputs[0], "--from", "1", "--to", "3000",
                "--points", "5", "--format", "json", "--sensitivity", *(names or []))
        hz = np.array([float(p["frequency_hz"]) for p in j["points"]])
        s = m.frf_sensitivity(m.inputs[0], m.outputs[0], hz, names)
        for i, point in enumerate(j["points"]):
            assert s.values[i] == complex(float(point["response"][0]), float(point["response"][1]))
            for q, e in enumerate(point["sensitivities"]):
                assert s.derivatives[q, i] == complex(float(e["dz_dp"][0]), float(e["dz_dp"][1]))

    def test_modes_against_central_differences(self, path, names):
        # An independent check of the exact derivative: (λ(p + h) − λ(p − h)) / 2h with h = 1e-4 p.
        # Truncation is O((h/p)²) ≈ 1e-8 relative; rounding, about 1e-13 |λ| per eigenvalue (QZ's
        # backward errors here), divided by 2h. Modes whose change over h is below 1e-9 |λ| carry no
        # signal in double precision and are skipped, as are parameters whose perturbation the model
        # refuses (the rotor's thin disk sits on the triangle inequality A + B = C).
        m = model(path, "full")
        s = m.modes_sensitivity(names)
        checked = 0
        for q, name in enumerate(s.parameters[:5]):
            p0 = s.parameter_values[q]
            if p0 == 0:
                continue
            h = 1e-4 * abs(p0)
            try:
                up = m.modes(all=True, **{name: p0 + h}).eigenvalues
                down = m.modes(all=True, **{name: p0 - h}).eigenvalues
            except ValueError:
                continue
            for k, lam in enumerate(s.modes.eigenvalues):
                d = s.dlambda[k, q]
                if s.notes[k] or not np.isfinite(lam) or h * abs(d) < 1e-9 * abs(lam):
                    continue
                fd = (up[np.argmin(np.abs(up - lam))] - down[np.argmin(np.abs(down - lam))]) / (2 * h)
                assert abs(fd - d) <= 1e-4 * abs(d) + 1e-12 * abs(lam) / h, (name, k, fd, d)
                checked += 1
        assert checked > 0


class TestRightHandSide:
    def test_simple_pendulum_closed_form(self):
        # m l² φ̈ = −m g l sin φ: φ̈ = −(g/l) sin φ, a few roundings.
        m = model("models/textbook/simple_pendulum.yaml", "full")
        for phi, l in ((0.3, 1.0), (2.5, 0.7), (-1.2, 2.0)):
            a = m.accelerations([phi], [0.4], l=l)
            assert a.shape == (1,)
            assert abs(a[0] + 9.81 / l * np.sin(phi)) <= 4e-16 * 9.81 / l

    def test_mass_matrix_at_rest_is_the_linear_models(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        assert np.array_equal(m.mass_matrix([0.0, 0.0], m1=1.7), m.linear(m1=1.7).M)

    def test_bad_states(self):
        m = model("models/textbook/double_pendulum.yaml", "full")
        with pytest.raises(ValueError, match="accelerations: y has 3 entries, the model 2"):
            m.accelerations([0.0, 0.0, 0.0], [0.0, 0.0])
        with pytest.raises(ValueError, match="y: a 1-D array"):
            m.accelerations([[0.0, 0.0]], [0.0, 0.0])
        with pytest.raises(mbsgen.Error, match="closed loops"):
            model("models/linkages/four_bar.yaml", "full").accelerations([0.0], [0.0])


class TestSimulation:
    def test_energy_of_the_pendulum_is_kept(self):
        # Undamped: m g l (1 − cos φ) + ½ m l² φ̇² is an invariant. BDF at rtol 1e-10 keeps it to
        # about 1e-8 relative over 2 s (6.7e-9 measured); 1e-6 fails on a wrong right-hand side.
        m = model("models/textbook/simple_pendulum.yaml", "full")
        r = m.simulate(2.0, initial={"phi": 0.5}, rtol=1e-10, atol=1e-12)
        assert r.t.shape == (1001,) and r.y.shape == (1, 1001) and r.t[-1] == 2.0
        energy = 9.81 * (1 - np.cos(r.y[0])) + 0.5 * r.yd[0] ** 2
        assert np.max(np.abs(energy - energy[0])) <= 1e-6 * energy[0]

    def test_a_small_sine_follows_the_frequency_response(self):
        # Started on the steady state of M_extra = A sin(2π f t) that the linear model predicts,
        # y0 + A Im(H e^{iΩt}), the nonlinear pendulum stays on it: to O(A|H|) relative from its
        # quadratic terms (A|H| ≈ 2e-6 rad) and to rtol·|y0| / (A|H|) ≈ 2e-6 from the integrator.
        m = model("models/textbook/torqued_pendulum.yaml", "full")
        y0 = m.operating_point().y0[0]
        f, A = 0.7, 1e-5
        H = m.frf("M_extra", "angle", [f]).values[0]
        r = m.simulate(3 / f, step=0.01, initial={"phi": y0 + A * H.imag, "phi_dot": A * 2 * np.pi * f * H.real},
                       inputs={"M_extra": f"sine:{A!r},{f!r}"}, rtol=1e-11, atol=1e-16)
        steady = y0 + A * np.imag(H * np.exp(2j * np.pi * f * r.t))
        assert np.max(np.abs(r.y[0] - steady)) <= 1e-4 * A * abs(H)

    def test_bad_requests(self):
        m = model("models/textbook/torqued_pendulum.yaml", "full")
        with pytest.raises(ValueError, match="no input 'torque'"):
            m.simulate(1.0, inputs={"torque": 1.0})
        with pytest.raises(ValueError, match="method 'euler'"):
            m.simulate(1.0, method="euler")
        with pytest.raises(ValueError, match="psi"):
            m.simulate(1.0, initial={"psi": 0.1})


def test_the_bicycles_stability_boundaries():
    # [Meijaard2007] (docs/test-references.md, recomputed at 40 digits): weave speed
    # 4.29238253634111 m/s, capsize speed 6.02426201538837 m/s. Each boundary states its own
    # bracket; the reference must lie inside it.
    s = model("models/bicycle/whipple_benchmark.yaml", "full").sweep("v", 0, 10, 11)
    assert list(s.becomes_unstable) == [0, 1]
    for value, tolerance, expected in zip(s.boundary_values, s.boundary_tolerances,
                                          (4.29238253634111, 6.02426201538837)):
        assert abs(value - expected) <= tolerance <= 1e-8
    assert s.eigenvalues.shape[0] == 11 and s.stability[5] == "marginal"


def test_a_study_equals_the_command_lines(tmp_path):
    # The same design, seed and quantities: every evaluation bit for bit (the CSV's 17 digits).
    path = "models/textbook/double_pendulum.yaml"
    m = model(path, "full")
    hz = [0.1, 0.31622776601683794, 1.0]
    s = m.study({"m1": ("uniform", 0.5, 1.5), "l2": ("normal", 1.0, 0.1)}, samples=20, design="latin-hypercube",
                seed=7, modes=2, input="F", output="tip_x", frequencies=hz, at=[0.5])
    csv_path = tmp_path / "samples.csv"
    done = subprocess.run([TOOL, "run", os.path.join(SOURCE, path), "--", "study", "--parameter", "m1=uniform:0.5:1.5",
                           "--parameter", "l2=normal:1.0:0.1", "--samples", "20", "--design", "lhs", "--seed", "7",
                           "--modes", "2", "--input", "F", "--output", "tip_x", "--at", "0.5", "--from", "0.1",
                           "--to", "1", "--points", "3",
                           "--write-samples", str(csv_path)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    rows = [line.split(",") for line in csv_path.read_text().splitlines() if not line.startswith("#")][1:]
    assert len(rows) == 20 and s.scalar_names == ["f1_hz", "zeta1", "f2_hz", "zeta2", "L_0.5Hz_dB"]
    for i, row in enumerate(rows):
        assert [float(x) for x in row[1:3]] == list(s.samples[i])
        assert [float(x) for x in row[3:8]] == list(s.scalars[i])
    assert s.sweep.shape == (20, 3) and not s.failed


def test_a_model_file_named_like_an_option(tmp_path, monkeypatch):
    # A file name is data: "-h.yaml" must be read as a file, not taken for --help.
    source = os.path.join(SOURCE, "models/textbook/simple_pendulum.yaml")
    (tmp_path / "-h.yaml").write_text(open(source, encoding="utf-8").read())
    monkeypatch.chdir(tmp_path)
    assert mbsgen.Model("-h.yaml").name == "simple_pendulum"


def test_threads_share_a_model():
    # The GIL is released in every analysis: Python threads calling one model at once must get
    # what each gets alone (the tape's workspaces are per call).
    import threading

    m = model("models/middle_ear/middle_ear.yaml", "full")
    hz = np.logspace(2, 4, 30)
    values = [400.0, 700.0, 900.0, 1200.0]
    alone = {v: m.frf("P", "v_stapes", hz, k_al_z=v).values for v in values}
    wrong = []

    def work(v):
        for _ in range(20):
            if not np.array_equal(m.frf("P", "v_stapes", hz, k_al_z=v).values, alone[v]):
                wrong.append(v)

    threads = [threading.Thread(target=work, args=(v,)) for v in values]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not wrong


def test_simulate_at_given_times():
    m = model("models/textbook/simple_pendulum.yaml", "full")
    t = np.linspace(0, 1, 101)
    r = m.simulate(t, initial={"phi": 0.2})
    assert np.allclose(r.t, t, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="evenly spaced"):
        m.simulate(np.array([0.0, 0.1, 0.3]))


# ---------------------------------------------------------------------------------------------
# fit (issue 42): the same fit as the command line's, bit for bit; arrays as data; FitWarning.

CHAIN = "models/textbook/chain3_sympy.yaml"


def chain_data(tmp_path, noise=0.01):
    """The chain's response F -> end_x with k = 12, 18, 33 and 1 % noise, as a data file."""
    m = model(CHAIN, "full")
    hz = np.logspace(np.log10(0.2), 1.0, 40)
    h = m.frf("F", "end_x", hz, k1=12, k2=18, k3=33).values
    rng = np.random.default_rng(4)
    h = h * np.exp(noise * rng.standard_normal(hz.size) + 1j * noise * rng.standard_normal(hz.size))
    path = tmp_path / "chain.csv"
    with open(path, "w", encoding="utf-8") as f:
        f.write("frequency_hz,re,im,sigma_magnitude,sigma_phase_deg\n")
        for a, b in zip(hz, h):
            f.write(f"{a!r},{b.real!r},{b.imag!r},{noise!r},{np.degrees(noise)!r}\n")
    return path, hz, h


@pytest.mark.skipif(not mbsgen._mbsgen.has_fit, reason="built without fit (Ceres Solver)")
def test_fit_equals_the_command_line(tmp_path):
    path, hz, h = chain_data(tmp_path)
    params = {"k1": (1, 100), "k2": (1, 100), "k3": (1, 100, 2.0)}
    r = model(CHAIN, "full").fit(str(path), params, input="F", output="end_x")
    c = cli(CHAIN, "full", "fit", "--data", str(path), "--input", "F", "--output", "end_x", "--format", "json",
            "--parameter", "k1=1:100", "--parameter", "k2=1:100", "--parameter", "k3=1:100:x2")
    assert r.converged and c["converged"]
    assert [p["estimate"] for p in c["parameters"]] == list(r.values)
    assert [p["upper95"] for p in c["parameters"]] == [e.upper95 for e in r.estimates]
    assert c["cost"] == r.cost
    # The same data as arrays: the same fit (the file's numbers are the arrays' to the last bit).
    a = model(CHAIN, "full").fit({"frequency_hz": hz, "response": h, "sigma_magnitude": 0.01,
                                  "sigma_phase_deg": np.degrees(0.01), "input": "F", "output": "end_x"}, params)
    assert list(a.values) == list(r.values)
    # The truth inside the intervals of the two unregularized stiffnesses (1 % noise, 40 points).
    for e, t in zip(r.estimates[:2], (12, 18)):
        assert e.lower95 <= t <= e.upper95, e


@pytest.mark.skipif(not mbsgen._mbsgen.has_fit, reason="built without fit (Ceres Solver)")
def test_fit_says_what_went_wrong(tmp_path):
    path, _, _ = chain_data(tmp_path)
    m = model(CHAIN, "full")
    with pytest.warns(mbsgen.FitWarning, match="did not converge"):
        r = m.fit(str(path), {"k1": (1, 100), "c1": (0.01, 1)}, input="F", output="end_x", max_iterations=1)
    assert not r.converged and "did not converge" in r.warnings[0]
    with pytest.raises(ValueError, match="unknown parameter 'k8'"):
        m.fit(str(path), {"k8": (1, 2)}, input="F", output="end_x")
    with pytest.raises(ValueError, match="not below the upper bound"):
        m.fit(str(path), {"k1": (5, 1)}, input="F", output="end_x")
    with pytest.raises(ValueError, match="which input and output"):
        m.fit({"frequency_hz": [1.0], "response": [1.0]}, {"k1": (1, 100)})
    with pytest.raises(ValueError, match="standard deviation that is not positive"):
        m.fit({"frequency_hz": [1.0], "response": [1.0], "sigma_magnitude": -1, "input": "F", "output": "end_x"},
              {"k1": (1, 100)})
    with pytest.raises(mbsgen.Error, match="bad.csv:2:3: re: .nan. is not finite"):
        bad = tmp_path / "bad.csv"
        bad.write_text("frequency_hz,re,im\n1,nan,0\n")
        m.fit(str(bad), {"k1": (1, 100)}, input="F", output="end_x")

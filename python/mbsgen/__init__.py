"""mbsgen from Python: multibody models as NumPy arrays (docs/python.md).

    import mbsgen
    ear = mbsgen.Model("models/middle_ear/middle_ear.yaml", scene="air_conduction")
    modes = ear.modes()                      # eigenvalues, frequencies, damping, error bounds
    h = ear.frf("p_ec", "v_stapes", np.logspace(2, 4, 300), k_al_z=500.0)

A model file is generated into mbsgen's cache as `mbsgen run` does it (the first time, through
the `mbsgen` command; later from the cache) and evaluated in this process from its tape, without
a compiler. Every analysis takes parameter values by keyword; the others keep their defaults.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import warnings
from typing import Dict, List, NamedTuple, Optional, Sequence

import numpy as np

from . import _mbsgen
from ._mbsgen import Error

__all__ = ["Model", "Parameter", "Modes", "Response", "BatchResponse", "Error", "ModelError", "linear", "tool",
           "FitResult", "FitEstimate", "FisherDirection", "FitWarning"]
__version__ = _mbsgen.__version__


class ModelError(Error):
    """A model file the generator refuses; the message is the generator's (file:line:col: what)."""


class Parameter(NamedTuple):
    name: str
    default: float
    unit: str


def tool() -> str:
    """The mbsgen command the package uses for model files: $MBSGEN when set, else the one it was
    built with (build tree) or installed with, else `mbsgen` on PATH."""
    given = os.environ.get("MBSGEN")
    if given:
        return given
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        with open(os.path.join(here, "tool_path.txt"), encoding="utf-8") as f:
            path = f.read().strip()
        if path and not os.path.isabs(path):  # installed: relative to the package
            path = os.path.normpath(os.path.join(here, path))
        if path and os.access(path, os.X_OK):
            return path
    except OSError:
        pass
    found = shutil.which("mbsgen")
    if found:
        return found
    raise Error("mbsgen: the mbsgen command was not found (set MBSGEN to its path, or put it on PATH)")


def _cached(command: str, path: str, scene: Optional[str]):
    """`mbsgen tape|kernels PATH [--scene SCENE]`: (exit code, the artifact's path, the messages)."""
    # The generator as a separate program, its arguments a list: nothing goes through a shell. A
    # path that starts with "-" would read as an option: it is given as ./-….
    if path.startswith("-"):
        path = os.path.join(".", path)
    args = [tool(), command, path]
    if scene is not None:
        args += ["--scene", scene]
    done = subprocess.run(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, check=False)
    return done.returncode, done.stdout.strip(), done.stderr.strip()


_CLOSED_LOOPS = 3  # `mbsgen tape`'s exit code for a model without a tape


def _artifact(path: str, scene: Optional[str], compiled: Optional[bool]) -> str:
    if compiled is not True:
        code, out, err = _cached("tape", path, scene)
        if code == 0:
            return out
        if code != _CLOSED_LOOPS or compiled is False:
            raise ModelError(err or f"mbsgen tape {path} failed (exit {code})")
    code, out, err = _cached("kernels", path, scene)
    if code != 0:
        raise ModelError(err or f"mbsgen kernels {path} failed (exit {code})")
    return out


def _is_loaded_directly(path: str) -> bool:
    if path.endswith(".tape"):
        return True
    try:
        with open(path, "rb") as f:
            return f.read(4) == b"\x7fELF"
    except OSError:
        return False


class Modes(NamedTuple):
    """Eigenvalues λ (1/s) of λ²M + λQ + K (one per conjugate pair unless all=True), with their
    natural and damped frequencies (Hz), damping ratios, backward errors, absolute error bounds,
    kinds ("finite", "zero", "infinite", "zero_within_bound"), right eigenvectors (columns of
    shapes), the stability verdict that respects the error bounds, and the method."""

    eigenvalues: np.ndarray
    natural_frequency_hz: np.ndarray
    damped_frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    backward_error: np.ndarray
    error_bound: np.ndarray
    kinds: List[str]
    shapes: np.ndarray
    stability: str
    method: str


class Response(NamedTuple):
    """A frequency response: the complex output per unit input at each frequency, the reciprocal
    condition number of each solve, a flag per frequency ("ok", "ill_conditioned", "pole"), the
    solver's warnings and the method used."""

    frequencies_hz: np.ndarray
    values: np.ndarray
    rcond: np.ndarray
    flags: List[str]
    warnings: List[str]
    method: str


class BatchResponse(NamedTuple):
    """Frequency responses of many parameter sets: values[k] for set k (NaN where it failed);
    failures: (set index, reason) of each failed set."""

    frequencies_hz: np.ndarray
    values: np.ndarray
    failures: List[tuple]


def _modes(m) -> Modes:
    return Modes(m.eigenvalues, m.natural_frequency_hz, m.damped_frequency_hz, m.damping_ratio, m.backward_error,
                 m.error_bound, list(m.kinds), m.shapes, m.stability, m.method)


def _frequencies(frequencies) -> np.ndarray:
    hz = np.ascontiguousarray(frequencies, dtype=np.float64)
    if hz.ndim != 1:
        raise ValueError(f"frequencies: a 1-D array of frequencies in Hz, not one of shape {hz.shape}")
    if not np.all(np.isfinite(hz)) or np.any(hz < 0):
        raise ValueError("frequencies: every frequency must be finite and >= 0 Hz")
    return hz


class Model:
    """A multibody model: Model(path, scene=None, compiled=None) for a model file (YAML, generated
    and cached as `mbsgen run` does), a tape (`.tape`, from `mbsgen generate --tape`) or a library
    of compiled kernels (`mbsgen kernels`).

    A model file is evaluated from its tape (no compiler), or, for a model with closed loops (no
    tape) or with compiled=True, from its kernels compiled into a shared library (cached; seconds
    the first time, faster per call). compiled=False refuses the compiler.

    parameters, coordinates, inputs and outputs name what the analyses take and return; each
    analysis takes parameter values by keyword (SI units), the others keeping their defaults."""

    def __init__(self, path, scene: Optional[str] = None, compiled: Optional[bool] = None):
        path = os.fspath(path)
        direct = scene is None and compiled is None and _is_loaded_directly(path)
        self._kernels = _mbsgen.Model(path if direct else _artifact(path, scene, compiled))
        names = self._kernels.parameter_names
        self._index: Dict[str, int] = {n: i for i, n in enumerate(names)}
        self.parameters: List[Parameter] = [
            Parameter(n, float(d), u) for n, d, u in zip(names, self._kernels.parameter_defaults, self._kernels.parameter_units)]
        self._defaults = np.array([q.default for q in self.parameters], dtype=np.float64)
        self._defaults.flags.writeable = False  # passed as is to calls without parameters
        self.coordinates: List[str] = list(self._kernels.coordinate_names)
        self.coordinate_units: List[str] = list(self._kernels.coordinate_units)
        self.inputs: List[str] = list(self._kernels.input_names)
        self.input_units: List[str] = list(self._kernels.input_units)
        self.outputs: List[str] = list(self._kernels.output_names)
        self.output_units: List[str] = list(self._kernels.output_units)
        self.name: str = self._kernels.name
        self.scene: str = self._kernels.scene
        self.evaluation: str = self._kernels.evaluation

    def __repr__(self) -> str:
        return (f"<mbsgen.Model {self.name!r} scene {self.scene!r}: {len(self.coordinates)} coordinates, "
                f"{len(self.parameters)} parameters, {len(self.inputs)} inputs, {len(self.outputs)} outputs>")

    def parameter_values(self, **params: float) -> np.ndarray:
        """Every parameter's value in the model's order: the defaults, with the given ones set."""
        return self._values(params).copy()

    def _values(self, params) -> np.ndarray:
        if not params:
            return self._defaults
        p = self._defaults.copy()
        for name, value in params.items():
            i = self._index.get(name)
            if i is None:
                known = ", ".join(self._index) or "none"
                raise ValueError(f"model {self.name!r} has no parameter {name!r} (parameters: {known})")
            try:
                p[i] = float(value)
            except (TypeError, ValueError):
                raise ValueError(f"parameter {name!r}: a number, not {value!r}") from None
        return p

    def operating_point(self, **params: float):
        """y0, yd0 and how they were found (given by the model, or a static equilibrium)."""
        return self._kernels.operating_point(self._values(params))

    def static(self, **params: float):
        """The static equilibrium (or the model's given operating point): as operating_point."""
        return self.operating_point(**params)

    def linear(self, **params: float):
        """The linear model at the operating point: M, Q, K, B, C_y, C_v (and C_a, D, B1, B2, D1,
        0×0 when zero) as NumPy arrays; for a model with rolling constraints E, A, B, C, D."""
        return self._kernels.linear(self._values(params))

    def modes(self, all: bool = False, **params: float) -> Modes:
        """The eigenvalues of the linear model (see Modes)."""
        return _modes(self._kernels.modes(self._values(params), all))

    def frf(self, input: str, output: str, frequencies: Sequence[float], method: str = "auto", params=None,
            threads: int = 0, **values: float):
        """The response of `output` to a harmonic `input` of unit amplitude at `frequencies` (Hz).
        method: auto, direct, banded, hessenberg, modal or real (as `frf --method`).

        With params, one response per parameter set, on `threads` threads (0: one per core) with
        the GIL released: params is an array of shape (n_sets, len(parameters)) in the model's
        parameter order, or a dict {name: array of n_sets values} (the others at their defaults or
        as given by keyword). Returns a BatchResponse."""
        hz = _frequencies(frequencies)
        if params is None:
            r = self._kernels.frf(self._values(values), input, output, hz, method)
            return Response(hz, r.values, r.rcond, list(r.flags), list(r.warnings), r.method)
        b = self._kernels.frf_batch(self.parameter_sets(params, **values), input, output, hz, method, int(threads))
        return BatchResponse(hz, b.values, list(zip(b.failed, b.reasons)))

    def modes_sensitivity(self, parameters: Optional[Sequence[str]] = None, **values: float):
        """dλ/dp of every eigenvalue (both members of each conjugate pair) by the named parameters
        (all when None): exact, by forward mode over the tape. Returns an object with modes,
        parameters, parameter_values, dlambda (modes × parameters, 1/s per unit), dfrequency_hz,
        relative_frequency ((p/f) df/dp), ddamping_ratio, and notes (why a mode's derivative is
        not defined: repeated, defective, zero, infinite; its entries are NaN)."""
        return self._kernels.modes_sensitivity(self._values(values), list(parameters or []))

    def frf_sensitivity(self, input: str, output: str, frequencies: Sequence[float],
                        parameters: Optional[Sequence[str]] = None, **values: float):
        """The response and dz/dp by the named parameters (all when None) at `frequencies` (Hz):
        values, derivatives (parameters × frequencies), rcond, parameters, parameter_values."""
        hz = _frequencies(frequencies)
        return self._kernels.frf_sensitivity(self._values(values), input, output, hz, list(parameters or []))

    def parameter_sets(self, params, **values: float) -> np.ndarray:
        """params (an array of shape (n_sets, len(parameters)), or a dict {name: n_sets values}) as
        an array of every parameter's value per set."""
        n_params = len(self.parameters)
        if isinstance(params, dict):
            lengths = {name: np.size(v) for name, v in params.items()}
            if len(set(lengths.values())) != 1:
                raise ValueError(f"params: every parameter needs as many values ({lengths})")
            n = next(iter(lengths.values()))
            sets = np.tile(self._values(values), (n, 1))
            for name, v in params.items():
                if name not in self._index:
                    raise ValueError(f"model {self.name!r} has no parameter {name!r} "
                                     f"(parameters: {', '.join(self._index)})")
                sets[:, self._index[name]] = np.asarray(v, dtype=np.float64).reshape(n)
            return sets
        sets = np.ascontiguousarray(params, dtype=np.float64)
        if sets.ndim != 2 or sets.shape[1] != n_params:
            raise ValueError(f"params: shape {sets.shape}, expected (n_sets, {n_params}) "
                             f"(every parameter of model {self.name!r}, in order)")
        if values:
            raise ValueError("params: give the values either in params or by keyword, not both")
        return sets

    def study(self, parameters: Dict[str, tuple], samples: int = 100, design: str = "latin-hypercube", seed: int = 1,
              modes: int = 0, input: str = "", output: str = "", frequencies=None, at=None, method: str = "auto",
              threads: int = 0, bootstrap: int = 1000, **params: float):
        """A parameter study on every core (docs/studies.md): parameters maps a name to
        ("uniform", lo, hi), ("normal", mean, sd) or ("lognormal", median, factor); design
        "monte-carlo", "latin-hypercube" or "saltelli" (Sobol' indices; samples is then the base
        size N, N·(d+2) evaluations). Each evaluation records the lowest `modes` natural
        frequencies and damping ratios, and with input and output the response magnitude at
        `frequencies` (Hz: the rows of `sweep`) and its level in dB at `at` (scalars). Returns
        samples (evaluations × parameters), scalar_names, scalars, sweep, failed and reasons, and
        for a Saltelli design the indices first, total and their 95 % bounds (scalars × parameters).
        The same seed gives the same numbers as `mbsgen run … -- study`."""
        q = _mbsgen.StudyRequest()
        texts = []
        for name, spec in parameters.items():
            if not isinstance(spec, tuple) or len(spec) != 3:
                raise ValueError(f"parameters[{name!r}]: (kind, a, b) with kind uniform, normal or lognormal, not {spec!r}")
            texts.append(f"{name}={spec[0]}:{float(spec[1])!r}:{float(spec[2])!r}")
        q.parameters, q.design, q.samples, q.seed, q.modes = texts, design, int(samples), int(seed), int(modes)
        q.input, q.output, q.method, q.threads, q.bootstrap = input, output, method, int(threads), int(bootstrap)
        q.sweep_hz = np.zeros(0) if frequencies is None else _frequencies(frequencies)
        q.at_hz = np.zeros(0) if at is None else _frequencies(at)
        return self._kernels.study(self._values(params), q)

    def sweep(self, parameter: str, start: float, stop: float, points: int = 51, relative_tolerance: float = 1e-14,
              **params: float):
        """The eigenvalues at `points` values of `parameter` from start to stop (linear), the others
        at their defaults or as given, and every value where the stability changes, refined by
        bisection to relative_tolerance (the verdicts respect each eigenvalue's error bound):
        values, eigenvalues (a row per value, NaN-padded), zeros, abscissa, stability;
        boundary_values, boundary_tolerances, becomes_unstable, boundary_eigenvalues, below, above."""
        return self._kernels.sweep(self._values(params), parameter, float(start), float(stop), int(points),
                                   float(relative_tolerance))

    def simulate(self, duration: float, step: float = 0.0, initial: Optional[Dict[str, float]] = None,
                 inputs: Optional[Dict[str, object]] = None, method: str = "bdf", rtol: float = 1e-8,
                 atol: float = 1e-10, outputs: bool = True, **params: float):
        """Integrates the nonlinear equations of motion from the operating point over [0, duration]
        (s), sampled every `step` (default duration/1000); duration may instead be the sample times
        (evenly spaced from 0, e.g. np.linspace(0, 5, 501)). initial: coordinates and rates by name
        ({"phi": 0.3, "phi_dot": 0}); inputs: per input name a number, a signal in the command
        line's form ("sine:AMPLITUDE,HZ[,PHASE_DEG[,OFFSET]]", "step:AMPLITUDE[,TIME[,BEFORE]]",
        "chirp:AMPLITUDE,F0,F1[,DURATION]") or a table (times, values); method: bdf, adams, radau,
        radau9 (docs/simulation.md). Returns t (samples) and y, yd, u, z (one row per coordinate,
        rate, input, output; one column per sample) with the integrator's statistics. Ctrl-C
        stops it."""
        if np.ndim(duration) == 1:  # sample times 0, h, 2h, …, T
            t = np.asarray(duration, dtype=np.float64)
            h = t[1] - t[0] if t.size > 1 else 0.0
            if t.size < 2 or t[0] != 0 or h <= 0 or np.max(np.abs(np.diff(t) - h)) > 1e-9 * t[-1]:
                raise ValueError("duration: a number, or the sample times 0, h, 2h, …, T (evenly spaced from 0)")
            duration, step = t[-1], h
        q = _mbsgen.SimulationRequest()
        q.method, q.duration, q.step, q.rtol, q.atol, q.outputs = method, float(duration), float(step), rtol, atol, outputs
        initial = initial or {}
        q.initial_names = list(initial)
        q.initial_values = [float(v) for v in initial.values()]
        specs, times, values = [""] * len(self.inputs), [np.zeros(0)] * len(self.inputs), [np.zeros(0)] * len(self.inputs)
        for name, signal in (inputs or {}).items():
            if name not in self.inputs:
                raise ValueError(f"model {self.name!r} has no input {name!r} (inputs: {', '.join(self.inputs) or 'none'})")
            j = self.inputs.index(name)
            if isinstance(signal, str):
                specs[j] = signal
            elif isinstance(signal, tuple) and len(signal) == 2:
                times[j] = np.ascontiguousarray(signal[0], dtype=np.float64)
                values[j] = np.ascontiguousarray(signal[1], dtype=np.float64)
                if times[j].ndim != 1 or times[j].shape != values[j].shape or times[j].size == 0:
                    raise ValueError(f"inputs[{name!r}]: a table (times, values) of two 1-D arrays of one length")
            else:
                specs[j] = repr(float(signal))
        q.input_specs, q.table_times, q.table_values = specs, times, values
        return self._kernels.simulate(self._values(params), q)

    def mass_matrix(self, y, **params: float) -> np.ndarray:
        """M(y) (a model without closed loops or rolling constraints)."""
        return self._kernels.mass_matrix(self._values(params), self._vector("y", y))

    def accelerations(self, y, yd, u=None, **params: float) -> np.ndarray:
        """ÿ = −M(y)⁻¹ (k − q)(y, ẏ, u): the right-hand side of the equations of motion, for an
        integrator (a model without closed loops or rolling constraints; u None: zero inputs)."""
        u = np.zeros(len(self.inputs)) if u is None else u
        return self._kernels.accelerations(self._values(params), self._vector("y", y),
                                           self._vector("yd", yd), self._vector("u", u))

    @staticmethod
    def _vector(name: str, v) -> np.ndarray:
        a = np.ascontiguousarray(v, dtype=np.float64)
        if a.ndim != 1:
            raise ValueError(f"{name}: a 1-D array, not one of shape {a.shape}")
        return a

    def output_values(self, **params: float) -> np.ndarray:
        """The outputs at the operating point."""
        return self._kernels.outputs(self._values(params))

    def fit(self, data, parameters, *, input: Optional[str] = None, output: Optional[str] = None, starts: int = 1,
            threads: int = 0, seed: int = 1, max_iterations: int = 200, profile: Sequence[str] = (),
            profile_points: int = 21, optimize: bool = True, **params: float) -> "FitResult":
        """Fits parameters to measured frequency responses and modal data (docs/fitting.md), from
        the defaults (or the values given by keyword), with the exact Jacobian and Ceres Solver.

        data: a CSV file (the columns of `fit --data`), or a dict {"frequency_hz": array,
        "response": complex array, "sigma_magnitude": σ of ln|H| (scalar or array),
        "sigma_phase_deg": σ of the phase, "input": name, "output": name, "set": label}, or a list
        of them. parameters: {name: (lo, hi)} or {name: (lo, hi, prior)} with prior a factor F > 1
        (log-normal about the start, one σ a factor F) or a string "xF", "+-W", "lin", or a list of
        "NAME=LO:HI[:PRIOR][:lin]" strings. Returns a FitResult; a fit that did not converge is
        returned with converged False and a FitWarning."""
        if not _mbsgen.has_fit:
            raise Error("fit: this build of mbsgen has no fit (built with MBSGEN_WITH_FIT=OFF, or without Ceres Solver)")
        q = _mbsgen.FitRequest()
        q.input, q.output = input or "", output or ""
        arrays = []
        for k, d in enumerate(data if isinstance(data, (list, tuple)) else [data]):
            if isinstance(d, (str, os.PathLike)):
                q.files = list(q.files) + [os.fspath(d)]
            elif isinstance(d, dict):
                arrays.append(_fit_arrays(d, k))
            else:
                raise ValueError(f"data[{k}]: a CSV file or a dict of arrays, not {type(d).__name__}")
        q.arrays = arrays
        q.parameters = _fit_parameters(parameters)
        q.starts, q.threads, q.seed, q.max_iterations = int(starts), int(threads), int(seed), int(max_iterations)
        q.profile, q.profile_points, q.optimize = list(profile), int(profile_points), bool(optimize)
        r = FitResult(_mbsgen.fit(self._kernels, self._values(params), q))
        if not r.converged:
            warnings.warn(FitWarning(f"the fit did not converge ({r.termination}): the values are where it stopped"),
                          stacklevel=2)
        return r


class FitWarning(UserWarning):
    """A fit that did not converge, or whose result needs a caveat (FitResult.warnings)."""


class FitEstimate(NamedTuple):
    name: str
    start: float
    value: float
    standard_error: float
    lower95: float
    upper95: float
    at_bound: str  # "", "lower" or "upper"


class FisherDirection(NamedTuple):
    eigenvalue: float
    sigma: float         # relative standard deviation along the direction (of ln p)
    verdict: str         # "identified", "weakly identified", "not identified"
    description: str     # e.g. "k_a and k_b are identified only as their ratio k_a/k_b"
    direction: np.ndarray


class FitResult:
    """What Model.fit found: estimates (FitEstimate per parameter), values, covariance (of ln p
    in log space, p in linear space), correlation, cost (½Σr² with priors), converged, fisher
    (FisherDirection, weakest first), minima (costs, values), profiles ({name: (values, costs,
    lower95, upper95)}), points (per data point: set, kind, hz, data, initial, fitted, weighted
    residuals) and warnings."""

    def __init__(self, o):
        self.names = list(o.names)
        self.values = np.array(o.values)
        self.estimates = [FitEstimate(n, s, v, e, lo, hi, b) for n, s, v, e, lo, hi, b in
                          zip(o.names, o.start, o.values, o.standard_error, o.lower95, o.upper95, o.at_bound)]
        self.covariance, self.correlation = np.array(o.covariance), np.array(o.correlation)
        self.initial_cost, self.cost, self.data_cost = o.initial_cost, o.cost, o.data_cost
        self.residuals, self.degrees_of_freedom, self.residual_variance = o.residuals, o.degrees_of_freedom, o.residual_variance
        self.weighted, self.converged, self.termination = o.weighted, o.converged, o.termination
        self.iterations, self.evaluations, self.seconds = o.iterations, o.evaluations, o.seconds
        self.fisher = [FisherDirection(e, s, v, d, o.fisher_directions[:, k]) for k, (e, s, v, d) in
                       enumerate(zip(o.fisher_eigenvalues, o.fisher_sigma, o.fisher_verdicts, o.fisher_descriptions))]
        self.minima = (np.array(o.minima_costs), np.array(o.minima_values))
        self.profiles = {n: (o.profile_values[k], o.profile_costs[k], o.profile_lower[k], o.profile_upper[k])
                         for k, n in enumerate(o.profile_names)}
        self.points = {"set": list(o.point_sets), "kind": list(o.point_kinds), "input": list(o.point_inputs),
                       "output": list(o.point_outputs), "hz": np.array(o.point_hz), "data": np.array(o.point_data),
                       "initial": np.array(o.point_initial), "fitted": np.array(o.point_fitted),
                       "residual_magnitude": np.array(o.residual_magnitude), "residual_phase": np.array(o.residual_phase)}
        self.warnings = list(o.warnings)

    def __repr__(self) -> str:
        rows = "\n".join(f"  {e.name}: {e.value:.6g} (95 % {e.lower95:.4g} to {e.upper95:.4g})" for e in self.estimates)
        return (f"<mbsgen.FitResult {'converged' if self.converged else 'NOT CONVERGED'}, cost {self.cost:.6g}, "
                f"{self.residuals} residuals:\n{rows}>")


def _fit_arrays(d: dict, k: int):
    unknown = set(d) - {"frequency_hz", "response", "sigma_magnitude", "sigma_phase_deg", "input", "output", "set"}
    if unknown:
        raise ValueError(f"data[{k}]: unknown keys {sorted(unknown)}")
    if "frequency_hz" not in d or "response" not in d:
        raise ValueError(f"data[{k}]: needs 'frequency_hz' and 'response'")
    a = _mbsgen.FitArrays()
    hz = np.ascontiguousarray(d["frequency_hz"], dtype=np.float64).reshape(-1)
    h = np.ascontiguousarray(d["response"], dtype=np.complex128).reshape(-1)
    if h.shape != hz.shape:
        raise ValueError(f"data[{k}]: {hz.size} frequencies but {h.size} responses")
    full = lambda v, scale: np.broadcast_to(np.asarray(np.nan if v is None else v, dtype=np.float64) * scale, hz.shape).copy()
    a.hz, a.values = hz, h
    a.sigma_magnitude = full(d.get("sigma_magnitude"), 1.0)
    a.sigma_phase_rad = full(d.get("sigma_phase_deg"), np.pi / 180)
    a.input, a.output, a.set = str(d.get("input", "")), str(d.get("output", "")), str(d.get("set", ""))
    return a


def _fit_parameters(parameters) -> List[str]:
    if isinstance(parameters, dict):
        specs = []
        for name, v in parameters.items():
            v = tuple(v)
            if len(v) not in (2, 3):
                raise ValueError(f"parameters[{name!r}]: (lo, hi) or (lo, hi, prior), not {v!r}")
            text = f"{name}={float(v[0])!r}:{float(v[1])!r}"
            if len(v) == 3:
                text += ":" + (v[2] if isinstance(v[2], str) else f"x{float(v[2])!r}")
            specs.append(text)
        return specs
    return [str(p) for p in parameters]


class linear:  # noqa: N801 (a namespace: mbsgen.linear.modes, mbsgen.linear.frf)
    """Analyses of linear models given as matrices: M ÿ + Q ẏ + K y = B u, z = C_y y + C_v ẏ."""

    @staticmethod
    def _matrix(name: str, a, rows: int, cols: int) -> np.ndarray:
        a = np.asarray(linear._dense(a), dtype=np.float64)
        if a.ndim != 2 or a.shape != (rows, cols):
            raise ValueError(f"{name}: shape {a.shape}, expected ({rows}, {cols})")
        return np.asfortranarray(a)

    @staticmethod
    def _dense(a):
        return a.toarray() if hasattr(a, "toarray") else a  # SciPy sparse matrices

    @staticmethod
    def modes(M, Q, K, all: bool = False) -> Modes:
        """The eigenvalues of λ²M + λQ + K (Q None: zero)."""
        M = np.asarray(linear._dense(M), dtype=np.float64)
        if M.ndim != 2 or M.shape[0] != M.shape[1]:
            raise ValueError(f"M: shape {M.shape}, expected a square matrix")
        f = M.shape[0]
        Q = np.zeros((f, f)) if Q is None else linear._dense(Q)
        return _modes(_mbsgen.modes_of(linear._matrix("M", M, f, f), linear._matrix("Q", Q, f, f),
                                       linear._matrix("K", linear._dense(K), f, f), all))

    @staticmethod
    def frf(M, Q, K, B, C_y, frequencies, input: int = 0, output: int = 0, C_v=None,
            method: str = "auto") -> Response:
        """The response of output row `output` to input column `input` (0-based) at `frequencies` (Hz)."""
        M = np.asarray(linear._dense(M), dtype=np.float64)
        if M.ndim != 2 or M.shape[0] != M.shape[1]:
            raise ValueError(f"M: shape {M.shape}, expected a square matrix")
        f = M.shape[0]
        B = np.asarray(linear._dense(B), dtype=np.float64)
        C_y = np.asarray(linear._dense(C_y), dtype=np.float64)
        if B.ndim != 2 or C_y.ndim != 2:
            raise ValueError(f"B and C_y: 2-D arrays, not of shapes {B.shape} and {C_y.shape}")
        m, p = B.shape[1], C_y.shape[0]
        if not 0 <= input < m:
            raise ValueError(f"input: {input} is not a column of B ({m} columns)")
        if not 0 <= output < p:
            raise ValueError(f"output: {output} is not a row of C_y ({p} rows)")
        Q = np.zeros((f, f)) if Q is None else linear._dense(Q)
        C_v = np.zeros((p, f)) if C_v is None else linear._dense(C_v)
        hz = _frequencies(frequencies)
        r = _mbsgen.frf_of(linear._matrix("M", M, f, f), linear._matrix("Q", Q, f, f),
                           linear._matrix("K", linear._dense(K), f, f), linear._matrix("B", B, f, m),
                           linear._matrix("C_y", C_y, p, f), linear._matrix("C_v", C_v, p, f), input, output, hz,
                           method)
        return Response(hz, r.values, r.rcond, list(r.flags), list(r.warnings), r.method)

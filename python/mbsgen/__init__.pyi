# Type hints of the mbsgen package (docs/python.md).
from typing import Any, Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

__version__: str

class Error(RuntimeError): ...
class ModelError(Error): ...

class Parameter(NamedTuple):
    name: str
    default: float
    unit: str

class Modes(NamedTuple):
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

class BatchResponse(NamedTuple):
    frequencies_hz: np.ndarray
    values: np.ndarray
    failures: List[tuple]

class Response(NamedTuple):
    frequencies_hz: np.ndarray
    values: np.ndarray
    rcond: np.ndarray
    flags: List[str]
    warnings: List[str]
    method: str

class OperatingPoint:
    y0: np.ndarray
    yd0: np.ndarray
    equilibrium: bool
    iterations: int
    residual_norm: float
    report: str

class Linear:
    descriptor: bool
    M: np.ndarray
    Q: np.ndarray
    K: np.ndarray
    B: np.ndarray
    C_y: np.ndarray
    C_v: np.ndarray
    C_a: np.ndarray
    D: np.ndarray
    B1: np.ndarray
    B2: np.ndarray
    D1: np.ndarray
    E: np.ndarray
    A: np.ndarray
    C: np.ndarray
    state_names: List[str]

def tool() -> str: ...

class Model:
    name: str
    scene: str
    evaluation: str
    parameters: List[Parameter]
    coordinates: List[str]
    coordinate_units: List[str]
    inputs: List[str]
    input_units: List[str]
    outputs: List[str]
    output_units: List[str]
    def __init__(self, path: str, scene: Optional[str] = None, compiled: Optional[bool] = None) -> None: ...
    def parameter_values(self, **params: float) -> np.ndarray: ...
    def operating_point(self, **params: float) -> OperatingPoint: ...
    def static(self, **params: float) -> OperatingPoint: ...
    def linear(self, **params: float) -> Linear: ...
    def modes(self, all: bool = False, **params: float) -> Modes: ...
    def frf(self, input: str, output: str, frequencies: Sequence[float], method: str = "auto", params=None,
            threads: int = 0, **values: float): ...
    def study(self, parameters: Dict[str, tuple], samples: int = 100, design: str = "latin-hypercube", seed: int = 1,
              modes: int = 0, input: str = "", output: str = "", frequencies: Optional[Sequence[float]] = None,
              at: Optional[Sequence[float]] = None, method: str = "auto", threads: int = 0, bootstrap: int = 1000,
              **params: float) -> Any: ...
    def sweep(self, parameter: str, start: float, stop: float, points: int = 51, relative_tolerance: float = 1e-14,
              **params: float) -> Any: ...
    def simulate(self, duration: float, step: float = 0.0, initial: Optional[Dict[str, float]] = None,
                 inputs: Optional[Dict[str, object]] = None, method: str = "bdf", rtol: float = 1e-8,
                 atol: float = 1e-10, outputs: bool = True, **params: float) -> Any: ...
    def mass_matrix(self, y: Sequence[float], **params: float) -> np.ndarray: ...
    def accelerations(self, y: Sequence[float], yd: Sequence[float], u: Optional[Sequence[float]] = None,
                      **params: float) -> np.ndarray: ...
    def modes_sensitivity(self, parameters: Optional[Sequence[str]] = None, **params: float): ...
    def frf_sensitivity(self, input: str, output: str, frequencies: Sequence[float],
                        parameters: Optional[Sequence[str]] = None, **params: float): ...
    def parameter_sets(self, params, **values: float) -> np.ndarray: ...
    def output_values(self, **params: float) -> np.ndarray: ...
    def fit(self, data: Any, parameters: Any, *, input: Optional[str] = ..., output: Optional[str] = ...,
            starts: int = ..., threads: int = ..., seed: int = ..., max_iterations: int = ...,
            profile: Sequence[str] = ..., profile_points: int = ..., optimize: bool = ..., **params: float) -> FitResult: ...

class FitWarning(UserWarning): ...

class FitEstimate(NamedTuple):
    name: str
    start: float
    value: float
    standard_error: float
    lower95: float
    upper95: float
    at_bound: str

class FisherDirection(NamedTuple):
    eigenvalue: float
    sigma: float
    verdict: str
    description: str
    direction: np.ndarray

class FitResult:
    names: List[str]
    values: np.ndarray
    estimates: List[FitEstimate]
    covariance: np.ndarray
    correlation: np.ndarray
    initial_cost: float
    cost: float
    data_cost: float
    residuals: int
    degrees_of_freedom: int
    residual_variance: float
    weighted: bool
    converged: bool
    termination: str
    iterations: int
    evaluations: int
    seconds: float
    fisher: List[FisherDirection]
    minima: Tuple[np.ndarray, np.ndarray]
    profiles: Dict[str, Tuple[np.ndarray, np.ndarray, float, float]]
    points: Dict[str, Any]
    warnings: List[str]

class linear:
    @staticmethod
    def modes(M: np.ndarray, Q: Optional[np.ndarray], K: np.ndarray, all: bool = False) -> Modes: ...
    @staticmethod
    def frf(M: np.ndarray, Q: Optional[np.ndarray], K: np.ndarray, B: np.ndarray, C_y: np.ndarray,
            frequencies: Sequence[float], input: int = 0, output: int = 0, C_v: Optional[np.ndarray] = None,
            method: str = "auto") -> Response: ...

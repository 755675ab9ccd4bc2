// The extension module mbsgen._mbsgen (issue 41): pybind11 bindings of facade.hpp. The Python
// layer (python/mbsgen/__init__.py) builds the public API on it: parameters by keyword, models by
// path through the cache, result objects.
#include <pybind11/complex.h>
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>

#include "facade.hpp"
#ifdef MBSGEN_PYTHON_FIT
#include "fit_facade.hpp"
#endif
#include "mbsgen/runtime/error.hpp"
#include "mbsgen/runtime/model/generated_model.hpp"
#include "mbsgen/runtime/version.hpp"

namespace py = pybind11;
using namespace mbsgen::python;

namespace {

const auto released = py::call_guard<py::gil_scoped_release>();

// The results of the model's analyses, read-only.
void bind_results(py::module_& m) {
  py::class_<Linear>(m, "Linear")
      .def_readonly("descriptor", &Linear::descriptor)
      .def_readonly("M", &Linear::M)
      .def_readonly("Q", &Linear::Q)
      .def_readonly("K", &Linear::K)
      .def_readonly("B", &Linear::B)
      .def_readonly("C_y", &Linear::C_y)
      .def_readonly("C_v", &Linear::C_v)
      .def_readonly("C_a", &Linear::C_a)
      .def_readonly("D", &Linear::D)
      .def_readonly("B1", &Linear::B1)
      .def_readonly("B2", &Linear::B2)
      .def_readonly("D1", &Linear::D1)
      .def_readonly("E", &Linear::E)
      .def_readonly("A", &Linear::A)
      .def_readonly("C", &Linear::C)
      .def_readonly("state_names", &Linear::state_names);

  py::class_<OperatingPoint>(m, "OperatingPoint")
      .def_readonly("y0", &OperatingPoint::y0)
      .def_readonly("yd0", &OperatingPoint::yd0)
      .def_readonly("equilibrium", &OperatingPoint::equilibrium)
      .def_readonly("iterations", &OperatingPoint::iterations)
      .def_readonly("residual_norm", &OperatingPoint::residual_norm)
      .def_readonly("report", &OperatingPoint::report);

  py::class_<Modes>(m, "Modes")
      .def_readonly("eigenvalues", &Modes::eigenvalues)
      .def_readonly("natural_frequency_hz", &Modes::natural_frequency_hz)
      .def_readonly("damped_frequency_hz", &Modes::damped_frequency_hz)
      .def_readonly("damping_ratio", &Modes::damping_ratio)
      .def_readonly("backward_error", &Modes::backward_error)
      .def_readonly("error_bound", &Modes::error_bound)
      .def_readonly("kinds", &Modes::kinds)
      .def_readonly("shapes", &Modes::shapes)
      .def_readonly("stability", &Modes::stability)
      .def_readonly("method", &Modes::method);

  py::class_<Response>(m, "Response")
      .def_readonly("values", &Response::values)
      .def_readonly("rcond", &Response::rcond)
      .def_readonly("flags", &Response::flags)
      .def_readonly("warnings", &Response::warnings)
      .def_readonly("method", &Response::method);

  py::class_<ModeSensitivities>(m, "ModeSensitivities")
      .def_readonly("modes", &ModeSensitivities::modes)
      .def_readonly("parameters", &ModeSensitivities::parameters)
      .def_readonly("parameter_values", &ModeSensitivities::parameter_values)
      .def_readonly("dlambda", &ModeSensitivities::dlambda)
      .def_readonly("dfrequency_hz", &ModeSensitivities::dfrequency_hz)
      .def_readonly("relative_frequency", &ModeSensitivities::relative_frequency)
      .def_readonly("ddamping_ratio", &ModeSensitivities::ddamping_ratio)
      .def_readonly("notes", &ModeSensitivities::notes);

  py::class_<ResponseSensitivity>(m, "ResponseSensitivity")
      .def_readonly("values", &ResponseSensitivity::values)
      .def_readonly("derivatives", &ResponseSensitivity::derivatives)
      .def_readonly("rcond", &ResponseSensitivity::rcond)
      .def_readonly("parameters", &ResponseSensitivity::parameters)
      .def_readonly("parameter_values", &ResponseSensitivity::parameter_values);

}

// Sweeps, studies and simulations: their requests and results.
void bind_analyses(py::module_& m) {
  py::class_<Sweep>(m, "Sweep")
      .def_readonly("values", &Sweep::values)
      .def_readonly("eigenvalues", &Sweep::eigenvalues)
      .def_readonly("zeros", &Sweep::zeros)
      .def_readonly("abscissa", &Sweep::abscissa)
      .def_readonly("stability", &Sweep::stability)
      .def_readonly("boundary_values", &Sweep::boundary_values)
      .def_readonly("boundary_tolerances", &Sweep::boundary_tolerances)
      .def_readonly("becomes_unstable", &Sweep::becomes_unstable)
      .def_readonly("boundary_eigenvalues", &Sweep::boundary_eigenvalues)
      .def_readonly("below", &Sweep::below)
      .def_readonly("above", &Sweep::above);

  py::class_<StudyRequest>(m, "StudyRequest")
      .def(py::init<>())
      .def_readwrite("parameters", &StudyRequest::parameters)
      .def_readwrite("design", &StudyRequest::design)
      .def_readwrite("samples", &StudyRequest::samples)
      .def_readwrite("seed", &StudyRequest::seed)
      .def_readwrite("modes", &StudyRequest::modes)
      .def_readwrite("input", &StudyRequest::input)
      .def_readwrite("output", &StudyRequest::output)
      .def_readwrite("method", &StudyRequest::method)
      .def_readwrite("sweep_hz", &StudyRequest::sweep_hz)
      .def_readwrite("at_hz", &StudyRequest::at_hz)
      .def_readwrite("threads", &StudyRequest::threads)
      .def_readwrite("bootstrap", &StudyRequest::bootstrap);

  py::class_<Study>(m, "Study")
      .def_readonly("parameter_names", &Study::parameter_names)
      .def_readonly("scalar_names", &Study::scalar_names)
      .def_readonly("samples", &Study::samples)
      .def_readonly("scalars", &Study::scalars)
      .def_readonly("sweep", &Study::sweep)
      .def_readonly("failed", &Study::failed)
      .def_readonly("reasons", &Study::reasons)
      .def_readonly("first", &Study::first)
      .def_readonly("first_low", &Study::first_low)
      .def_readonly("first_high", &Study::first_high)
      .def_readonly("total", &Study::total)
      .def_readonly("total_low", &Study::total_low)
      .def_readonly("total_high", &Study::total_high);

  py::class_<Simulation>(m, "Simulation")
      .def_readonly("t", &Simulation::t)
      .def_readonly("y", &Simulation::y)
      .def_readonly("yd", &Simulation::yd)
      .def_readonly("u", &Simulation::u)
      .def_readonly("z", &Simulation::z)
      .def_readonly("analytic_jacobian", &Simulation::analytic_jacobian)
      .def_readonly("constraint_drift", &Simulation::constraint_drift)
      .def_readonly("steps", &Simulation::steps)
      .def_readonly("rhs_evaluations", &Simulation::rhs_evaluations)
      .def_readonly("jacobian_evaluations", &Simulation::jacobian_evaluations)
      .def_readonly("error_test_failures", &Simulation::error_test_failures)
      .def_readonly("nonlinear_failures", &Simulation::nonlinear_failures);

  py::class_<SimulationRequest>(m, "SimulationRequest")
      .def(py::init<>())
      .def_readwrite("method", &SimulationRequest::method)
      .def_readwrite("duration", &SimulationRequest::duration)
      .def_readwrite("step", &SimulationRequest::step)
      .def_readwrite("rtol", &SimulationRequest::rtol)
      .def_readwrite("atol", &SimulationRequest::atol)
      .def_readwrite("initial_names", &SimulationRequest::initial_names)
      .def_readwrite("initial_values", &SimulationRequest::initial_values)
      .def_readwrite("input_specs", &SimulationRequest::input_specs)
      .def_readwrite("table_times", &SimulationRequest::table_times)
      .def_readwrite("table_values", &SimulationRequest::table_values)
      .def_readwrite("outputs", &SimulationRequest::outputs);

  py::class_<BatchResponse>(m, "BatchResponse")
      .def_readonly("values", &BatchResponse::values)
      .def_readonly("failed", &BatchResponse::failed)
      .def_readonly("reasons", &BatchResponse::reasons);

}

void bind_model(py::module_& m) {
  py::class_<Model>(m, "Model")
      .def(py::init<const std::string&>(), py::arg("path"), released)
      .def_property_readonly("name", &Model::name)
      .def_property_readonly("scene", &Model::scene)
      .def_property_readonly("evaluation", &Model::evaluation)
      .def_property_readonly("parameter_names", &Model::parameter_names)
      .def_property_readonly("parameter_units", &Model::parameter_units)
      .def_property_readonly("parameter_defaults", &Model::parameter_defaults)
      .def_property_readonly("coordinate_names", &Model::coordinate_names)
      .def_property_readonly("coordinate_units", &Model::coordinate_units)
      .def_property_readonly("input_names", &Model::input_names)
      .def_property_readonly("input_units", &Model::input_units)
      .def_property_readonly("output_names", &Model::output_names)
      .def_property_readonly("output_units", &Model::output_units)
      .def_property_readonly("descriptor", &Model::descriptor)
      .def_property_readonly("default_from_hz", &Model::default_from_hz)
      .def_property_readonly("default_to_hz", &Model::default_to_hz)
      .def_property_readonly("default_points", &Model::default_points)
      .def("operating_point", &Model::operating_point, py::arg("p"), released)
      .def("linear", &Model::linear, py::arg("p"), released)
      .def("modes", &Model::modes, py::arg("p"), py::arg("all") = false, released)
      .def("frf", &Model::frf, py::arg("p"), py::arg("input"), py::arg("output"), py::arg("hz"),
           py::arg("method") = "auto", released)
      .def(
          "frf_batch",
          [](const Model& model, const ConstRowMajorRef& sets, const std::string& input, const std::string& output,
             const ConstVectorRef& hz, const std::string& method, int threads) {
            // Ctrl-C: the calling thread looks for a pending signal after each of its sets.
            const auto interrupted = [] {
              py::gil_scoped_acquire gil;
              return PyErr_CheckSignals() != 0;
            };
            try {
              return model.frf_batch(sets, input, output, hz, method, threads, interrupted);
            } catch (const Stopped&) {
              py::gil_scoped_acquire gil;
              throw py::error_already_set();  // the KeyboardInterrupt (or other) PyErr_CheckSignals set
            }
          },
          py::arg("sets"), py::arg("input"), py::arg("output"), py::arg("hz"), py::arg("method") = "auto",
          py::arg("threads") = 0, released)
      .def("modes_sensitivity", &Model::modes_sensitivity, py::arg("p"), py::arg("names"), released)
      .def("frf_sensitivity", &Model::frf_sensitivity, py::arg("p"), py::arg("input"), py::arg("output"),
           py::arg("hz"), py::arg("names"), released)
      .def("outputs", &Model::outputs, py::arg("p"), released)
      .def("study", &Model::study, py::arg("p"), py::arg("request"), released)
      .def("sweep", &Model::sweep, py::arg("p"), py::arg("parameter"), py::arg("start"), py::arg("stop"),
           py::arg("points"), py::arg("relative_tolerance") = 1e-14, released)
      .def(
          "simulate",
          [](const Model& model, const ConstVectorRef& p, const SimulationRequest& request) {
            const auto interrupted = [] {
              py::gil_scoped_acquire gil;
              return PyErr_CheckSignals() != 0;
            };
            try {
              return model.simulate(p, request, interrupted);
            } catch (const Stopped&) {
              py::gil_scoped_acquire gil;
              throw py::error_already_set();
            }
          },
          py::arg("p"), py::arg("request"), released)
      .def("mass_matrix", &Model::mass_matrix, py::arg("p"), py::arg("y"))
      .def("accelerations", &Model::accelerations, py::arg("p"), py::arg("y"), py::arg("yd"), py::arg("u"));

  // For bench/python_bench.py: the same facade calls timed in C++ (n calls in a row, seconds in
  // all), so that the Python overhead per call is a difference measured in one process.
}

#ifdef MBSGEN_PYTHON_FIT
// fit (issue 42): its request and result, and Model.fit with Ctrl-C.
void bind_fit(py::module_& m) {
  py::class_<FitArrays>(m, "FitArrays")
      .def(py::init<>())
      .def_readwrite("input", &FitArrays::input)
      .def_readwrite("output", &FitArrays::output)
      .def_readwrite("set", &FitArrays::set)
      .def_readwrite("hz", &FitArrays::hz)
      .def_readwrite("values", &FitArrays::values)
      .def_readwrite("sigma_magnitude", &FitArrays::sigma_magnitude)
      .def_readwrite("sigma_phase_rad", &FitArrays::sigma_phase_rad);
  py::class_<FitRequest>(m, "FitRequest")
      .def(py::init<>())
      .def_readwrite("files", &FitRequest::files)
      .def_readwrite("input", &FitRequest::input)
      .def_readwrite("output", &FitRequest::output)
      .def_readwrite("arrays", &FitRequest::arrays)
      .def_readwrite("parameters", &FitRequest::parameters)
      .def_readwrite("starts", &FitRequest::starts)
      .def_readwrite("threads", &FitRequest::threads)
      .def_readwrite("max_iterations", &FitRequest::max_iterations)
      .def_readwrite("profile_points", &FitRequest::profile_points)
      .def_readwrite("seed", &FitRequest::seed)
      .def_readwrite("optimize", &FitRequest::optimize)
      .def_readwrite("profile", &FitRequest::profile);
  py::class_<FitOutcome> f(m, "FitOutcome");
#define MBSGEN_FIELD(name) f.def_readonly(#name, &FitOutcome::name)
  MBSGEN_FIELD(names); MBSGEN_FIELD(at_bound); MBSGEN_FIELD(warnings); MBSGEN_FIELD(start); MBSGEN_FIELD(values);
  MBSGEN_FIELD(standard_error); MBSGEN_FIELD(lower95); MBSGEN_FIELD(upper95); MBSGEN_FIELD(covariance);
  MBSGEN_FIELD(correlation); MBSGEN_FIELD(initial_cost); MBSGEN_FIELD(cost); MBSGEN_FIELD(data_cost);
  MBSGEN_FIELD(residual_variance); MBSGEN_FIELD(seconds); MBSGEN_FIELD(residuals); MBSGEN_FIELD(degrees_of_freedom);
  MBSGEN_FIELD(iterations); MBSGEN_FIELD(evaluations); MBSGEN_FIELD(weighted); MBSGEN_FIELD(converged);
  MBSGEN_FIELD(termination); MBSGEN_FIELD(fisher_eigenvalues); MBSGEN_FIELD(fisher_sigma); MBSGEN_FIELD(fisher_directions);
  MBSGEN_FIELD(fisher_verdicts); MBSGEN_FIELD(fisher_descriptions); MBSGEN_FIELD(minima_costs); MBSGEN_FIELD(minima_values);
  MBSGEN_FIELD(profile_names); MBSGEN_FIELD(profile_values); MBSGEN_FIELD(profile_costs); MBSGEN_FIELD(profile_lower);
  MBSGEN_FIELD(profile_upper); MBSGEN_FIELD(point_sets); MBSGEN_FIELD(point_kinds); MBSGEN_FIELD(point_inputs);
  MBSGEN_FIELD(point_outputs); MBSGEN_FIELD(point_hz); MBSGEN_FIELD(residual_magnitude); MBSGEN_FIELD(residual_phase);
  MBSGEN_FIELD(point_data); MBSGEN_FIELD(point_initial); MBSGEN_FIELD(point_fitted);
#undef MBSGEN_FIELD
  m.def(
      "fit",
      [](const Model& model, const ConstVectorRef& p, const FitRequest& request) {
        const auto interrupted = [] {
          py::gil_scoped_acquire gil;
          return PyErr_CheckSignals() != 0;
        };
        try {
          return fit(model, p, request, interrupted);
        } catch (const Stopped&) {
          py::gil_scoped_acquire gil;
          throw py::error_already_set();
        }
      },
      py::arg("model"), py::arg("p"), py::arg("request"), py::call_guard<py::gil_scoped_release>());
  m.attr("has_fit") = true;
}
#endif

// The analyses of matrices, and the facade's calls timed in C++.
void bind_functions(py::module_& m) {
  auto timing = m.def_submodule("_timing", "the facade's calls timed in C++ (bench/python_bench.py)");
  timing.def(
      "linear", [](const Model& model, const Vector& p, int n) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < n; ++k) (void)model.linear(p);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      },
      py::arg("model"), py::arg("p"), py::arg("n"), released);
  timing.def(
      "frf", [](const Model& model, const Vector& p, const std::string& input, const std::string& output,
                const Vector& hz, int n) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < n; ++k) (void)model.frf(p, input, output, hz, "auto");
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      },
      py::arg("model"), py::arg("p"), py::arg("input"), py::arg("output"), py::arg("hz"), py::arg("n"), released);

  m.def("modes_of", &modes_of, py::arg("M"), py::arg("Q"), py::arg("K"), py::arg("all") = false, released);
  m.def("frf_of", &frf_of, py::arg("M"), py::arg("Q"), py::arg("K"), py::arg("B"), py::arg("C_y"), py::arg("C_v"),
        py::arg("input"), py::arg("output"), py::arg("hz"), py::arg("method") = "auto", released);
}

}  // namespace

PYBIND11_MODULE(_mbsgen, m) {
  m.doc() = "mbsgen's runtime from Python: models loaded from tapes, modes and frequency responses";
  m.attr("__version__") = mbsgen::kRuntimeVersion;

  // mbsgen::Error and its kinds. A bad value from the caller (an unknown name, a wrong size, a NaN,
  // a negative mass) is a ValueError; the rest (a damaged tape, no equilibrium, LAPACK) an Error.
  static py::exception<mbsgen::Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const mbsgen::NameError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const mbsgen::DimensionError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const mbsgen::NonFiniteError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const mbsgen::Error& e) {
      error(e.what());
    }
  });

  bind_results(m);
  bind_analyses(m);
  bind_model(m);
  bind_functions(m);
#ifdef MBSGEN_PYTHON_FIT
  bind_fit(m);
#else
  m.attr("has_fit") = false;
#endif
}

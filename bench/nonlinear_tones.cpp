// Issue 18 §2–3: where the linearization stops holding. Tones on the damped textbook models and the
// middle ear, simulated with the nonlinear equations (sine_response: from the linear steady
// state, the outputs' fundamentals fitted over the last periods), against the frequency response.
//
//   nonlinear_tones OUT_DIR
//
// writes OUT_DIR/tone_slopes.csv (model, output, Hz, amplitude, |Z/(A G) − 1|) and
// OUT_DIR/middle_ear_spl.csv (Hz, dB SPL, peak pressure, linear and simulated stapes velocity,
// their ratio in dB, distortion), and prints, per frequency, the level where the simulated
// stapes velocity departs from the linear prediction by 1 dB (found by bisection on the level).
#include <Eigen/Core>

#include <cmath>
#include <complex>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "chain3_sympy_model.hpp"
#include "jeffcott_rotor_model.hpp"
#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "mbsgen/runtime/time/simulation.hpp"
#include "middle_ear_model.hpp"

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kReferencePa = 20e-6;  // 0 dB SPL (RMS)

struct Tone {
  std::complex<double> simulated, linear;
  double distortion = 0;
};

Tone tone(const mbsgen::GeneratedModel& model, const mbsgen::OperatingPoint& op, const mbsgen::LinearModel& lin,
          Eigen::Index input, Eigen::Index output, double hz, double amplitude, const mbsgen::SineResponseOptions& o) {
  const mbsgen::SineResponse s = mbsgen::sine_response(model, op, input, hz, amplitude, o);
  mbsgen::FrequencyResponse frf(lin);
  frf.compute(Eigen::VectorXd::Constant(1, kTwoPi * hz), input, {output});
  return {s.fundamental[output], amplitude * frf.response()(0, 0), s.distortion[output]};
}

void slopes(const std::string& dir) {
  struct Case {
    const mbsgen::ModelKernels* k;
    const char *input, *output;
    double hz, largest;
    int periods;
    double rtol;
  };
  const std::vector<Case> cases = {{&jeffcott_rotor::kernels(), "F", "deflection_x", 30, 1e3, 40, 1e-11},
                                   {&chain3_sympy::kernels(), "F", "end_x", 0.5, 3, 20, 1e-11},
                                   {&middle_ear::kernels(), "P", "v_stapes", 1000, 2e4, 20, 1e-10},
                                   {&middle_ear::kernels(), "P", "v_stapes", 4000, 2e4, 40, 1e-10}};
  std::ofstream csv(dir + "/tone_slopes.csv");
  csv << "model,output,hz,amplitude,relative_error\n";
  for (const Case& c : cases) {
    mbsgen::GeneratedModel model(*c.k);
    const mbsgen::OperatingPoint op = model.operating_point();
    const mbsgen::LinearModel lin = model.linear_model(op);
    mbsgen::SineResponseOptions o;
    o.periods = c.periods;
    o.fit_periods = c.periods / 2;
    o.rtol = c.rtol;
    for (int e = 0; e <= 16; ++e) {
      const double A = c.largest * std::pow(10.0, -e / 4.0);
      try {
        const Tone t = tone(model, op, lin, model.input_index(c.input), model.output_index(c.output), c.hz, A, o);
        const double error = std::abs(t.simulated / t.linear - 1.0);
        csv << c.k->model << "," << c.output << "," << c.hz << "," << A << "," << error << "\n";
        std::printf("%-15s %6g Hz  A %-10.4g |Z/(AG) - 1| %.3e\n", c.k->model, c.hz, A, error);
      } catch (const std::exception& x) {
        std::printf("%-15s %6g Hz  A %-10.4g failed: %s\n", c.k->model, c.hz, A, x.what());
      }
    }
  }
}

void middle_ear_levels(const std::string& dir) {
  mbsgen::GeneratedModel model(middle_ear::kernels());
  const mbsgen::OperatingPoint op = model.operating_point();
  const mbsgen::LinearModel lin = model.linear_model(op);
  const Eigen::Index input = model.input_index("P"), output = model.output_index("v_stapes");
  mbsgen::SineResponseOptions o;
  o.rtol = 1e-10;
  o.periods = 20;
  o.fit_periods = 10;
  std::ofstream csv(dir + "/middle_ear_spl.csv");
  csv << "hz,spl_db,peak_pa,v_linear,v_simulated,ratio_db,distortion\n";
  for (double hz : {500.0, 1000.0, 4000.0}) {
    auto at = [&](double spl) {
      const double peak = std::sqrt(2.0) * kReferencePa * std::pow(10.0, spl / 20);
      const Tone t = tone(model, op, lin, input, output, hz, peak, o);
      return std::pair<double, Tone>(peak, t);
    };
    double below = 0, above = 0;  // levels bracketing a 1 dB departure
    for (double spl = 60; spl <= 220; spl += 10) {
      try {
        const auto [peak, t] = at(spl);
        const double ratio_db = 20 * std::log10(std::abs(t.simulated) / std::abs(t.linear));
        csv << hz << "," << spl << "," << peak << "," << std::abs(t.linear) << "," << std::abs(t.simulated) << ","
            << ratio_db << "," << t.distortion << "\n";
        std::printf("middle ear %5g Hz %4g dB SPL: v_stapes %.6e (linear %.6e), %+.3e dB, distortion %.2e\n", hz, spl,
                    std::abs(t.simulated), std::abs(t.linear), ratio_db, t.distortion);
        if (std::abs(ratio_db) < 1) below = spl;
        if (std::abs(ratio_db) >= 1 && above == 0) above = spl;
      } catch (const std::exception& x) {
        std::printf("middle ear %5g Hz %4g dB SPL: failed: %s\n", hz, spl, x.what());
        break;
      }
    }
    if (above > 0 && below > 0 && below < above) {
      for (int it = 0; it < 12; ++it) {
        const double mid = 0.5 * (below + above);
        const auto [peak, t] = at(mid);
        (std::abs(20 * std::log10(std::abs(t.simulated) / std::abs(t.linear))) < 1 ? below : above) = mid;
      }
      std::printf("middle ear %5g Hz: 1 dB departure from linear at %.2f dB SPL\n", hz, 0.5 * (below + above));
    } else {
      std::printf("middle ear %5g Hz: no 1 dB departure up to %g dB SPL\n", hz, below);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: nonlinear_tones OUT_DIR\n");
    return 2;
  }
  slopes(argv[1]);
  middle_ear_levels(argv[1]);
  return 0;
}

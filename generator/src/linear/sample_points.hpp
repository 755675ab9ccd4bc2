// The program's values at the pseudo-random points of the structure tests (internal to the
// generator: linearize.cpp's symmetry test and structural_zeros.cpp's screen). Each point's
// intermediates are evaluated once and kept for the next test at the same point: the two tests
// evaluated the same definitions at the same points (sharing them saved about 4 % of a 40-link
// chain's generation).
#pragma once

#include "mbsgen/generator/linear/linearize.hpp"
#include "mbsgen/generator/linear/structural_zeros.hpp"
#include "symbolic/point_evaluator.hpp"

#include <cstdint>
#include <memory>
#include <vector>

namespace mbsgen::detail {

/// A pseudo-random point for the structure tests of the linear matrices (linearize.cpp,
/// structural_zeros.cpp): every coordinate, rate, input and parameter uniform in [0.5, 2.5)
/// (exact rationals from the xorshift64 sequence in `state`, advanced); with at_operating_point,
/// the rates, and for a `given` operating point the coordinates, at the operating point of those
/// parameters (an equilibrium's coordinates stay free: they are known only numerically; so do
/// those of a model with closed loops, whose dependent coordinates the kernels refine).
inline GiNaC::exmap sample_point(const Equations& eq, const LinearEquations& lin, std::uint64_t& state,
                                 bool at_operating_point) {
  GiNaC::exmap values = random_point({&eq.y, &eq.yd, &eq.u, &eq.p}, state);
  if (at_operating_point) {
    GiNaC::exmap p;
    for (const auto& x : eq.p) p[x] = values[x];
    for (std::size_t k = 0; k < eq.y.size(); ++k) {
      // The loops' dependent coordinates stay free: the kernels close them by Newton's method, so
      // a zero at the operating point must hold for any of their values.
      const bool dependent = std::binary_search(eq.loops.dependent.begin(), eq.loops.dependent.end(), k);
      if (!lin.equilibrium && !dependent) values[eq.y[k]] = GiNaC::evalf(lin.y0[k].subs(p, GiNaC::subs_options::no_pattern));
      values[eq.yd[k]] = GiNaC::evalf(lin.yd0[k].subs(p, GiNaC::subs_options::no_pattern));
    }
  }
  return values;
}

/// Start of the xorshift64 sequence of the sample points (sample_point).
inline constexpr std::uint64_t kSampleSeed = 0x2545f4914f6cdd1dULL;

class SamplePoints {
 public:
  /// eq and lin must outlive this object; lin's operating point must not change meanwhile (the
  /// points at the operating point hold it).
  SamplePoints(const Equations& eq, const LinearEquations& lin)
      : eq_(eq), lin_(lin), tape_(std::make_shared<ProgramTape>(eq.program)) {}

  /// Values of `entries` at point `index` (0, 1, …) of the sequence from kSampleSeed, made by
  /// sample_point with at_operating_point. GiNaC::Digits must be PointEvaluator::kDigits.
  /// Throws where the evaluation fails, as PointEvaluator does.
  std::vector<GiNaC::numeric> evaluate(bool at_operating_point, std::size_t index,
                                       const std::vector<GiNaC::ex>& entries) {
    Sequence& s = sequences_[at_operating_point];
    while (s.points.size() <= index) {
      const GiNaC::exmap values = sample_point(eq_, lin_, s.state, at_operating_point);
      s.points.push_back(std::make_unique<PointEvaluator>(tape_, values));
    }
    return s.points[index]->evaluate(entries);
  }

 private:
  struct Sequence {
    std::uint64_t state = kSampleSeed;
    std::vector<std::unique_ptr<PointEvaluator>> points;
  };
  const Equations& eq_;
  const LinearEquations& lin_;
  std::shared_ptr<ProgramTape> tape_;  // the program compiled once for all points
  Sequence sequences_[2];  // by at_operating_point
};

/// find_structural_zeros (structural_zeros.hpp) with the values at the sample points shared with
/// earlier tests.
StructuralZeros find_structural_zeros(Equations& eq, LinearEquations& lin, SamplePoints& points);

}  // namespace mbsgen::detail

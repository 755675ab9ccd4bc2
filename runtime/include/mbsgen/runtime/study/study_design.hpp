// Designs of experiments over named parameters for parameter studies (Monte Carlo, Latin
// hypercube, Saltelli's design for Sobol' indices), and their statistics (percentiles, Sobol'
// indices with bootstrap confidence intervals).
//
// Deterministic by construction: every uniform number is a counter-based hash of (seed, stream,
// index), so a point depends only on the seed and its index, never on the order in which points
// are requested, the number of threads or MPI ranks, or the standard library's distributions
// (whose algorithms are implementation-defined and not used here). The uniforms, permutations and
// bootstrap resamples are bitwise identical on every platform; the transformation to normal and
// lognormal values goes through Boost.Math and std::exp, which are deterministic on one platform
// but may differ in the last bit between math libraries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mbsgen {

enum class Distribution { uniform, normal, lognormal };

/// The distribution of one parameter of a study.
struct ParameterDistribution {
  std::string name;  ///< the model parameter it sets
  Distribution kind = Distribution::uniform;
  /// uniform: lower bound a < upper bound b; normal: mean a, standard deviation b > 0;
  /// lognormal: median a > 0, factor b > 1 at one standard deviation (ln X ~ N(ln a, ln b)).
  /// Both finite.
  double a = 0;
  double b = 1;
};

/// Parses "NAME=uniform:LO:HI", "NAME=normal:MEAN:SD" or "NAME=lognormal:MEDIAN:FACTOR". NAME is
/// non-empty and has no '=', ':' or white space; the numbers are C-locale decimal numbers (as
/// std::from_chars reads them: no leading '+') that fill their field and are finite, and satisfy
/// the conditions of ParameterDistribution. Throws Error whose message quotes `text`, says what
/// is wrong and what is expected.
ParameterDistribution parse_distribution(const std::string& text);

/// The text parse_distribution reads back to the same distribution (numbers with 17 significant
/// digits), e.g. "k=normal:1000:50".
std::string format_distribution(const ParameterDistribution& d);

/// Throws Error naming `context` and the distribution when d's numbers are not finite or violate
/// the conditions of ParameterDistribution, or its name is empty.
void validate(const ParameterDistribution& d, const std::string& context);

/// The inverse of the cumulative distribution function of d at u, 0 < u < 1:
///   uniform:   a + (b − a) u                       (a value in [a, b])
///   normal:    a + b Φ⁻¹(u)
///   lognormal: a · exp(ln b · Φ⁻¹(u))             (= exp of the normal quantile with mean ln a,
///                                                    standard deviation ln b; exactly a at u = ½)
/// with Φ⁻¹ from Boost.Math (boost::math::quantile of the standard normal, a few ulps accurate).
/// Throws Error for u outside (0, 1) or NaN.
double quantile(const ParameterDistribution& d, double u);

enum class Design { monte_carlo, latin_hypercube, saltelli };

/// "monte-carlo" or "mc", "latin-hypercube" or "lhs", "saltelli"; throws Error quoting the text
/// and listing these otherwise.
Design parse_design(const std::string& text);

/// The canonical name parse_design reads: "monte-carlo", "latin-hypercube" or "saltelli".
const char* design_name(Design design);

/// The points of a design of experiments over d = distributions.size() parameters, each point a
/// value per parameter (in the order of the distributions), obtained as quantile(distribution_k,
/// u_k) of a point u in the open unit cube (0, 1)^d:
///  - Monte Carlo: u_ik independent uniforms, i = 0..n−1.
///  - Latin hypercube (McKay, Beckman & Conover 1979): u_ik = (π_k(i) + v_ik)/n with independent
///    uniform random permutations π_k of 0..n−1 and independent uniforms v_ik, so each of the n
///    strata [m/n, (m+1)/n) of each dimension holds exactly one point.
///  - Saltelli (Saltelli et al. 2010, Comput. Phys. Commun. 181:259): two independent Monte
///    Carlo matrices A and B (n×d) and d matrices AB_j, A with column j taken from B. The n(d+2)
///    evaluations are, in this order: 0..n−1 the rows of A, n..2n−1 the rows of B, and
///    n(2+j)..n(3+j)−1 the rows of AB_j, j = 0..d−1. A equals the Monte Carlo design of the same
///    seed. sobol_indices() reads function values in this layout.
///
/// Uniforms: u = (⌊x / 2¹²⌋ + ½) · 2⁻⁵² with x = detail::hash(seed, stream, index), a value in
/// [2⁻⁵³, 1 − 2⁻⁵³] (52 bits, so that 1 − 2⁻⁵³ is a double and u < 1 holds after rounding).
/// Permutations: Fisher–Yates shuffles with unbiased bounded integers (rejection) from the hash,
/// seeded by (seed, dimension), computed once in the constructor.
///
/// Cost: the constructor is O(n·d) time and memory for a Latin hypercube (the permutations), O(d)
/// otherwise; point() is O(d). point() is const and thread-safe.
class StudyDesign {
 public:
  /// Throws Error for n = 0, no distributions, an invalid distribution (see validate()), two
  /// distributions with the same name, or a size() that overflows std::size_t.
  StudyDesign(Design design, std::vector<ParameterDistribution> distributions, std::size_t n,
              std::uint64_t seed);

  /// The number of evaluations: n (Monte Carlo, Latin hypercube) or n(d+2) (Saltelli).
  std::size_t size() const { return size_; }
  /// d, the number of parameters.
  std::size_t dimension() const { return distributions_.size(); }
  /// n, the number of base samples.
  std::size_t base_size() const { return n_; }
  Design design() const { return design_; }
  std::uint64_t seed() const { return seed_; }
  const std::vector<ParameterDistribution>& distributions() const { return distributions_; }

  /// The parameter values of evaluation i (0 ≤ i < size()) into values[0..d−1], in the order of
  /// the distributions. Throws Error for i ≥ size().
  void point(std::size_t i, double* values) const;
  /// The same, returned (d values).
  std::vector<double> point(std::size_t i) const;
  /// The point u in (0, 1)^d behind evaluation i, before the quantiles (values[k] =
  /// quantile(distributions()[k], u[k])). Throws Error for i ≥ size().
  void unit_point(std::size_t i, double* u) const;

 private:
  double unit(std::size_t row, std::size_t k, bool from_b) const;

  Design design_;
  std::vector<ParameterDistribution> distributions_;
  std::size_t n_;
  std::uint64_t seed_;
  std::size_t size_ = 0;
  std::vector<std::size_t> permutations_;  ///< Latin hypercube: π_k(i) at k·n + i
};

/// Percentile q (0 ≤ q ≤ 100) of the finite members of `values` (non-finite values are ignored)
/// by linear interpolation between order statistics, Hyndman & Fan (1996) type 7 (numpy's
/// default): with the N sorted values x_0 ≤ … ≤ x_{N−1} and h = (N−1) q/100,
/// x_⌊h⌋ + (h − ⌊h⌋)(x_⌊h⌋+1 − x_⌊h⌋). NaN when there is no finite value. Throws Error for q
/// outside [0, 100] or NaN. O(N).
double percentile(std::vector<double> values, double q);

/// A first-order and a total Sobol' index with the bounds of their bootstrap confidence intervals.
struct SobolIndex {
  double first = 0, first_low = 0, first_high = 0;
  double total = 0, total_low = 0, total_high = 0;
};

struct SobolResult {
  std::vector<SobolIndex> indices;  ///< one per parameter, in the order of the design
  std::size_t rows_used = 0;        ///< rows r of the n kept (all their d+2 values finite)
  double variance = 0;              ///< V, the variance of f over the kept A and B rows
};

/// Sobol' indices of a function from its values f on a Saltelli design (layout of StudyDesign:
/// f.size() == n(d+2), f[i] the value at evaluation i). Rows r in 0..n−1 where any of f_A[r],
/// f_B[r], f_ABk[r] (k = 0..d−1) is not finite are dropped (a failed evaluation); with m rows
/// kept and V the sample variance (divisor 2m − 1) of the 2m values f_A, f_B:
///   first order S_j = mean_r(f_B (f_ABj − f_A)) / V     (Saltelli et al. 2010, Comput. Phys.
///                                                         Commun. 181:259)
///   total      ST_j = mean_r((f_A − f_ABj)²) / (2V)      (Jansen 1999, Comput. Phys. Commun.
///                                                         117:35)
/// where f is first centred by the mean of the kept f_A and f_B values (S_j's expectation does
/// not change; its variance no longer grows with the mean of f). Confidence intervals: percentile
/// bootstrap, n_bootstrap resamples of the m kept rows with replacement (drawn from the hash with
/// `seed`, reproducible), each giving V, S_j and ST_j again; the bounds are the percentiles
/// (1 ∓ confidence)/2 of those (type 7, as percentile(); NaN when n_bootstrap = 0; a resample
/// with V = 0 is left out). When V = 0 (f constant) the indices and bounds are NaN.
/// Cost O((n_bootstrap + 1) · m · d) time, O(n_bootstrap · d + m · d) memory.
/// Throws DimensionError when f.size() ≠ n(d+2) (naming both) or n = 0 or d = 0, Error when fewer
/// than two rows are finite, confidence is not in (0, 1) or n_bootstrap ≥ 2³².
SobolResult sobol_indices(const std::vector<double>& f, std::size_t n, std::size_t d,
                          std::size_t n_bootstrap, std::uint64_t seed, double confidence = 0.95);

namespace detail {

/// The SplitMix64 output function (Steele, Lea & Flood 2014): the generator seeded with s returns
/// splitmix64(s + k·0x9e3779b97f4a7c15) as its k-th number, k = 0, 1, …
std::uint64_t splitmix64(std::uint64_t x);

/// The counter-based hash behind every random number of this module:
/// splitmix64(splitmix64(splitmix64(seed) ^ stream) ^ index).
std::uint64_t hash(std::uint64_t seed, std::uint64_t stream, std::uint64_t index);

/// The uniform in (0, 1) of (seed, stream, index): (⌊hash / 2¹²⌋ + ½) · 2⁻⁵².
double uniform(std::uint64_t seed, std::uint64_t stream, std::uint64_t index);

}  // namespace detail

}  // namespace mbsgen

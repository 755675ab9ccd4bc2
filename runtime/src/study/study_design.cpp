#include "mbsgen/runtime/study/study_design.hpp"

#include "mbsgen/runtime/error.hpp"

#include <boost/math/distributions/normal.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

namespace mbsgen {

namespace detail {

std::uint64_t splitmix64(std::uint64_t x) {
  std::uint64_t z = x + 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t hash(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return splitmix64(splitmix64(splitmix64(seed) ^ stream) ^ index);
}

double uniform(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  // 52 bits: (2^52 − 1 + ½) is exact, so u ≤ 1 − 2^-53 < 1; with 53 bits the sum would round up
  // to 2^53 and give u = 1.
  return (static_cast<double>(hash(seed, stream, index) >> 12) + 0.5) * 0x1p-52;
}

}  // namespace detail

namespace {

// Hash streams: a tag in the high 32 bits, the dimension (or resample) in the low 32 bits.
enum Tag : std::uint64_t { tag_a = 0, tag_b = 1, tag_lhs_jitter = 2, tag_lhs_permutation = 3, tag_bootstrap = 4 };

std::uint64_t stream(Tag tag, std::size_t k) { return (static_cast<std::uint64_t>(tag) << 32) | k; }

// Unbiased integer in [0, bound) (bound ≥ 1) from consecutive hash values of (seed, s, *counter):
// reject the x < 2^64 mod bound lowest values so that every remainder is equally likely.
std::uint64_t bounded(std::uint64_t seed, std::uint64_t s, std::uint64_t* counter, std::uint64_t bound) {
  const std::uint64_t threshold = (std::uint64_t{0} - bound) % bound;  // 2^64 mod bound
  for (;;) {
    const std::uint64_t x = detail::hash(seed, s, (*counter)++);
    if (x >= threshold) return x % bound;
  }
}

std::string in_quotes(const std::string& text) { return "\"" + text + "\""; }

std::string number(double x) {
  std::ostringstream s;
  s << std::setprecision(17) << x;
  return s.str();
}

[[noreturn]] void bad_distribution(const std::string& text, const std::string& what) {
  throw Error("parse_distribution: " + in_quotes(text) + ": " + what +
              "; expected NAME=uniform:LO:HI, NAME=normal:MEAN:SD or NAME=lognormal:MEDIAN:FACTOR");
}

double parse_number(const std::string& text, const std::string& field, const char* role) {
  double x = 0;
  const char* first = field.data();
  const char* last = first + field.size();
  const auto [end, ec] = std::from_chars(first, last, x);
  if (field.empty() || ec != std::errc() || end != last || !std::isfinite(x))
    bad_distribution(text, std::string(role) + " " + in_quotes(field) + " is not a finite number");
  return x;
}

std::vector<std::string> split(const std::string& s, char separator) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = s.find(separator, begin);
    parts.push_back(s.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
    if (end == std::string::npos) return parts;
    begin = end + 1;
  }
}

}  // namespace

void validate(const ParameterDistribution& d, const std::string& context) {
  const std::string where = context + ": parameter " + in_quotes(d.name) + ": ";
  if (d.name.empty()) throw Error(context + ": a parameter distribution has an empty name");
  if (!std::isfinite(d.a) || !std::isfinite(d.b))
    throw Error(where + "non-finite numbers " + number(d.a) + ", " + number(d.b));
  switch (d.kind) {
    case Distribution::uniform:
      if (!(d.a < d.b))
        throw Error(where + "uniform needs lower < upper, got " + number(d.a) + " and " + number(d.b));
      break;
    case Distribution::normal:
      if (!(d.b > 0)) throw Error(where + "normal needs a standard deviation > 0, got " + number(d.b));
      break;
    case Distribution::lognormal:
      if (!(d.a > 0)) throw Error(where + "lognormal needs a median > 0, got " + number(d.a));
      if (!(d.b > 1)) throw Error(where + "lognormal needs a factor > 1, got " + number(d.b));
      break;
  }
}

ParameterDistribution parse_distribution(const std::string& text) {
  const std::size_t equals = text.find('=');
  if (equals == std::string::npos) bad_distribution(text, "no '='");
  ParameterDistribution d;
  d.name = text.substr(0, equals);
  if (d.name.empty()) bad_distribution(text, "empty parameter name");
  for (const char c : d.name)
    if (c == ':' || c == '=' || std::isspace(static_cast<unsigned char>(c)))
      bad_distribution(text, "parameter name " + in_quotes(d.name) + " contains '" + std::string(1, c) + "'");
  const std::vector<std::string> fields = split(text.substr(equals + 1), ':');
  if (fields[0] == "uniform")
    d.kind = Distribution::uniform;
  else if (fields[0] == "normal")
    d.kind = Distribution::normal;
  else if (fields[0] == "lognormal")
    d.kind = Distribution::lognormal;
  else
    bad_distribution(text, "unknown distribution " + in_quotes(fields[0]));
  if (fields.size() != 3)
    bad_distribution(text, fields[0] + " needs 2 numbers, got " + std::to_string(fields.size() - 1));
  const char* roles[3][2] = {{"lower bound", "upper bound"}, {"mean", "standard deviation"}, {"median", "factor"}};
  const auto r = static_cast<std::size_t>(d.kind);
  d.a = parse_number(text, fields[1], roles[r][0]);
  d.b = parse_number(text, fields[2], roles[r][1]);
  try {
    validate(d, "parse_distribution: " + in_quotes(text));
  } catch (const Error& e) {
    throw Error(std::string(e.what()) +
                "; expected NAME=uniform:LO:HI, NAME=normal:MEAN:SD or NAME=lognormal:MEDIAN:FACTOR");
  }
  return d;
}

std::string format_distribution(const ParameterDistribution& d) {
  static const char* kinds[] = {"uniform", "normal", "lognormal"};
  return d.name + "=" + kinds[static_cast<std::size_t>(d.kind)] + ":" + number(d.a) + ":" + number(d.b);
}

double quantile(const ParameterDistribution& d, double u) {
  if (!(u > 0 && u < 1)) throw Error("quantile: u = " + number(u) + " is not in (0, 1) (parameter " + in_quotes(d.name) + ")");
  if (d.kind == Distribution::uniform) return d.a + (d.b - d.a) * u;
  const double z = boost::math::quantile(boost::math::normal_distribution<double>(0.0, 1.0), u);
  if (d.kind == Distribution::normal) return d.a + d.b * z;
  return d.a * std::exp(std::log(d.b) * z);
}

Design parse_design(const std::string& text) {
  if (text == "monte-carlo" || text == "mc") return Design::monte_carlo;
  if (text == "latin-hypercube" || text == "lhs") return Design::latin_hypercube;
  if (text == "saltelli") return Design::saltelli;
  throw Error("parse_design: unknown design " + in_quotes(text) +
              "; expected monte-carlo (mc), latin-hypercube (lhs) or saltelli");
}

const char* design_name(Design design) {
  switch (design) {
    case Design::monte_carlo: return "monte-carlo";
    case Design::latin_hypercube: return "latin-hypercube";
    case Design::saltelli: return "saltelli";
  }
  return "?";
}

StudyDesign::StudyDesign(Design design, std::vector<ParameterDistribution> distributions, std::size_t n,
                         std::uint64_t seed)
    : design_(design), distributions_(std::move(distributions)), n_(n), seed_(seed) {
  const std::size_t d = distributions_.size();
  if (n == 0) throw Error("StudyDesign: n = 0 base samples; need at least 1");
  if (d == 0) throw Error("StudyDesign: no parameter distributions");
  if (d >= (std::size_t{1} << 31)) throw Error("StudyDesign: " + std::to_string(d) + " parameters is too many");
  std::set<std::string> names;
  for (const auto& dist : distributions_) {
    validate(dist, "StudyDesign");
    if (!names.insert(dist.name).second) throw Error("StudyDesign: parameter " + in_quotes(dist.name) + " appears twice");
  }
  size_ = n;
  if (design_ == Design::saltelli) {
    if (n > std::numeric_limits<std::size_t>::max() / (d + 2))
      throw Error("StudyDesign: n(d+2) overflows for n = " + std::to_string(n) + ", d = " + std::to_string(d));
    size_ = n * (d + 2);
  }
  if (design_ == Design::latin_hypercube) {
    permutations_.resize(n * d);
    for (std::size_t k = 0; k < d; ++k) {
      std::size_t* p = permutations_.data() + k * n;
      for (std::size_t i = 0; i < n; ++i) p[i] = i;
      std::uint64_t counter = 0;
      for (std::size_t i = n - 1; i > 0; --i)
        std::swap(p[i], p[bounded(seed_, stream(tag_lhs_permutation, k), &counter, i + 1)]);
    }
  }
}

double StudyDesign::unit(std::size_t row, std::size_t k, bool from_b) const {
  if (design_ != Design::latin_hypercube) return detail::uniform(seed_, stream(from_b ? tag_b : tag_a, k), row);
  const double v = detail::uniform(seed_, stream(tag_lhs_jitter, k), row);
  const double u = (static_cast<double>(permutations_[k * n_ + row]) + v) / static_cast<double>(n_);
  // (n − 1 + v)/n can round to 1; the stratum's largest double below 1 keeps u in (0, 1).
  return std::min(u, 1.0 - 0x1p-53);
}

void StudyDesign::unit_point(std::size_t i, double* u) const {
  if (i >= size_)
    throw Error("StudyDesign::point: index " + std::to_string(i) + " is not below size() = " + std::to_string(size_));
  const std::size_t block = i / n_, row = i % n_;
  for (std::size_t k = 0; k < distributions_.size(); ++k) {
    // Saltelli: block 0 is A, 1 is B, 2 + j is AB_j (A with column j from B).
    const bool from_b = design_ == Design::saltelli && (block == 1 || (block >= 2 && block - 2 == k));
    u[k] = unit(row, k, from_b);
  }
}

void StudyDesign::point(std::size_t i, double* values) const {
  unit_point(i, values);
  for (std::size_t k = 0; k < distributions_.size(); ++k) values[k] = quantile(distributions_[k], values[k]);
}

std::vector<double> StudyDesign::point(std::size_t i) const {
  std::vector<double> values(distributions_.size());
  point(i, values.data());
  return values;
}

double percentile(std::vector<double> values, double q) {
  if (!(q >= 0 && q <= 100)) throw Error("percentile: q = " + number(q) + " is not in [0, 100]");
  values.erase(std::remove_if(values.begin(), values.end(), [](double x) { return !std::isfinite(x); }),
               values.end());
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double h = static_cast<double>(values.size() - 1) * (q / 100);
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const auto lo_it = values.begin() + static_cast<std::ptrdiff_t>(lo);
  std::nth_element(values.begin(), lo_it, values.end());
  const double x_lo = *lo_it;
  const double t = h - static_cast<double>(lo);
  if (t == 0 || lo + 1 >= values.size()) return x_lo;
  const double x_hi = *std::min_element(lo_it + 1, values.end());
  return x_lo + t * (x_hi - x_lo);
}

namespace {

// The kept rows of a Saltelli layout, centred: a[r], b[r], ab[j·m + r].
struct SaltelliRows {
  std::size_t m = 0, d = 0;
  std::vector<double> a, b, ab;
};

struct Estimate {
  double variance = 0;
  std::vector<double> first, total;
};

// V, S_j and ST_j over the rows rows[0..m−1] of s (indices into the kept rows, repeats allowed).
// Centring by the sample's own mean, then the estimators of sobol_indices().
Estimate estimate(const SaltelliRows& s, const std::vector<std::size_t>& rows) {
  const std::size_t m = rows.size();
  double mean = 0;
  for (const std::size_t r : rows) mean += s.a[r] + s.b[r];
  mean /= static_cast<double>(2 * m);
  double ss = 0;
  for (const std::size_t r : rows) ss += (s.a[r] - mean) * (s.a[r] - mean) + (s.b[r] - mean) * (s.b[r] - mean);
  Estimate e;
  e.variance = ss / static_cast<double>(2 * m - 1);
  e.first.assign(s.d, std::numeric_limits<double>::quiet_NaN());
  e.total = e.first;
  if (!(e.variance > 0)) return e;
  for (std::size_t j = 0; j < s.d; ++j) {
    const double* ab = s.ab.data() + j * s.m;
    double first = 0, total = 0;
    for (const std::size_t r : rows) {
      const double diff = ab[r] - s.a[r];
      first += (s.b[r] - mean) * diff;
      total += diff * diff;
    }
    e.first[j] = first / static_cast<double>(m) / e.variance;
    e.total[j] = total / static_cast<double>(m) / (2 * e.variance);
  }
  return e;
}

}  // namespace

SobolResult sobol_indices(const std::vector<double>& f, std::size_t n, std::size_t d, std::size_t n_bootstrap,
                          std::uint64_t seed, double confidence) {
  if (n == 0 || d == 0 || f.size() != n * (d + 2))
    throw DimensionError("sobol_indices: f has " + std::to_string(f.size()) + " values; a Saltelli design with n = " +
                         std::to_string(n) + ", d = " + std::to_string(d) + " has n(d+2) = " +
                         std::to_string(n * (d + 2)) + " (n and d must be ≥ 1)");
  if (!(confidence > 0 && confidence < 1))
    throw Error("sobol_indices: confidence = " + number(confidence) + " is not in (0, 1)");
  if (n_bootstrap >= (std::size_t{1} << 32))
    throw Error("sobol_indices: n_bootstrap = " + std::to_string(n_bootstrap) + " is not below 2^32");
  SaltelliRows s;
  s.d = d;
  std::vector<std::size_t> kept;
  for (std::size_t r = 0; r < n; ++r) {
    bool finite = std::isfinite(f[r]) && std::isfinite(f[n + r]);
    for (std::size_t j = 0; j < d && finite; ++j) finite = std::isfinite(f[n * (2 + j) + r]);
    if (finite) kept.push_back(r);
  }
  s.m = kept.size();
  if (s.m < 2)
    throw Error("sobol_indices: only " + std::to_string(s.m) + " of " + std::to_string(n) +
                " rows have finite values at A, B and every AB_j; need at least 2");
  s.ab.resize(s.m * d);
  for (const std::size_t r : kept) s.a.push_back(f[r]), s.b.push_back(f[n + r]);
  for (std::size_t j = 0; j < d; ++j)
    for (std::size_t t = 0; t < s.m; ++t) s.ab[j * s.m + t] = f[n * (2 + j) + kept[t]];

  std::vector<std::size_t> rows(s.m);
  for (std::size_t t = 0; t < s.m; ++t) rows[t] = t;
  const Estimate full = estimate(s, rows);

  // Bootstrap: resample b draws its m rows from stream (bootstrap, b).
  std::vector<std::vector<double>> first(d), total(d);
  for (std::size_t b = 0; b < n_bootstrap; ++b) {
    std::uint64_t counter = 0;
    for (std::size_t t = 0; t < s.m; ++t) rows[t] = bounded(seed, stream(tag_bootstrap, b), &counter, s.m);
    const Estimate e = estimate(s, rows);
    for (std::size_t j = 0; j < d; ++j) first[j].push_back(e.first[j]), total[j].push_back(e.total[j]);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double q_low = 50 * (1 - confidence), q_high = 50 * (1 + confidence);
  SobolResult result;
  result.rows_used = s.m;
  result.variance = full.variance;
  for (std::size_t j = 0; j < d; ++j) {
    SobolIndex x;
    x.first = full.first[j];
    x.total = full.total[j];
    const bool ci = n_bootstrap > 0 && full.variance > 0;
    x.first_low = ci ? percentile(first[j], q_low) : nan;
    x.first_high = ci ? percentile(first[j], q_high) : nan;
    x.total_low = ci ? percentile(total[j], q_low) : nan;
    x.total_high = ci ? percentile(total[j], q_high) : nan;
    result.indices.push_back(x);
  }
  return result;
}

}  // namespace mbsgen

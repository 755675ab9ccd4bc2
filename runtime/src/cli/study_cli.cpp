#include "cli/study_cli.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <limits>
#include <sstream>
#include <thread>

#include "cli/bode_plot.hpp"
#include "cli/cli_files.hpp"
#include "cli/cli_output.hpp"
#include "cli/study_cluster.hpp"
#include "mbsgen/runtime/study/study.hpp"
#include "mbsgen/runtime/study/study_design.hpp"

namespace mbsgen::cli {

namespace {

// Files a study writes begin with this (write_all_or_nothing's marker).
constexpr const char* kMarker = "mbsgen study";
const std::vector<double> kPercentiles = {5, 25, 50, 75, 95};


bool is_json(const std::string& path) {
  return path.size() >= 5 && path.compare(path.size() - 5, 5, ".json") == 0;
}

std::string json_array(const std::vector<double>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + num(v[i], true);
  return s + "]";
}

struct Study {
  const ModelKernels& k;
  const StudyOptions& o;
  StudyDesign design;
  StudyQuantities q;
  StudyResults results;
  double wall_seconds = 0;
  int threads = 1;
  std::string where;  // "2 threads × one process"
};

std::string banner(const Study& s) {
  return std::string("# ") + kMarker + ": model " + csv_field(s.k.model) + " (scene " + csv_field(s.k.scene) + "), " +
         design_name(s.design.design()) + " design, seed " + std::to_string(s.design.seed()) + ", " +
         std::to_string(s.design.size()) + " evaluations\n";
}

std::string samples_csv(const Study& s) {
  std::ostringstream c;
  c << banner(s) << "index";
  for (const auto& d : s.design.distributions()) c << "," << csv_field(d.name);
  for (const auto& n : s.results.scalar_names) c << "," << n;
  c << ",status\n";
  std::size_t f = 0;
  const std::size_t ns = s.results.scalar_names.size();
  std::vector<double> values(s.design.dimension());
  for (std::size_t i = 0; i < s.results.count; ++i) {
    s.design.point(i, values.data());
    c << i;
    for (double v : values) c << "," << num(v, false);
    for (std::size_t j = 0; j < ns; ++j) c << "," << num(s.results.scalars[i * ns + j], false);
    const bool failed = f < s.results.failures.size() && s.results.failures[f].index == i;
    c << "," << (failed ? csv_field(s.results.failures[f++].message) : std::string("ok")) << "\n";
  }
  return c.str();
}

std::string bands_text(const Study& s, const std::vector<std::vector<double>>& bands, bool json) {
  std::ostringstream c;
  if (json) {
    c << "{\"generator\": \"" << kMarker << "\", \"model\": " << json_string(s.k.model) << ", \"input\": "
      << json_string(s.q.input) << ", \"output\": " << json_string(s.q.output) << ", \"evaluations\": "
      << s.results.count << ", \"failures\": " << s.results.failures.size() << ",\n \"percentiles\": "
      << json_array(kPercentiles) << ",\n \"frequency_hz\": " << json_array(s.q.sweep_hz) << ",\n \"bands\": {";
    for (std::size_t k = 0; k < bands.size(); ++k)
      c << (k ? ",\n  " : "\n  ") << "\"p" << static_cast<int>(kPercentiles[k]) << "\": " << json_array(bands[k]);
    c << "}}\n";
    return c.str();
  }
  c << banner(s) << "# " << csv_field("|" + s.q.output + " / " + s.q.input + "|")
    << ": percentiles over the evaluations that did not fail\n";
  c << "frequency_hz,p5,p25,p50,p75,p95\n";
  for (std::size_t i = 0; i < s.q.sweep_hz.size(); ++i) {
    c << num(s.q.sweep_hz[i], false);
    for (const auto& b : bands) c << "," << num(b[i], false);
    c << "\n";
  }
  return c.str();
}

std::string sobol_text(const Study& s, const std::vector<SobolResult>& sobol, bool json) {
  std::ostringstream c;
  const auto& dists = s.design.distributions();
  if (json) c << "{\"generator\": \"" << kMarker << "\", \"model\": " << json_string(s.k.model) << ", \"base_samples\": "
              << s.design.base_size() << ", \"bootstrap\": " << s.o.bootstrap << ", \"confidence\": 0.95, \"quantities\": [";
  else c << banner(s) << "quantity,parameter,first,first_low,first_high,total,total_low,total_high,rows_used\n";
  for (std::size_t q = 0; q < sobol.size(); ++q) {
    if (json) c << (q ? "," : "") << "\n {\"quantity\": " << json_string(s.results.scalar_names[q]) << ", \"rows_used\": "
                << sobol[q].rows_used << ", \"variance\": " << num(sobol[q].variance, true) << ", \"indices\": [";
    for (std::size_t j = 0; j < dists.size(); ++j) {
      const SobolIndex& x = sobol[q].indices[j];
      if (json)
        c << (j ? ", " : "") << "\n  {\"parameter\": " << json_string(dists[j].name) << ", \"first\": [" << num(x.first, true)
          << ", " << num(x.first_low, true) << ", " << num(x.first_high, true) << "], \"total\": [" << num(x.total, true)
          << ", " << num(x.total_low, true) << ", " << num(x.total_high, true) << "]}";
      else
        c << s.results.scalar_names[q] << "," << csv_field(dists[j].name) << "," << num(x.first, false) << ","
          << num(x.first_low, false) << "," << num(x.first_high, false) << "," << num(x.total, false) << ","
          << num(x.total_low, false) << "," << num(x.total_high, false) << "," << sobol[q].rows_used << "\n";
    }
    if (json) c << "]}";
  }
  if (json) c << "\n]}\n";
  return c.str();
}

// The Sobol' indices of each scalar quantity (Saltelli designs).
std::vector<SobolResult> sobol_of(const Study& s) {
  std::vector<SobolResult> out;
  const std::size_t ns = s.results.scalar_names.size(), n = s.design.base_size(), d = s.design.dimension();
  for (std::size_t q = 0; q < ns; ++q) {
    std::vector<double> f(s.results.count);
    for (std::size_t i = 0; i < s.results.count; ++i) f[i] = s.results.scalars[i * ns + q];
    try {
      out.push_back(sobol_indices(f, n, d, static_cast<std::size_t>(s.o.bootstrap), s.design.seed() ^ 0x50b01ULL));
    } catch (const Error&) {  // fewer than 2 rows without a failure: no indices (NaN), the failures say why
      const double nan = std::numeric_limits<double>::quiet_NaN();
      out.push_back({std::vector<SobolIndex>(d, SobolIndex{nan, nan, nan, nan, nan, nan}), 0, nan});
    }
  }
  return out;
}

// A table cell: left-aligned in w characters, one space after.
std::string cell(const std::string& s, std::size_t w) { return s.size() >= w ? s + " " : s + std::string(w - s.size() + 1, ' '); }

void write_summary(std::ostream& out, const Study& s, const std::vector<SobolResult>& sobol) {
  const auto& r = s.results;
  const std::size_t ns = r.scalar_names.size();
  const double per = r.count ? 1e6 / static_cast<double>(r.count) : 0;
  out << "study of model " << s.k.model << " (scene " << s.k.scene << "): " << design_name(s.design.design())
      << " design, " << r.count << " evaluations, seed " << s.design.seed() << ", " << s.where << "\n";
  out << "failures: " << r.failures.size() << "\n";
  out << "time: " << fixed(s.wall_seconds, "%.3f") << " s wall; per evaluation, thread time: kernels "
      << fixed(r.seconds_kernels * per, "%.1f") << " us, modes " << fixed(r.seconds_modes * per, "%.1f")
      << " us, response " << fixed(r.seconds_response * per, "%.1f") << " us\n";
  if (ns) out << "\n" << cell("quantity", 20) << cell("mean", 14) << cell("sd", 14) << cell("p5", 14) << cell("p50", 14) << "p95\n";
  std::vector<std::string> undefined;
  for (std::size_t j = 0; j < ns; ++j) {
    std::vector<double> v;
    double sum = 0, sum2 = 0;
    for (std::size_t i = 0; i < r.count; ++i)
      if (std::isfinite(r.scalars[i * ns + j])) v.push_back(r.scalars[i * ns + j]), sum += v.back();
    const double mean = v.empty() ? NAN : sum / static_cast<double>(v.size());
    for (double x : v) sum2 += (x - mean) * (x - mean);
    const double sd = v.size() > 1 ? std::sqrt(sum2 / static_cast<double>(v.size() - 1)) : NAN;
    out << cell(r.scalar_names[j], 20) << cell(fixed(mean, "%.6g"), 14) << cell(fixed(sd, "%.6g"), 14)
        << cell(fixed(percentile(v, 5), "%.6g"), 14) << cell(fixed(percentile(v, 50), "%.6g"), 14)
        << fixed(percentile(v, 95), "%.6g") << "\n";
    if (v.size() < 2) undefined.push_back(r.scalar_names[j] + " (" + std::to_string(v.size()) + " finite value" + (v.size() == 1 ? ")" : "s)"));
  }
  if (!undefined.empty()) {
    out << "# '-': a statistic with too few finite values: ";
    for (std::size_t i = 0; i < undefined.size(); ++i) out << (i ? ", " : "") << undefined[i];
    out << " (failed evaluations, listed on standard error, give no value)\n";
  }
  if (sobol.empty()) return;
  out << "\nSobol' indices (" << s.o.bootstrap << " bootstrap resamples, 95 % intervals):\n"
      << cell("quantity", 20) << cell("parameter", 20) << cell("first order", 28) << "total\n";
  for (std::size_t q = 0; q < sobol.size(); ++q)
    for (std::size_t j = 0; j < sobol[q].indices.size(); ++j) {
      const SobolIndex& x = sobol[q].indices[j];
      const std::string first = fixed(x.first, "%.4f") + " [" + fixed(x.first_low, "%.4f") + ", " +
                                fixed(x.first_high, "%.4f") + "]";
      const std::string total = fixed(x.total, "%.4f") + " [" + fixed(x.total_low, "%.4f") + ", " +
                                fixed(x.total_high, "%.4f") + "]";
      out << cell(r.scalar_names[q], 20) << cell(s.design.distributions()[j].name, 20) << cell(first, 28) << total << "\n";
    }
}

// The failures on the error stream: how many, and the first ten with their parameter values.
void report_failures(std::ostream& err, const Study& s) {
  const auto& f = s.results.failures;
  if (f.empty()) return;
  err << "study: " << f.size() << " of " << s.results.count << " evaluations failed";
  err << (f.size() > 10 ? "; the first 10:\n" : ":\n");
  for (std::size_t i = 0; i < f.size() && i < 10; ++i) {
    err << "  #" << f[i].index << " (";
    for (std::size_t j = 0; j < f[i].parameters.size(); ++j)
      err << (j ? ", " : "") << s.design.distributions()[j].name << " = " << num(f[i].parameters[j], false);
    err << "): " << f[i].message << "\n";
  }
  if (!s.o.samples_file.empty()) err << "  (all of them in " << s.o.samples_file << ", column status)\n";
}

void write_outputs(const Study& s, const std::vector<SobolResult>& sobol, std::ostream& err) {
  std::vector<OutputFile> files;
  if (!s.o.samples_file.empty()) files.push_back({s.o.samples_file, samples_csv(s)});
  std::vector<std::vector<double>> bands;
  if (!s.q.sweep_hz.empty()) bands = percentile_bands(s.results, s.q.sweep_hz.size(), kPercentiles);
  if (!s.o.bands_file.empty()) files.push_back({s.o.bands_file, bands_text(s, bands, is_json(s.o.bands_file))});
  if (!s.o.sobol_file.empty()) files.push_back({s.o.sobol_file, sobol_text(s, sobol, is_json(s.o.sobol_file))});
  write_all_or_nothing(files, kMarker, "study");
  for (const auto& f : files) err << "wrote " << f.path.string() << "\n";
  if (!s.o.plot.empty()) {
    BandPlot plot;
    plot.title = std::string(s.k.model) + ": " + s.q.output + " / " + s.q.input + ", " + std::to_string(s.results.count) +
                 " evaluations (" + design_name(s.design.design()) + ")";
    plot.amplitude_label = "|" + s.q.output + " / " + s.q.input + "|";
    write_band_plot(s.o.plot, s.q.sweep_hz, bands, plot);
    err << "wrote " << s.o.plot << "\n";
  }
}

}  // namespace

CLI::App* add_study(CLI::App& app, StudyOptions& o) {
  CLI::App* s = app.add_subcommand("study", "a parameter study: Monte Carlo, Latin hypercube or Sobol' indices (Saltelli)");
  s->add_option("--set", o.set, "set a parameter, NAME=VALUE (SI units); repeatable");
  s->add_option("--parameter", o.parameters,
                "a varied parameter: NAME=uniform:LO:HI, NAME=normal:MEAN:SD or NAME=lognormal:MEDIAN:FACTOR; repeatable")
      ->required();
  s->add_option("--design", o.design, "monte-carlo (mc), latin-hypercube (lhs) or saltelli (Sobol' indices)");
  s->add_option("--samples", o.samples, "evaluations (Saltelli: base samples N, N·(d+2) evaluations)")
      ->required()
      ->check(CLI::Range(1L, 100000000L));
  s->add_option("--seed", o.seed, "seed of the design (the same seed gives the same numbers on any number of processes)")
      ->check(seed_value());
  s->add_option("--modes", o.modes, "record the lowest K modes' natural frequencies and damping ratios")
      ->check(CLI::Range(0, 100000));
  s->add_option("--input", o.input, "input of the response");
  s->add_option("--output", o.output, "output of the response");
  s->add_option("--from", o.from, "first frequency of the band [Hz] (default: the scene's)")->check(frequency_hz());
  s->add_option("--to", o.to, "last frequency of the band [Hz]")->check(frequency_hz());
  s->add_option("--points", o.points, "frequencies of the band (0: none)")->check(CLI::Range(0L, 100000L));
  s->add_option("--spacing", o.spacing, "frequency spacing")->check(CLI::IsMember({"log", "linear"}));
  s->add_option("--at", o.at_hz, "response levels (dB) at these frequencies [Hz], for statistics and Sobol' indices")
      ->delimiter(',')
      ->check(frequency_hz());
  s->add_option("--method", o.method, "frequency-response method");
  s->add_option("--threads", o.threads, "threads per process (default: the cores, shared by the processes)")
      ->check(CLI::Range(0, 4096));
  s->add_option("--bootstrap", o.bootstrap, "bootstrap resamples of the Sobol' intervals, 10 to 100000")
      ->check(CLI::Range(10L, 100000L));  // fewer give no 2.5 % and 97.5 % percentiles (0 printed [nan, nan])
  s->add_option("--write-samples", o.samples_file, "write every evaluation (parameters, quantities, status) as CSV");
  s->add_option("--bands", o.bands_file, "write the 5/25/50/75/95 % bands of the response (FILE.csv or FILE.json)");
  s->add_option("--sobol", o.sobol_file, "write the Sobol' indices (FILE.csv or FILE.json; saltelli design)");
  s->add_option("--plot", o.plot, "plot the response's bands (FILE.svg or FILE.png)");
  s->add_option("--format", o.format, "summary format")->check(CLI::IsMember({"table"}));
  return s;
}

namespace {

// The quantities asked for, checked against each other before any work.
StudyQuantities quantities(const ModelKernels& k, const StudyOptions& o) {
  StudyQuantities q;
  q.modes = o.modes;
  q.input = o.input, q.output = o.output, q.method = o.method;
  q.at_hz = o.at_hz;
  const bool response = !o.input.empty() || !o.output.empty();
  if (response && (o.input.empty() || o.output.empty()))
    throw NameError("study: a response needs both --input and --output");
  if (!response && !o.at_hz.empty()) throw NameError("study: --at needs --input and --output");
  if (response && o.points > 0) {
    double from = o.from, to = o.to;
    if (from == 0 && to == 0) from = k.default_from_hz, to = k.default_to_hz;
    if (from == 0 && to == 0)
      throw NameError("study: the band needs --from and --to (the scene gives no frequency range), or --points 0");
    const std::string problem = sweep_problem(from, to, o.points, o.spacing == "log");
    if (!problem.empty()) throw NameError("study: " + problem);
    const Eigen::VectorXd hz = sweep_hz(from, to, o.points, o.spacing == "log");
    q.sweep_hz.assign(hz.data(), hz.data() + hz.size());
  }
  if (q.modes == 0 && !response) throw NameError("study: nothing to record: ask for --modes K, or a response (--input, --output)");
  return q;
}

}  // namespace

namespace {

// --parameter: the library's parse, its refusal a usage error (exit 2) naming the option instead
// of the function ("parse_distribution: ..." was exit 1).
ParameterDistribution distribution_option(const std::string& text) {
  try {
    return parse_distribution(text);
  } catch (const Error& e) {
    std::string what = e.what();
    const std::string prefix = "parse_distribution: ";
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    throw NameError("--parameter " + what);
  }
}

// Everything before the evaluations: the model's parameters, the design, the quantities, and the
// checks that can fail (on rank 0, the files it will write). Throws what a bad option gives.
std::unique_ptr<Study> prepare(const ModelKernels& k, const StudyOptions& o, GeneratedModel& model,
                               const Cluster& cluster) {
  for (const auto& a : o.set) model.set(a);
  std::vector<ParameterDistribution> dists;
  for (const auto& p : o.parameters) dists.push_back(distribution_option(p));
  const Design design_kind = parse_design(o.design);
  auto s = std::make_unique<Study>(Study{k, o, StudyDesign(design_kind, dists, static_cast<std::size_t>(o.samples), o.seed),
                                         quantities(k, o), {}, 0, 1, ""});
  if (design_kind == Design::saltelli && scalar_names(s->q).empty())
    throw NameError("study: Sobol' indices (saltelli) need scalar quantities: --modes K or --at FREQUENCIES");
  if (design_kind != Design::saltelli && !o.sobol_file.empty())
    throw NameError("study: --sobol needs the saltelli design");
  if ((!o.bands_file.empty() || !o.plot.empty()) && s->q.sweep_hz.empty())
    throw NameError("study: --bands and --plot need a response band (--input, --output and --points > 0)");
  const std::string ext = std::filesystem::path(o.plot).extension().string();
  if (!o.plot.empty() && ext != ".svg" && ext != ".png")
    throw NameError("study: --plot " + o.plot + ": the file name must end in .svg or .png");
  // One gather (MPI_Gatherv) carries at most 2^31 − 1 values of each kind.
  const std::size_t per_evaluation = std::max(s->q.sweep_hz.size(), scalar_names(s->q).size());
  const std::size_t values = s->design.size() * per_evaluation;
  if (cluster.size() > 1 && values > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw Error("study: " + std::to_string(s->design.size()) + " evaluations of " +
                std::to_string(per_evaluation) + " values are more than one MPI gather carries "
                "(2^31 - 1 values): run fewer samples per study, or fewer --points");
  if (cluster.rank() == 0) {  // the files, before the work: not after hours of it
    std::vector<std::filesystem::path> data;
    for (const auto* f : {&o.samples_file, &o.bands_file, &o.sobol_file, &o.plot})
      if (!f->empty()) refuse_special_file(*f, "study");
    for (const auto* f : {&o.samples_file, &o.bands_file, &o.sobol_file})
      if (!f->empty()) data.push_back(*f);
    refuse_foreign_files(data, kMarker, "study");
  }
  const int hw = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  s->threads = o.threads > 0 ? o.threads : std::max(1, hw / cluster.local_size());
  s->where = std::to_string(s->threads) + (s->threads == 1 ? " thread" : " threads") + " per process, " +
             cluster.description();
  return s;
}

}  // namespace

int run_study(const ModelKernels& k, StudyOptions o, std::ostream& out, std::ostream& err) {
  Cluster cluster;
  GeneratedModel model(k);
  std::unique_ptr<Study> study;
  std::exception_ptr problem;
  // Every rank checks the same options, and all stop together when one of them cannot go on
  // (an exception on one rank alone must not leave the others waiting in a collective call).
  try {
    study = prepare(k, o, model, cluster);
  } catch (...) {
    problem = std::current_exception();
  }
  if (cluster.any(problem != nullptr)) {
    if (problem) std::rethrow_exception(problem);
    return 1;
  }
  Study& s = *study;
  const std::size_t total = s.design.size();
  const std::size_t begin = total * static_cast<std::size_t>(cluster.rank()) / static_cast<std::size_t>(cluster.size());
  const std::size_t end = total * static_cast<std::size_t>(cluster.rank() + 1) / static_cast<std::size_t>(cluster.size());
  const bool progress = cluster.rank() == 0 && total >= 200 && ::isatty(STDERR_FILENO);
  const auto t0 = std::chrono::steady_clock::now();
  StudyResults local;
  try {
    local = evaluate(model, s.design, s.q, begin, end - begin, s.threads, progress ? [&](std::size_t done) {
      err << "\rstudy: " << done * static_cast<std::size_t>(cluster.size()) << " / " << total << std::flush;
    } : std::function<void(std::size_t)>());
  } catch (...) {
    problem = std::current_exception();
  }
  if (progress) err << "\r                                        \r";
  if (cluster.any(problem != nullptr)) {  // every rank stops, before the gather
    if (problem) std::rethrow_exception(problem);
    return 1;
  }
  s.results = cluster.gather(std::move(local));
  s.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (cluster.rank() != 0) return 0;
  const std::vector<SobolResult> sobol = s.design.design() == Design::saltelli ? sobol_of(s) : std::vector<SobolResult>{};
  write_summary(out, s, sobol);
  report_failures(err, s);
  write_outputs(s, sobol, err);
  return s.results.failures.size() == s.results.count ? 1 : 0;
}

}  // namespace mbsgen::cli

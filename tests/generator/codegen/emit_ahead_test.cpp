// Kernels emitted ahead in a child process (emit_ahead, emit.hpp; issue 17 §1) are the code
// emit() alone writes, byte for byte; a kernel the child made from another derivation or with
// other options is not taken. And the child process helper itself (child_task.hpp).
#include "mbsgen/generator/codegen/emit.hpp"
#include "mbsgen/generator/model/parametric_chains.hpp"
#include "mbsgen/generator/model/scene.hpp"
#include "mbsgen/generator/model/yaml_reader.hpp"

#include "codegen/child_task.hpp"

#include <gtest/gtest.h>

#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <fstream>
#include <sstream>

#include <chrono>
#include <stdexcept>
#include <string>

namespace mbsgen {
namespace {

const std::string kSourceDir = MBSGEN_SOURCE_DIR;

// emit_ahead starts no child on one processor.
bool two_processors() {
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  return ::sched_getaffinity(0, sizeof cpus, &cpus) == 0 && CPU_COUNT(&cpus) >= 2;
}

std::string file_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  std::size_t at = 0, n = 0;
  while ((at = text.find(from, at)) != std::string::npos) {
    text.replace(at, from.size(), to);
    at += to.size();
    ++n;
  }
  EXPECT_GT(n, 0u) << from;
  return text;
}

struct Emitted {
  GeneratedCode code;
  std::size_t taken = 0;
};

// model (pruned) derived, linearized and emitted, with the kernels that need only the derivation
// emitted ahead with ahead_options when `ahead`.
Emitted generate(const Model& model, const EmitOptions& options, bool ahead, const EmitOptions* ahead_options = nullptr) {
  KernelsAhead early;
  if (ahead) early = emit_ahead(model, ahead_options ? *ahead_options : options);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  Emitted e;
  e.code = emit(model, eq, lin, options, ahead ? &early : nullptr);
  e.taken = early.taken();
  return e;
}

void expect_same(const GeneratedCode& a, const GeneratedCode& b, const std::string& what) {
  EXPECT_EQ(a.id, b.id) << what;
  EXPECT_TRUE(a.header == b.header) << what << ": header";
  EXPECT_TRUE(a.source == b.source) << what << ": source";
  EXPECT_TRUE(a.manifest == b.manifest) << what << ": manifest";
  ASSERT_EQ(a.parts.size(), b.parts.size()) << what;
  for (std::size_t k = 0; k < a.parts.size(); ++k) EXPECT_TRUE(a.parts[k] == b.parts[k]) << what << ": part " << k + 1;
  ASSERT_EQ(a.kernels.size(), b.kernels.size()) << what;
  for (std::size_t k = 0; k < a.kernels.size(); ++k) {
    EXPECT_EQ(a.kernels[k].name, b.kernels[k].name) << what;
    EXPECT_EQ(a.kernels[k].signature, b.kernels[k].signature) << what;
    EXPECT_EQ(a.kernels[k].operations, b.kernels[k].operations) << what;
  }
}

TEST(EmitAhead, SameCodeAsEmitAloneAndTakenFromTheChild) {
  if (!two_processors()) GTEST_SKIP() << "one processor: emit_ahead starts no child";
  struct Case {
    std::string what;
    Model model;
    EmitOptions options;
  };
  EmitOptions parts;  // kernels cut into parts and spread over files: the parts travel too
  parts.chunk_operations = 300;
  parts.parts = 3;
  EmitOptions dynamics;
  dynamics.dynamics = true;
  const Model rotor = read_model_file(kSourceDir + "/models/textbook/rotor_disk.yaml");
  const std::vector<Case> cases = {
      {"4-link spatial chain, parts", spatial_chain(4), parts},
      {"PUMA 560, dynamics", read_model_file(kSourceDir + "/models/robots/puma560.yaml"), dynamics},
      {"middle ear", read_model_file(kSourceDir + "/models/middle_ear/middle_ear.yaml"), EmitOptions{}},
      {"rotor, scene " + rotor.scenes().back().name, apply_scene(rotor, rotor.scenes().back().name),
       [&] {
         EmitOptions o;
         o.scene = rotor.scenes().back().name;
         return o;
       }()},
  };
  for (const Case& c : cases) {
    const Emitted alone = generate(c.model, c.options, false);
    const Emitted ahead = generate(c.model, c.options, true);
    expect_same(alone.code, ahead.code, c.what);
    // Every kernel that needs only the derivation came from the child.
    std::size_t derivation_only = 0;
    for (const KernelInfo& k : alone.code.kernels)
      derivation_only += k.name == "mass_matrix" || k.name == "residual" || k.name == "dynamics" || k.name == "bodies";
    EXPECT_EQ(ahead.taken, derivation_only) << c.what;
    if (c.options.scene.empty()) {
      EXPECT_GE(derivation_only, c.options.dynamics ? 4u : 3u) << c.what;
    }
  }
}

TEST(EmitAhead, NothingTakenFromAModelWithClosedLoopsOrRollingConstraints) {
  for (const std::string file : {"/models/linkages/four_bar.yaml", "/models/rolling/rolling_disk.yaml"}) {
    const Model model = read_model_file(kSourceDir + file);
    const Emitted alone = generate(model, EmitOptions{}, false);
    const Emitted ahead = generate(model, EmitOptions{}, true);
    expect_same(alone.code, ahead.code, file);
    EXPECT_EQ(ahead.taken, 0u) << file;
  }
}

// The child's kernels of model `ahead_of`, asked for by `model`'s emit(): none taken, and the code
// is emit()'s alone.
void expect_none_taken(const Model& ahead_of, const EmitOptions& ahead_options, const Model& model,
                       const EmitOptions& options, const std::string& what) {
  KernelsAhead early = emit_ahead(ahead_of, ahead_options);
  Equations eq = derive(model);
  LinearEquations lin = linearize(eq);
  const GeneratedCode with_other = emit(model, eq, lin, options, &early);
  EXPECT_EQ(early.taken(), 0u) << what;
  expect_same(generate(model, options, false).code, with_other, what);
}

TEST(EmitAhead, KernelsOfAnotherDerivationOrOtherOptionsAreNotTaken) {
  EmitOptions options;
  options.id = "chain";
  const std::string chain3 = file_text(kSourceDir + "/models/textbook/chain3_sympy.yaml");
  const Model model = read_model_string(chain3, "chain3_sympy.yaml");
  // The same model ahead: taken (the control of the cases below).
  if (two_processors()) {
    EXPECT_EQ(generate(model, options, true).taken, 3u);
  }
  // Another chain under the same id, kernels of the same names.
  expect_none_taken(spatial_chain(3), options, model, options, "the spatial chain's kernels for chain3's");
  // The same model but for a coordinate's name (which orders the printed code).
  expect_none_taken(read_model_string(replaced(chain3, "q3", "z3"), "renamed.yaml"), options, model, options,
                    "a coordinate renamed");
  // The same model but for a number in an expression.
  expect_none_taken(read_model_string(replaced(chain3, "com: [0, -l3, 0]", "com: [0, -l3/2, 0]"), "moved.yaml"),
                    options, model, options, "a centre of mass moved");
  // Other options than emit()'s.
  EmitOptions cut = options, no_cse = options, id = options;
  cut.chunk_operations = 300;
  no_cse.cse = false;
  id.id = "other";
  expect_none_taken(model, cut, model, options, "other chunk_operations");
  expect_none_taken(model, no_cse, model, options, "without CSE");
  expect_none_taken(model, id, model, options, "another id");
}

TEST(ChildTask, GivesWhatTheWorkReturnsOrNothingWhenItFails) {
  const std::string big(3'000'000, 'x');  // beyond any pipe's buffer
  auto task = detail::ChildTask::start([&] { return big + "end"; });
  ASSERT_NE(task, nullptr);
  const std::optional<std::string> r = task->result();
  ASSERT_TRUE(r.has_value());
  EXPECT_TRUE(*r == big + "end");
  EXPECT_FALSE(task->result().has_value());  // once only

  auto throws = detail::ChildTask::start([]() -> std::string { throw std::runtime_error("no"); });
  ASSERT_NE(throws, nullptr);
  EXPECT_FALSE(throws->result().has_value());

  auto killed = detail::ChildTask::start([]() -> std::string {
    ::raise(SIGKILL);
    return "never";
  });
  ASSERT_NE(killed, nullptr);
  EXPECT_FALSE(killed->result().has_value());
}

TEST(ChildTask, AChildNotWaitedForIsKilledWhenTheTaskIsDestroyed) {
  const auto start = std::chrono::steady_clock::now();
  {
    auto task = detail::ChildTask::start([]() -> std::string {
      for (;;) ::pause();
    });
    ASSERT_NE(task, nullptr);
  }  // a destructor that waited for the child would never return (ctest's timeout)
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);
  // Reaped: no child of this process is left, not even a zombie.
  errno = 0;
  EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

}  // namespace
}  // namespace mbsgen

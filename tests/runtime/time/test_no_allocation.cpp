// The per-frequency loop of FrequencyResponse does not allocate (issue 3 §1): malloc is
// interposed in this executable and the allocations of compute() are counted for 10 and for
// 1000 frequencies (each after a warm-up call of the same size); per-call selection work
// allocates the same in both, so the counts must be equal. And the mass matrix's factorizations
// and solves at every evaluation of simulate()'s accelerations (runtime/src/time/block_cholesky.hpp),
// and Radau IIA's steps (runtime/src/time/radau.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>

#include "mbsgen/runtime/spectral/frequency_response.hpp"
#include "time/block_cholesky.hpp"
#include "time/radau.hpp"
#include "models.hpp"

// AddressSanitizer owns malloc itself (the ci preset): interposing it here would hand glibc's
// blocks to ASan's free. Under ASan the allocations are counted through the sanitizer's own
// hook instead (called on every malloc, calloc, realloc and operator new it serves).
#if defined(__SANITIZE_ADDRESS__)
#define MBSGEN_ASAN_HOOKS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MBSGEN_ASAN_HOOKS 1
#endif
#endif

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
}  // namespace

#if defined(MBSGEN_ASAN_HOOKS)
// compiler-rt's sanitizer/allocator_interface.h, which gcc does not install; libasan exports it.
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*)(const volatile void*, std::size_t),
                                                         void (*)(const volatile void*));

namespace {
void count_malloc(const volatile void*, std::size_t) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
}
void ignore_free(const volatile void*) {}
const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(count_malloc, ignore_free);
}  // namespace
#define MBSGEN_COUNT_ALLOCATIONS (g_hooks_installed != 0)
#else
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
}

extern "C" void* malloc(std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_malloc(n);
}
extern "C" void* calloc(std::size_t a, std::size_t b) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) ++g_allocations;
  return __libc_realloc(p, n);
}
#define MBSGEN_COUNT_ALLOCATIONS true
#endif

namespace {
long allocations_of_compute(mbsgen::FrequencyResponse& f, const Eigen::VectorXd& w) {
  g_allocations = 0;
  g_counting = true;
  f.compute(w, 0, {0, 3});
  g_counting = false;
  return g_allocations.load();
}
}  // namespace

TEST(NoAllocation, PerFrequencyLoopOfEveryMethod) {
  ASSERT_TRUE(MBSGEN_COUNT_ALLOCATIONS) << "the sanitizer's allocation hook was not installed";
  const testmodels::Qep p = testmodels::ear_chain(8, true);
  const mbsgen::LinearModel plain(p.M, p.Q, p.K);
  // The same with outputs on ÿ and u (pseudo-rows and the combination after each frequency).
  Eigen::MatrixXd Ca = Eigen::MatrixXd::Zero(8, 8), D = Eigen::MatrixXd::Zero(8, 8);
  Ca(0, 0) = 1e-6;
  Ca(3, 2) = 2e-6;
  D(3, 0) = -1.0;
  const mbsgen::LinearModel terms = plain.with_output_terms(Ca, D);
  Eigen::VectorXd w10 = Eigen::VectorXd::LinSpaced(10, 600.0, 1.2e5);
  Eigen::VectorXd w1000 = Eigen::VectorXd::LinSpaced(1000, 600.0, 1.2e5);
  for (const mbsgen::LinearModel* mp : {&plain, &terms})
  for (auto meth : {mbsgen::FrfMethod::direct, mbsgen::FrfMethod::banded,
                    mbsgen::FrfMethod::hessenberg, mbsgen::FrfMethod::modal,
                    mbsgen::FrfMethod::real}) {
    const mbsgen::LinearModel& m = *mp;
    mbsgen::FrfOptions o;
    o.method = meth;
    mbsgen::FrequencyResponse f(m, o);
    // Warm-up calls of the same size first: one-time setup (factorizations, reductions, modes)
    // and the result arrays are then in place; what remains is per-call selection work.
    f.compute(w10, 0, {0, 3});
    const long a10 = allocations_of_compute(f, w10);
    f.compute(w1000, 0, {0, 3});
    const long a1000 = allocations_of_compute(f, w1000);
    EXPECT_EQ(a10, a1000) << to_string(meth) << (mp == &terms ? " with C_a, D" : "")
                          << ": the loop over frequencies allocates";
  }
}

// The mass matrix's solve at every evaluation of simulate()'s accelerations (block_cholesky.hpp):
// after the first factorization has found the blocks, factorizations (fixed-size blocks and a
// dynamic one) and solves, refined or not, allocate nothing.
TEST(NoAllocation, MassMatrixSolvesPerEvaluation) {
  ASSERT_TRUE(MBSGEN_COUNT_ALLOCATIONS) << "the sanitizer's allocation hook was not installed";
  for (const int dynamic : {0, 10}) {  // blocks of 6, 6 and 2; and of 6 and 10 (not refined)
    const Eigen::Index n = 14;
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
    auto block = [&M](Eigen::Index at, Eigen::Index size) {
      const Eigen::MatrixXd R = Eigen::MatrixXd::Random(size, size);
      M.block(at, at, size, size) = R * R.transpose() + static_cast<double>(size) * Eigen::MatrixXd::Identity(size, size);
    };
    if (dynamic) {
      block(0, 4), block(4, 10);
    } else {
      block(0, 6), block(6, 6), block(12, 2);
    }
    const Eigen::MatrixXd near = M * (1 + 1e-7);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
    Eigen::VectorXd x(n);
    mbsgen::detail::BlockCholesky factors(n);
    ASSERT_TRUE(factors.compute(M));  // finds the blocks
    factors.solve_negated(b, x);
    EXPECT_EQ(factors.solve_refined(near, b, x), !dynamic);
    g_allocations = 0;
    g_counting = true;
    for (int k = 0; k < 100; ++k) {
      factors.compute(M);
      factors.solve_negated(b, x);
      factors.solve_refined(near, b, x);
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << (dynamic ? "with a dynamic block" : "fixed-size blocks");
  }
}

namespace {
// ÿ = −(y + 0.1 ẏ + y³) (n = 2, uncoupled): the Jacobian changes along the motion; analytic, or
// the integrator's difference quotients.
class Duffing : public mbsgen::detail::SecondOrderSystem {
 public:
  explicit Duffing(bool analytic) : analytic_(analytic) {}
  bool accelerations(double, const double* y, const double* v, Eigen::VectorXd& a) override {
    for (Eigen::Index i = 0; i < 2; ++i) a[i] = -(y[i] + 0.1 * v[i] + y[i] * y[i] * y[i]);
    return true;
  }
  bool has_jacobian() const override { return analytic_; }
  bool jacobian(double, const double* y, const double*, Eigen::MatrixXd& M, Eigen::MatrixXd& Ky,
                Eigen::MatrixXd& Kv) override {
    M.setIdentity();
    Ky.setZero();
    Kv = 0.1 * Eigen::MatrixXd::Identity(2, 2);
    for (Eigen::Index i = 0; i < 2; ++i) Ky(i, i) = 1 + 3 * y[i] * y[i];
    return true;
  }
  bool jacobian_mass(double t, const double* y, const double* v, Eigen::MatrixXd& M, Eigen::VectorXd& a) override {
    M.setIdentity();
    return accelerations(t, y, v, a);
  }

 private:
  bool analytic_;
};
}  // namespace

// Radau IIA's steps (three and five stages), with their Newton iterations, factorizations,
// Jacobians (analytic or difference quotients), error estimates and dense output, allocate
// nothing after the first step.
TEST(NoAllocation, RadauSteps) {
  ASSERT_TRUE(MBSGEN_COUNT_ALLOCATIONS) << "the sanitizer's allocation hook was not installed";
  for (const bool analytic : {true, false})
  for (const int stages : {3, 5}) {
    Duffing system(analytic);
    const auto radau = mbsgen::detail::Radau::make(system, 2, 1e-8, Eigen::VectorXd::Constant(4, 1e-10), stages);
    ASSERT_TRUE(radau->start(0, Eigen::Vector4d(1.5, -0.5, 0, 0)));
    ASSERT_EQ(radau->step(100), mbsgen::detail::Radau::Status::ok);
    Eigen::VectorXd x(4);
    g_allocations = 0;
    g_counting = true;
    for (int k = 0; k < 200 && radau->time() < 100; ++k) {
      if (radau->step(100) != mbsgen::detail::Radau::Status::ok) break;
      radau->interpolate(radau->time(), x.data());
    }
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0) << stages << " stages" << (analytic ? "" : ", difference quotients");
    EXPECT_GT(radau->statistics().jacobians, 1) << stages << " stages";
    EXPECT_GT(radau->statistics().factorizations, 2) << stages << " stages";
    EXPECT_GT(radau->statistics().steps, 100) << stages << " stages";
  }
}

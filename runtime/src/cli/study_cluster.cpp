#include "cli/study_cluster.hpp"

#include <cstdlib>
#include <cstring>
#include <vector>

#ifdef MBSGEN_WITH_MPI
#include <mpi.h>
#endif

namespace mbsgen::cli {

namespace {

#ifdef MBSGEN_WITH_MPI
// Whether an MPI launcher started this process (then MPI_Init finds its peers; without one,
// OpenMPI's singleton start can need a runtime daemon, so a plain run does not initialize MPI).
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

// Failures as bytes: index, number of values, values, length of the message, message.
template <class T>
void put(std::vector<char>& out, const T& x) {
  const char* p = reinterpret_cast<const char*>(&x);
  out.insert(out.end(), p, p + sizeof(T));
}
template <class T>
T take(const std::vector<char>& in, std::size_t& at) {
  T x;
  std::memcpy(&x, in.data() + at, sizeof(T));
  at += sizeof(T);
  return x;
}

std::vector<char> encode(const std::vector<StudyFailure>& failures) {
  std::vector<char> out;
  for (const auto& f : failures) {
    put(out, static_cast<std::uint64_t>(f.index));
    put(out, static_cast<std::uint64_t>(f.parameters.size()));
    for (double v : f.parameters) put(out, v);
    put(out, static_cast<std::uint64_t>(f.message.size()));
    out.insert(out.end(), f.message.begin(), f.message.end());
  }
  return out;
}

std::vector<StudyFailure> decode(const std::vector<char>& in) {
  std::vector<StudyFailure> out;
  for (std::size_t at = 0; at < in.size();) {
    StudyFailure f;
    f.index = static_cast<std::size_t>(take<std::uint64_t>(in, at));
    const auto n = take<std::uint64_t>(in, at);
    for (std::uint64_t k = 0; k < n; ++k) f.parameters.push_back(take<double>(in, at));
    const auto len = take<std::uint64_t>(in, at);
    f.message.assign(in.data() + at, static_cast<std::size_t>(len));
    at += static_cast<std::size_t>(len);
    out.push_back(std::move(f));
  }
  return out;
}

// Gathers each rank's vector on rank 0, in rank order (MPI_Gatherv with the sizes first).
template <class T>
std::vector<T> gather_vector(const std::vector<T>& local, MPI_Datatype type, int size) {
  const int n = static_cast<int>(local.size());
  std::vector<int> counts(static_cast<std::size_t>(size)), offsets(static_cast<std::size_t>(size));
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  long total = 0;
  for (int r = 0; r < size; ++r) offsets[static_cast<std::size_t>(r)] = static_cast<int>(total), total += counts[static_cast<std::size_t>(r)];
  std::vector<T> all(static_cast<std::size_t>(total));
  MPI_Gatherv(local.data(), n, type, all.data(), counts.data(), offsets.data(), type, 0, MPI_COMM_WORLD);
  return all;
}
#endif

}  // namespace

bool built_with_mpi() {
#ifdef MBSGEN_WITH_MPI
  return true;
#else
  return false;
#endif
}

Cluster::Cluster() {
#ifdef MBSGEN_WITH_MPI
  if (!launched_by_mpi()) return;
  int already = 0;
  MPI_Initialized(&already);
  if (!already) {
    // The study's worker threads make no MPI calls; the main thread makes them all.
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    initialized_ = true;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
  MPI_Comm_size(local, &local_size_);
  MPI_Comm_free(&local);
#endif
}

Cluster::~Cluster() {
#ifdef MBSGEN_WITH_MPI
  if (initialized_) MPI_Finalize();
#endif
}

std::string Cluster::description() const {
  return size_ > 1 ? "MPI, " + std::to_string(size_) + " ranks" : "one process";
}

bool Cluster::any(bool flag) const {
#ifdef MBSGEN_WITH_MPI
  if (size_ > 1) {
    int mine = flag ? 1 : 0, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return all != 0;
  }
#endif
  return flag;
}

std::vector<double> Cluster::all_gather(const std::vector<double>& local) const {
#ifdef MBSGEN_WITH_MPI
  if (size_ > 1) {
    const int n = static_cast<int>(local.size());
    std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
    MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    long total = 0;
    for (int r = 0; r < size_; ++r) offsets[static_cast<std::size_t>(r)] = static_cast<int>(total), total += counts[static_cast<std::size_t>(r)];
    std::vector<double> all(static_cast<std::size_t>(total));
    MPI_Allgatherv(local.data(), n, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    return all;
  }
#endif
  return local;
}

StudyResults Cluster::gather(StudyResults local) const {
#ifdef MBSGEN_WITH_MPI
  if (size_ > 1) {
    StudyResults all = local;
    all.scalars = gather_vector(local.scalars, MPI_DOUBLE, size_);
    all.sweep = gather_vector(local.sweep, MPI_DOUBLE, size_);
    all.failures = decode(gather_vector(encode(local.failures), MPI_CHAR, size_));
    unsigned long count = local.count, total = 0;
    MPI_Reduce(&count, &total, 1, MPI_UNSIGNED_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
    double t[3] = {local.seconds_kernels, local.seconds_modes, local.seconds_response}, sum[3] = {0, 0, 0};
    MPI_Reduce(t, sum, 3, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank_ != 0) return local;
    all.count = total;
    all.seconds_kernels = sum[0], all.seconds_modes = sum[1], all.seconds_response = sum[2];
    return all;
  }
#endif
  return local;
}

}  // namespace mbsgen::cli

// The processes of a study (issue 20 §2): one, or the ranks of an MPI job when the solver library
// was built with MBSGEN_WITH_MPI and the solver was started by mpirun or srun (docs/studies.md).
#pragma once

#include <string>
#include <vector>

#include "mbsgen/runtime/study/study.hpp"

namespace mbsgen::cli {

class Cluster {
 public:
  /// Initializes MPI when the library has it and the process was started by an MPI launcher
  /// (OpenMPI's OMPI_COMM_WORLD_SIZE, PMI_SIZE of MPICH and Slurm, PMIX_RANK); otherwise one
  /// process.
  Cluster();
  ~Cluster();  ///< MPI_Finalize when it initialized MPI
  Cluster(const Cluster&) = delete;
  Cluster& operator=(const Cluster&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Processes on this machine (for the default number of threads per process).
  int local_size() const { return local_size_; }
  /// "MPI (N ranks)" or "one process".
  std::string description() const;
  /// True on every rank when flag is true on some rank.
  bool any(bool flag) const;
  /// Rank 0: every rank's results appended in rank order (the ranks hold consecutive ranges);
  /// the other ranks: their own results, unchanged. Timings are summed.
  StudyResults gather(StudyResults local) const;
  /// Every rank's vector concatenated in rank order, on every rank (one process: local). For the
  /// starts of a fit (issue 42).
  std::vector<double> all_gather(const std::vector<double>& local) const;

 private:
  int rank_ = 0, size_ = 1, local_size_ = 1;
  bool initialized_ = false;
};

/// Whether this build has MPI (MBSGEN_WITH_MPI).
bool built_with_mpi();

}  // namespace mbsgen::cli

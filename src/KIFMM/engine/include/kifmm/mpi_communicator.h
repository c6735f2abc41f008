// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// kifmm::Communicator over an MPI communicator (library kifmm_engine_mpi; the engine itself
// does not depend on MPI). Counts of more than INT_MAX elements are refused (exception).
// It works on a duplicate of the given communicator (its own tag space). alltoallv is a sparse
// exchange: only the non-empty messages are sent (synchronous sends, probe and receive, then a
// non-blocking barrier once this rank's sends are matched: the "NBX" consensus of Hoefler,
// Siebert and Lumsdaine 2010), so no rank handles O(P) counts.
#pragma once

#include "communicator.h"

#include <mpi.h>

namespace kifmm {

class MpiCommunicator : public Communicator {
 public:
  explicit MpiCommunicator(MPI_Comm comm);
  ~MpiCommunicator() override;
  MpiCommunicator(const MpiCommunicator &) = delete;
  MpiCommunicator &operator=(const MpiCommunicator &) = delete;
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void allreduce_sum(double *data, std::size_t n) override;
  void allreduce_sum(uint64_t *data, std::size_t n) override;
  void allreduce_min(double *data, std::size_t n) override;
  void allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts) override;
  void allgatherv(const std::vector<double> &mine, std::vector<double> &all, std::vector<int> &counts) override;
  void alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) override;
  void alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv) override;

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  int exchanges_ = 0;    // alltoallv calls so far: consecutive ones use different tags
  template <class T>
  void exchange(MPI_Datatype type, const std::vector<std::vector<T>> &send, std::vector<std::vector<T>> &recv);
};

}    // namespace kifmm

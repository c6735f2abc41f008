// kifmm::Communicator over an MPI communicator (library kifmm_engine_mpi; the engine itself
// does not depend on MPI). Counts of more than INT_MAX elements are refused (exception).
#pragma once

#include "communicator.h"

#include <mpi.h>

namespace kifmm {

class MpiCommunicator : public Communicator {
 public:
  explicit MpiCommunicator(MPI_Comm comm);
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void allreduce_sum(double *data, std::size_t n) override;
  void allreduce_sum(uint64_t *data, std::size_t n) override;
  void allreduce_min(double *data, std::size_t n) override;
  void allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts) override;
  void alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) override;
  void alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv) override;

 private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
};

}    // namespace kifmm

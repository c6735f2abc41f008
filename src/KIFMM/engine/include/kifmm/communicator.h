// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Communication interface of the distributed evaluation (Evaluator::evaluate_distributed).
// The engine has no MPI dependency: the MPI implementation is mpi_communicator.h/.cpp
// (library kifmm_engine_mpi); SerialCommunicator is the one-process case. Every call is
// collective (all ranks call it, in the same order). Counters: bytes this rank sent.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace kifmm {

class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // in place, over all ranks
  virtual void allreduce_sum(double *data, std::size_t n) = 0;
  virtual void allreduce_sum(uint64_t *data, std::size_t n) = 0;
  virtual void allreduce_min(double *data, std::size_t n) = 0;
  // every rank's `mine` concatenated in rank order; counts[r] = entries from rank r
  virtual void allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts) = 0;
  virtual void allgatherv(const std::vector<double> &mine, std::vector<double> &all, std::vector<int> &counts) = 0;
  // send[r] goes to rank r; recv[r] is what rank r sent here
  virtual void alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) = 0;
  virtual void alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv) = 0;

  // bytes sent by this rank since reset_counters (payload of every call above; a reduction
  // counts its buffer once)
  std::size_t bytes_sent() const { return bytes_sent_; }
  void reset_counters() { bytes_sent_ = 0; }

 protected:
  std::size_t bytes_sent_ = 0;
};

// One process: reductions are identities, exchanges copy to self.
class SerialCommunicator : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void allreduce_sum(double *, std::size_t) override {}
  void allreduce_sum(uint64_t *, std::size_t) override {}
  void allreduce_min(double *, std::size_t) override {}
  void allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts) override
  {
    all = mine;
    counts.assign(1, (int) mine.size());
  }
  void allgatherv(const std::vector<double> &mine, std::vector<double> &all, std::vector<int> &counts) override
  {
    all = mine;
    counts.assign(1, (int) mine.size());
  }
  void alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv) override
  {
    recv = send;
  }
  void alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv) override
  {
    recv = send;
  }
};

}    // namespace kifmm

// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "mpi_communicator.h"

#include <climits>
#include <stdexcept>

namespace kifmm {

namespace {
int checked(std::size_t n)
{
  if (n > (std::size_t) INT_MAX) throw std::length_error("kifmm::MpiCommunicator: message larger than INT_MAX elements");
  return (int) n;
}

}    // namespace

MpiCommunicator::MpiCommunicator(MPI_Comm comm)
{
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
}

MpiCommunicator::~MpiCommunicator()
{
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && comm_ != MPI_COMM_NULL) MPI_Comm_free(&comm_);
}

// Sparse exchange (NBX): a synchronous send per non-empty message; receive whatever arrives
// (probe: source and size); when this rank's sends are all matched, enter a non-blocking
// barrier; when the barrier completes every rank's sends have been received. A rank can leave
// while others still probe, so the next exchange uses the other tag: it can start only after
// every rank has entered this exchange's barrier, i.e. left the previous exchange.
template <class T>
void MpiCommunicator::exchange(MPI_Datatype type, const std::vector<std::vector<T>> &send,
                               std::vector<std::vector<T>> &recv)
{
  const int tag = 0x4b46 + (exchanges_++ & 1);
  recv.assign(size_, {});
  std::vector<MPI_Request> sends;
  for (int r = 0; r < size_ && r < (int) send.size(); ++r) {
    if (send[r].empty()) continue;
    if (r == rank_) {
      recv[r] = send[r];
      continue;
    }
    sends.emplace_back();
    MPI_Issend(send[r].data(), checked(send[r].size()), type, r, tag, comm_, &sends.back());
    bytes_sent_ += sizeof(T) * send[r].size();
  }
  MPI_Request barrier = MPI_REQUEST_NULL;
  bool in_barrier = false;
  for (;;) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, tag, comm_, &flag, &st);
    if (flag) {
      int count = 0;
      MPI_Get_count(&st, type, &count);
      std::vector<T> &v = recv[st.MPI_SOURCE];
      v.resize(count);
      MPI_Recv(v.data(), count, type, st.MPI_SOURCE, tag, comm_, MPI_STATUS_IGNORE);
      continue;
    }
    int done = 0;
    if (!in_barrier) {
      MPI_Testall((int) sends.size(), sends.data(), &done, MPI_STATUSES_IGNORE);
      if (done) {
        MPI_Ibarrier(comm_, &barrier);
        in_barrier = true;
      }
    } else {
      MPI_Test(&barrier, &done, MPI_STATUS_IGNORE);
      if (done) break;
    }
  }
}

void MpiCommunicator::allreduce_sum(double *data, std::size_t n)
{
  if (size_ > 1) bytes_sent_ += sizeof(double) * n;
  MPI_Allreduce(MPI_IN_PLACE, data, checked(n), MPI_DOUBLE, MPI_SUM, comm_);
}

void MpiCommunicator::allreduce_sum(uint64_t *data, std::size_t n)
{
  if (size_ > 1) bytes_sent_ += sizeof(uint64_t) * n;
  MPI_Allreduce(MPI_IN_PLACE, data, checked(n), MPI_UINT64_T, MPI_SUM, comm_);
}

void MpiCommunicator::allreduce_min(double *data, std::size_t n)
{
  if (size_ > 1) bytes_sent_ += sizeof(double) * n;
  MPI_Allreduce(MPI_IN_PLACE, data, checked(n), MPI_DOUBLE, MPI_MIN, comm_);
}

namespace {
template <class T>
void gather_all(MPI_Comm comm, int size, MPI_Datatype type, const std::vector<T> &mine,
                std::vector<T> &all, std::vector<int> &counts, int n)
{
  counts.assign(size, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  std::vector<int> displ(size);
  std::size_t total = 0;
  for (int r = 0; r < size; ++r) {
    displ[r] = checked(total);
    total += counts[r];
  }
  all.resize(total);
  MPI_Allgatherv(mine.data(), n, type, all.data(), counts.data(), displ.data(), type, comm);
}
}    // namespace

void MpiCommunicator::allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts)
{
  gather_all(comm_, size_, MPI_INT, mine, all, counts, checked(mine.size()));
  if (size_ > 1) bytes_sent_ += sizeof(int) * (mine.size() + 1);
}

void MpiCommunicator::allgatherv(const std::vector<double> &mine, std::vector<double> &all, std::vector<int> &counts)
{
  gather_all(comm_, size_, MPI_DOUBLE, mine, all, counts, checked(mine.size()));
  if (size_ > 1) bytes_sent_ += sizeof(double) * mine.size() + sizeof(int);
}

void MpiCommunicator::alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv)
{
  exchange(MPI_DOUBLE, send, recv);
}

void MpiCommunicator::alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv)
{
  exchange(MPI_INT, send, recv);
}

}    // namespace kifmm

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

template <class T>
void exchange(MPI_Comm comm, int size, MPI_Datatype type, const std::vector<std::vector<T>> &send,
              std::vector<std::vector<T>> &recv, std::size_t &bytes)
{
  std::vector<int> scount(size), rcount(size), sdispl(size), rdispl(size);
  std::size_t stotal = 0;
  for (int r = 0; r < size; ++r) {
    scount[r] = checked(r < (int) send.size() ? send[r].size() : 0);
    sdispl[r] = checked(stotal);
    stotal += scount[r];
  }
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  std::size_t rtotal = 0;
  for (int r = 0; r < size; ++r) {
    rdispl[r] = checked(rtotal);
    rtotal += rcount[r];
  }
  std::vector<T> sbuf(stotal), rbuf(rtotal);
  for (int r = 0; r < size; ++r)
    if (scount[r] > 0) std::copy(send[r].begin(), send[r].end(), sbuf.begin() + sdispl[r]);
  MPI_Alltoallv(sbuf.data(), scount.data(), sdispl.data(), type, rbuf.data(), rcount.data(), rdispl.data(), type, comm);
  recv.assign(size, {});
  for (int r = 0; r < size; ++r) recv[r].assign(rbuf.begin() + rdispl[r], rbuf.begin() + rdispl[r] + rcount[r]);
  int me = 0;
  MPI_Comm_rank(comm, &me);
  for (int r = 0; r < size; ++r)
    if (r != me) bytes += sizeof(T) * (std::size_t) scount[r] + sizeof(int);
}
}    // namespace

MpiCommunicator::MpiCommunicator(MPI_Comm comm) : comm_(comm)
{
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
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

void MpiCommunicator::allgatherv(const std::vector<int> &mine, std::vector<int> &all, std::vector<int> &counts)
{
  int n = checked(mine.size());
  counts.assign(size_, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_);
  std::vector<int> displ(size_);
  std::size_t total = 0;
  for (int r = 0; r < size_; ++r) {
    displ[r] = checked(total);
    total += counts[r];
  }
  all.resize(total);
  MPI_Allgatherv(mine.data(), n, MPI_INT, all.data(), counts.data(), displ.data(), MPI_INT, comm_);
  if (size_ > 1) bytes_sent_ += sizeof(int) * (mine.size() + 1);
}

void MpiCommunicator::alltoallv(const std::vector<std::vector<double>> &send, std::vector<std::vector<double>> &recv)
{
  exchange(comm_, size_, MPI_DOUBLE, send, recv, bytes_sent_);
}

void MpiCommunicator::alltoallv(const std::vector<std::vector<int>> &send, std::vector<std::vector<int>> &recv)
{
  exchange(comm_, size_, MPI_INT, send, recv, bytes_sent_);
}

}    // namespace kifmm

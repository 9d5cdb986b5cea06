// Zoltan2 behind perinox's partition choice (the only translation unit with Zoltan2's headers).
#include "perinox/evaluator/Partitioner.hpp"

#include <Teuchos_DefaultMpiComm.hpp>
#include <Teuchos_DefaultSerialComm.hpp>
#include <Zoltan2_BasicVectorAdapter.hpp>
#include <Zoltan2_PartitioningProblem.hpp>
#include <mpi.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace perinox {

namespace {

using Types = Zoltan2::BasicUserTypes<double, int, long long>;
using Adapter = Zoltan2::BasicVectorAdapter<Types>;

/// Zoltan2's part for each particle of the id range [begin, end), for `parts` parts over comm.
std::vector<int> geometricParts(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& d,
                                long long begin, long long end, PartitionMethod method, int parts) {
  const int n = static_cast<int>(end - begin), D = d.dim;
  std::vector<long long> ids(static_cast<std::size_t>(n));
  std::iota(ids.begin(), ids.end(), begin);
  std::vector<double> coord(static_cast<std::size_t>(n) * D);
  for (int l = 0; l < n; ++l)
    for (int a = 0; a < D; ++a) coord[static_cast<std::size_t>(a) * n + l] = d.X[begin + l][a];
  std::vector<const double*> entries;
  std::vector<int> strides(static_cast<std::size_t>(D), 1);
  for (int a = 0; a < D; ++a) entries.push_back(coord.data() + static_cast<std::size_t>(a) * n);
  std::vector<const double*> weights;
  std::vector<int> weightStrides;
  Adapter adapter(n, ids.data(), entries, strides, weights, weightStrides);
  Teuchos::ParameterList params("Zoltan2");
  params.set("algorithm", method == PartitionMethod::Rcb ? "rcb" : "multijagged");
  params.set("num_global_parts", parts);
  params.set("imbalance_tolerance", 1.01);
  params.set("error_check_level", "no_assertions");
  Zoltan2::PartitioningProblem<Adapter> problem(&adapter, &params, comm);
  problem.solve();
  const int* part = problem.getSolution().getPartListView();
  std::vector<int> out(static_cast<std::size_t>(n), 0);
  if (part) std::copy(part, part + n, out.begin());
  return out;
}

MPI_Comm rawComm(const Teuchos::Comm<int>& comm) {
  const auto* mpi = dynamic_cast<const Teuchos::MpiComm<int>*>(&comm);
  return mpi ? static_cast<MPI_Comm>((*mpi->getRawMpiComm())()) : MPI_COMM_SELF;
}

}  // namespace

std::vector<long long> ownedParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& d,
                                      PartitionMethod method) {
  const long long n = d.size();
  const int ranks = comm->getSize(), rank = comm->getRank();
  const long long begin = partitionBegin(n, ranks, rank), end = partitionBegin(n, ranks, rank + 1);
  std::vector<long long> owned;
  if (ranks == 1 || method == PartitionMethod::Slabs) {
    owned.resize(static_cast<std::size_t>(end - begin));
    std::iota(owned.begin(), owned.end(), begin);
    return owned;
  }
  // Part q goes to rank q: each slab owner sends its particles' ids to their parts' ranks.
  const std::vector<int> part = geometricParts(comm, d, begin, end, method, ranks);
  std::vector<int> sendCount(static_cast<std::size_t>(ranks), 0), recvCount(static_cast<std::size_t>(ranks), 0);
  for (int q : part) ++sendCount[q];
  std::vector<int> sendOffset(static_cast<std::size_t>(ranks), 0), recvOffset(static_cast<std::size_t>(ranks), 0);
  std::partial_sum(sendCount.begin(), sendCount.end() - 1, sendOffset.begin() + 1);
  std::vector<long long> send(part.size());
  std::vector<int> fill = sendOffset;
  for (std::size_t l = 0; l < part.size(); ++l) send[fill[part[l]]++] = begin + static_cast<long long>(l);
  const MPI_Comm mc = rawComm(*comm);
  MPI_Alltoall(sendCount.data(), 1, MPI_INT, recvCount.data(), 1, MPI_INT, mc);
  std::partial_sum(recvCount.begin(), recvCount.end() - 1, recvOffset.begin() + 1);
  owned.resize(static_cast<std::size_t>(recvOffset.back() + recvCount.back()));
  MPI_Alltoallv(send.data(), sendCount.data(), sendOffset.data(), MPI_LONG_LONG, owned.data(), recvCount.data(),
                recvOffset.data(), MPI_LONG_LONG, mc);
  std::sort(owned.begin(), owned.end());
  long long mine = static_cast<long long>(owned.size()), fewest = 0;
  Teuchos::reduceAll(*comm, Teuchos::REDUCE_MIN, 1, &mine, &fewest);
  if (fewest == 0)
    throw std::invalid_argument("Discretization/Partition = " + std::string(partitionName(method)) +
                                " left a rank without particles (" + std::to_string(n) + " particles on " +
                                std::to_string(ranks) + " ranks): run on fewer ranks");
  return owned;
}

std::vector<int> partsOf(const Discretization& d, PartitionMethod method, int parts) {
  const long long n = d.size();
  if (parts == 1) return std::vector<int>(static_cast<std::size_t>(n), 0);
  if (method == PartitionMethod::Slabs) {
    std::vector<int> part(static_cast<std::size_t>(n));
    for (int q = 0; q < parts; ++q)
      for (long long i = partitionBegin(n, parts, q); i < partitionBegin(n, parts, q + 1); ++i) part[i] = q;
    return part;
  }
  auto self = Teuchos::rcp<const Teuchos::Comm<int>>(new Teuchos::SerialComm<int>());
  return geometricParts(self, d, 0, n, method, parts);
}

}  // namespace perinox

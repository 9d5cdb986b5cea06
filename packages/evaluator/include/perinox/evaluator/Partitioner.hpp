#pragma once
// Which particles each MPI rank owns: contiguous id slabs, or Zoltan2's geometric partitioning
// (recursive coordinate bisection or multi-jagged) of the particles' reference positions.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <vector>

#include "perinox/model/Partition.hpp"

namespace perinox {

/// The particles this rank owns (global ids, sorted), by method; collective over comm. Each rank
/// hands Zoltan2 the coordinates of its id slab only and receives the ids of its part from their
/// slab owners, so the partitioning needs no global array. One rank owns everything.
/// Deterministic: the same discretisation on the same rank count gives the same parts.
std::vector<long long> ownedParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& d,
                                      PartitionMethod method);

/// The part of every particle when d is split into `parts` parts on this process alone (for
/// benchmarks that compare partitions for rank counts the machine cannot run, docs/performance.md).
std::vector<int> partsOf(const Discretization& d, PartitionMethod method, int parts);

}  // namespace perinox

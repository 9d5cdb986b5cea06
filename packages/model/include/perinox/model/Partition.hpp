#pragma once
// Splitting a discretisation among MPI ranks. A rank owns a set of particles (sorted global ids)
// and sees, as ghosts, the family members of its owned particles that other ranks own. Which
// particles a rank owns is the partitioner's choice (packages/evaluator/src/Partitioner.cpp:
// contiguous id slabs, or Zoltan2's geometric bisection); everything below it works on any set.
#include <string>
#include <vector>

#include "perinox/core/Discretization.hpp"
#include "perinox/model/Model.hpp"

namespace perinox {

/// How particles are split among ranks (`Discretization/Partition`).
enum class PartitionMethod {
  Rcb,          ///< Zoltan2 recursive coordinate bisection (the default)
  MultiJagged,  ///< Zoltan2 multi-jagged (several cuts per level)
  Slabs         ///< contiguous id ranges [n r / p, n (r+1) / p): lattice rows; kept for tests
};
const char* partitionName(PartitionMethod m);                       // "RCB", "Multi-Jagged", "Slabs"
bool parsePartition(const std::string& name, PartitionMethod& out);  // exact names; false if unknown

/// First particle id of rank r's slab of nranks (balanced by count).
long long partitionBegin(long long n, int nranks, int r);

/// The given owned particles (global ids, sorted ascending, no repeats) and their ghosts (family
/// members that are not owned, sorted by global id), with families in local ids.
LocalParticles localParticles(const Discretization& d, const std::vector<long long>& owned);
/// The owned slab [begin, end) and its ghosts.
LocalParticles localParticles(const Discretization& d, long long begin, long long end);

/// Number of distinct ghosts (family members owned by another part) of each part, for a part
/// assignment of every particle (part[i] in [0, parts)). For reports and benchmarks.
std::vector<long long> ghostCounts(const Discretization& d, const std::vector<int>& part, int parts);

}  // namespace perinox

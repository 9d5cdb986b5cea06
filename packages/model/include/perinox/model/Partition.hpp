#pragma once
// Splitting a discretisation among MPI ranks. A rank owns a set of particles (sorted global ids)
// and sees, as ghosts, the family members of its owned particles that other ranks own. Which
// particles a rank owns is the partitioner's choice (packages/evaluator/src/Partitioner.cpp:
// contiguous id slabs, or Zoltan2's geometric bisection); everything below it works on any set.
#include <cstdint>
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

/// The families of a rank's local particles as built (before any bond breaks): the owned
/// particles' in local ids (a copy of LocalParticles' families, which lose bonds as they break)
/// and the ghosts' in global ids (the matrix graph couples a particle to its neighbours'
/// neighbours, two horizons away, which need not be local).
struct LocalFamilies {
  std::vector<std::int64_t> ownedOffset{0};  // owned l: ownedIndex[ownedOffset[l] .. ownedOffset[l + 1])
  std::vector<int> ownedIndex;               // local ids
  std::vector<std::int64_t> ghostOffset{0};  // ghost k (local id numOwned + k): ghostMembers[...]
  std::vector<long long> ghostMembers;       // global ids, ascending per particle
};

/// The given owned particles (global ids, sorted ascending, no repeats) and their ghosts (family
/// members that are not owned, sorted by global id), with families in local ids. d may come
/// without families (familyOffset empty, as a scene builds it): the families are then found by a
/// cell-list search over the particles within two horizons of the owned particles' bounding box
/// only, with buildFamilies' distance test and order, so they equal those of the whole d entry for
/// entry and no family array of global size is made. families, if given, receives LocalFamilies.
LocalParticles localParticles(const Discretization& d, const std::vector<long long>& owned,
                              LocalFamilies* families = nullptr);
/// The owned slab [begin, end) and its ghosts.
LocalParticles localParticles(const Discretization& d, long long begin, long long end);

/// Number of distinct ghosts (family members owned by another part) of each part, for a part
/// assignment of every particle (part[i] in [0, parts)). For reports and benchmarks.
std::vector<long long> ghostCounts(const Discretization& d, const std::vector<int>& part, int parts);

}  // namespace perinox

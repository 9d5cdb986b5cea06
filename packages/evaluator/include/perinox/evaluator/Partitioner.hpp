#pragma once
// Which particles each MPI rank owns: contiguous id slabs, or Zoltan2's geometric partitioning
// (recursive coordinate bisection or multi-jagged) of the particles' reference positions.
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <cstdint>
#include <vector>

#include "perinox/core/ExodusMesh.hpp"
#include "perinox/model/Partition.hpp"

namespace perinox {

/// The particles this rank owns (global ids, sorted), by method; collective over comm. Each rank
/// hands Zoltan2 the coordinates of its id slab only and receives the ids of its part from their
/// slab owners, so the partitioning needs no global array. One rank owns everything.
/// Deterministic: the same discretisation on the same rank count gives the same parts.
std::vector<long long> ownedParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& d,
                                      PartitionMethod method);

/// Sends records of `width` doubles between ranks (collective): record k (values[k * width ..])
/// goes to rank to[k]. Returns the records this rank receives, in the senders' rank order.
std::vector<double> exchangeRecords(const Teuchos::Comm<int>& comm, const std::vector<double>& values, int width,
                                    const std::vector<int>& to);
/// The rank whose id slab [partitionBegin(n, ranks, q), partitionBegin(n, ranks, q + 1)) holds
/// particle id: a rendezvous every rank can name without a table (a directory of owners by slab).
int idSlabOf(long long id, long long n, int ranks);

/// This rank's id slab of an Exodus mesh (collective): the elements [partitionBegin(E, p, r),
/// partitionBegin(E, p, r + 1)) of the E in file order, read with readExodusMeshRange (every
/// failure agreed: all ranks throw the lowest failing rank's std::runtime_error), with the
/// body's box and the whole mesh's nominal spacing (its exact median volume over the ranks).
/// The sets hold their members in the slab, so heldMembers finds any rank's members.
ExodusMesh readLocalExodusMesh(const Teuchos::Comm<int>& comm, const std::string& path, int dim, double thickness);

/// The ids among `held` (this rank's particles, any ids of the n) that are members of a set
/// every rank holds the part of in its id slab (`slabMembers`, sorted): collective, a question
/// to each id's slab rank and its answer.
std::vector<long long> heldMembers(const Teuchos::Comm<int>& comm, const std::vector<long long>& held, long long n,
                                   const std::vector<int>& slabMembers);

/// The part of every particle when d is split into `parts` parts on this process alone (for
/// benchmarks that compare partitions for rank counts the machine cannot run, docs/performance.md).
std::vector<int> partsOf(const Discretization& d, PartitionMethod method, int parts);

/// One rank's share of a lattice, built without an array of global size on any rank.
struct LocalLattice {
  /// Owned particles (sorted global ids, the same as ownedParticles on the whole lattice gives)
  /// then their ghosts (family members owned elsewhere, sorted), families of the owned particles
  /// in local ids: equal, entry for entry, to localParticles(buildLattice(spec), owned).
  LocalParticles particles;
  std::vector<std::uint8_t> fictitious, sideMask;  // per local particle
  std::vector<int> block;                          // per local particle
  long long globalCount = 0;                       // particles of the whole lattice
  /// The most this rank held at once while building: particles (owned + the candidates within one
  /// cell-list width of its box) and bonds (their families). Tests check these against the share.
  std::size_t heldParticles = 0, heldBonds = 0;
};

/// Builds this rank's share of the lattice of spec (collective): each rank generates the lattice
/// sites of its slab of site indices (ids and the jitter's random stream continued by prefix
/// sums), sends them to their id slabs and then to their parts (Zoltan2, as ownedParticles), and
/// receives as ghost candidates the particles other ranks own within one horizon of its owned
/// bounding box; the families come from a cell-list search over owned + candidates.
/// The first step of the distributed construction (docs/architecture.md, "What is still
/// replicated"): the evaluator does not use it yet.
LocalLattice buildLocalLattice(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const LatticeSpec& spec,
                               PartitionMethod method);

}  // namespace perinox

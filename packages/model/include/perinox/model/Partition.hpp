#pragma once
// Splitting a discretisation among MPI ranks: rank r owns the contiguous particle ids
// [begin(r), end(r)). Particle ids are spatially coherent (lattice order), so blocks are compact.
#include "perinox/core/Discretization.hpp"
#include "perinox/model/Model.hpp"

namespace perinox {

/// First particle id owned by rank r of nranks (balanced by count).
long long partitionBegin(long long n, int nranks, int r);

/// The owned particles [begin, end) and their ghosts (family members outside the range,
/// sorted by global id), with families in local ids.
LocalParticles localParticles(const Discretization& d, long long begin, long long end);

}  // namespace perinox

// Zoltan2 behind perinox's partition choice, and the distributed lattice construction (the only
// translation unit with Zoltan2's headers).
#include "perinox/evaluator/Partitioner.hpp"
#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/evaluator/Problem.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Zoltan2_BasicVectorAdapter.hpp>
#include <Zoltan2_PartitioningProblem.hpp>
#include <mpi.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace perinox {

namespace {

using Types = Zoltan2::BasicUserTypes<double, int, long long>;
using Adapter = Zoltan2::BasicVectorAdapter<Types>;

/// Zoltan2's part for each of the given particles (this rank's share of the points), for
/// `parts` parts over comm.
std::vector<int> geometricParts(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, int D,
                                const std::vector<long long>& ids, const std::vector<Vec3>& X, PartitionMethod method,
                                int parts) {
  const int n = static_cast<int>(ids.size());
  std::vector<double> coord(static_cast<std::size_t>(n) * D);
  for (int l = 0; l < n; ++l)
    for (int a = 0; a < D; ++a) coord[static_cast<std::size_t>(a) * n + l] = X[l][a];
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
  // Zoltan2's "rcb" runs Zoltan's RCB, which prints its parameters unless told not to.
  params.sublist("zoltan_parameters").set("debug_level", "0");
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

/// Sends records of `width` values to ranks: record k (values[k*width ..]) to rank to[k]. Returns
/// what this rank receives, in rank order.
template <class T>
std::vector<T> exchange(const Teuchos::Comm<int>& comm, const std::vector<T>& values, int width,
                        const std::vector<int>& to) {
  const int ranks = comm.getSize();
  std::vector<int> sendCount(ranks, 0), recvCount(ranks, 0), sendOffset(ranks, 0), recvOffset(ranks, 0);
  for (int q : to) sendCount[q] += width;
  std::partial_sum(sendCount.begin(), sendCount.end() - 1, sendOffset.begin() + 1);
  std::vector<T> send(values.size());
  std::vector<int> fill = sendOffset;
  for (std::size_t k = 0; k < to.size(); ++k) {
    std::copy_n(values.begin() + static_cast<std::ptrdiff_t>(k * width), width, send.begin() + fill[to[k]]);
    fill[to[k]] += width;
  }
  const MPI_Comm mc = rawComm(comm);
  MPI_Alltoall(sendCount.data(), 1, MPI_INT, recvCount.data(), 1, MPI_INT, mc);
  std::partial_sum(recvCount.begin(), recvCount.end() - 1, recvOffset.begin() + 1);
  std::vector<T> recv(static_cast<std::size_t>(recvOffset.back() + recvCount.back()));
  const MPI_Datatype type = std::is_same<T, double>::value ? MPI_DOUBLE : MPI_LONG_LONG;
  MPI_Alltoallv(send.data(), sendCount.data(), sendOffset.data(), type, recv.data(), recvCount.data(), recvOffset.data(),
                type, mc);
  return recv;
}

void requireEveryRankOwns(const Teuchos::Comm<int>& comm, std::size_t owned, long long n, PartitionMethod method) {
  long long mine = static_cast<long long>(owned), fewest = 0;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, 1, &mine, &fewest);
  if (fewest == 0)
    throw std::invalid_argument("Discretization/Partition = " + std::string(partitionName(method)) +
                                " left a rank without particles (" + std::to_string(n) + " particles on " +
                                std::to_string(comm.getSize()) + " ranks): run on fewer ranks");
}

/// A particle as it travels between ranks: id, X (3), volume, fictitious, side mask, block.
constexpr int kRecord = 8;

void pack(std::vector<double>& out, long long id, const Discretization& d, std::size_t i) {
  const double r[kRecord] = {static_cast<double>(id), d.X[i][0], d.X[i][1], d.X[i][2], d.volume[i],
                             static_cast<double>(d.fictitious[i]), static_cast<double>(d.sideMask[i]),
                             static_cast<double>(d.block[i])};
  out.insert(out.end(), r, r + kRecord);
}

/// Unpacks records into particles sorted by id: ids[k], d's arrays (no families).
void unpackSorted(const std::vector<double>& recs, Discretization& d, std::vector<long long>& ids) {
  const std::size_t m = recs.size() / kRecord;
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return recs[a * kRecord] < recs[b * kRecord]; });
  for (std::size_t k : order) {
    const double* r = &recs[k * kRecord];
    ids.push_back(static_cast<long long>(r[0]));
    d.X.emplace_back(r[1], r[2], r[3]);
    d.volume.push_back(r[4]);
    d.fictitious.push_back(static_cast<std::uint8_t>(r[5]));
    d.sideMask.push_back(static_cast<std::uint8_t>(r[6]));
    d.block.push_back(static_cast<int>(r[7]));
  }
}

}  // namespace

std::vector<long long> ownedParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& d,
                                      PartitionMethod method) {
  const long long n = d.size();
  const int ranks = comm->getSize(), rank = comm->getRank();
  const long long begin = partitionBegin(n, ranks, rank), end = partitionBegin(n, ranks, rank + 1);
  std::vector<long long> slab(static_cast<std::size_t>(end - begin));
  std::iota(slab.begin(), slab.end(), begin);
  if (ranks == 1 || method == PartitionMethod::Slabs) return slab;
  // Part q goes to rank q: each slab owner sends its particles' ids to their parts' ranks.
  const std::vector<Vec3> X(d.X.begin() + begin, d.X.begin() + end);
  std::vector<long long> owned = exchange(*comm, slab, 1, geometricParts(comm, d.dim, slab, X, method, ranks));
  std::sort(owned.begin(), owned.end());
  requireEveryRankOwns(*comm, owned.size(), n, method);
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
  auto self = Teuchos::rcp<const Teuchos::Comm<int>>(new Teuchos::MpiComm<int>(MPI_COMM_SELF));
  std::vector<long long> ids(static_cast<std::size_t>(n));
  std::iota(ids.begin(), ids.end(), 0LL);
  return geometricParts(self, d.dim, ids, d.X, method, parts);
}

namespace {

/// The id slab (rank) of particle id among n on `ranks` ranks.
int slabOf(long long id, long long n, int ranks) {
  int q = static_cast<int>((static_cast<double>(id) * ranks) / static_cast<double>(std::max(n, 1LL)));
  q = std::min(std::max(q, 0), ranks - 1);
  while (q > 0 && id < partitionBegin(n, ranks, q)) --q;
  while (q + 1 < ranks && id >= partitionBegin(n, ranks, q + 1)) ++q;
  return q;
}

/// d's scalars (dimension, spacing, horizon, box) without particles.
Discretization emptyLike(const Discretization& d) {
  Discretization e;
  e.dim = d.dim, e.dx = d.dx, e.horizon = d.horizon, e.thickness = d.thickness;
  e.boxLower = d.boxLower, e.boxUpper = d.boxUpper;
  return e;
}

/// Particles with their ids, in id order.
struct Share {
  Discretization d;
  std::vector<long long> ids;
};

Share receiveSorted(const Teuchos::Comm<int>& comm, const Discretization& like, const std::vector<double>& recs,
                    const std::vector<int>& to) {
  Share s{emptyLike(like), {}};
  unpackSorted(exchange(comm, recs, kRecord, to), s.d, s.ids);
  return s;
}

/// 2: particles numbered from firstId (this rank's consecutive part of the ids), sent to their id
/// slabs (so that Zoltan2 sees what ownedParticles gives it and cuts the same parts), then to
/// their parts. n: the body's particle count; `like`'s scalars (box included) are the body's.
Share partitioned(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Discretization& part, long long firstId,
                  long long n, PartitionMethod method) {
  const int ranks = comm->getSize();
  std::vector<double> recs;
  std::vector<int> to;
  for (std::size_t i = 0; i < part.X.size(); ++i) {
    const long long id = firstId + static_cast<long long>(i);
    pack(recs, id, part, i);
    to.push_back(slabOf(id, n, ranks));
  }
  Share share = receiveSorted(*comm, part, recs, to);
  if (method == PartitionMethod::Slabs || ranks == 1) return share;
  const std::vector<int> parts = geometricParts(comm, part.dim, share.ids, share.d.X, method, ranks);
  recs.clear();
  for (std::size_t i = 0; i < share.ids.size(); ++i) pack(recs, share.ids[i], share.d, i);
  return receiveSorted(*comm, part, recs, parts);
}

/// part's box becomes the body's: the particles' bounds over every rank's part (a rank without
/// particles adds nothing).
void takeBodyBox(const Teuchos::Comm<int>& comm, Discretization& part) {
  const bool any = !part.X.empty();
  double lo[3], hi[3], bodyLo[3], bodyHi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = any ? part.boxLower[a] : std::numeric_limits<double>::infinity();
    hi[a] = any ? -part.boxUpper[a] : std::numeric_limits<double>::infinity();
  }
  MPI_Allreduce(lo, bodyLo, 3, MPI_DOUBLE, MPI_MIN, rawComm(comm));
  MPI_Allreduce(hi, bodyHi, 3, MPI_DOUBLE, MPI_MIN, rawComm(comm));
  for (int a = 0; a < 3; ++a) part.boxLower[a] = bodyLo[a], part.boxUpper[a] = -bodyHi[a];
}

/// The k-th smallest (0-based) of the positive finite values every rank holds a part of, exactly
/// (collective): bisection on the values' bit patterns, which order positive doubles as integers,
/// counting over the ranks at each of at most 64 steps.
double kthSmallest(const Teuchos::Comm<int>& comm, const std::vector<double>& mine, long long k) {
  auto bits = [](double v) {
    std::int64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  std::int64_t top = 0, most = 0;
  for (double v : mine) top = std::max(top, bits(v));
  MPI_Allreduce(&top, &most, 1, MPI_INT64_T, MPI_MAX, rawComm(comm));
  std::int64_t lo = 0, hi = most;  // count(<= hi) > k; find the least such pattern
  while (lo < hi) {
    const std::int64_t mid = lo + (hi - lo) / 2;
    long long below = 0, all = 0;
    for (double v : mine) below += bits(v) <= mid;
    MPI_Allreduce(&below, &all, 1, MPI_LONG_LONG, MPI_SUM, rawComm(comm));
    if (all > k) hi = mid;
    else lo = mid + 1;
  }
  double v;
  std::memcpy(&v, &lo, sizeof v);
  return v;
}

/// 1-2 for a lattice: this rank's slab of lattice sites generated (ids and the jitter's random
/// stream continued by prefix sums of the slabs' counts), then partitioned. n: the lattice's size.
Share ownedShare(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const LatticeSpec& spec, PartitionMethod method,
                 long long& n) {
  const int ranks = comm->getSize(), rank = comm->getRank();
  const MPI_Comm mc = rawComm(*comm);
  const std::int64_t sites = latticeSiteCount(spec);
  const std::int64_t first = sites * rank / ranks, last = sites * (rank + 1) / ranks;
  const LatticeSiteCounts mine = countLatticeSites(spec, first, last);
  long long counts[2] = {mine.particles, mine.real}, before[2] = {0, 0}, total[2] = {0, 0};
  MPI_Exscan(counts, before, 2, MPI_LONG_LONG, MPI_SUM, mc);
  if (rank == 0) before[0] = before[1] = 0;  // MPI_Exscan leaves rank 0's result undefined
  MPI_Allreduce(counts, total, 2, MPI_LONG_LONG, MPI_SUM, mc);
  if (total[1] == 0) throw std::invalid_argument("no real particle left in the lattice after cutting the holes");
  n = total[0];
  return partitioned(comm, latticeSites(spec, first, last, before[1]), before[0], n, method);
}

/// 1-2 for a particle file: each rank reads the lines that start in its slice of the file's
/// bytes (the ids follow the file's order, by prefix sums of the slices' counts), then the
/// particles are partitioned. n: the file's particle count.
Share ownedShare(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const ParticleFileSpec& file,
                 PartitionMethod method, long long& n) {
  const int ranks = comm->getSize(), rank = comm->getRank();
  const MPI_Comm mc = rawComm(*comm);
  std::uint64_t size = 0, begin = 0, end = 0;
  long newlines = 0, lastLine = 0;
  throwAgreed<std::runtime_error>(*comm, [&] {
    size = particleFileSize(file.path);
    begin = size * static_cast<std::uint64_t>(rank) / static_cast<std::uint64_t>(ranks);
    end = size * static_cast<std::uint64_t>(rank + 1) / static_cast<std::uint64_t>(ranks);
    newlines = particleFileNewlines(file.path, begin, end);
  });
  long before = 0;
  MPI_Exscan(&newlines, &before, 1, MPI_LONG, MPI_SUM, mc);
  if (rank == 0) before = 0;
  Discretization part;
  throwAgreed<std::runtime_error>(*comm, [&] {
    part = readParticleFileRange(file.path, file.dim, file.horizon, file.dx, file.thickness, begin, end, before,
                                 &lastLine, file.columns);
  });
  long long mine = part.size(), first = 0;
  MPI_Exscan(&mine, &first, 1, MPI_LONG_LONG, MPI_SUM, mc);
  if (rank == 0) first = 0;
  MPI_Allreduce(&mine, &n, 1, MPI_LONG_LONG, MPI_SUM, mc);
  long lines = 0;
  MPI_Allreduce(&lastLine, &lines, 1, MPI_LONG, MPI_MAX, mc);
  if (n == 0) throw std::runtime_error(file.path + ":" + std::to_string(lines) + ": no particles in file");
  takeBodyBox(*comm, part);
  return partitioned(comm, part, first, n, method);
}

/// 3: owned + the particles other ranks own within `horizons` horizons of this rank's owned
/// bounding box (every rank's box is a small table of 2 x 3 numbers per rank), in id order.
Share withNeighbours(const Teuchos::Comm<int>& comm, const Share& owned, double horizons) {
  const int ranks = comm.getSize(), rank = comm.getRank();
  const Discretization& d = owned.d;
  const double reach = horizons * d.horizon * (1.0 + 1e-9);
  std::vector<double> box(6, 0.0), boxes(static_cast<std::size_t>(6 * ranks));
  for (int a = 0; a < 3; ++a) box[a] = box[3 + a] = d.X[0][a];
  for (const Vec3& x : d.X)
    for (int a = 0; a < 3; ++a) box[a] = std::min(box[a], x[a]), box[3 + a] = std::max(box[3 + a], x[a]);
  MPI_Allgather(box.data(), 6, MPI_DOUBLE, boxes.data(), 6, MPI_DOUBLE, rawComm(comm));
  std::vector<double> recs;
  std::vector<int> to;
  for (int q = 0; q < ranks; ++q) {
    const double* b = &boxes[static_cast<std::size_t>(6 * q)];
    for (std::size_t i = 0; i < owned.ids.size(); ++i) {
      bool inside = q != rank;
      for (int a = 0; a < d.dim; ++a) inside = inside && d.X[i][a] >= b[a] - reach && d.X[i][a] <= b[3 + a] + reach;
      if (inside) pack(recs, owned.ids[i], d, i), to.push_back(q);
    }
  }
  std::vector<double> all = exchange(comm, recs, kRecord, to);
  for (std::size_t i = 0; i < owned.ids.size(); ++i) pack(all, owned.ids[i], d, i);
  Share near{emptyLike(d), {}};
  unpackSorted(all, near.d, near.ids);
  return near;
}

}  // namespace

LocalLattice buildLocalLattice(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const LatticeSpec& spec,
                               PartitionMethod method) {
  LocalLattice out;
  const Share owned = ownedShare(comm, spec, method, out.globalCount);
  requireEveryRankOwns(*comm, owned.ids.size(), out.globalCount, method);
  // 4. Families: the cell-list search over owned + neighbours in id order (the whole lattice's
  //    distance test and family order), kept for the owned particles; the neighbours in an owned
  //    family are the ghosts.
  Share near = withNeighbours(*comm, owned, 1.0);
  buildFamilies(near.d);
  const Discretization& nd = near.d;
  std::vector<int> ownedNear;  // index in near of each owned particle
  for (std::size_t k = 0, o = 0; k < near.ids.size(); ++k)
    if (o < owned.ids.size() && near.ids[k] == owned.ids[o]) ownedNear.push_back(static_cast<int>(k)), ++o;
  std::vector<int> ghostNear;
  for (int k : ownedNear)
    for (auto q = nd.familyOffset[k]; q < nd.familyOffset[k + 1]; ++q)
      if (!std::binary_search(owned.ids.begin(), owned.ids.end(), near.ids[nd.familyIndex[q]]))
        ghostNear.push_back(nd.familyIndex[q]);
  std::sort(ghostNear.begin(), ghostNear.end());
  ghostNear.erase(std::unique(ghostNear.begin(), ghostNear.end()), ghostNear.end());
  std::vector<int> local = ownedNear, localOfNear(near.ids.size(), -1);
  local.insert(local.end(), ghostNear.begin(), ghostNear.end());
  LocalParticles& lp = out.particles;
  lp.dim = spec.dim;
  lp.numOwned = static_cast<int>(owned.ids.size());
  for (std::size_t l = 0; l < local.size(); ++l) {
    const int k = local[l];
    localOfNear[k] = static_cast<int>(l);
    lp.globalId.push_back(near.ids[k]);
    lp.X.push_back(nd.X[k]);
    lp.volume.push_back(nd.volume[k]);
    out.fictitious.push_back(nd.fictitious[k]);
    out.sideMask.push_back(nd.sideMask[k]);
    out.block.push_back(nd.block[k]);
  }
  lp.famOffset.push_back(0);
  for (int k : ownedNear) {
    for (auto q = nd.familyOffset[k]; q < nd.familyOffset[k + 1]; ++q) lp.famIndex.push_back(localOfNear[nd.familyIndex[q]]);
    lp.famOffset.push_back(static_cast<std::int64_t>(lp.famIndex.size()));
  }
  out.heldParticles = nd.X.size();
  out.heldBonds = static_cast<std::size_t>(nd.familyOffset.back());
  return out;
}

namespace {

/// The distributed problem of a rank's owned share (collective): the owned particles and those
/// within two horizons of them, loading arrays sized, nothing prescribed.
std::shared_ptr<ProblemSpec> problemOnShare(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, Share owned,
                                            long long globalCount, const MaterialSpec& material,
                                            PartitionMethod partition) {
  auto P = std::make_shared<ProblemSpec>();
  P->distributed = true;
  P->partition = partition;
  P->material = material;
  P->globalCount = globalCount;
  requireEveryRankOwns(*comm, owned.ids.size(), P->globalCount, partition);
  // Two horizons: the ghosts' families (the Jacobian graph's rows two horizons out) and the
  // cells of the lattice operator's owned nodes lie within them.
  Share near = withNeighbours(*comm, owned, 2.0);
  P->owned = std::move(owned.ids);
  P->disc = std::move(near.d);
  P->globalId = std::move(near.ids);
  const std::size_t n = P->disc.X.size(), D = static_cast<std::size_t>(P->disc.dim);
  P->fixedMask.assign(n, 0);
  P->prescribed.assign(n * D, 0.0);
  P->bodyForce.assign(n * D, 0.0);
  return P;
}

}  // namespace

namespace {

/// problemOnShare of the share ownedShare builds from spec (a lattice or a particle file).
template <class Spec>
std::shared_ptr<ProblemSpec> problemOnOwnedShare(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Spec& spec,
                                                 const MaterialSpec& material, PartitionMethod partition) {
  long long n = 0;
  Share owned = ownedShare(comm, spec, partition, n);
  return problemOnShare(comm, std::move(owned), n, material, partition);
}

}  // namespace

std::shared_ptr<ProblemSpec> problemOnLocalLattice(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                   const LatticeSpec& lattice, const MaterialSpec& material,
                                                   PartitionMethod partition) {
  return problemOnOwnedShare(comm, lattice, material, partition);
}

std::shared_ptr<ProblemSpec> problemOnLocalParticleFile(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                        const ParticleFileSpec& file, const MaterialSpec& material,
                                                        PartitionMethod partition) {
  return problemOnOwnedShare(comm, file, material, partition);
}

std::shared_ptr<ProblemSpec> problemOnLocalParticles(const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                                                     const Discretization& slab, long long firstId,
                                                     const MaterialSpec& material, PartitionMethod partition) {
  long long mine = slab.size(), n = 0, first = 0;
  const MPI_Comm mc = rawComm(*comm);
  MPI_Allreduce(&mine, &n, 1, MPI_LONG_LONG, MPI_SUM, mc);
  MPI_Exscan(&mine, &first, 1, MPI_LONG_LONG, MPI_SUM, mc);
  if (comm->getRank() == 0) first = 0;
  long long disagree = first != firstId, any = 0;
  MPI_Allreduce(&disagree, &any, 1, MPI_LONG_LONG, MPI_MAX, mc);
  if (any) throw std::invalid_argument("problemOnLocalParticles: the ranks' particles must have consecutive ids in rank order "
                                       "(a rank's firstId is the particle count of the ranks before it)");
  if (n == 0) throw std::invalid_argument("problemOnLocalParticles: no rank has particles");
  if (!(slab.horizon > 0)) throw std::invalid_argument("problemOnLocalParticles: the horizon must be positive");
  Discretization part = emptyLike(slab);
  part.X = slab.X, part.volume = slab.volume, part.block = slab.block;
  part.fictitious = slab.fictitious, part.sideMask = slab.sideMask;
  part.fictitious.resize(part.X.size(), 0), part.sideMask.resize(part.X.size(), 0), part.block.resize(part.X.size(), 0);
  if (part.volume.size() != part.X.size())
    throw std::invalid_argument("problemOnLocalParticles: the slab has " + std::to_string(part.X.size()) + " positions but " +
                                std::to_string(part.volume.size()) + " volumes");
  takeBodyBox(*comm, part);
  return problemOnShare(comm, partitioned(comm, part, firstId, n, partition), n, material, partition);
}

ExodusMesh readLocalExodusMesh(const Teuchos::Comm<int>& comm, const std::string& path, int dim, double thickness) {
  const int ranks = comm.getSize(), rank = comm.getRank();
  ExodusMeshSize size;
  throwAgreed<std::runtime_error>(comm, [&] { size = exodusMeshSize(path, dim); });
  const ExodusRange range{partitionBegin(size.elements, ranks, rank), partitionBegin(size.elements, ranks, rank + 1),
                          partitionBegin(size.nodes, ranks, rank), partitionBegin(size.nodes, ranks, rank + 1)};
  ExodusMesh mesh = readExodusMeshRange(path, dim, thickness, range, [&](const std::function<void()>& phase) {
    throwAgreed<std::runtime_error>(comm, phase);
  });
  takeBodyBox(comm, mesh.disc);
  mesh.disc.dx = meshSpacing(mesh.disc, kthSmallest(comm, mesh.disc.volume, size.elements / 2));
  return mesh;
}

std::vector<long long> heldMembers(const Teuchos::Comm<int>& comm, const std::vector<long long>& held, long long n,
                                   const std::vector<int>& slabMembers) {
  const int ranks = comm.getSize(), rank = comm.getRank();
  std::vector<double> asks;
  std::vector<int> to;
  for (long long id : held) asks.push_back(static_cast<double>(id)), asks.push_back(rank), to.push_back(slabOf(id, n, ranks));
  const std::vector<double> got = exchange(comm, asks, 2, to);
  std::vector<double> yes;
  to.clear();
  for (std::size_t k = 0; k + 1 < got.size(); k += 2)
    if (std::binary_search(slabMembers.begin(), slabMembers.end(), static_cast<int>(got[k])))
      yes.push_back(got[k]), to.push_back(static_cast<int>(got[k + 1]));
  std::vector<long long> members;
  for (double id : exchange(comm, yes, 1, to)) members.push_back(static_cast<long long>(id));
  std::sort(members.begin(), members.end());
  return members;
}

std::vector<double> exchangeRecords(const Teuchos::Comm<int>& comm, const std::vector<double>& values, int width,
                                    const std::vector<int>& to) {
  return exchange(comm, values, width, to);
}

int idSlabOf(long long id, long long n, int ranks) { return slabOf(id, n, ranks); }

}  // namespace perinox

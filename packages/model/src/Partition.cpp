#include "perinox/model/Partition.hpp"

#include <algorithm>
#include <numeric>
#include <optional>
#include <unordered_map>

namespace perinox {

const char* partitionName(PartitionMethod m) {
  switch (m) {
    case PartitionMethod::Rcb: return "RCB";
    case PartitionMethod::MultiJagged: return "Multi-Jagged";
    case PartitionMethod::Slabs: return "Slabs";
  }
  return "?";
}

bool parsePartition(const std::string& name, PartitionMethod& out) {
  for (PartitionMethod m : {PartitionMethod::Rcb, PartitionMethod::MultiJagged, PartitionMethod::Slabs})
    if (name == partitionName(m)) {
      out = m;
      return true;
    }
  return false;
}

long long partitionBegin(long long n, int nranks, int r) {
  return (n * static_cast<long long>(r)) / nranks;
}

namespace {

/// The particles of d within reach of the owned particles' bounding box (ids ascending) with
/// their families among themselves: complete for every particle within reach - delta of the box.
struct NearParticles {
  Discretization d;
  std::vector<long long> ids;  // global id of each
  int indexOf(long long g) const {
    return static_cast<int>(std::lower_bound(ids.begin(), ids.end(), g) - ids.begin());
  }
};

NearParticles particlesNear(const Discretization& d, const std::vector<long long>& owned, double reach) {
  NearParticles n;
  n.d.dim = d.dim;
  n.d.dx = d.dx;
  n.d.horizon = d.horizon;
  n.d.thickness = d.thickness;
  if (!owned.empty()) {
    Vec3 lo = d.X[owned.front()], hi = lo;
    for (long long i : owned) {
      lo = lo.cwiseMin(d.X[i]);
      hi = hi.cwiseMax(d.X[i]);
    }
    for (int i = 0; i < d.size(); ++i) {
      bool inside = true;
      for (int a = 0; a < d.dim && inside; ++a) inside = d.X[i][a] >= lo[a] - reach && d.X[i][a] <= hi[a] + reach;
      if (!inside) continue;
      n.ids.push_back(i);
      n.d.X.push_back(d.X[i]);
    }
  }
  buildFamilies(n.d);
  return n;
}

/// Family of global particle g (ascending global ids): from d's families, or from near's.
template <class F>
void forFamily(const Discretization& d, const NearParticles* near, long long g, F&& f) {
  if (!near) {
    for (auto q = d.familyOffset[g]; q < d.familyOffset[g + 1]; ++q) f(static_cast<long long>(d.familyIndex[q]));
    return;
  }
  const int k = near->indexOf(g);
  for (auto q = near->d.familyOffset[k]; q < near->d.familyOffset[k + 1]; ++q) f(near->ids[near->d.familyIndex[q]]);
}

}  // namespace

LocalParticles localParticles(const Discretization& d, const std::vector<long long>& owned, LocalFamilies* families) {
  // Without families on d: a neighbour's family reaches two horizons from an owned particle
  // (margin: buildFamilies' own tolerance is 1e-12 of delta).
  std::optional<NearParticles> near;
  if (d.familyOffset.empty()) near = particlesNear(d, owned, 2.0 * d.horizon * (1.0 + 1e-9));
  const NearParticles* np = near ? &*near : nullptr;
  LocalParticles p;
  p.dim = d.dim;
  p.numOwned = static_cast<int>(owned.size());
  p.globalId = owned;
  std::unordered_map<long long, int> local;
  local.reserve(owned.size() * 2 + 1);
  for (int l = 0; l < p.numOwned; ++l) local[owned[l]] = l;
  std::vector<long long> ghosts;
  for (long long i : owned)
    forFamily(d, np, i, [&](long long j) {
      if (!local.count(j)) ghosts.push_back(j);
    });
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  for (long long g : ghosts) {
    local[g] = static_cast<int>(p.globalId.size());
    p.globalId.push_back(g);
  }
  for (long long g : p.globalId) {
    p.X.push_back(d.X[g]);
    p.volume.push_back(d.volume[g]);
  }
  p.famOffset.push_back(0);
  for (long long i : owned) {
    forFamily(d, np, i, [&](long long j) { p.famIndex.push_back(local.at(j)); });
    p.famOffset.push_back(static_cast<std::int64_t>(p.famIndex.size()));
  }
  if (families) {
    *families = LocalFamilies{};
    families->ownedOffset = p.famOffset;
    families->ownedIndex = p.famIndex;
    for (std::size_t l = owned.size(); l < p.globalId.size(); ++l) {
      forFamily(d, np, p.globalId[l], [&](long long j) { families->ghostMembers.push_back(j); });
      families->ghostOffset.push_back(static_cast<std::int64_t>(families->ghostMembers.size()));
    }
  }
  return p;
}

LocalParticles localParticles(const Discretization& d, long long begin, long long end) {
  std::vector<long long> owned(static_cast<std::size_t>(end - begin));
  std::iota(owned.begin(), owned.end(), begin);
  return localParticles(d, owned);
}

std::vector<long long> ghostCounts(const Discretization& d, const std::vector<int>& part, int parts) {
  // A ghost of part q is a particle of another part in the family of one of q's particles;
  // counted once per (part, particle) pair.
  std::vector<long long> count(static_cast<std::size_t>(parts), 0);
  std::vector<int> seenBy(static_cast<std::size_t>(d.size()), -1);
  std::vector<std::vector<int>> members(static_cast<std::size_t>(parts));
  for (int i = 0; i < d.size(); ++i) members[part[i]].push_back(i);
  for (int q = 0; q < parts; ++q)
    for (int i : members[q])
      for (auto k = d.familyOffset[i]; k < d.familyOffset[i + 1]; ++k) {
        const int j = d.familyIndex[k];
        if (part[j] != q && seenBy[j] != q) {
          seenBy[j] = q;
          ++count[q];
        }
      }
  return count;
}

}  // namespace perinox

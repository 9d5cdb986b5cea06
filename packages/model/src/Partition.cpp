#include "perinox/model/Partition.hpp"

#include <algorithm>
#include <numeric>
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

LocalParticles localParticles(const Discretization& d, const std::vector<long long>& owned) {
  LocalParticles p;
  p.dim = d.dim;
  p.numOwned = static_cast<int>(owned.size());
  p.globalId = owned;
  std::unordered_map<long long, int> local;
  local.reserve(owned.size() * 2 + 1);
  for (int l = 0; l < p.numOwned; ++l) local[owned[l]] = l;
  std::vector<long long> ghosts;
  for (long long i : owned)
    for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q)
      if (!local.count(d.familyIndex[q])) ghosts.push_back(d.familyIndex[q]);
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
    for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q) p.famIndex.push_back(local.at(d.familyIndex[q]));
    p.famOffset.push_back(static_cast<std::int64_t>(p.famIndex.size()));
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

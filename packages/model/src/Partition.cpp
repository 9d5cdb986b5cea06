#include "perinox/model/Partition.hpp"

#include <algorithm>
#include <unordered_map>

namespace perinox {

long long partitionBegin(long long n, int nranks, int r) {
  return (n * static_cast<long long>(r)) / nranks;
}

LocalParticles localParticles(const Discretization& d, long long begin, long long end) {
  LocalParticles p;
  p.dim = d.dim;
  p.numOwned = static_cast<int>(end - begin);
  std::vector<long long> ghosts;
  for (long long i = begin; i < end; ++i)
    for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q) {
      const long long j = d.familyIndex[q];
      if (j < begin || j >= end) ghosts.push_back(j);
    }
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  for (long long i = begin; i < end; ++i) p.globalId.push_back(i);
  p.globalId.insert(p.globalId.end(), ghosts.begin(), ghosts.end());
  std::unordered_map<long long, int> local;
  local.reserve(ghosts.size() * 2 + 1);
  for (int l = p.numOwned; l < static_cast<int>(p.globalId.size()); ++l) local[p.globalId[l]] = l;
  for (long long g : p.globalId) {
    p.X.push_back(d.X[g]);
    p.volume.push_back(d.volume[g]);
  }
  p.famOffset.push_back(0);
  for (long long i = begin; i < end; ++i) {
    for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q) {
      const long long j = d.familyIndex[q];
      p.famIndex.push_back(j >= begin && j < end ? static_cast<int>(j - begin) : local.at(j));
    }
    p.famOffset.push_back(static_cast<std::int64_t>(p.famIndex.size()));
  }
  return p;
}

}  // namespace perinox

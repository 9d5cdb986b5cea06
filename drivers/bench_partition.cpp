// bench_partition: how the particles of a scene split among ranks, by partition method: owned
// and ghost particles per part (ghosts: family members owned by another part, what a rank
// receives in every halo exchange) and the time to partition. Parts are computed on one process,
// so any part count can be measured on this 2-core machine (Zoltan2 gives the same geometric
// cuts whether it runs on p ranks or computes p parts on one). docs/performance.md.
//
//   bench_partition SCENE.xml [--set Key=value]... [--parts 1,2,4,8,16]
#include <Tpetra_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "perinox/evaluator/Partitioner.hpp"
#include "perinox/io/Scene.hpp"

using namespace perinox;

constexpr const char* kUsage = "usage: bench_partition SCENE.xml [--set Key=value]... [--parts 1,2,4,8,16]\n";

int main(int argc, char** argv) {
  Tpetra::ScopeGuard tpetra(&argc, &argv);  // MPI and Kokkos, which Zoltan2 uses
  std::vector<std::string> overrides;
  std::vector<int> parts{1, 2, 4, 8, 16};
  std::string scenePath;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) {
      overrides.push_back(argv[++i]);
    } else if (a == "--parts" && i + 1 < argc) {
      parts.clear();
      std::stringstream list(argv[++i]);
      for (std::string t; std::getline(list, t, ',');) parts.push_back(std::stoi(t));
    } else if (scenePath.empty() && a.rfind("--", 0) != 0) {
      scenePath = a;
    } else {
      std::cerr << kUsage;
      return 2;
    }
  }
  if (scenePath.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    const Scene scene = loadScene(scenePath, overrides, std::string(PERINOX_SOURCE_DIR) + "/xml/solvers");
    Discretization d = scene.problem->disc;
    buildFamilies(d);  // a scene leaves them to the evaluator; the ghost counts need all of them
    std::int64_t bonds = d.familyOffset.back();
    std::printf("# %s: %d particles, %lld bonds, dim %d\n", scenePath.c_str(), d.size(), static_cast<long long>(bonds), d.dim);
    std::printf("%-13s %5s %10s %10s %10s %10s %9s %10s\n", "method", "parts", "owned_max", "ghosts_max", "ghosts_mean",
                "ghost/own", "imbalance", "seconds");
    for (PartitionMethod m : {PartitionMethod::Slabs, PartitionMethod::Rcb, PartitionMethod::MultiJagged})
      for (int p : parts) {
        const auto t0 = std::chrono::steady_clock::now();
        const std::vector<int> part = partsOf(d, m, p);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::vector<long long> owned(static_cast<std::size_t>(p), 0);
        for (int q : part) ++owned[q];
        const auto ghosts = ghostCounts(d, part, p);
        const long long ownedMax = *std::max_element(owned.begin(), owned.end());
        const long long ghostMax = *std::max_element(ghosts.begin(), ghosts.end());
        const double ghostMean = std::accumulate(ghosts.begin(), ghosts.end(), 0.0) / p;
        const double mean = static_cast<double>(d.size()) / p;
        std::printf("%-13s %5d %10lld %10lld %10.1f %10.3f %9.3f %10.3f\n", partitionName(m), p, ownedMax, ghostMax, ghostMean,
                    static_cast<double>(ghostMax) / ownedMax, ownedMax / mean, seconds);
      }
  } catch (const std::exception& e) {
    std::cerr << "bench_partition: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

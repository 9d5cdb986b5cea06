// Performance sanity: a 1000 x 1000 lattice with its families builds in seconds. Not a timed
// assertion (the machine is shared); the time is printed for the record.
#include "perinox/core/Discretization.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <iostream>

using namespace perinox;

TEST(Performance, MillionParticleLattice2d) {
  LatticeSpec s;
  s.dim = 2;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(1, 1, 0);
  s.counts = {{1000, 1000, 1}};
  s.horizonFactor = 1.015;
  const auto t0 = std::chrono::steady_clock::now();
  const Discretization d = buildLattice(s);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "buildLattice 1000x1000 (1e6 particles, 4-neighbour families): " << seconds << " s\n";
  ASSERT_EQ(d.size(), 1000000);
  // Nearest-neighbour bonds: 2 * 1000 * 999 undirected, each stored twice.
  EXPECT_EQ(d.familyIndex.size(), 2u * 2u * 1000u * 999u);
  EXPECT_EQ(d.familySize(500 * 1000 + 500), 4);
  EXPECT_EQ(d.familySize(0), 2);
}

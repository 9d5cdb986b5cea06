// Families: sizes on lattices, symmetry, and agreement with an O(n^2) brute-force search.
#include "perinox/core/Discretization.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace perinox;

namespace {

/// Cubic lattice of n^dim unit cells centred at the origin (odd n: a particle sits at 0).
Discretization cube(int dim, int n, double horizonFactor) {
  LatticeSpec s;
  s.dim = dim;
  s.lower = Vec3::Zero();
  s.upper = Vec3::Zero();
  for (int a = 0; a < dim; ++a) {
    s.lower[a] = -0.5 * n;
    s.upper[a] = 0.5 * n;
    s.counts[a] = n;
  }
  s.horizonFactor = horizonFactor;
  return buildLattice(s);
}

/// Number of points v != 0 of Z^dim with |v| <= r.
int latticeBallCount(int dim, double r) {
  const int m = static_cast<int>(r) + 1;
  int count = 0;
  for (int i = -m; i <= m; ++i)
    for (int j = (dim > 1 ? -m : 0); j <= (dim > 1 ? m : 0); ++j)
      for (int k = (dim > 2 ? -m : 0); k <= (dim > 2 ? m : 0); ++k)
        if ((i || j || k) && i * i + j * j + k * k <= r * r) ++count;
  return count;
}

int interiorFamilySize(int dim, int n, double hf) {
  const Discretization d = cube(dim, n, hf);
  const int c = selectNearest(d, Vec3::Zero(), Population::All);
  EXPECT_NEAR(d.X[c].norm(), 0.0, 1e-12);
  return d.familySize(c);
}

/// Families by checking all pairs, with the same inclusion rule as the contract.
std::vector<std::vector<int>> bruteForce(const Discretization& d) {
  const double r = d.horizon * (1 + 1e-12);
  std::vector<std::vector<int>> fam(d.size());
  for (int i = 0; i < d.size(); ++i)
    for (int j = 0; j < d.size(); ++j)
      if (j != i && (d.X[j] - d.X[i]).squaredNorm() <= r * r) fam[i].push_back(j);
  return fam;
}

void expectSameAsBruteForce(const Discretization& d) {
  const auto ref = bruteForce(d);
  ASSERT_EQ(d.familyOffset.size(), static_cast<std::size_t>(d.size()) + 1);
  ASSERT_EQ(d.familyOffset.front(), 0);
  std::size_t total = 0;
  for (int i = 0; i < d.size(); ++i) {
    const std::vector<int> got(d.familyIndex.begin() + d.familyOffset[i],
                               d.familyIndex.begin() + d.familyOffset[i + 1]);
    ASSERT_EQ(got, ref[i]) << "family of particle " << i;
    total += ref[i].size();
  }
  EXPECT_EQ(d.familyIndex.size(), total);
}

void expectSymmetricSortedNoSelf(const Discretization& d) {
  for (int i = 0; i < d.size(); ++i) {
    const auto b = d.familyIndex.begin() + d.familyOffset[i];
    const auto e = d.familyIndex.begin() + d.familyOffset[i + 1];
    ASSERT_TRUE(std::is_sorted(b, e));
    ASSERT_EQ(std::adjacent_find(b, e), e);  // no duplicates
    for (auto it = b; it != e; ++it) {
      const int j = *it;
      ASSERT_NE(j, i);
      const auto bj = d.familyIndex.begin() + d.familyOffset[j];
      const auto ej = d.familyIndex.begin() + d.familyOffset[j + 1];
      ASSERT_TRUE(std::binary_search(bj, ej, i)) << i << " in H_" << j << " missing";
    }
  }
}

Discretization randomCloud(int dim, int n, double extent, double horizon, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(0.0, extent);
  Discretization d;
  d.dim = dim;
  d.dx = extent / std::pow(n, 1.0 / dim);
  d.horizon = horizon;
  for (int i = 0; i < n; ++i) {
    Vec3 x = Vec3::Zero();
    for (int a = 0; a < dim; ++a) x[a] = u(gen);
    d.X.push_back(x);
  }
  d.volume.assign(n, 1.0);
  d.fictitious.assign(n, 0);
  d.sideMask.assign(n, 0);
  d.block.assign(n, 1);
  buildFamilies(d);
  return d;
}

}  // namespace

TEST(Families, BruteForceBallCountsSanity) {
  EXPECT_EQ(latticeBallCount(2, 1.015), 4);
  EXPECT_EQ(latticeBallCount(2, 2.015), 12);
  EXPECT_EQ(latticeBallCount(2, 3.015), 28);
  EXPECT_EQ(latticeBallCount(1, 3.015), 6);
}

TEST(Families, InteriorSizes2d) {
  EXPECT_EQ(interiorFamilySize(2, 11, 1.015), 4);
  EXPECT_EQ(interiorFamilySize(2, 11, 2.015), 12);
  EXPECT_EQ(interiorFamilySize(2, 11, 3.015), 28);
  // Integer factors: neighbours exactly on the horizon are included despite rounding.
  EXPECT_EQ(interiorFamilySize(2, 11, 1.0), 4);
  EXPECT_EQ(interiorFamilySize(2, 11, 2.0), latticeBallCount(2, 2.0));
}

TEST(Families, InteriorSizes3d) {
  EXPECT_EQ(interiorFamilySize(3, 7, 1.015), 6);
  const int expected = latticeBallCount(3, 2.015);
  EXPECT_EQ(expected, 32);  // 6 + 12 + 8 + 6: the brute force agrees with the hand count
  EXPECT_EQ(interiorFamilySize(3, 7, 2.015), expected);
  EXPECT_EQ(interiorFamilySize(3, 9, 3.015), latticeBallCount(3, 3.015));
}

TEST(Families, InteriorSizes1d) { EXPECT_EQ(interiorFamilySize(1, 11, 3.015), 6); }

TEST(Families, NeighbourOnHorizonSurvivesRounding) {
  // On [0.3, 1.3] with dx = 0.1 some computed distances of 2 dx exceed 2 * dx by a few ulps;
  // the relative tolerance 1e-12 of the contract must still include them.
  LatticeSpec s;
  s.dim = 1;
  s.lower = Vec3(0.3, 0, 0);
  s.upper = Vec3(1.3, 0, 0);
  s.counts = {{10, 1, 1}};
  s.horizonFactor = 2.0;
  const Discretization d = buildLattice(s);
  for (int i = 2; i < 8; ++i) EXPECT_EQ(d.familySize(i), 4) << "particle " << i;
}

TEST(Families, LatticeWithLayersAndHoleMatchesBruteForce) {
  LatticeSpec s;
  s.dim = 2;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(3, 2, 0);
  s.counts = {{30, 20, 1}};
  s.horizonFactor = 3.015;
  s.fictitiousSides = {Side::XMin, Side::YMax};
  Hole h;
  h.center = Vec3(1.5, 1.0, 0);
  h.radius = 0.4;
  s.holes = {h};
  s.jitter = 0.5;
  const Discretization d = buildLattice(s);
  expectSameAsBruteForce(d);
  expectSymmetricSortedNoSelf(d);
}

TEST(Families, Jittered3dLatticeMatchesBruteForce) {
  LatticeSpec s;
  s.dim = 3;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(8, 6, 5);
  s.counts = {{8, 6, 5}};
  s.horizonFactor = 2.015;
  s.fictitiousSides = {Side::ZMin, Side::XMax};
  s.jitter = 0.8;
  const Discretization d = buildLattice(s);
  expectSameAsBruteForce(d);
  expectSymmetricSortedNoSelf(d);
}

TEST(Families, RandomCloudsMatchBruteForce) {
  expectSameAsBruteForce(randomCloud(1, 500, 10.0, 0.2, 1));
  expectSameAsBruteForce(randomCloud(2, 2000, 10.0, 0.6, 2));
  expectSameAsBruteForce(randomCloud(3, 2000, 10.0, 1.3, 3));
  expectSymmetricSortedNoSelf(randomCloud(3, 2000, 10.0, 1.3, 3));
}

TEST(Families, SparseClustersMatchBruteForce) {
  // Two tight clusters a million horizons apart: the grid must not allocate a cell per horizon.
  Discretization d = randomCloud(2, 400, 1.0, 0.1, 4);
  for (int i = 200; i < 400; ++i) d.X[i] += Vec3(1e5, -3e4, 0);
  buildFamilies(d);
  expectSameAsBruteForce(d);
}

TEST(Families, RebuildAndEdgeCases) {
  Discretization d = randomCloud(2, 300, 5.0, 0.5, 5);
  d.horizon = 1.0;  // rebuild with a larger horizon replaces the old families
  buildFamilies(d);
  expectSameAsBruteForce(d);

  Discretization one;
  one.dim = 3;
  one.horizon = 1.0;
  one.X = {Vec3(1, 2, 3)};
  buildFamilies(one);
  EXPECT_EQ(one.familyOffset, (std::vector<std::int64_t>{0, 0}));

  Discretization same;  // coincident particles are neighbours at distance 0
  same.dim = 2;
  same.horizon = 0.1;
  same.X = {Vec3(1, 1, 0), Vec3(1, 1, 0)};
  buildFamilies(same);
  EXPECT_EQ(same.familyIndex, (std::vector<int>{1, 0}));

  one.horizon = 0.0;
  EXPECT_THROW(buildFamilies(one), std::invalid_argument);
}

// Region selection on lattices: boxes, side layers, fictitious layers, nearest particle.
#include "perinox/core/Discretization.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

using namespace perinox;

namespace {

LatticeSpec bar2d() {  // [0,10] x [0,1], 50 x 5 cells, dx = 0.2
  LatticeSpec s;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(10, 1, 0);
  s.counts = {{50, 5, 1}};
  s.horizonFactor = 2.015;
  return s;
}

}  // namespace

TEST(Regions, SideLayerIsLastColumn) {
  LatticeSpec s = bar2d();
  s.fictitiousSides = {Side::XMin, Side::XMax};  // fictitious particles are never in a side layer
  const Discretization d = buildLattice(s);
  const auto ids = selectSideLayer(d, Side::XMax, d.dx);
  ASSERT_EQ(ids.size(), 5u);
  for (int i : ids) {
    EXPECT_FALSE(d.fictitious[i]);
    EXPECT_NEAR(d.X[i].x(), 9.9, 1e-12);
  }
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_EQ(selectSideLayer(d, Side::XMin, d.dx).size(), 5u);
  EXPECT_EQ(selectSideLayer(d, Side::YMin, d.dx).size(), 50u);
  EXPECT_EQ(selectSideLayer(d, Side::YMax, 2 * d.dx).size(), 100u);
  EXPECT_THROW(selectSideLayer(d, Side::ZMax, d.dx), std::invalid_argument);
}

TEST(Regions, NearestToFreeEndMidHeight) {
  const Discretization d = buildLattice(bar2d());
  const int i = selectNearest(d, Vec3(10, 0.5, 0), Population::Real);
  ASSERT_GE(i, 0);
  EXPECT_NEAR(d.X[i].x(), 9.9, 1e-12);
  EXPECT_NEAR(d.X[i].y(), 0.5, 1e-12);
  EXPECT_EQ(i, 2 * 50 + 49);
  EXPECT_EQ(selectNearest(d, Vec3(10, 0.5, 0), Population::Fictitious), -1);  // none exist
}

TEST(Regions, NearestTieGoesToTheSmallestPositionWhateverTheOrder) {
  // (0.5, 0) is equally near (0, 0) and (1, 0): the tie goes to the smaller x, in either order.
  Discretization d;
  d.dim = 2;
  d.dx = 1;
  d.X = {Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(5, 5, 0)};
  d.fictitious = {0, 0, 1};
  d.sideMask = {0, 0, 1};
  EXPECT_EQ(selectNearest(d, Vec3(0.5, 0, 0), Population::All), 1);
  d.X = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(5, 5, 0)};
  EXPECT_EQ(selectNearest(d, Vec3(0.5, 0, 0), Population::All), 0);
  EXPECT_EQ(selectNearest(d, Vec3(0.5, 0, 0), Population::Fictitious), 2);
  // Equal x: the smaller y; a distance that differs only by round-off (0.1 + 0.2 against 0.3) still ties.
  d.X = {Vec3(0.3, 1, 0), Vec3(0.3, -1, 0), Vec3(5, 5, 0)};
  EXPECT_EQ(selectNearest(d, Vec3(0.3, 0, 0), Population::All), 1);
  d.X = {Vec3(0.1 + 0.2, 0, 0), Vec3(-0.3, 0, 0), Vec3(5, 5, 0)};
  EXPECT_EQ(selectNearest(d, Vec3(0, 0, 0), Population::All), 1);
  // A particle nearer by more than the tie tolerance wins whatever its position.
  d.X = {Vec3(0.3, 0, 0), Vec3(-0.3 - 1e-6, 0, 0), Vec3(5, 5, 0)};
  EXPECT_EQ(selectNearest(d, Vec3(0, 0, 0), Population::All), 0);
  // Unused axes of the query point are ignored in 2D.
  d.X = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(5, 5, 0)};
  EXPECT_EQ(selectNearest(d, Vec3(4.9, 4.9, 100), Population::Real), 1);
  // A caller holding part of a body passes the nearest distance over all parts: a part whose own
  // particles are all farther has no candidate.
  EXPECT_EQ(selectNearest(d, Vec3(0.5, 0, 0), Population::All, 0.1), -1);
  EXPECT_DOUBLE_EQ(nearestDistance(d, Vec3(0.5, 0, 0), Population::All), 0.5);
}

TEST(Regions, BoxIsClosedAndFiltersPopulation) {
  LatticeSpec s = bar2d();
  s.fictitiousSides = {Side::XMin};
  const Discretization d = buildLattice(s);
  // Faces exactly through particle centres are included (x = 0.1 and 0.5, y = 0.1 .. 0.9).
  const auto real = selectBox(d, Vec3(0.1, 0.1, -1), Vec3(0.5, 0.9, 1), Population::Real);
  EXPECT_EQ(real.size(), 3u * 5u);
  const auto fict = selectBox(d, Vec3(-1, -1, 0), Vec3(0.5, 2, 0), Population::Fictitious);
  EXPECT_EQ(fict.size(), 10u);
  const auto all = selectBox(d, Vec3(-1, -1, 0), Vec3(0.5, 2, 0), Population::All);
  EXPECT_EQ(all.size(), 10u + 15u);
  EXPECT_TRUE(std::is_sorted(all.begin(), all.end()));
  // z is unused in 2D: a box with any z range selects by x and y only.
  EXPECT_EQ(selectBox(d, Vec3(0.1, 0.1, 7), Vec3(0.5, 0.9, 8), Population::Real), real);
}

TEST(Regions, BoxToleratesRoundedCentres) {
  // With dx = 0.1 the centre of column 3 is computed as 0.35000000000000003: a box face given
  // as 0.35 must still include it.
  LatticeSpec s;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(2, 1, 0);
  s.counts = {{20, 10, 1}};
  s.horizonFactor = 1.5;
  const Discretization d = buildLattice(s);
  EXPECT_EQ(selectBox(d, Vec3(0.15, 0, 0), Vec3(0.35, 1, 0), Population::Real).size(), 30u);
}

TEST(Regions, FictitiousSidesIncludeCorners) {
  LatticeSpec s = bar2d();
  s.fictitiousSides = {Side::XMin, Side::YMin};
  const Discretization d = buildLattice(s);
  const auto xs = selectFictitiousSide(d, Side::XMin);
  const auto ys = selectFictitiousSide(d, Side::YMin);
  EXPECT_EQ(xs.size(), 2u * 7u);   // 2 columns over 5 + 2 rows
  EXPECT_EQ(ys.size(), 2u * 52u);  // 2 rows over 50 + 2 columns
  EXPECT_TRUE(selectFictitiousSide(d, Side::XMax).empty());
  for (int i : xs) EXPECT_LT(d.X[i].x(), 0.0);
  EXPECT_THROW(selectFictitiousSide(d, Side::ZMin), std::invalid_argument);
}

// Lattice construction: counts, positions, volumes, fictitious layers, holes, jitter, errors.
#include "perinox/core/Discretization.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

using namespace perinox;

namespace {

/// The 2D bar used throughout: [0,10] x [0,1], 50 x 5 cells, dx = 0.2, thickness 0.5.
LatticeSpec bar2d(double horizonFactor = 3.015) {
  LatticeSpec s;
  s.dim = 2;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(10, 1, 0);
  s.counts = {{50, 5, 1}};
  s.thickness = 0.5;
  s.horizonFactor = horizonFactor;
  return s;
}

int countFictitious(const Discretization& d) {
  int n = 0;
  for (auto f : d.fictitious) n += f;
  return n;
}

/// Expects `f` to throw std::invalid_argument whose message contains `word`.
template <class F>
void expectInvalid(F f, const std::string& word) {
  try {
    f();
    ADD_FAILURE() << "expected std::invalid_argument mentioning '" << word << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << "message: " << e.what();
  }
}

}  // namespace

TEST(Sides, NamesRoundTrip) {
  for (int i = 0; i < 6; ++i) {
    Side s = Side::XMin, parsed = Side::ZMax;
    s = static_cast<Side>(i);
    ASSERT_TRUE(parseSide(sideName(s), parsed));
    EXPECT_EQ(parsed, s);
  }
  Side out = Side::YMax;
  EXPECT_STREQ(sideName(Side::XMin), "xmin");
  EXPECT_STREQ(sideName(Side::ZMax), "zmax");
  EXPECT_TRUE(parseSide("XMax", out));
  EXPECT_EQ(out, Side::XMax);
  EXPECT_FALSE(parseSide("left", out));
  EXPECT_EQ(out, Side::XMax);  // untouched on failure
}

TEST(Lattice, Bar2dCountsPositionsVolumes) {
  const Discretization d = buildLattice(bar2d());
  const double dx = 0.2;
  ASSERT_EQ(d.size(), 250);
  EXPECT_EQ(d.dim, 2);
  EXPECT_NEAR(d.dx, dx, 1e-14);
  EXPECT_NEAR(d.horizon, 3.015 * dx, 1e-14);
  EXPECT_EQ(countFictitious(d), 0);
  for (int iy = 0; iy < 5; ++iy)
    for (int ix = 0; ix < 50; ++ix) {
      const int id = iy * 50 + ix;  // x fastest
      EXPECT_NEAR(d.X[id].x(), (ix + 0.5) * dx, 1e-12);
      EXPECT_NEAR(d.X[id].y(), (iy + 0.5) * dx, 1e-12);
      EXPECT_EQ(d.X[id].z(), 0.0);
      EXPECT_NEAR(d.volume[id], dx * dx * 0.5, 1e-15);
      EXPECT_EQ(d.block[id], 1);
      EXPECT_EQ(d.sideMask[id], 0);
    }
  EXPECT_EQ(d.boxLower, Vec3(0, 0, 0));
  EXPECT_EQ(d.boxUpper, Vec3(10, 1, 0));
  ASSERT_EQ(d.familyOffset.size(), 251u);
  EXPECT_EQ(d.familyOffset.back(), static_cast<std::int64_t>(d.familyIndex.size()));
}

TEST(Lattice, FictitiousXMinAddsTwoColumns) {
  LatticeSpec s = bar2d(2.015);
  s.fictitiousSides = {Side::XMin};
  const Discretization d = buildLattice(s);
  ASSERT_EQ(d.size(), 260);
  EXPECT_EQ(countFictitious(d), 10);
  for (int i = 0; i < d.size(); ++i) {
    if (d.fictitious[i]) {
      EXPECT_LT(d.X[i].x(), 0.0);
      EXPECT_EQ(d.sideMask[i], 1u << static_cast<int>(Side::XMin));
      const double x = d.X[i].x();
      EXPECT_TRUE(std::abs(x + 0.1) < 1e-12 || std::abs(x + 0.3) < 1e-12) << x;
    } else {
      EXPECT_GT(d.X[i].x(), 0.0);
      EXPECT_EQ(d.sideMask[i], 0);
    }
  }
  // Row-major order: every row of 52 starts with the two fictitious columns.
  for (int iy = 0; iy < 5; ++iy) {
    EXPECT_TRUE(d.fictitious[iy * 52] && d.fictitious[iy * 52 + 1]);
    EXPECT_NEAR(d.X[iy * 52].x(), -0.3, 1e-12);
    EXPECT_FALSE(d.fictitious[iy * 52 + 2]);
  }
  // The real body's box does not include the fictitious layer.
  EXPECT_EQ(d.boxLower, Vec3(0, 0, 0));
  // Fictitious particles have the lattice volume too.
  EXPECT_NEAR(d.volume[0], 0.2 * 0.2 * 0.5, 1e-15);
}

TEST(Lattice, FictitiousCornersAndMasks) {
  LatticeSpec s = bar2d(2.015);
  s.fictitiousSides = {Side::XMin, Side::YMin};
  const Discretization d = buildLattice(s);
  EXPECT_EQ(d.size(), 52 * 7);
  EXPECT_EQ(countFictitious(d), 52 * 7 - 250);
  const unsigned xmin = 1u << 0, ymin = 1u << 2;
  int corners = 0, onlyX = 0, onlyY = 0;
  for (int i = 0; i < d.size(); ++i) {
    if (!d.fictitious[i]) continue;
    const bool bx = d.X[i].x() < 0, by = d.X[i].y() < 0;
    EXPECT_EQ((d.sideMask[i] & xmin) != 0, bx);
    EXPECT_EQ((d.sideMask[i] & ymin) != 0, by);
    corners += bx && by;
    onlyX += bx && !by;
    onlyY += by && !bx;
  }
  EXPECT_EQ(corners, 4);
  EXPECT_EQ(onlyX, 10);
  EXPECT_EQ(onlyY, 100);
  // The corner site nearest the origin exists.
  const int c = selectNearest(d, Vec3(-0.1, -0.1, 0), Population::All);
  ASSERT_GE(c, 0);
  EXPECT_NEAR((d.X[c] - Vec3(-0.1, -0.1, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(d.sideMask[c], xmin | ymin);
  // First id is the far corner (-0.3, -0.3): ordering over the extended lattice.
  EXPECT_NEAR(d.X[0].x(), -0.3, 1e-12);
  EXPECT_NEAR(d.X[0].y(), -0.3, 1e-12);
}

TEST(Lattice, OrderIsLexicographicZYX) {
  LatticeSpec s;
  s.dim = 3;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(4, 3, 2);
  s.counts = {{4, 3, 2}};
  s.horizonFactor = 1.5;
  s.fictitiousSides = {Side::XMax, Side::ZMin};
  const Discretization d = buildLattice(s);
  EXPECT_EQ(d.size(), 5 * 3 * 3);
  for (int i = 1; i < d.size(); ++i) {
    const Vec3& p = d.X[i - 1];
    const Vec3& q = d.X[i];
    const bool less = p.z() < q.z() || (p.z() == q.z() && (p.y() < q.y() || (p.y() == q.y() && p.x() < q.x())));
    EXPECT_TRUE(less) << "ids " << i - 1 << ", " << i;
  }
  for (int i = 0; i < d.size(); ++i) EXPECT_NEAR(d.volume[i], 1.0, 1e-15);  // dx^3
}

TEST(Lattice, OneDimensional) {
  LatticeSpec s;
  s.dim = 1;
  s.lower = Vec3(-1, 7, 7);  // unused axes ignored and zeroed
  s.upper = Vec3(1, 9, 9);
  s.counts = {{10, 0, 0}};   // unused counts are not checked
  s.thickness = 3.0;         // cross-section area
  s.horizonFactor = 3.015;
  s.fictitiousSides = {Side::XMin, Side::XMax};
  const Discretization d = buildLattice(s);
  EXPECT_EQ(d.size(), 16);
  EXPECT_EQ(countFictitious(d), 6);
  for (int i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d.X[i].x(), -1 + (i - 3 + 0.5) * 0.2, 1e-12);
    EXPECT_EQ(d.X[i].y(), 0.0);
    EXPECT_NEAR(d.volume[i], 0.2 * 3.0, 1e-15);
  }
  EXPECT_EQ(d.boxLower, Vec3(-1, 0, 0));
  EXPECT_EQ(d.sideMask[0], 1u);
  EXPECT_EQ(d.sideMask[15], 2u);
}

TEST(Lattice, CircularHoleBruteForce) {
  LatticeSpec s;
  s.dim = 2;
  s.lower = Vec3(-75, -25, 0);
  s.upper = Vec3(75, 25, 0);
  s.counts = {{30, 10, 1}};
  s.horizonFactor = 3.015;
  s.fictitiousSides = {Side::XMin};
  Hole h;
  h.kind = Hole::Kind::Circle;
  h.center = Vec3(0, 0, 0);
  h.radius = 10;
  s.holes.push_back(h);
  const Discretization d = buildLattice(s);

  int expected = 0;
  for (int iy = 0; iy < 10; ++iy)
    for (int ix = 0; ix < 30; ++ix) {
      const double x = -75 + (ix + 0.5) * 5, y = -25 + (iy + 0.5) * 5;
      expected += std::hypot(x, y) >= 10;
    }
  ASSERT_LT(expected, 300);  // the hole does cut something
  int real = 0;
  for (int i = 0; i < d.size(); ++i) {
    if (d.fictitious[i]) continue;
    ++real;
    EXPECT_GE(d.X[i].head<2>().norm(), 10.0);
  }
  EXPECT_EQ(real, expected);
  EXPECT_EQ(countFictitious(d), 3 * 10);  // holes never remove fictitious particles
}

TEST(Lattice, HoleBoundaryIsExclusive) {
  // Sites exactly on the hole boundary are kept (strict inequality); values are exact in binary.
  LatticeSpec s;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(4, 4, 0);
  s.counts = {{4, 4, 1}};
  s.horizonFactor = 1.5;
  Hole c;
  c.center = Vec3(1.5, 1.5, 0);
  c.radius = 1.0;  // (0.5,1.5), (2.5,1.5), (1.5,0.5), (1.5,2.5) lie exactly on the circle
  s.holes = {c};
  EXPECT_EQ(buildLattice(s).size(), 15);
  Hole r;
  r.kind = Hole::Kind::Rectangle;
  r.center = Vec3(2.5, 2.5, 0);
  r.halfWidths = Vec3(1.0, 0.5, 0);  // (1.5,2.5) and (3.5,2.5) on the boundary, y half-width
  s.holes = {r};                     // 0.5 < distance 1 of the other rows
  EXPECT_EQ(buildLattice(s).size(), 15);
}

TEST(Lattice, RectangularHoleAndCylinder3d) {
  LatticeSpec s;
  s.dim = 3;
  s.lower = Vec3(0, 0, 0);
  s.upper = Vec3(6, 6, 3);
  s.counts = {{6, 6, 3}};
  s.horizonFactor = 1.5;
  Hole cyl;
  cyl.kind = Hole::Kind::Circle;
  cyl.center = Vec3(3, 3, -100);  // z of the centre is irrelevant: cylinder along z
  cyl.radius = 1.0;               // removes the 4 columns around (3,3)
  Hole box;
  box.kind = Hole::Kind::Rectangle;
  box.center = Vec3(0.5, 0.5, 1.5);
  box.halfWidths = Vec3(0.6, 0.6, 0.6);  // removes the single site (0.5,0.5,1.5)
  s.holes = {cyl, box};
  const Discretization d = buildLattice(s);
  EXPECT_EQ(d.size(), 6 * 6 * 3 - 4 * 3 - 1);
  for (const Vec3& x : d.X) {
    EXPECT_GE((x.head<2>() - Vec3(3, 3, 0).head<2>()).norm(), 1.0);
    EXPECT_FALSE((x - Vec3(0.5, 0.5, 1.5)).norm() < 1e-12);
  }
}

TEST(Lattice, JitterIsDeterministicBoundedAndRealOnly) {
  LatticeSpec s = bar2d(2.015);
  s.fictitiousSides = {Side::XMax};
  const Discretization ref = buildLattice(s);
  s.jitter = 0.4;
  const Discretization a = buildLattice(s);
  const Discretization b = buildLattice(s);
  s.jitterSeed = 999;
  const Discretization c = buildLattice(s);
  ASSERT_EQ(a.size(), ref.size());
  double maxShift = 0.0;
  bool differsFromC = false;
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.X[i], b.X[i]);
    const Vec3 shift = a.X[i] - ref.X[i];
    if (a.fictitious[i]) {
      EXPECT_EQ(shift.norm(), 0.0);
    } else {
      EXPECT_LE(shift.cwiseAbs().maxCoeff(), 0.4 * 0.2 / 2 + 1e-15);
      EXPECT_EQ(shift.z(), 0.0);
      maxShift = std::max(maxShift, shift.cwiseAbs().maxCoeff());
    }
    differsFromC = differsFromC || a.X[i] != c.X[i];
  }
  EXPECT_GT(maxShift, 0.03);  // really shifted (near the bound 0.04)
  EXPECT_TRUE(differsFromC);
  EXPECT_EQ(a.familyOffset, b.familyOffset);
  EXPECT_EQ(a.familyIndex, b.familyIndex);
}

TEST(LatticeErrors, SpacingMismatch) {
  LatticeSpec s = bar2d();
  s.counts = {{50, 4, 1}};
  expectInvalid([&] { buildLattice(s); }, "spacing");
}

TEST(LatticeErrors, HorizonBelowSpacing) {
  LatticeSpec s = bar2d(0.9);
  expectInvalid([&] { buildLattice(s); }, "horizon");
}

TEST(LatticeErrors, ZeroCounts) {
  LatticeSpec s = bar2d();
  s.counts = {{0, 5, 1}};
  expectInvalid([&] { buildLattice(s); }, "counts");
}

TEST(LatticeErrors, OtherBadInput) {
  LatticeSpec s = bar2d();
  s.upper.x() = s.lower.x();
  expectInvalid([&] { buildLattice(s); }, "box");
  s = bar2d();
  s.thickness = 0;
  expectInvalid([&] { buildLattice(s); }, "thickness");
  s = bar2d();
  s.fictitiousSides = {Side::ZMin};
  expectInvalid([&] { buildLattice(s); }, "zmin");
  s = bar2d();
  s.dim = 1;
  s.counts = {{50, 1, 1}};
  s.fictitiousSides = {Side::YMin};
  expectInvalid([&] { buildLattice(s); }, "ymin");
  s = bar2d();
  Hole all;
  all.kind = Hole::Kind::Rectangle;
  all.center = Vec3(5, 0.5, 0);
  all.halfWidths = Vec3(6, 1, 0);
  s.holes = {all};
  expectInvalid([&] { buildLattice(s); }, "no real particle");
  s = bar2d();
  s.jitter = -0.1;
  expectInvalid([&] { buildLattice(s); }, "jitter");
}

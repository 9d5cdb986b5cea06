// Input validation: constructor rejects unphysical constants and inconsistent kinematics;
// stress/stressTangent/cauchy refuse inverted or non-finite F and leave their outputs alone.
#include <limits>
#include <stdexcept>

#include "MaterialTestUtil.hpp"

using namespace perinox;
using namespace perinox::testutil;

TEST(MaterialValidation, ConstructorRejectsBadConstants) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (double nu : {0.5, 0.7, -1.0, -1.5, nan}) {
    SCOPED_TRACE(nu);
    EXPECT_THROW(Material(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, kE, nu)), std::invalid_argument);
  }
  for (double E : {0.0, -1.0, nan, inf}) {
    SCOPED_TRACE(E);
    EXPECT_THROW(Material(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None, E, kNu)), std::invalid_argument);
  }
  EXPECT_NO_THROW(Material(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, kE, 0.4999)));
  EXPECT_NO_THROW(Material(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, kE, -0.999)));
}

TEST(MaterialValidation, ConstructorRejectsBadKinematics) {
  for (int dim : {0, 4, -1}) {
    SCOPED_TRACE(dim);
    EXPECT_THROW(Material(makeSpec(MaterialKind::Hencky, dim, PlanarMode::None)), std::invalid_argument);
  }
  EXPECT_THROW(Material(makeSpec(MaterialKind::Hencky, 2, PlanarMode::None)), std::invalid_argument);
  EXPECT_THROW(Material(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::None)), std::invalid_argument);
  // 1D and 3D have no planar reduction: the field is ignored (normalised to None).
  EXPECT_EQ(Material(makeSpec(MaterialKind::Hencky, 3, PlanarMode::PlaneStrain)).spec().planar, PlanarMode::None);
  EXPECT_EQ(Material(makeSpec(MaterialKind::Hencky, 1, PlanarMode::PlaneStress)).spec().planar, PlanarMode::None);
}

TEST(MaterialValidation, ErrorMessageIsASentence) {
  try {
    Material m(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, kE, 0.5));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Poisson"), std::string::npos) << e.what();
  }
}

TEST(MaterialValidation, LameConstants) {
  // E = 200, nu = 0.3: lambda = 60/0.52, mu = 200/2.6, plane stress lambda = E nu / (1 - nu^2).
  const MaterialSpec s = makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress);
  EXPECT_NEAR(lameLambda(s), 60.0 / 0.52, 1e-12);
  EXPECT_NEAR(lameMu(s), 200.0 / 2.6, 1e-12);
  const Material ps(s);
  EXPECT_NEAR(ps.lambdaEff(), 200.0 * 0.3 / (1 - 0.09), 1e-12);
  EXPECT_NEAR(ps.mu(), 200.0 / 2.6, 1e-12);
  const Material pe(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
  EXPECT_NEAR(pe.lambdaEff(), 60.0 / 0.52, 1e-12);
}

namespace {
// Every entry point must return false and leave its output untouched (sentinel 42).
template <int D>
void expectRejected(const Material& m, const MatD<D>& F) {
  MatD<D> P = MatD<D>::Constant(42.0);
  TangentD<D> A = TangentD<D>::Constant(42.0);
  Eigen::Matrix3d sig = Eigen::Matrix3d::Constant(42.0);
  EXPECT_FALSE(m.stress<D>(F, P));
  EXPECT_TRUE((P.array() == 42.0).all());
  P.setConstant(42.0);
  EXPECT_FALSE(m.stressTangent<D>(F, P, A));
  EXPECT_TRUE((P.array() == 42.0).all());
  EXPECT_TRUE((A.array() == 42.0).all());
  EXPECT_FALSE(m.cauchy<D>(F, sig));
  EXPECT_TRUE((sig.array() == 42.0).all());
}
}  // namespace

TEST(MaterialValidation, HenckyRejectsInvertedOrDegenerateF) {
  const Material m1(makeSpec(MaterialKind::Hencky, 1, PlanarMode::None));
  for (double f : {0.0, -0.5, -1.0}) expectRejected<1>(m1, (MatD<1>() << f).finished());
  for (PlanarMode pm : {PlanarMode::PlaneStrain, PlanarMode::PlaneStress}) {
    const Material m2(makeSpec(MaterialKind::Hencky, 2, pm));
    expectRejected<2>(m2, Eigen::Vector2d(-1.0, 1.0).asDiagonal().toDenseMatrix());
    expectRejected<2>(m2, Eigen::Matrix2d::Zero());
    expectRejected<2>(m2, (Eigen::Matrix2d() << 1, 2, 2, 4).finished());  // singular
    expectRejected<2>(m2, (Eigen::Matrix2d() << 0, 1, 1, 0).finished());  // reflection, det = -1
  }
  const Material m3(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None));
  expectRejected<3>(m3, Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal().toDenseMatrix());
  expectRejected<3>(m3, Eigen::Matrix3d::Zero());
  expectRejected<3>(m3, -Eigen::Matrix3d::Identity());
}

TEST(MaterialValidation, RejectsNonFiniteF) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (MaterialKind k : {MaterialKind::Hencky, MaterialKind::SmallStrain}) {
    for (double bad : {nan, inf, -inf}) {
      const Material m1(makeSpec(k, 1, PlanarMode::None));
      expectRejected<1>(m1, (MatD<1>() << bad).finished());
      const Material m2(makeSpec(k, 2, PlanarMode::PlaneStress));
      Eigen::Matrix2d F2 = Eigen::Matrix2d::Identity();
      F2(0, 1) = bad;
      expectRejected<2>(m2, F2);
      const Material m3(makeSpec(k, 3, PlanarMode::None));
      Eigen::Matrix3d F3 = Eigen::Matrix3d::Identity();
      F3(2, 1) = bad;
      expectRejected<3>(m3, F3);
    }
  }
}

TEST(MaterialValidation, SmallStrainOnlyChecksFiniteness) {
  // Linear elasticity is defined for any F; an inverted F is the caller's business.
  const Material m(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStrain));
  Eigen::Matrix2d P;
  ASSERT_TRUE(m.stress<2>(Eigen::Vector2d(-1.0, 1.0).asDiagonal().toDenseMatrix(), P));
  // eps = diag(-2, 0): sigma11 = (lambda + 2 mu)(-2), sigma22 = lambda (-2).
  const double lam = lameLambda(m.spec()), mu = lameMu(m.spec());
  EXPECT_NEAR(P(0, 0), -2 * (lam + 2 * mu), 1e-12 * kE);
  EXPECT_NEAR(P(1, 1), -2 * lam, 1e-12 * kE);
}

TEST(MaterialValidation, DimensionMismatchIsAProgrammingError) {
  const Material m(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
  Eigen::Matrix3d P3;
  EXPECT_THROW(m.stress<3>(Eigen::Matrix3d::Identity(), P3), std::logic_error);
}

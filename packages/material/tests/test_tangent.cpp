// Tangent A = dP/dF against central finite differences of stress(), and the major symmetry of
// the Hencky tangent, for every kind, dimension and planar mode, at distinct, nearly equal and
// exactly equal principal stretches.
#include "MaterialTestUtil.hpp"

using namespace perinox;
using namespace perinox::testutil;

namespace {

// Tolerance of the finite-difference check. With step h = 1e-6 |F|_max the central difference
// has truncation error ~h^2 |d^3P/dF^3| ~ 1e-12 |A| and roundoff ~ 1e-16 |P| / h ~ 1e-10 |A|
// (|P| ~ |A| |F| here), so 1e-6 leaves four orders of margin yet is ~1e5 below the O(1) error
// of any wrong or missing term (e.g. dropping the tau dF^T term, or using 1/l_a instead of the
// divided difference on a distinct-eigenvalue state).
constexpr double kFdTol = 1e-6;
// Major symmetry is exact in exact arithmetic; what remains is roundoff of a few 3x3 products.
constexpr double kSymTol = 1e-10;

template <int D>
void checkTangentAgainstFd(const MaterialSpec& spec) {
  const Material m(spec);
  for (const auto& c : deformationCases<D>()) {
    SCOPED_TRACE(c.name);
    MatD<D> P, P2;
    TangentD<D> A;
    ASSERT_TRUE(m.stressTangent<D>(c.F, P, A));
    ASSERT_TRUE(m.stress<D>(c.F, P2));
    EXPECT_EQ((P - P2).cwiseAbs().maxCoeff(), 0.0) << "stressTangent and stress disagree on P";
    ASSERT_TRUE(A.allFinite());
    const double h = 1e-6 * c.F.cwiseAbs().maxCoeff();
    const TangentD<D> Afd = fdTangent<D>(m, c.F, h);
    EXPECT_LE(relMaxDiff(A, Afd), kFdTol) << "A =\n" << A << "\nA_fd =\n" << Afd;
  }
}

template <int D>
void checkMajorSymmetry(const MaterialSpec& spec) {
  const Material m(spec);
  for (const auto& c : deformationCases<D>()) {
    SCOPED_TRACE(c.name);
    MatD<D> P;
    TangentD<D> A;
    ASSERT_TRUE(m.stressTangent<D>(c.F, P, A));
    const TangentD<D> At = A.transpose();
    EXPECT_LE(relMaxDiff(A, At), kSymTol);
  }
}

}  // namespace

TEST(MaterialTangent, HenckyPlaneStrainMatchesFiniteDifferences) {
  checkTangentAgainstFd<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
}
TEST(MaterialTangent, HenckyPlaneStressMatchesFiniteDifferences) {
  checkTangentAgainstFd<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress));
}
TEST(MaterialTangent, Hencky3DMatchesFiniteDifferences) {
  checkTangentAgainstFd<3>(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None));
}
TEST(MaterialTangent, Hencky1DMatchesFiniteDifferences) {
  checkTangentAgainstFd<1>(makeSpec(MaterialKind::Hencky, 1, PlanarMode::None));
}
// A nearly incompressible and an auxetic material stress the volumetric vs deviatoric split.
TEST(MaterialTangent, HenckyExtremePoissonMatchesFiniteDifferences) {
  for (double nu : {0.49, -0.8}) {
    SCOPED_TRACE(nu);
    checkTangentAgainstFd<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, kE, nu));
    checkTangentAgainstFd<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress, kE, nu));
    checkTangentAgainstFd<3>(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None, kE, nu));
  }
}
TEST(MaterialTangent, SmallStrainMatchesFiniteDifferences) {
  checkTangentAgainstFd<1>(makeSpec(MaterialKind::SmallStrain, 1, PlanarMode::None));
  checkTangentAgainstFd<2>(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStrain));
  checkTangentAgainstFd<2>(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStress));
  checkTangentAgainstFd<3>(makeSpec(MaterialKind::SmallStrain, 3, PlanarMode::None));
}

TEST(MaterialTangent, HenckyTangentHasMajorSymmetry) {
  checkMajorSymmetry<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
  checkMajorSymmetry<2>(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress));
  checkMajorSymmetry<3>(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None));
}
TEST(MaterialTangent, SmallStrainTangentHasMajorSymmetry) {
  checkMajorSymmetry<2>(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStrain));
  checkMajorSymmetry<3>(makeSpec(MaterialKind::SmallStrain, 3, PlanarMode::None));
}

// Continuity through the eigenvalue coincidence: the tangent at a gap of 1e-7 must agree with the
// tangent at the exactly equal state to O(gap), i.e. the nearly-equal branch is not just
// self-consistent but also converges to the right limit.
TEST(MaterialTangent, HenckyTangentContinuousAtEqualStretches) {
  const Material m(makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
  const Eigen::Matrix2d F0 = 1.3 * rot2(25);
  for (double gap : {1e-3, 1e-5, 1e-7, 1e-10}) {
    SCOPED_TRACE(gap);
    const Eigen::Matrix2d F1 = rot2(25) * Eigen::Vector2d(1.3, 1.3 * (1 + gap)).asDiagonal();
    Eigen::Matrix2d P0, P1;
    TangentD<2> A0, A1;
    ASSERT_TRUE(m.stressTangent<2>(F0, P0, A0));
    ASSERT_TRUE(m.stressTangent<2>(F1, P1, A1));
    // A is smooth in F (Lipschitz constant O(|A|/|F|)), so the difference is bounded by ~gap.
    EXPECT_LE(relMaxDiff(A1, A0), 10 * gap + 1e-14);
  }
}

// Either side of the switch between the series and log1p forms of the divided difference
// (|x| = 1e-5, x ~ -2 gap here), with a tighter tolerance than above: the finite-difference
// error is ~1e-10 (estimate in kFdTol), while an error in the series' linear coefficient would
// show up at ~0.1 |x| ~ 1e-6 of the shear part of A. 1e-8 separates the two.
TEST(MaterialTangent, HenckyTangentAccurateAroundSeriesSwitch) {
  for (PlanarMode pm : {PlanarMode::PlaneStrain, PlanarMode::PlaneStress}) {
    const Material m(makeSpec(MaterialKind::Hencky, 2, pm));
    for (double gap : {4.5e-6, 5.5e-6, -4.5e-6, -5.5e-6}) {
      SCOPED_TRACE(gap);
      const Eigen::Matrix2d F = rot2(-15) * Eigen::Vector2d(1.3, 1.3 * (1 + gap)).asDiagonal() * rot2(50);
      Eigen::Matrix2d P;
      TangentD<2> A;
      ASSERT_TRUE(m.stressTangent<2>(F, P, A));
      EXPECT_LE(relMaxDiff(A, fdTangent<2>(m, F, 1e-6 * 1.3)), 1e-8);
    }
  }
  const Material m3(makeSpec(MaterialKind::Hencky, 3, PlanarMode::None));
  for (double gap : {4.5e-6, 5.5e-6}) {
    SCOPED_TRACE(gap);
    const Eigen::Matrix3d F =
        rot3(40, {1, 1, 0}) * Eigen::Vector3d(1.3, 1.3 * (1 + gap), 0.8).asDiagonal() * rot3(10, {0, 1, 2});
    Eigen::Matrix3d P;
    TangentD<3> A;
    ASSERT_TRUE(m3.stressTangent<3>(F, P, A));
    EXPECT_LE(relMaxDiff(A, fdTangent<3>(m3, F, 1e-6 * 1.3)), 1e-8);
  }
}

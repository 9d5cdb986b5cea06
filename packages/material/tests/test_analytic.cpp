// Closed-form states, objectivity, stress-free rigid motions, Cauchy output and
// P = dW/dF for the Hencky energy W = mu |eps|^2 + lambda/2 tr(eps)^2.
#include "MaterialTestUtil.hpp"

using namespace perinox;
using namespace perinox::testutil;

namespace {
// Closed forms are evaluated with a few logs/divisions on either side: agreement to a few ulps
// of |stress| ~ E is expected; 1e-12 E leaves room for the eigen decomposition's roundoff while
// catching any wrong constant (e.g. lambda vs lambda_eff differs by O(E)).
constexpr double kTol = 1e-12 * kE;

const MaterialSpec kPlaneStrain = makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain);
const MaterialSpec kPlaneStress = makeSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress);
const MaterialSpec k3D = makeSpec(MaterialKind::Hencky, 3, PlanarMode::None);
const MaterialSpec k1D = makeSpec(MaterialKind::Hencky, 1, PlanarMode::None);

const double kLam = lameLambda(kPlaneStrain);
const double kMu = lameMu(kPlaneStrain);
const double kLamEff = 2 * kLam * kMu / (kLam + 2 * kMu);

template <int D>
MatD<D> stressOf(const Material& m, const MatD<D>& F) {
  MatD<D> P;
  EXPECT_TRUE(m.stress<D>(F, P));
  return P;
}
template <int D>
Eigen::Matrix3d cauchyOf(const Material& m, const MatD<D>& F) {
  Eigen::Matrix3d s;
  EXPECT_TRUE(m.cauchy<D>(F, s));
  return s;
}
}  // namespace

TEST(MaterialAnalytic, HydrostaticHencky) {
  for (double x : {1.3, 0.7, 1.61}) {
    SCOPED_TRACE(x);
    const double lx = std::log(x);
    // Plane strain, F = x I: tau = (2 lambda + 2 mu) ln x I, P = tau / x.
    Eigen::Matrix2d P = stressOf<2>(Material(kPlaneStrain), x * Eigen::Matrix2d::Identity());
    EXPECT_NEAR(P(0, 0), 2 * (kLam + kMu) * lx / x, kTol);
    EXPECT_NEAR(P(1, 1), 2 * (kLam + kMu) * lx / x, kTol);
    EXPECT_NEAR(P(0, 1), 0.0, kTol);
    EXPECT_NEAR(P(1, 0), 0.0, kTol);
    // Plane stress, F = diag(x, x): the same with lambda_eff.
    P = stressOf<2>(Material(kPlaneStress), x * Eigen::Matrix2d::Identity());
    EXPECT_NEAR(P(0, 0), 2 * (kLamEff + kMu) * lx / x, kTol);
    EXPECT_NEAR(P(1, 1), 2 * (kLamEff + kMu) * lx / x, kTol);
    // 3D: P = (3 lambda + 2 mu) ln x / x I.
    const Eigen::Matrix3d P3 = stressOf<3>(Material(k3D), x * Eigen::Matrix3d::Identity());
    EXPECT_LE((P3 - (3 * kLam + 2 * kMu) * lx / x * Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), kTol);
  }
}

TEST(MaterialAnalytic, UniaxialStrainHencky) {
  // F = diag(x, 1(, 1)): tau11 = (lambda + 2 mu) ln x, tau22 = lambda ln x; P11 = tau11/x, P22 = tau22.
  for (double x : {1.8, 0.6}) {
    SCOPED_TRACE(x);
    const double lx = std::log(x);
    const Eigen::Matrix2d P = stressOf<2>(Material(kPlaneStrain), Eigen::Vector2d(x, 1).asDiagonal().toDenseMatrix());
    EXPECT_NEAR(P(0, 0), (kLam + 2 * kMu) * lx / x, kTol);
    EXPECT_NEAR(P(1, 1), kLam * lx, kTol);
    const Eigen::Matrix3d P3 = stressOf<3>(Material(k3D), Eigen::Vector3d(x, 1, 1).asDiagonal().toDenseMatrix());
    EXPECT_NEAR(P3(0, 0), (kLam + 2 * kMu) * lx / x, kTol);
    EXPECT_NEAR(P3(1, 1), kLam * lx, kTol);
    EXPECT_NEAR(P3(2, 2), kLam * lx, kTol);
  }
}

TEST(MaterialAnalytic, UniaxialStressHencky) {
  // Lateral stretch x^-nu makes the lateral stress vanish and tau11 = E ln x in 3D, in plane
  // stress (whose eps22 / eps11 = -lambda_eff/(lambda_eff + 2 mu) = -nu) and in the 1D bar.
  for (double x : {1.8, 0.6}) {
    SCOPED_TRACE(x);
    const double lx = std::log(x), y = std::pow(x, -kNu);
    const Eigen::Matrix3d P3 = stressOf<3>(Material(k3D), Eigen::Vector3d(x, y, y).asDiagonal().toDenseMatrix());
    EXPECT_NEAR(P3(0, 0), kE * lx / x, kTol);
    EXPECT_NEAR(P3(1, 1), 0.0, kTol);
    EXPECT_NEAR(P3(2, 2), 0.0, kTol);
    const Eigen::Matrix2d F2 = Eigen::Vector2d(x, y).asDiagonal();
    const Eigen::Matrix2d P2 = stressOf<2>(Material(kPlaneStress), F2);
    EXPECT_NEAR(P2(0, 0), kE * lx / x, kTol);
    EXPECT_NEAR(P2(1, 1), 0.0, kTol);
    // Cauchy: F33 = x^-nu as well, J = x^(1 - 2 nu), sigma11 = E ln x / J, sigma33 = 0.
    const Eigen::Matrix3d s2 = cauchyOf<2>(Material(kPlaneStress), F2);
    EXPECT_NEAR(s2(0, 0), kE * lx / std::pow(x, 1 - 2 * kNu), kTol);
    EXPECT_NEAR(s2(1, 1), 0.0, kTol);
    EXPECT_EQ(s2(2, 2), 0.0);
    // The same state in 3D gives the same Cauchy stress.
    const Eigen::Matrix3d s3 = cauchyOf<3>(Material(k3D), Eigen::Vector3d(x, y, y).asDiagonal().toDenseMatrix());
    EXPECT_LE((s3 - s2).cwiseAbs().maxCoeff(), kTol);
    // 1D bar.
    const MatD<1> F1 = (MatD<1>() << x).finished();
    EXPECT_NEAR(stressOf<1>(Material(k1D), F1)(0, 0), kE * lx / x, kTol);
    const Eigen::Matrix3d s1 = cauchyOf<1>(Material(k1D), F1);
    EXPECT_NEAR(s1(0, 0), kE * lx / x, kTol);
    EXPECT_EQ(s1.cwiseAbs().sum() - std::abs(s1(0, 0)), 0.0);
  }
}

TEST(MaterialAnalytic, PlaneStrainCauchyHasOutOfPlaneStress) {
  // F = x I in plane strain: J = x^2, sigma_in = 2 (lambda + mu) ln x / x^2, sigma33 = lambda 2 ln x / x^2,
  // identical to the 3D state F = diag(x, x, 1).
  const double x = 1.25, lx = std::log(x);
  const Eigen::Matrix3d s = cauchyOf<2>(Material(kPlaneStrain), x * Eigen::Matrix2d::Identity());
  EXPECT_NEAR(s(0, 0), 2 * (kLam + kMu) * lx / (x * x), kTol);
  EXPECT_NEAR(s(2, 2), 2 * kLam * lx / (x * x), kTol);
  const Eigen::Matrix2d F2 = rot2(40) * Eigen::Vector2d(1.4, 0.8).asDiagonal() * rot2(-10);
  Eigen::Matrix3d F3 = Eigen::Matrix3d::Identity();
  F3.topLeftCorner<2, 2>() = F2;
  EXPECT_LE((cauchyOf<2>(Material(kPlaneStrain), F2) - cauchyOf<3>(Material(k3D), F3)).cwiseAbs().maxCoeff(), kTol);
  // ... and the first Piola-Kirchhoff stress equals the in-plane block of the 3D one.
  EXPECT_LE((stressOf<2>(Material(kPlaneStrain), F2) - stressOf<3>(Material(k3D), F3).topLeftCorner<2, 2>())
                .cwiseAbs().maxCoeff(),
            kTol);
}

TEST(MaterialAnalytic, ObjectivityHencky) {
  // P(R F) = R P(F), sigma(R F) = R sigma(F) R^T.
  const Eigen::Matrix2d F2 = rot2(10) * Eigen::Vector2d(1.7, 0.75).asDiagonal() * rot2(-35);
  for (const MaterialSpec& s : {kPlaneStrain, kPlaneStress}) {
    const Material m(s);
    for (double deg : {23.0, 90.0, 180.0, -137.0}) {
      SCOPED_TRACE(deg);
      const Eigen::Matrix2d R = rot2(deg);
      EXPECT_LE((stressOf<2>(m, R * F2) - R * stressOf<2>(m, F2)).cwiseAbs().maxCoeff(), kTol);
      Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity();
      R3.topLeftCorner<2, 2>() = R;
      EXPECT_LE((cauchyOf<2>(m, R * F2) - R3 * cauchyOf<2>(m, F2) * R3.transpose()).cwiseAbs().maxCoeff(), kTol);
    }
  }
  const Material m3(k3D);
  const Eigen::Matrix3d F3 = rot3(20, {1, 0, 1}) * Eigen::Vector3d(1.7, 0.75, 1.2).asDiagonal() * rot3(-35, {0, 1, 1});
  for (double deg : {23.0, 90.0, 180.0}) {
    SCOPED_TRACE(deg);
    const Eigen::Matrix3d R = rot3(deg, {0.2, -0.5, 1});
    EXPECT_LE((stressOf<3>(m3, R * F3) - R * stressOf<3>(m3, F3)).cwiseAbs().maxCoeff(), kTol);
    EXPECT_LE((cauchyOf<3>(m3, R * F3) - R * cauchyOf<3>(m3, F3) * R.transpose()).cwiseAbs().maxCoeff(), kTol);
  }
}

TEST(MaterialAnalytic, RigidRotationIsStressFree) {
  // R R^T = I to ~1e-16, so |eps| ~ 1e-16 and |P| ~ E 1e-16: kTol = 1e-12 E is loose but exact 0
  // cannot be demanded after trigonometry.
  for (double deg : {0.0, 17.0, 90.0, 180.0, -90.0, 271.0}) {
    SCOPED_TRACE(deg);
    for (const MaterialSpec& s : {kPlaneStrain, kPlaneStress}) {
      EXPECT_LE(stressOf<2>(Material(s), rot2(deg)).cwiseAbs().maxCoeff(), kTol);
      EXPECT_LE(cauchyOf<2>(Material(s), rot2(deg)).cwiseAbs().maxCoeff(), kTol);
    }
    const Eigen::Matrix3d R = rot3(deg, {1, -2, 0.5});
    EXPECT_LE(stressOf<3>(Material(k3D), R).cwiseAbs().maxCoeff(), kTol);
    EXPECT_LE(cauchyOf<3>(Material(k3D), R).cwiseAbs().maxCoeff(), kTol);
  }
  // Identity is exactly stress free.
  EXPECT_EQ(stressOf<2>(Material(kPlaneStrain), Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(stressOf<3>(Material(k3D), Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(stressOf<1>(Material(k1D), MatD<1>::Identity())(0, 0), 0.0);
}

TEST(MaterialAnalytic, ReferenceTangentIsLinearElasticity) {
  // At F = I the Hencky tangent reduces to the small-strain tangent (plus zero initial stress).
  for (const MaterialSpec& s : {kPlaneStrain, kPlaneStress}) {
    MaterialSpec lin = s;
    lin.kind = MaterialKind::SmallStrain;
    Eigen::Matrix2d P;
    TangentD<2> A, Al;
    ASSERT_TRUE(Material(s).stressTangent<2>(Eigen::Matrix2d::Identity(), P, A));
    ASSERT_TRUE(Material(lin).stressTangent<2>(Eigen::Matrix2d::Identity(), P, Al));
    EXPECT_LE((A - Al).cwiseAbs().maxCoeff(), kTol);
  }
  MaterialSpec lin3 = k3D;
  lin3.kind = MaterialKind::SmallStrain;
  Eigen::Matrix3d P;
  TangentD<3> A, Al;
  ASSERT_TRUE(Material(k3D).stressTangent<3>(Eigen::Matrix3d::Identity(), P, A));
  ASSERT_TRUE(Material(lin3).stressTangent<3>(Eigen::Matrix3d::Identity(), P, Al));
  EXPECT_LE((A - Al).cwiseAbs().maxCoeff(), kTol);
  // 1D: E.
  MatD<1> P1;
  TangentD<1> A1;
  ASSERT_TRUE(Material(k1D).stressTangent<1>(MatD<1>::Identity(), P1, A1));
  EXPECT_NEAR(A1(0, 0), kE, kTol);
}

TEST(MaterialAnalytic, SmallStrainIsLinearElasticity) {
  const double e = 1e-3, g = 2e-3;
  // Uniaxial stress: eps = diag(e, -nu e, -nu e) gives sigma = diag(E e, 0, 0).
  const Material m3(makeSpec(MaterialKind::SmallStrain, 3, PlanarMode::None));
  const Eigen::Matrix3d s3 =
      stressOf<3>(m3, Eigen::Matrix3d::Identity() + Eigen::Vector3d(e, -kNu * e, -kNu * e).asDiagonal().toDenseMatrix());
  EXPECT_LE((s3 - Eigen::Vector3d(kE * e, 0, 0).asDiagonal().toDenseMatrix()).cwiseAbs().maxCoeff(), kTol);
  // Plane stress, uniaxial: eps = diag(e, -nu e) gives sigma11 = E e, sigma22 = 0, sigma33 = 0.
  const Material mps(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStress));
  const Eigen::Matrix2d Fps = Eigen::Matrix2d::Identity() + Eigen::Vector2d(e, -kNu * e).asDiagonal().toDenseMatrix();
  const Eigen::Matrix3d sps = cauchyOf<2>(mps, Fps);
  EXPECT_NEAR(sps(0, 0), kE * e, kTol);
  EXPECT_NEAR(sps(1, 1), 0.0, kTol);
  EXPECT_EQ(sps(2, 2), 0.0);
  // Plane strain, uniaxial strain: sigma11 = (lambda + 2 mu) e, sigma22 = sigma33 = lambda e.
  const Material mpe(makeSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStrain));
  const Eigen::Matrix3d spe = cauchyOf<2>(mpe, Eigen::Matrix2d::Identity() + Eigen::Vector2d(e, 0).asDiagonal().toDenseMatrix());
  EXPECT_NEAR(spe(0, 0), (kLam + 2 * kMu) * e, kTol);
  EXPECT_NEAR(spe(1, 1), kLam * e, kTol);
  EXPECT_NEAR(spe(2, 2), kLam * e, kTol);
  // Simple shear F = I + g e1 e2^T: sigma12 = sigma21 = mu g, no normal stress; it is
  // linear, so not objective: a pure rotation gives stress (second order in the angle).
  Eigen::Matrix2d Fs = Eigen::Matrix2d::Identity();
  Fs(0, 1) = g;
  const Eigen::Matrix2d ss = stressOf<2>(mpe, Fs);
  EXPECT_NEAR(ss(0, 1), kMu * g, kTol);
  EXPECT_NEAR(ss(1, 0), kMu * g, kTol);
  EXPECT_NEAR(ss(0, 0), 0.0, kTol);
  // 1D: E (F - 1).
  const Material m1(makeSpec(MaterialKind::SmallStrain, 1, PlanarMode::None));
  EXPECT_NEAR(stressOf<1>(m1, (MatD<1>() << 1 + e).finished())(0, 0), kE * e, kTol);
  // Linearity: sigma(I + a H) = a sigma(I + H).
  const Eigen::Matrix3d H = (Eigen::Matrix3d() << 1e-3, 2e-3, -1e-3, 5e-4, -2e-3, 3e-3, 0, 1e-3, 4e-4).finished();
  EXPECT_LE((stressOf<3>(m3, Eigen::Matrix3d::Identity() + 3 * H) - 3 * stressOf<3>(m3, Eigen::Matrix3d::Identity() + H))
                .cwiseAbs().maxCoeff(),
            kTol);
}

namespace {
/// Independent evaluation of the Hencky energy W = mu |eps|^2 + lambda/2 tr(eps)^2 with
/// eps = 1/2 ln(F F^T) from Eigen's general eigen solver (1D: W = E/2 ln(F)^2).
template <int D>
double henckyEnergy(const MatD<D>& F, double lambda, double mu) {
  Eigen::SelfAdjointEigenSolver<MatD<D>> es(F * F.transpose());
  const Eigen::Matrix<double, D, 1> e = 0.5 * es.eigenvalues().array().log();
  return mu * e.squaredNorm() + 0.5 * lambda * e.sum() * e.sum();
}

template <int D>
void checkEnergy(const Material& m, double lambda, double mu) {
  for (const auto& c : deformationCases<D>()) {
    SCOPED_TRACE(c.name);
    // Central differences of W with h = 1e-5 |F|: truncation ~h^2 |W'''| ~ 1e-10 E, roundoff
    // ~1e-16 W / h ~ 1e-11 E; relative to |P| ~ 0.1..1 E this is < 1e-8, checked at 1e-6.
    // (Near F = I, |P| is ~0.05 E, still well above the error.) Skipped at F = I, where P = 0.
    const MatD<D> P = stressOf<D>(m, c.F);
    if (P.cwiseAbs().maxCoeff() == 0.0) continue;
    const double h = 1e-5 * c.F.cwiseAbs().maxCoeff();
    MatD<D> Pfd;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) {
        MatD<D> Fp = c.F, Fm = c.F;
        Fp(a, b) += h;
        Fm(a, b) -= h;
        Pfd(a, b) = (henckyEnergy<D>(Fp, lambda, mu) - henckyEnergy<D>(Fm, lambda, mu)) / (2 * h);
      }
    EXPECT_LE(relMaxDiff(P, Pfd), 1e-6) << "P =\n" << P << "\ndW/dF =\n" << Pfd;
  }
}
}  // namespace

TEST(MaterialAnalytic, HenckyStressDerivesFromEnergy) {
  checkEnergy<2>(Material(kPlaneStrain), kLam, kMu);
  checkEnergy<2>(Material(kPlaneStress), kLamEff, kMu);  // the reduced energy of plane stress
  checkEnergy<3>(Material(k3D), kLam, kMu);
  // 1D: W = E/2 ln(F)^2 is mu |eps|^2 + lambda/2 tr(eps)^2 with mu = E/2, lambda = 0.
  checkEnergy<1>(Material(k1D), 0.0, 0.5 * kE);
}

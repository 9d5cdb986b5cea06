// J2 plasticity: the algorithmic tangent against central finite differences of the stress at a
// fixed committed state, in every regime (elastic, plastic loading from a virgin and from a
// hardened state, just inside and just past the yield surface, equal principal stretches,
// elastic unloading), for both kinematics and every dimension and planar mode; the material
// point against closed forms (uniaxial loading, unloading and reloading with linear hardening,
// Voce hardening against its integral); objectivity; plastic incompressibility; the elastic limit.
#include "MaterialTestUtil.hpp"

#include <vector>

using namespace perinox;
using namespace perinox::testutil;

namespace {

constexpr double kY = 0.5;   // initial yield stress: yield strain 2.5e-3 with E = 200
constexpr double kH = 10.0;  // linear hardening modulus

MaterialSpec plasticSpec(MaterialKind kind, int dim, PlanarMode planar, bool voce = false) {
  MaterialSpec s = makeSpec(kind, dim, planar);
  s.plastic.enabled = true;
  s.plastic.yieldStress = kY;
  s.plastic.hardeningModulus = voce ? 2.0 : kH;
  s.plastic.voce = voce;
  s.plastic.saturationStress = 0.8;
  s.plastic.saturationRate = 50.0;
  return s;
}

/// Follows F(t) = I + t (F1 - I), t in (0, 1], in n committed steps from the virgin state.
template <int D>
std::vector<double> history(const Material& m, const MatD<D>& F1, int n = 10) {
  std::vector<double> st(m.stateSize());
  m.initialState(st.data());
  for (int k = 1; k <= n; ++k) {
    const MatD<D> F = MatD<D>::Identity() + (double(k) / n) * (F1 - MatD<D>::Identity());
    MatD<D> P;
    EXPECT_TRUE(m.stress<D>(F, st.data(), P, st.data()));  // trial aliases committed: allowed
  }
  return st;
}

/// The tangent at F from `committed` against finite differences; returns whether the point flowed.
template <int D>
bool checkTangent(const Material& m, const MatD<D>& F, const std::vector<double>& committed) {
  MatD<D> P, P2;
  TangentD<D> A;
  std::vector<double> trial(m.stateSize()), before = committed;
  EXPECT_TRUE(m.stressTangent<D>(F, committed.data(), P, A, trial.data()));
  EXPECT_TRUE(m.stress<D>(F, committed.data(), P2, nullptr));
  EXPECT_EQ((P - P2).cwiseAbs().maxCoeff(), 0.0) << "stressTangent and stress disagree on P";
  EXPECT_EQ(before, committed) << "an evaluation wrote the committed state";
  // Step 1e-7: plastic strains here are ~1e-2, so the step moves the trial Mises stress by
  // ~1e-5 of the yield stress and never crosses the surface in the "just inside / just past"
  // cases (1 % away); truncation ~h^2 and round-off ~1e-15 |P| / h ~ 1e-9 |A| stay far below 1e-6.
  const double h = 1e-7;
  const TangentD<D> Afd = fdTangent<D>(m, F, h, committed.data());
  EXPECT_LE(relMaxDiff(A, Afd), 1e-6) << "A =\n" << A << "\nA_fd =\n" << Afd;
  return m.yielding(trial.data());
}

/// Deviatoric-dominated deformation gradients for each dimension, scaled by s (s = 1 is well past yield).
template <int D>
MatD<D> shear(double s);
template <>
MatD<1> shear<1>(double s) { return (MatD<1>() << 1.0 + 0.02 * s).finished(); }
template <>
MatD<2> shear<2>(double s) {
  MatD<2> F;
  F << 1.0 + 0.012 * s, 0.02 * s, 0.004 * s, 1.0 - 0.006 * s;
  return F;
}
template <>
MatD<3> shear<3>(double s) {
  MatD<3> F;
  F << 1.0 + 0.012 * s, 0.02 * s, -0.003 * s, 0.004 * s, 1.0 - 0.006 * s, 0.007 * s, 0.001 * s, -0.005 * s,
      1.0 - 0.002 * s;
  return F;
}

/// The factor s at which shear<D>(s) from the virgin state reaches the yield surface (bisection).
template <int D>
double yieldFactor(const Material& m) {
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 200; ++it) {
    const double s = 0.5 * (lo + hi);
    std::vector<double> st(m.stateSize());
    MatD<D> P;
    EXPECT_TRUE(m.stress<D>(shear<D>(s), nullptr, P, st.data()));
    (m.yielding(st.data()) ? hi : lo) = s;
  }
  return 0.5 * (lo + hi);
}

template <int D>
void allRegimes(const MaterialSpec& spec) {
  const Material m(spec);
  std::vector<double> virgin(m.stateSize());
  m.initialState(virgin.data());
  const double sy = yieldFactor<D>(m);
  ASSERT_GT(sy, 0.0);
  ASSERT_LT(sy, 0.5);
  {
    SCOPED_TRACE("elastic");
    EXPECT_FALSE(checkTangent<D>(m, shear<D>(0.5 * sy), virgin));
  }
  {
    SCOPED_TRACE("just inside the yield surface");
    EXPECT_FALSE(checkTangent<D>(m, shear<D>(0.99 * sy), virgin));
  }
  {
    SCOPED_TRACE("just past the yield surface");
    EXPECT_TRUE(checkTangent<D>(m, shear<D>(1.01 * sy), virgin));
  }
  {
    SCOPED_TRACE("plastic loading from the virgin state");
    EXPECT_TRUE(checkTangent<D>(m, shear<D>(1.0), virgin));
  }
  const std::vector<double> hardened = history<D>(m, shear<D>(1.0));
  ASSERT_GT(m.equivalentPlasticStrain(hardened.data()), 0.0);
  {
    SCOPED_TRACE("plastic loading from a hardened state");
    EXPECT_TRUE(checkTangent<D>(m, shear<D>(1.3), hardened));
  }
  {
    SCOPED_TRACE("elastic unloading from a hardened state");
    EXPECT_FALSE(checkTangent<D>(m, shear<D>(0.9), hardened));
  }
  {
    SCOPED_TRACE("reverse loading past the yield surface");
    EXPECT_TRUE(checkTangent<D>(m, shear<D>(-1.5), hardened));
  }
  if constexpr (D >= 2) {
    // Equal principal stretches in the loaded plane with plastic flow: pure shear is replaced by
    // a stretch that is equal in two directions and differs in the third.
    MatD<D> Feq = MatD<D>::Identity();
    if constexpr (D == 3) {
      Feq = rot3(30, {1, 2, 3}) * Eigen::Vector3d(1.02, 1.02, 0.96).asDiagonal() * rot3(-50, {-2, 1, 0.5});
    } else {
      Feq = 1.02 * rot2(25);  // equal in-plane stretches; the out-of-plane one differs
    }
    SCOPED_TRACE("equal principal stretches");
    const bool flowed = checkTangent<D>(m, Feq, virgin);
    if (D == 3 || spec.planar == PlanarMode::PlaneStrain) {
      EXPECT_TRUE(flowed);
    }
  }
}

}  // namespace

TEST(Plasticity, Tangent1DHencky) { allRegimes<1>(plasticSpec(MaterialKind::Hencky, 1, PlanarMode::None)); }
TEST(Plasticity, Tangent1DSmallStrain) { allRegimes<1>(plasticSpec(MaterialKind::SmallStrain, 1, PlanarMode::None)); }
TEST(Plasticity, TangentPlaneStrainHencky) {
  allRegimes<2>(plasticSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStrain));
}
TEST(Plasticity, TangentPlaneStressHencky) {
  allRegimes<2>(plasticSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress));
}
TEST(Plasticity, TangentPlaneStrainSmallStrain) {
  allRegimes<2>(plasticSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStrain));
}
TEST(Plasticity, TangentPlaneStressSmallStrain) {
  allRegimes<2>(plasticSpec(MaterialKind::SmallStrain, 2, PlanarMode::PlaneStress));
}
TEST(Plasticity, Tangent3DHencky) { allRegimes<3>(plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None)); }
TEST(Plasticity, Tangent3DSmallStrain) { allRegimes<3>(plasticSpec(MaterialKind::SmallStrain, 3, PlanarMode::None)); }
TEST(Plasticity, Tangent3DHenckyVoce) { allRegimes<3>(plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None, true)); }
TEST(Plasticity, TangentPlaneStressHenckyVoce) {
  allRegimes<2>(plasticSpec(MaterialKind::Hencky, 2, PlanarMode::PlaneStress, true));
}
TEST(Plasticity, Tangent3DPerfectPlasticity) {
  MaterialSpec s = plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None);
  s.plastic.hardeningModulus = 0.0;
  allRegimes<3>(s);
}

namespace {

/// Uniaxial stress in 3D: F = diag(f, g, g) with P22 = P33 = 0, solved for g by Newton on the
/// tangent. Returns the axial Kirchhoff stress (Hencky) or axial stress (small strain) and
/// commits the state.
double uniaxial3(const Material& m, double f, std::vector<double>& st, double& g) {
  const bool finite = m.spec().kind == MaterialKind::Hencky;
  MatD<3> P;
  TangentD<3> A;
  for (int it = 0; it < 50; ++it) {
    const MatD<3> F = Eigen::Vector3d(f, g, g).asDiagonal();
    EXPECT_TRUE(m.stressTangent<3>(F, st.data(), P, A, nullptr));
    const double dg = -P(1, 1) / (A(4, 4) + A(4, 8));
    g += dg;
    if (std::abs(dg) < 1e-15) break;
  }
  const MatD<3> F = Eigen::Vector3d(f, g, g).asDiagonal();
  EXPECT_TRUE(m.stress<3>(F, st.data(), P, st.data()));
  EXPECT_LE(std::abs(P(1, 1)), 1e-12 * kY);
  return finite ? P(0, 0) * f : P(0, 0);
}

double axialStrain(const Material& m, double f) {
  return m.spec().kind == MaterialKind::Hencky ? std::log(f) : f - 1.0;
}

}  // namespace

// sigma = sigma_y + E H / (E + H) (eps - sigma_y / E) on loading; elastic unloading with slope E;
// the residual plastic strain after unloading to zero stress is eps_max - sigma_max / E; on
// reloading the point stays elastic up to sigma_max and then follows the same hardening line.
// In log strain and Kirchhoff stress this holds exactly at finite strain (coaxial loading).
TEST(Plasticity, UniaxialLoadUnloadReloadClosedForm) {
  for (MaterialKind kind : {MaterialKind::Hencky, MaterialKind::SmallStrain}) {
    for (int dim : {1, 3}) {
      SCOPED_TRACE(std::string(kind == MaterialKind::Hencky ? "Hencky " : "small strain ") + std::to_string(dim) + "D");
      const Material m(plasticSpec(kind, dim, PlanarMode::None));
      std::vector<double> st(m.stateSize());
      m.initialState(st.data());
      double g = 1.0;
      auto at = [&](double f) {
        if (dim == 3) return uniaxial3(m, f, st, g);
        MatD<1> F, P;
        F << f;
        EXPECT_TRUE(m.stress<1>(F, st.data(), P, st.data()));
        return kind == MaterialKind::Hencky ? P(0, 0) * f : P(0, 0);
      };
      const double E = kE, H = kH;
      auto hardeningLine = [&](double eps) { return kY + E * H / (E + H) * (eps - kY / E); };
      double sMax = 0.0, eMax = 0.0;
      for (double f = 1.0005; f <= 1.0301; f += 0.0025) {  // loading to 3 % (12 yield strains)
        const double s = at(f), e = axialStrain(m, f);
        const double expect = e <= kY / E ? E * e : hardeningLine(e);
        EXPECT_NEAR(s, expect, 1e-11 * kY) << "loading, eps = " << e;
        sMax = s;
        eMax = e;
      }
      EXPECT_NEAR(m.equivalentPlasticStrain(st.data()), eMax - sMax / E, 1e-12);
      // Unloading to zero stress: f0 with eps = eMax - sMax / E, the residual plastic strain.
      const double eRes = eMax - sMax / E;
      const double f0 = kind == MaterialKind::Hencky ? std::exp(eRes) : 1.0 + eRes;
      for (double t = 0.25; t <= 1.0; t += 0.25) {
        const double e = eMax + t * (eRes - eMax);
        const double f = kind == MaterialKind::Hencky ? std::exp(e) : 1.0 + e;
        EXPECT_NEAR(at(f), sMax + E * (e - eMax), 1e-11 * kY) << "unloading, eps = " << e;
        EXPECT_FALSE(m.yielding(st.data()));
      }
      EXPECT_NEAR(at(f0), 0.0, 1e-11 * kY);
      EXPECT_NEAR(m.equivalentPlasticStrain(st.data()), eRes, 1e-12);
      // Reloading: elastic up to sMax (a point 1e-4 below the previous maximum strain), then hardening.
      const double eBelow = eMax - 1e-4, eAbove = eMax + 5e-3;
      const double fBelow = kind == MaterialKind::Hencky ? std::exp(eBelow) : 1.0 + eBelow;
      const double fAbove = kind == MaterialKind::Hencky ? std::exp(eAbove) : 1.0 + eAbove;
      EXPECT_NEAR(at(fBelow), sMax - E * 1e-4, 1e-11 * kY);
      EXPECT_FALSE(m.yielding(st.data()));
      EXPECT_NEAR(at(fAbove), hardeningLine(eAbove), 1e-11 * kY);
      EXPECT_TRUE(m.yielding(st.data()));
    }
  }
}

// Voce hardening with H = 0: in uniaxial stress the axial stress at equivalent plastic strain a
// is sigma_inf - (sigma_inf - sigma_y0) exp(-delta a), and a = eps - sigma / E.
TEST(Plasticity, UniaxialVoceMatchesItsIntegral) {
  for (int dim : {1, 3}) {
    SCOPED_TRACE(std::to_string(dim) + "D");
    MaterialSpec spec = plasticSpec(MaterialKind::Hencky, dim, PlanarMode::None, true);
    spec.plastic.hardeningModulus = 0.0;
    const Material m(spec);
    std::vector<double> st(m.stateSize());
    m.initialState(st.data());
    double g = 1.0;
    for (double e = 0.005; e <= 0.2; e += 0.005) {
      const double f = std::exp(e);
      double s;
      if (dim == 3) {
        s = uniaxial3(m, f, st, g);
      } else {
        MatD<1> F, P;
        F << f;
        EXPECT_TRUE(m.stress<1>(F, st.data(), P, st.data()));
        s = P(0, 0) * f;
      }
      const double a = e - s / kE;
      EXPECT_NEAR(m.equivalentPlasticStrain(st.data()), a, 1e-12);
      EXPECT_NEAR(s, 0.8 - (0.8 - kY) * std::exp(-50.0 * a), 1e-12) << "eps = " << e;
    }
  }
}

// A superposed rotation: P(R F) = R P(F) from the same committed state, the same trial state;
// re-evaluating at the F a state was committed at creates no further plastic flow.
TEST(Plasticity, ObjectiveAndNoFlowUnderRotation) {
  const Material m(plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None));
  const MatD<3> F1 = shear<3>(1.0);
  const std::vector<double> st = history<3>(m, F1);
  const MatD<3> F2 = shear<3>(1.4);
  const Eigen::Matrix3d R = rot3(70, {1, -2, 0.5});
  MatD<3> P1, P2;
  std::vector<double> t1(8), t2(8);
  ASSERT_TRUE(m.stress<3>(F2, st.data(), P1, t1.data()));
  ASSERT_TRUE(m.stress<3>(R * F2, st.data(), P2, t2.data()));
  EXPECT_LE(relMaxDiff(P2, R * P1), 1e-13);
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(t1[k], t2[k], 1e-13) << k;
  // Rigid rotation of the committed configuration: no new plastic strain, stress rotated.
  MatD<3> P0, P3;
  std::vector<double> t3(8);
  ASSERT_TRUE(m.stress<3>(F1, st.data(), P0, nullptr));
  ASSERT_TRUE(m.stress<3>(R * F1, st.data(), P3, t3.data()));
  EXPECT_LE(t3[6] - st[6], 1e-14);
  EXPECT_LE(relMaxDiff(P3, R * P0), 1e-13);
}

// det Fp = 1: det c = det Cp^{-1} stays 1 through a long cyclic history, to round-off.
TEST(Plasticity, PlasticFlowIsIsochoric) {
  const Material m(plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None));
  std::vector<double> st(8);
  m.initialState(st.data());
  for (int k = 0; k < 200; ++k) {
    const double s = 6.0 * std::sin(0.1 * k);  // +-6 x the shear<3>(1) amplitude
    MatD<3> P;
    ASSERT_TRUE(m.stress<3>(shear<3>(s), st.data(), P, st.data()));
  }
  Eigen::Matrix3d c;
  c << st[0], st[1], st[2], st[1], st[3], st[4], st[2], st[4], st[5];
  EXPECT_GT(st[6], 0.5);  // a large accumulated plastic strain
  EXPECT_NEAR(c.determinant(), 1.0, 1e-13);
}

// Below the yield surface the plastic material is the elastic one, including plane stress (where
// it solves for F33 itself instead of using the closed form).
TEST(Plasticity, ElasticRegimeEqualsElasticMaterial) {
  for (MaterialKind kind : {MaterialKind::Hencky, MaterialKind::SmallStrain}) {
    for (PlanarMode mode : {PlanarMode::PlaneStrain, PlanarMode::PlaneStress}) {
      MaterialSpec es = makeSpec(kind, 2, mode), ps = plasticSpec(kind, 2, mode);
      ps.plastic.yieldStress = 1e6;
      const Material me(es), mp(ps);
      for (const auto& c : deformationCases<2>()) {
        SCOPED_TRACE(c.name);
        MatD<2> Pe, Pp;
        TangentD<2> Ae, Ap;
        Eigen::Matrix3d se, sp;
        ASSERT_TRUE(me.stressTangent<2>(c.F, Pe, Ae));
        ASSERT_TRUE(mp.stressTangent<2>(c.F, nullptr, Pp, Ap, nullptr));
        ASSERT_TRUE(me.cauchy<2>(c.F, se));
        ASSERT_TRUE(mp.cauchy<2>(c.F, nullptr, sp));
        const double scale = kE;
        EXPECT_LE((Pe - Pp).cwiseAbs().maxCoeff(), 1e-12 * scale);
        EXPECT_LE((Ae - Ap).cwiseAbs().maxCoeff(), 1e-12 * scale);
        EXPECT_LE((se - sp).cwiseAbs().maxCoeff(), 1e-12 * scale);
      }
    }
  }
}

TEST(Plasticity, RejectsBadParameters) {
  auto expectThrow = [](MaterialSpec s, const char* word) {
    try {
      Material m(s);
      ADD_FAILURE() << "accepted: " << word;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  MaterialSpec s = plasticSpec(MaterialKind::Hencky, 3, PlanarMode::None, true);
  MaterialSpec b = s;
  b.plastic.yieldStress = 0.0;
  expectThrow(b, "yield stress");
  b = s;
  b.plastic.hardeningModulus = -1.0;
  expectThrow(b, "hardening modulus");
  b = s;
  b.plastic.saturationStress = 0.4;
  expectThrow(b, "saturation stress");
  b = s;
  b.plastic.saturationRate = 0.0;
  expectThrow(b, "saturation rate");
  b = s;
  b.plastic.yieldStress = std::numeric_limits<double>::infinity();
  expectThrow(b, "yield stress");
}

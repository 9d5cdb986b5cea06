// Model-level verification: the element tangent against central finite differences of the
// residual, symmetry, the patch test, objectivity, and the stabilisation's affine invariance.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"
#include "ModelTestUtil.hpp"

using namespace perinox;
using perinox::testutil::DenseSink;
using perinox::testutil::smallLattice;

namespace {

MaterialSpec material(int dim, PlanarMode pm = PlanarMode::PlaneStrain) {
  MaterialSpec m;
  m.dim = dim;
  m.planar = dim == 2 ? pm : PlanarMode::None;
  m.E = 12.0e6;
  m.nu = dim == 1 ? 0.0 : 0.2;
  return m;
}

std::unique_ptr<Model> makeModel(const Discretization& d, const MaterialSpec& m, double G) {
  auto model = std::make_unique<Model>(m, localParticles(d, 0, d.size()));
  model->enableCorrespondence();
  if (G > 0) model->enableStabilization({G, micromodulusC(m, d.horizon, d.thickness)});
  return model;
}

std::vector<double> randomDisplacement(int n, int D, double amp, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  std::vector<double> x(n * D);
  for (auto& v : x) v = u(gen);
  return x;
}

/// Max relative difference between the analytic element tangent and central differences, and
/// the relative asymmetry, for a model at a random state.
std::pair<double, double> tangentErrors(const Model& model, const Discretization& d, const std::vector<double>& u,
                                        double relStep = 1e-6) {
  const int n = d.size(), D = d.dim;
  DenseSink s(D, n);
  model.evaluate(u, s, true);
  const double h = relStep * d.dx;
  Eigen::MatrixXd Kfd(n * D, n * D);
  for (int k = 0; k < n * D; ++k) {
    auto up = u, um = u;
    up[k] += h;
    um[k] -= h;
    DenseSink sp(D, n), sm(D, n);
    model.evaluate(up, sp, false);
    model.evaluate(um, sm, false);
    Kfd.col(k) = (sp.r - sm.r) / (2 * h);
  }
  const double scale = s.K.cwiseAbs().maxCoeff();
  return {(s.K - Kfd).cwiseAbs().maxCoeff() / scale, (s.K - s.K.transpose()).cwiseAbs().maxCoeff() / scale};
}

/// The matrix-free product J v against an assembled tangent K: max |J v - K v| and max |K v|.
std::pair<double, double> productDifference(const Model& model, const Eigen::MatrixXd& K, const std::vector<double>& u,
                                            const std::vector<double>& v) {
  const int N = static_cast<int>(v.size());
  Eigen::VectorXd ve(N);
  for (int k = 0; k < N; ++k) ve[k] = v[k];
  const Eigen::VectorXd r = K * ve;
  std::vector<double> y(N, 0.0);
  model.applyTangent(u, v, y.data());
  double dd = 0;
  for (int k = 0; k < N; ++k) dd = std::max(dd, std::abs(y[k] - r[k]));
  return {dd, r.cwiseAbs().maxCoeff()};
}

struct Case {
  int dim;
  double factor;
  double G;
  PlanarMode pm;
};

class TangentFD : public ::testing::TestWithParam<Case> {};

}  // namespace

// The analytic tangent must match central differences of the assembled residual. Central
// differences with step h have truncation error O(h^2 |R'''|) and round-off O(eps |R| / h);
// with h = 1e-6 * dx both are below 1e-8 relative for these smooth fields, so 1e-6 leaves a
// margin while any missing term (which changes entries at O(1)) fails clearly.
TEST_P(TangentFD, MatchesFiniteDifferencesAndIsSymmetric) {
  const Case c = GetParam();
  const int nx = c.dim == 1 ? 12 : (c.dim == 2 ? 9 : 7);
  Discretization d = smallLattice(c.dim, c.factor, nx);
  auto model = makeModel(d, material(c.dim, c.pm), c.G);
  const int n = d.size(), D = c.dim;
  // Large, random deformation (up to 3% of the spacing per particle on top of a 20% stretch
  // and a rotation), so nonlinear terms matter.
  std::vector<double> u = randomDisplacement(n, D, 0.03 * d.dx, 7 + c.dim);
  for (int i = 0; i < n; ++i) {
    u[i * D] += 0.2 * d.X[i][0];
    if (D > 1) {
      const double th = 0.3;
      const double x = d.X[i][0] * 1.2, y = d.X[i][1];
      u[i * D] += (std::cos(th) - 1) * x - std::sin(th) * y;
      u[i * D + 1] += std::sin(th) * x + (std::cos(th) - 1) * y;
    }
  }
  const auto [err, asym] = tangentErrors(*model, d, u);
  EXPECT_LT(err, 1e-6);
  EXPECT_LT(asym, 1e-10);
}

INSTANTIATE_TEST_SUITE_P(
    AllDims, TangentFD,
    ::testing::Values(Case{1, 1.015, 0, PlanarMode::None}, Case{1, 3.015, 0.1, PlanarMode::None},
                      Case{2, 1.015, 0, PlanarMode::PlaneStrain}, Case{2, 2.015, 0, PlanarMode::PlaneStrain},
                      Case{2, 3.015, 0, PlanarMode::PlaneStrain}, Case{2, 2.015, 0, PlanarMode::PlaneStress},
                      Case{2, 2.015, 0.05, PlanarMode::PlaneStrain}, Case{2, 3.015, 5.0, PlanarMode::PlaneStress},
                      Case{3, 1.015, 0, PlanarMode::None}, Case{3, 2.015, 0, PlanarMode::None},
                      Case{3, 2.015, 1.0, PlanarMode::None}));

// Patch test: an affine field u = H X gives F = I + H at every particle whose family is
// complete (it holds for every family in fact, since sum Y (x) xi V = (I+H) K exactly).
TEST(Model, PatchTestAffineFieldReproducesGradient) {
  for (int dim : {2, 3}) {
    Discretization d = smallLattice(dim, 2.015, dim == 2 ? 9 : 7);
    auto model = makeModel(d, material(dim), 0.0);
    const int D = dim;
    Eigen::Matrix3d H;
    H << 0.1, -0.05, 0.02, 0.03, -0.07, 0.01, 0.04, 0.02, 0.05;
    std::vector<double> u(d.size() * D);
    for (int i = 0; i < d.size(); ++i)
      for (int a = 0; a < D; ++a) u[i * D + a] = (H.topLeftCorner(D, 3) * d.X[i])[a] + 0.3;  // plus a translation
    auto out = model->outputs(u);
    for (const auto& o : out)
      EXPECT_LT((o.F.topLeftCorner(D, D) - (Eigen::MatrixXd::Identity(D, D) + H.topLeftCorner(D, D))).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// Objectivity: a rigid rotation (including 90 degrees) gives zero stress and zero residual.
TEST(Model, RigidRotationGivesNoForce) {
  for (double deg : {17.0, 90.0}) {
    Discretization d = smallLattice(2, 3.015, 9);
    auto model = makeModel(d, material(2), 0.3);
    const double th = deg * M_PI / 180;
    std::vector<double> u(d.size() * 2);
    for (int i = 0; i < d.size(); ++i) {
      const double x = d.X[i][0], y = d.X[i][1];
      u[2 * i] = std::cos(th) * x - std::sin(th) * y - x + 1.0;
      u[2 * i + 1] = std::sin(th) * x + std::cos(th) * y - y - 2.0;
    }
    DenseSink s(2, d.size());
    model->evaluate(u, s, false);
    // The scale of a unit-strain force: E * V * dx (per particle).
    const double fscale = 12e6 * d.volume[0] / d.dx;
    EXPECT_LT(s.r.cwiseAbs().maxCoeff(), 1e-9 * fscale) << "rotation " << deg;
    for (const auto& o : model->outputs(u)) EXPECT_LT(o.cauchy.cwiseAbs().maxCoeff(), 1e-6);
  }
}

// The stabilisation force vanishes for any affine deformation (seed 000 eq. 43): residuals with
// and without it agree, even for a large G.
TEST(Model, StabilizationVanishesForAffineDeformation) {
  Discretization d = smallLattice(2, 3.015, 9);
  auto plain = makeModel(d, material(2), 0.0);
  auto stab = makeModel(d, material(2), 10.0);
  std::vector<double> u(d.size() * 2);
  for (int i = 0; i < d.size(); ++i) {
    u[2 * i] = 0.3 * d.X[i][0] + 0.1 * d.X[i][1];
    u[2 * i + 1] = -0.2 * d.X[i][0] + 0.15 * d.X[i][1];
  }
  DenseSink a(2, d.size()), b(2, d.size());
  plain->evaluate(u, a, false);
  stab->evaluate(u, b, false);
  EXPECT_LT((a.r - b.r).cwiseAbs().maxCoeff(), 1e-9 * a.r.cwiseAbs().maxCoeff());
}

// The zero-energy mode of the correspondence model: a checkerboard displacement
// u_i = a (-1)^(ix+iy) e_x leaves F = I at every particle with a symmetric family (the odd
// neighbours cancel in sum (u_j - u_i) (x) xi_j), so the unstabilised model gives no force at
// particles whose whole neighbourhood is interior, while Silling's term restores it with a
// force proportional to G and opposed to the displacement.
TEST(Model, CheckerboardModeIsRestoredOnlyByStabilization) {
  for (double factor : {1.015, 2.015, 3.015}) {
    LatticeSpec s;
    s.dim = 2;
    s.counts = {24, 24, 1};
    s.upper = Vec3(2.4, 2.4, 1.0);
    s.horizonFactor = factor;
    Discretization d = buildLattice(s);
    const MaterialSpec m = material(2);
    auto plain = makeModel(d, m, 0.0);
    auto g1 = makeModel(d, m, 0.1);
    auto g2 = makeModel(d, m, 0.2);
    const double a = 1e-3 * d.dx;
    std::vector<double> u(d.size() * 2, 0.0);
    for (int i = 0; i < d.size(); ++i) {
      const int ix = static_cast<int>(std::floor(d.X[i][0] / d.dx)), iy = static_cast<int>(std::floor(d.X[i][1] / d.dx));
      u[2 * i] = ((ix + iy) % 2 ? -a : a);
    }
    DenseSink r0(2, d.size()), r1(2, d.size()), r2(2, d.size());
    plain->evaluate(u, r0, false);
    g1->evaluate(u, r1, false);
    g2->evaluate(u, r2, false);
    // Interior: at least two horizons (plus a spacing) from every edge, so every particle whose
    // state reaches i has a complete, symmetric family.
    const double margin = 2 * d.horizon + d.dx;
    int count = 0;
    double maxPlain = 0, maxStab = 0;
    for (int i = 0; i < d.size(); ++i) {
      const auto& X = d.X[i];
      if (X[0] < margin || X[1] < margin || X[0] > 2.4 - margin || X[1] > 2.4 - margin) continue;
      ++count;
      maxPlain = std::max(maxPlain, std::abs(r0.r[2 * i]) + std::abs(r0.r[2 * i + 1]));
      maxStab = std::max(maxStab, std::abs(r1.r[2 * i]));
      EXPECT_GT(r1.r[2 * i] * u[2 * i], 0.0) << "stabilisation must oppose the mode";
      EXPECT_NEAR(r2.r[2 * i], 2.0 * r1.r[2 * i], 1e-9 * std::abs(r1.r[2 * i])) << "force must be proportional to G";
    }
    ASSERT_GT(count, 10);
    ASSERT_GT(maxStab, 0.0);
    EXPECT_LT(maxPlain, 1e-9 * maxStab) << "horizon " << factor;
  }
}

// Damage: the softened tangent against finite differences, with bonds below s_min, inside the
// softening band and beyond s_cr. s_min and s_cr are placed in gaps of the bond-stretch
// distribution (no bond within 1e-5 of a kink; the differencing step moves stretches by ~1e-7), where central differences are smooth.
TEST(Model, DamageTangentMatchesFiniteDifferences) {
  for (int dim : {2, 3}) {
    Discretization d = smallLattice(dim, 2.015, dim == 2 ? 8 : 6);
    const int n = d.size(), D = dim;
    std::vector<double> u = randomDisplacement(n, D, 0.01 * d.dx, 11);
    for (int i = 0; i < n; ++i) u[i * D] += 0.03 * d.X[i][0];  // mostly positive stretches
    // Stretches of all bonds.
    std::vector<double> s;
    for (int i = 0; i < n; ++i)
      for (auto q = d.familyOffset[i]; q < d.familyOffset[i + 1]; ++q) {
        const int j = d.familyIndex[q];
        Eigen::VectorXd xi(D), y(D);
        for (int a = 0; a < D; ++a) {
          xi[a] = d.X[j][a] - d.X[i][a];
          y[a] = xi[a] + u[j * D + a] - u[i * D + a];
        }
        s.push_back((y.norm() - xi.norm()) / xi.norm());
      }
    std::sort(s.begin(), s.end());
    s.erase(std::unique(s.begin(), s.end()), s.end());  // each bond appears from both ends
    auto gapNear = [&](double frac) {
      for (std::size_t k = static_cast<std::size_t>(frac * s.size()); k + 1 < s.size(); ++k)
        if (s[k] > 0 && s[k + 1] - s[k] > 2e-5) return 0.5 * (s[k] + s[k + 1]);
      return s.back() + 1.0;
    };
    DamageSpec ds;
    ds.sMin = gapNear(0.3);
    ds.sCr = gapNear(0.75);
    ds.beta = 3.0;
    ASSERT_LT(ds.sMin, ds.sCr);
    int below = 0, band = 0, beyond = 0;
    for (double v : s) (v < ds.sMin ? below : (v < ds.sCr ? band : beyond))++;
    ASSERT_GT(below, 0);
    ASSERT_GT(band, 0);
    ASSERT_GT(beyond, 0);

    for (auto law : {DamageSpec::Softening::Paper, DamageSpec::Softening::Continuous}) {
      ds.softening = law;
      auto model = makeModel(d, material(dim), 0.05);
      model->enableDamage(ds);
      const auto [err, asym] = tangentErrors(*model, d, u, 1e-7);
      EXPECT_LT(err, 1e-6) << "dim " << dim << (law == DamageSpec::Softening::Paper ? ", Paper" : ", Continuous");
      // Damage makes the tangent unsymmetric (that is why GMRES is required).
      EXPECT_GT(asym, 1e-6);
    }
  }
}

/// dT_s/ds against a central difference (h = 1e-9, truncation ~1e-12 relative; bound 1e-5) and
/// negative, at three stretches inside the band of ds = (0.0015, 0.002).
void expectSofteningDerivativeInBand(const DamageSpec& ds) {
  for (double s : {0.0016, 0.00175, 0.0019}) {
    double T, dT, Tp, Tm, d0;
    const double h = 1e-9;
    bondSoftening(ds, s + h, Tp, d0);
    bondSoftening(ds, s - h, Tm, d0);
    bondSoftening(ds, s, T, dT);
    EXPECT_NEAR(dT, (Tp - Tm) / (2 * h), 1e-5 * std::abs(dT)) << "s = " << s;
    EXPECT_LT(dT, 0.0);
  }
}

// The softening function: values at the band's ends and the corrected derivative
// dT_s/ds = -1/2 sech^2(n) dn/ds against a central difference.
TEST(Model, BondSofteningFunction) {
  DamageSpec ds{0.0015, 0.002, 3.0};
  double T, dT;
  bondSoftening(ds, 0.001, T, dT);
  EXPECT_EQ(T, 1.0);
  bondSoftening(ds, 0.0025, T, dT);
  EXPECT_EQ(T, 0.0);
  bondSoftening(ds, 0.00175, T, dT);  // middle of the band: n = 0
  EXPECT_NEAR(T, 0.5, 1e-15);
  expectSofteningDerivativeInBand(ds);
  // The paper's law jumps at both ends of the band: by 1/2 (1 - tanh 3) = 0.0025.
  const double e = 1e-12;
  bondSoftening(ds, ds.sMin, T, dT);
  EXPECT_NEAR(1.0 - T, 0.5 * (1.0 - std::tanh(3.0)), 1e-12);
  bondSoftening(ds, ds.sCr - e, T, dT);
  EXPECT_NEAR(T, 0.5 * (1.0 - std::tanh(3.0)), 1e-8);
}

// The continuous law: exactly 1 at s_min and 0 at s_cr (no jump; |T(s_cr - e)| is of order
// |dT/ds| e = 6000 * 0.0099 / tanh(3) * 1e-12 ~ 6e-14, bound 1e-10), 1/2 in the middle, and
// its derivative dT/ds = -1/2 sech^2(n) (dn/ds) / tanh(beta) against a central difference.
TEST(Model, ContinuousSofteningFunction) {
  DamageSpec ds{0.0015, 0.002, 3.0, DamageSpec::Softening::Continuous};
  double T, dT;
  const double e = 1e-12;
  bondSoftening(ds, ds.sMin, T, dT);
  EXPECT_NEAR(T, 1.0, 1e-14);
  bondSoftening(ds, ds.sMin - e, T, dT);
  EXPECT_EQ(T, 1.0);
  bondSoftening(ds, ds.sCr - e, T, dT);
  EXPECT_NEAR(T, 0.0, 1e-10);
  bondSoftening(ds, ds.sCr, T, dT);
  EXPECT_EQ(T, 0.0);
  bondSoftening(ds, 0.00175, T, dT);
  EXPECT_NEAR(T, 0.5, 1e-15);
  expectSofteningDerivativeInBand(ds);
  for (double s : {0.0016, 0.00175, 0.0019}) {
    bondSoftening(ds, s, T, dT);
    // It lies below the paper's law's rescaling endpoints: T_c = (T_p - T_p(sCr-)) / tanh(beta).
    DamageSpec dp = ds;
    dp.softening = DamageSpec::Softening::Paper;
    double Tpap, dTp;
    bondSoftening(dp, s, Tpap, dTp);
    EXPECT_NEAR(T, (Tpap - 0.5 * (1.0 - std::tanh(3.0))) / std::tanh(3.0), 1e-14);
  }
}

// Broken bonds stay broken, and the damage index matches a hand count: in a 1D chain with
// horizon 1.015 dx, pulling the last particle away breaks exactly its one bond; the last
// particle then has phi = 1 and its neighbour phi = 1/2 (one of two equal-volume bonds).
TEST(Model, BreakingIsPermanentAndDamageIndexCounts) {
  Discretization d = smallLattice(1, 1.015, 6);
  auto model = makeModel(d, material(1), 0.0);
  model->enableDamage(DamageSpec{0.01, 0.02, 3.0});
  const int n = d.size();
  std::vector<double> u(n, 0.0);
  u[n - 1] = 0.05 * d.dx;  // stretch 5 % > s_cr
  EXPECT_EQ(model->breakBonds(u), 1);
  auto phi = model->damageIndex();
  EXPECT_DOUBLE_EQ(phi[n - 1], 1.0);
  EXPECT_DOUBLE_EQ(phi[n - 2], 0.5);
  for (int i = 0; i < n - 2; ++i) EXPECT_DOUBLE_EQ(phi[i], 0.0);
  // Unloading does not heal the bond.
  std::fill(u.begin(), u.end(), 0.0);
  EXPECT_EQ(model->breakBonds(u), 0);
  EXPECT_DOUBLE_EQ(model->damageIndex()[n - 1], 1.0);
  // The isolated particle has a singular shape tensor and is reported.
  auto sing = model->singularParticles();
  ASSERT_EQ(sing.size(), 1u);
  EXPECT_EQ(sing[0], n - 1);
}


// Supplementary-force controls (seed 001 eqs 7-8): tangents against finite differences. The
// springs derive from an energy (symmetric); the average displacement state does not.
TEST(Model, ControlTangentsMatchFiniteDifferences) {
  for (int dim : {1, 2, 3}) {
    Discretization d = smallLattice(dim, 2.015, dim == 1 ? 10 : (dim == 2 ? 7 : 5));
    const auto u = randomDisplacement(d.size(), dim, 0.02 * d.dx, 5);
    for (auto kind : {ControlSpec::Kind::Springs, ControlSpec::Kind::AverageDisplacement}) {
      auto model = makeModel(d, material(dim), 0.0);
      model->enableControl(ControlSpec{kind, 3.0e9});
      const auto [err, asym] = tangentErrors(*model, d, u);
      EXPECT_LT(err, 1e-6) << "dim " << dim;
      if (kind == ControlSpec::Kind::Springs) {
        EXPECT_LT(asym, 1e-10);
      }
    }
  }
}

// Stress points in 1D (seed 001, 3.1), with a variable modulus: tangent against finite
// differences and symmetric (energy-derived); and the interior equation of a uniform bar at
// small strain is the three-point stencil u_{i-1} - 2 u_i + u_{i+1} = 0 (seed 001 eq. 12): a
// linear field is an equilibrium while the no-control scheme's zero-energy mode is not.
TEST(Model, StressPoints1D) {
  Discretization d = smallLattice(1, 1.015, 12);
  MaterialSpec m = material(1);
  m.kind = MaterialKind::SmallStrain;
  auto lp = localParticles(d, 0, d.size());
  for (int i = 0; i < d.size(); ++i) lp.modulusScale.push_back(1.0 + 0.5 * std::sin(3.0 * i));
  Model model(m, lp);
  model.enableStressPoints();
  const auto u = randomDisplacement(d.size(), 1, 0.02 * d.dx, 9);
  const auto [err, asym] = tangentErrors(model, d, u);
  EXPECT_LT(err, 1e-6);
  EXPECT_LT(asym, 1e-10);

  Model uniform(m, localParticles(d, 0, d.size()));
  uniform.enableStressPoints();
  Model plain(m, localParticles(d, 0, d.size()));
  plain.enableCorrespondence();
  std::vector<double> zigzag(d.size()), linear(d.size());
  for (int i = 0; i < d.size(); ++i) {
    zigzag[i] = (i % 2 ? 1e-3 : -1e-3) * d.dx;
    linear[i] = 1e-3 * d.X[i][0];
  }
  DenseSink zs(1, d.size()), zp(1, d.size()), ls(1, d.size());
  uniform.evaluate(zigzag, zs, false);
  plain.evaluate(zigzag, zp, false);
  uniform.evaluate(linear, ls, false);
  double maxZs = 0, maxZp = 0, maxLs = 0;
  for (int i = 2; i < d.size() - 2; ++i) {  // interior: both neighbours have two stress points
    maxZs = std::max(maxZs, std::abs(zs.r[i]));
    maxZp = std::max(maxZp, std::abs(zp.r[i]));
    maxLs = std::max(maxLs, std::abs(ls.r[i]));
  }
  EXPECT_GT(maxZs, 0.0);
  EXPECT_LT(maxZp, 1e-12 * maxZs) << "no control: the zigzag is a zero-energy mode";
  EXPECT_LT(maxLs, 1e-12 * maxZs) << "stress points: a linear field is in equilibrium";
}

// Stress points in 2D and 3D (seed 001, 3.2): tangent against finite differences, symmetric
// (energy-derived), and the patch test: an affine field gives zero force at every particle whose
// neighbours all have complete families (every stress point then has K_p = V dx^2 I).
TEST(Model, StressPoints2D3D) {
  for (int dim : {2, 3}) {
    Discretization d = smallLattice(dim, 1.015, dim == 2 ? 8 : 6);
    MaterialSpec m = material(dim);
    Model model(m, localParticles(d, 0, d.size()));
    model.enableStressPoints(7);
    const auto u = randomDisplacement(d.size(), dim, 0.02 * d.dx, 21);
    const auto [err, asym] = tangentErrors(model, d, u);
    EXPECT_LT(err, 1e-6) << "dim " << dim;
    EXPECT_LT(asym, 1e-10) << "dim " << dim;

    Eigen::Matrix3d H;
    H << 0.02, -0.01, 0.005, 0.015, -0.03, 0.01, 0.0, 0.02, 0.01;
    std::vector<double> ua(d.size() * dim);
    for (int i = 0; i < d.size(); ++i)
      for (int a = 0; a < dim; ++a) ua[i * dim + a] = (H.topLeftCorner(dim, 3) * d.X[i])[a];
    DenseSink s(dim, d.size());
    model.evaluate(ua, s, false);
    double interior = 0, all = 0;
    for (int i = 0; i < d.size(); ++i) {
      bool inside = true;
      for (int a = 0; a < dim; ++a)
        inside = inside && d.X[i][a] > 1.9 * d.dx && d.X[i][a] < d.boxUpper[a] - 1.9 * d.dx;
      for (int a = 0; a < dim; ++a) {
        all = std::max(all, std::abs(s.r[i * dim + a]));
        if (inside) interior = std::max(interior, std::abs(s.r[i * dim + a]));
      }
    }
    ASSERT_GT(all, 0.0);
    EXPECT_LT(interior, 1e-10 * all) << "dim " << dim;
  }
}

// The matrix-free tangent product (Model::applyTangent, built from the linearised kernels)
// equals the assembled element tangents times v, for every effect alone and combined, in 1D,
// 2D and 3D, with damage on bonds below, inside and beyond the softening band. Both are exact
// derivatives summed in different orders, so they agree to round-off: 1e-12 relative. A second
// product at one state without damage takes the affine path (dt_l = A xi_l + c dY_l + k);
// the Jacobian's diagonal (Model::addJacobianDiagonal) equals the assembled one's too.
TEST(Model, MatrixFreeProductEqualsAssembledTangent) {
  struct Case {
    const char* name;
    bool corr, stab, springs, ads, sp, dmg, smallStrain, continuous = false;
  };
  const Case cases[] = {
      {"correspondence", true, false, false, false, false, false, false},
      {"correspondence small strain", true, false, false, false, false, false, true},
      {"stabilised", true, true, false, false, false, false, false},
      {"springs", true, false, true, false, false, false, false},
      {"average displacement", true, false, false, true, false, false, false},
      {"stress points", false, false, false, false, true, false, false},
      {"stress points + damage", false, false, false, false, true, true, false},
      {"stabilised + damage", true, true, false, false, false, true, false},
      {"stabilised + continuous damage", true, true, false, false, false, true, false, true},
      {"springs + damage", true, false, true, false, false, true, false},
      {"average displacement + damage", true, false, false, true, false, true, false},
  };
  for (int dim : {1, 2, 3}) {
    for (const Case& c : cases)
    for (const auto form : {Model::ProductForm::PerBond, Model::ProductForm::Gathered}) {
      const double factor = c.sp ? 1.015 : 2.015;
      Discretization d = smallLattice(dim, factor, dim == 1 ? 12 : (dim == 2 ? 7 : 5));
      const int n = d.size(), D = dim;
      MaterialSpec m = material(dim);
      if (c.smallStrain) m.kind = MaterialKind::SmallStrain;
      auto lp = localParticles(d, 0, n);
      for (int i = 0; i < n; ++i) lp.modulusScale.push_back(1.0 + 0.3 * std::cos(2.0 * i));
      Model model(m, lp);
      model.setProductForm(form);
      if (c.sp) model.enableStressPoints(3);
      if (c.corr) model.enableCorrespondence();
      if (c.springs) model.enableControl(ControlSpec{ControlSpec::Kind::Springs, 2.0e9});
      if (c.ads) model.enableControl(ControlSpec{ControlSpec::Kind::AverageDisplacement, 2.0e9});
      if (c.stab) model.enableStabilization({0.3, micromodulusC(m, d.horizon, d.thickness)});
      auto u = randomDisplacement(n, D, 0.01 * d.dx, 17);
      for (int i = 0; i < n; ++i) u[i * D] += 0.03 * d.X[i][0];  // stretches spread over the band
      if (c.dmg)
        model.enableDamage(DamageSpec{0.02, 0.04, 3.0,
                                      c.continuous ? DamageSpec::Softening::Continuous : DamageSpec::Softening::Paper});
      // J v against the assembled tangent at (uu, vv). The model keeps the linearisation between
      // products at one state: a second direction at the same state, a new state, and the same
      // state after bonds broke must each agree too (a stale linearisation would not).
      auto againstAssembled = [&](const std::vector<double>& uu, const std::vector<double>& vv, const char* what) {
        DenseSink ss(D, n);
        model.evaluate(uu, ss, true);
        Eigen::VectorXd vve(n * D);
        for (int k = 0; k < n * D; ++k) vve[k] = vv[k];
        const Eigen::VectorXd r = ss.K * vve;
        std::vector<double> y(n * D, 0.0);
        model.applyTangent(uu, vv, y.data());
        double dd = 0;
        for (int k = 0; k < n * D; ++k) dd = std::max(dd, std::abs(y[k] - r[k]));
        ASSERT_GT(r.cwiseAbs().maxCoeff(), 0.0) << c.name << ", dim " << dim << ": " << what;
        EXPECT_LT(dd, 1e-12 * r.cwiseAbs().maxCoeff()) << c.name << ", dim " << dim << ": " << what;
        // The diagonal from the element tangents' diagonal blocks alone is the assembled one's.
        std::vector<double> dg(n * D, 0.0);
        model.addJacobianDiagonal(uu, dg.data());
        double ddg = 0;
        for (int k = 0; k < n * D; ++k) ddg = std::max(ddg, std::abs(dg[k] - ss.K(k, k)));
        EXPECT_LT(ddg, 1e-12 * ss.K.diagonal().cwiseAbs().maxCoeff()) << c.name << ", dim " << dim << ": diagonal, " << what;
      };
      const auto v = randomDisplacement(n, D, 1.0, 23);
      std::vector<double> jv(n * D, 0.0);
      againstAssembled(u, v, "first product");
      againstAssembled(u, randomDisplacement(n, D, 1.0, 29), "second direction, same state");
      auto u2 = u;
      for (int i = 0; i < n; ++i) u2[i * D] += 0.0005 * d.X[i][0] * d.X[i][0] / d.dx;
      againstAssembled(u2, v, "new state");
      if (c.dmg && !c.sp) {
        model.applyTangent(u2, v, jv.data());
        ASSERT_GT(model.breakBondsAbove(u2, model.maxIntactStretch(u2) - 1e-14), 0) << c.name;
        againstAssembled(u2, v, "same state, bonds broken");
      }
    }
  }
}

// Stress output with stress points (seed 001: "reported stress is the average over a particle's
// stress points"): in 1D the left stress point owns the bond to i-1 and the right one the bond
// to i+1, so at a kink of the displacement the particle's F and Cauchy stress must be the means
// of sigma(F_left) and sigma(F_right) (equal bond volumes), times the particle's modulus scale.
// Hencky makes sigma nonlinear in F, so the mean of the stresses differs from the stress of the
// mean F (the plain correspondence output), and the test tells the two apart.
TEST(Model, StressPointOutputIsTheStressPointAverage) {
  Discretization d = smallLattice(1, 1.015, 12);
  MaterialSpec m = material(1);
  m.kind = MaterialKind::Hencky;
  auto lp = localParticles(d, 0, d.size());
  for (int i = 0; i < d.size(); ++i) lp.modulusScale.push_back(1.0 + 0.25 * i);
  Model sp(m, lp);
  sp.enableStressPoints();
  Model plain(m, lp);
  plain.enableCorrespondence();
  const int k = 6;
  const double a = 0.05, b = 0.30;  // strains left and right of particle k
  std::vector<double> u(d.size());
  for (int i = 0; i < d.size(); ++i) {
    const double x = d.X[i][0] - d.X[k][0];
    u[i] = x <= 0 ? a * x : b * x;
  }
  const auto outS = sp.outputs(u), outP = plain.outputs(u);
  Material mat(m);
  Eigen::Matrix3d sl, sr, sm;
  ASSERT_TRUE(mat.cauchy<1>(MatD<1>::Constant(1.0 + a), sl));
  ASSERT_TRUE(mat.cauchy<1>(MatD<1>::Constant(1.0 + b), sr));
  ASSERT_TRUE(mat.cauchy<1>(MatD<1>::Constant(1.0 + 0.5 * (a + b)), sm));
  const double scale = 1.0 + 0.25 * k;
  EXPECT_NEAR(outS[k].F(0, 0), 1.0 + 0.5 * (a + b), 1e-12);
  EXPECT_NEAR(outS[k].cauchy(0, 0), scale * 0.5 * (sl(0, 0) + sr(0, 0)), 1e-9 * std::abs(sr(0, 0)));
  EXPECT_NEAR(outP[k].cauchy(0, 0), scale * sm(0, 0), 1e-9 * std::abs(sr(0, 0)));
  EXPECT_GT(std::abs(outS[k].cauchy(0, 0) - outP[k].cauchy(0, 0)), 1e-3 * std::abs(sr(0, 0)))
      << "the average of the stress-point stresses must differ from the stress of the mean F";
  // Away from the kink both stress points see the same F: the output is that state's stress.
  Eigen::Matrix3d sb;
  ASSERT_TRUE(mat.cauchy<1>(MatD<1>::Constant(1.0 + b), sb));
  EXPECT_NEAR(outS[k + 3].cauchy(0, 0), (1.0 + 0.25 * (k + 3)) * sb(0, 0), 1e-9 * std::abs(sb(0, 0)));
}

// Blocks with their own materials (ProblemSpec::blocks): a two-material model, material 0 for
// x < the middle and material 1 beyond (different E, nu; also one small-strain, one Hencky), each
// particle's element with its own P and A, its own G and C, and per-material damage laws (a bond
// across takes the law of the smaller critical stretch). The tangent against central differences
// (bound and step as TangentFD), symmetric without damage; the matrix-free product against the
// assembled tangent to 1e-12.
namespace {

std::unique_ptr<Model> twoBlockModel(const Discretization& d, int dim, double G, bool mixedKinds, bool stressPoints = false) {
  std::vector<MaterialSpec> mats{material(dim), material(dim)};
  mats[1].E = 3.5 * mats[0].E;
  mats[1].nu = dim == 1 ? 0.0 : 0.35;
  if (mixedKinds) mats[1].kind = MaterialKind::SmallStrain;
  auto lp = localParticles(d, 0, d.size());
  const double mid = 0.5 * (d.boxLower[0] + d.boxUpper[0]);
  for (int l = 0; l < lp.size(); ++l) lp.material.push_back(lp.X[l][0] < mid ? 0 : 1);
  auto model = std::make_unique<Model>(mats, lp);
  if (stressPoints) model->enableStressPoints(5);
  else model->enableCorrespondence();
  if (G > 0)
    model->enableStabilization(std::vector<StabilizationSpec>{{G, micromodulusC(mats[0], d.horizon, d.thickness)},
                                                              {0.5 * G, micromodulusC(mats[1], d.horizon, d.thickness)}});
  return model;
}

std::vector<double> stretchedRotated(const Discretization& d, unsigned seed) {
  const int n = d.size(), D = d.dim;
  std::vector<double> u = randomDisplacement(n, D, 0.03 * d.dx, seed);
  for (int i = 0; i < n; ++i) {
    u[i * D] += 0.2 * d.X[i][0];
    if (D > 1) {
      const double th = 0.3, x = d.X[i][0] * 1.2, y = d.X[i][1];
      u[i * D] += (std::cos(th) - 1) * x - std::sin(th) * y;
      u[i * D + 1] += std::sin(th) * x + (std::cos(th) - 1) * y;
    }
  }
  return u;
}

}  // namespace

TEST(Blocks, TwoMaterialTangentMatchesFiniteDifferences) {
  for (int dim : {1, 2, 3})
    for (double G : {0.0, 0.2})
      for (bool mixed : {false, true}) {
        Discretization d = smallLattice(dim, 2.015, dim == 1 ? 12 : (dim == 2 ? 8 : 6));
        auto model = twoBlockModel(d, dim, G, mixed);
        const auto [err, asym] = tangentErrors(*model, d, stretchedRotated(d, 31 + dim));
        EXPECT_LT(err, 1e-6) << "dim " << dim << ", G " << G << (mixed ? ", Hencky + small strain" : "");
        EXPECT_LT(asym, 1e-10) << "dim " << dim << ", G " << G;
      }
}

TEST(Blocks, ElementUsesItsOwnMaterial) {
  // A uniform stretch: every particle's F is the same, so its Cauchy stress is its block's.
  Discretization d = smallLattice(2, 2.015, 8);
  auto model = twoBlockModel(d, 2, 0.0, false);
  std::vector<double> u(d.size() * 2, 0.0);
  for (int i = 0; i < d.size(); ++i) u[i * 2] = 0.01 * d.X[i][0];
  const auto out = model->outputs(u);
  Material m0(material(2));
  MaterialSpec s1 = material(2);
  s1.E *= 3.5;
  s1.nu = 0.35;
  Material m1(s1);
  Eigen::Matrix2d F = Eigen::Matrix2d::Identity();
  F(0, 0) = 1.01;
  Eigen::Matrix3d c0, c1;
  ASSERT_TRUE(m0.cauchy<2>(F, c0));
  ASSERT_TRUE(m1.cauchy<2>(F, c1));
  const double mid = 0.5 * (d.boxLower[0] + d.boxUpper[0]);
  for (int i = 0; i < d.size(); ++i)
    EXPECT_LT((out[i].cauchy - (d.X[i][0] < mid ? c0 : c1)).norm(), 1e-9 * c1.norm()) << "particle " << i;
}

TEST(Blocks, TwoMaterialDamageTangentAndBondRule) {
  for (int dim : {2, 3}) {
    Discretization d = smallLattice(dim, 2.015, dim == 2 ? 8 : 6);
    const int n = d.size(), D = dim;
    std::vector<double> u = randomDisplacement(n, D, 0.01 * d.dx, 11);
    for (int i = 0; i < n; ++i) u[i * D] += 0.03 * d.X[i][0];
    // Laws chosen so that every region of both softening curves is visited (stretches spread
    // over about 0 to 0.06 here) and the two differ.
    const std::vector<DamageSpec> laws{DamageSpec{0.0201, 0.0399, 3.0, DamageSpec::Softening::Paper},
                                       DamageSpec{0.0251, 0.0449, 2.0, DamageSpec::Softening::Continuous}};
    auto model = twoBlockModel(d, dim, 0.05, false);
    model->enableDamage(laws);
    const auto [err, asym] = tangentErrors(*model, d, u, 1e-7);
    EXPECT_LT(err, 1e-6) << "dim " << dim;
    EXPECT_GT(asym, 1e-6);
    // The bond rule: within a block its own law, across the one of the smaller critical stretch,
    // the same seen from both ends.
    const auto& lp = model->particles();
    int across = 0;
    for (int i = 0; i < lp.numOwned; ++i)
      for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) {
        const int j = lp.famIndex[q];
        const DamageSpec& law = model->bondDamage(i, j);
        EXPECT_EQ(&law, &model->bondDamage(j, i));
        const int a = lp.material[i], b = lp.material[j];
        EXPECT_EQ(law.sCr, a == b ? laws[a].sCr : laws[0].sCr);
        across += a != b;
      }
    EXPECT_GT(across, 0);
    // Breaking uses each bond's law: after breakBonds no intact bond is at or past its own s_cr.
    ASSERT_GT(model->breakBonds(u), 0);
    for (int i = 0; i < lp.numOwned; ++i)
      for (auto q = lp.famOffset[i]; q < lp.famOffset[i + 1]; ++q) {
        const int j = lp.famIndex[q];
        Eigen::VectorXd xi(D), y(D);
        for (int c = 0; c < D; ++c) {
          xi[c] = lp.X[j][c] - lp.X[i][c];
          y[c] = xi[c] + u[j * D + c] - u[i * D + c];
        }
        EXPECT_LT((y.norm() - xi.norm()) / xi.norm(), model->bondDamage(i, j).sCr);
      }
  }
}

TEST(Blocks, MatrixFreeProductEqualsAssembledTangent) {
  for (int dim : {1, 2, 3})
    for (int variant = 0; variant < 3; ++variant) {  // stabilised, stabilised + damage, stress points
      const bool sp = variant == 2;
      Discretization d = smallLattice(dim, sp ? 1.015 : 2.015, dim == 1 ? 12 : (dim == 2 ? 7 : 5));
      const int n = d.size(), D = dim;
      auto model = twoBlockModel(d, dim, sp ? 0.0 : 0.3, true, sp);
      if (variant == 1)
        model->enableDamage(std::vector<DamageSpec>{DamageSpec{0.02, 0.04, 3.0, DamageSpec::Softening::Paper},
                                                    DamageSpec{0.015, 0.03, 3.0, DamageSpec::Softening::Continuous}});
      auto u = randomDisplacement(n, D, 0.01 * d.dx, 17);
      for (int i = 0; i < n; ++i) u[i * D] += 0.03 * d.X[i][0];
      const auto v = randomDisplacement(n, D, 1.0, 23);
      DenseSink ss(D, n);
      model->evaluate(u, ss, true);
      const auto [dd, scale] = productDifference(*model, ss.K, u, v);
      ASSERT_GT(scale, 0.0);
      EXPECT_LT(dd, 1e-12 * scale) << "dim " << dim << ", variant " << variant;
    }
}

TEST(Blocks, StressPointTangentMatchesFiniteDifferences) {
  for (int dim : {1, 2, 3}) {
    Discretization d = smallLattice(dim, 1.015, dim == 1 ? 12 : (dim == 2 ? 8 : 6));
    auto model = twoBlockModel(d, dim, 0.0, true, true);
    const auto [err, asym] = tangentErrors(*model, d, stretchedRotated(d, 41 + dim));
    EXPECT_LT(err, 1e-6) << "dim " << dim;
    EXPECT_LT(asym, 1e-10) << "dim " << dim;
  }
}

// The gathered form of the repeated product (sums of per-particle records, positions taken from
// the owned particles' centroid) against the per-bond form on a body far larger than its
// horizon and far from the origin, owning a middle slice so that ghosts take scattered shares:
// for a random direction, a smooth one and a homogeneous stretch (whose product vanishes inside
// the body, so only cancellation is left there). The gathered sums carry positions of size L
// (here L / delta = 40) where the per-bond form carries bonds of size delta. Measured: 1.9e-14,
// 5.9e-13 and 3.4e-12 of the largest entry; the bound 1e-11 is 3x the worst of them. The same
// sums with positions from the global origin, 1e4 away, gave 1.1e-11, 4.9e-10 and 2.6e-9 and
// fail it (checked).
TEST(Model, GatheredProductKeepsDigitsOnLargeBodies) {
  LatticeSpec s;
  s.dim = 2;
  s.counts = {240, 240, 1};
  s.lower = Vec3(1.0e4, -3.0e3, 0.0);
  s.upper = s.lower + Vec3(24.0, 24.0, 1.0);
  s.horizonFactor = 3.015;
  s.thickness = 0.05;
  const Discretization d = buildLattice(s);
  const int n = d.size(), D = 2;
  const MaterialSpec m = material(2);
  Model model(m, localParticles(d, n / 3, 2 * n / 3));
  model.enableCorrespondence();
  model.enableStabilization({0.3, micromodulusC(m, d.horizon, d.thickness)});
  const int nl = model.particles().size();
  std::vector<double> u = randomDisplacement(nl, D, 1e-3 * d.dx, 5);
  for (int l = 0; l < nl; ++l) u[l * D] += 1e-3 * (model.particles().X[l][0] - s.lower[0]);
  std::vector<std::vector<double>> dirs(3, std::vector<double>(nl * D));
  dirs[0] = randomDisplacement(nl, D, 1.0, 11);
  for (int l = 0; l < nl; ++l) {
    const Vec3 x = (model.particles().X[l] - s.lower) / 24.0;
    dirs[1][l * D] = std::sin(3.0 * x[0]) * std::cos(2.0 * x[1]);
    dirs[1][l * D + 1] = std::cos(x[0] + x[1]);
    dirs[2][l * D] = 2e-3 * (x[0] - 0.5) + 1e-3 * x[1];
    dirs[2][l * D + 1] = -1e-3 * x[1];
  }
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    std::vector<double> y[2];
    int f = 0;
    for (const auto form : {Model::ProductForm::PerBond, Model::ProductForm::Gathered}) {
      model.setProductForm(form);
      std::vector<double> first(nl * D, 0.0);
      model.applyTangent(u, dirs[(k + 1) % dirs.size()], first.data());  // the fresh product keeps the state
      y[f].assign(nl * D, 0.0);
      model.applyTangent(u, dirs[k], y[f].data());
      ++f;
    }
    double diff = 0, big = 0;
    for (int q = 0; q < nl * D; ++q) {
      diff = std::max(diff, std::abs(y[1][q] - y[0][q]));
      big = std::max(big, std::abs(y[0][q]));
    }
    ASSERT_GT(big, 0.0) << "direction " << k;
    EXPECT_LT(diff, 1e-11 * big) << "direction " << k;
    std::printf("direction %zu: gathered - per-bond = %.3g of the largest entry\n", k, diff / big);
  }
}

// An irregular body like Peridigm's tensile test (docs/performance.md, "The auxiliary cycle from level 1, and the last Newton system"): 3D particles
// jittered by up to 0.3 spacings with volumes varying by +-30 %, horizon 2.52 spacings, weak
// stabilisation (G = 0.02), at a small-strain state (0.5 % stretch plus noise) and at a large one.
// The element tangent against central differences (1e-6, as TangentFD), and both forms of the
// matrix-free product (per bond and gathered), each at a first and a second direction of one
// state, against the assembled tangent (1e-12, as MatrixFreeProductEqualsAssembledTangent). The
// lattice tests above have regular positions and equal volumes.
TEST(Model, IrregularBodyTangentAndProducts) {
  LatticeSpec s;
  s.dim = 3;
  s.counts = {7, 6, 5};
  s.upper = Vec3(0.7, 0.6, 0.5);
  s.horizonFactor = 2.52;
  s.jitter = 0.3;
  Discretization d = buildLattice(s);
  for (int i = 0; i < d.size(); ++i) d.volume[i] *= 1.0 + 0.3 * std::sin(3.7 * i);
  const int n = d.size(), D = 3;
  const MaterialSpec m = material(3);
  for (double stretch : {0.005, 0.2}) {
    auto u = randomDisplacement(n, D, (stretch < 0.01 ? 0.001 : 0.03) * d.dx, 41);
    for (int i = 0; i < n; ++i) u[i * D + 1] += stretch * d.X[i][1];
    auto model = makeModel(d, m, 0.02);
    const auto [err, asym] = tangentErrors(*model, d, u);
    EXPECT_LT(err, 1e-6) << "stretch " << stretch;
    EXPECT_LT(asym, 1e-10) << "stretch " << stretch;
    DenseSink ss(D, n);
    model->evaluate(u, ss, true);
    for (const auto form : {Model::ProductForm::PerBond, Model::ProductForm::Gathered}) {
      auto mf = makeModel(d, m, 0.02);
      mf->setProductForm(form);
      for (unsigned seed : {23u, 29u}) {
        const auto [dd, scale] = productDifference(*mf, ss.K, u, randomDisplacement(n, D, 1.0, seed));
        ASSERT_GT(scale, 0.0);
        EXPECT_LT(dd, 1e-12 * scale)
            << "stretch " << stretch << ", " << (form == Model::ProductForm::Gathered ? "gathered" : "per bond")
            << " product, direction " << seed;
      }
    }
  }
}

// Peridigm's hourglass coefficient (StabilizationSpec::Form::PeridigmHourglass): the model must
// be Silling's stabilisation with each particle's own G_i = c delta S_i / (3 V_i), S_i = sum_j
// V_j / |xi_ij| (docs/peridigm.md derives the rule), here computed independently and given to a
// model in which every particle is its own material: residual and tangent equal to round-off.
// Its tangent against central differences (bound and step as TangentFD), symmetric; the
// matrix-free product against it. On a cube of 6 x 5 x 4 particles with a 3-spacing horizon no
// family is whole, so the G_i differ from particle to particle (checked).
TEST(Model, PeridigmHourglassFormIsSillingWithEachFamilysG) {
  const double c = 0.04;
  Discretization d = smallLattice(3, 3.015, 6);
  const int n = d.size();
  MaterialSpec m = material(3);
  const double C = micromodulusC(m, d.horizon, d.thickness);
  auto lp = localParticles(d, 0, n);
  Model peridigm(m, lp);
  peridigm.enableCorrespondence();
  StabilizationSpec form{c, C};
  form.form = StabilizationSpec::Form::PeridigmHourglass;
  form.horizon = d.horizon;
  peridigm.enableStabilization(form);

  std::vector<StabilizationSpec> own(n);
  double lo = 1e300, hi = 0;
  for (int i = 0; i < n; ++i) {
    double S = 0;
    for (int j = 0; j < n; ++j) {
      const double r = (d.X[j] - d.X[i]).norm();
      if (j != i && r <= d.horizon) S += d.volume[j] / r;
    }
    own[i] = {c * d.horizon * S / (3 * d.volume[i]), C};
    lo = std::min(lo, own[i].G);
    hi = std::max(hi, own[i].G);
  }
  EXPECT_GT(hi / lo, 1.5) << "the families differ";
  auto lpOwn = lp;
  for (int l = 0; l < lpOwn.size(); ++l) lpOwn.material.push_back(l);
  Model silling(std::vector<MaterialSpec>(n, m), lpOwn);
  silling.enableCorrespondence();
  silling.enableStabilization(own);

  const std::vector<double> u = stretchedRotated(d, 7);
  DenseSink a(3, n), b(3, n);
  peridigm.evaluate(u, a, true);
  silling.evaluate(u, b, true);
  EXPECT_LT((a.r - b.r).cwiseAbs().maxCoeff(), 1e-12 * b.r.cwiseAbs().maxCoeff());
  EXPECT_LT((a.K - b.K).cwiseAbs().maxCoeff(), 1e-12 * b.K.cwiseAbs().maxCoeff());
  const auto [err, asym] = tangentErrors(peridigm, d, u);
  EXPECT_LT(err, 1e-6);
  EXPECT_LT(asym, 1e-10);
  const auto [dd, scale] = productDifference(peridigm, a.K, u, randomDisplacement(n, 3, 1.0, 5));
  EXPECT_LT(dd, 1e-12 * scale);
}

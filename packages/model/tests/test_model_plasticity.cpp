// The model with a plastic material: evaluations are pure functions of (u, committed state);
// the element tangent at a committed plastic state against central differences of the residual;
// the matrix-free product and its diagonal against the assembled tangent, before and after a
// commit (a stale linearisation would not agree); commit, restore and unloading.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"
#include "ModelTestUtil.hpp"

using namespace perinox;
using perinox::testutil::DenseSink;

namespace {

MaterialSpec plastic(int dim, PlanarMode pm, MaterialKind kind) {
  MaterialSpec m;
  m.dim = dim;
  m.kind = kind;
  m.planar = dim == 2 ? pm : PlanarMode::None;
  m.E = 12.0e6;
  m.nu = dim == 1 ? 0.0 : 0.3;
  m.plastic.enabled = true;
  m.plastic.yieldStress = 12.0e3;  // yield strain 1e-3
  m.plastic.hardeningModulus = 0.05 * m.E;
  return m;
}

std::vector<double> field(const Discretization& d, double stretch, double amp, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> r(-amp, amp);
  const int D = d.dim;
  std::vector<double> u(d.size() * D);
  for (int i = 0; i < d.size(); ++i)
    for (int a = 0; a < D; ++a) u[i * D + a] = (a == 0 ? stretch * d.X[i][0] : 0.0) + r(gen) * d.dx;
  return u;
}

Eigen::VectorXd residual(const Model& m, const Discretization& d, const std::vector<double>& u) {
  DenseSink s(d.dim, d.size());
  m.evaluate(u, s, false);
  return s.r;
}

struct Case {
  const char* name;
  int dim;
  PlanarMode pm;
  MaterialKind kind;
  bool stressPoints;
  double G;
};

}  // namespace

TEST(ModelPlasticity, TangentProductsAndCommit) {
  const Case cases[] = {
      {"1D Hencky", 1, PlanarMode::None, MaterialKind::Hencky, false, 0.0},
      {"plane strain Hencky, stabilised", 2, PlanarMode::PlaneStrain, MaterialKind::Hencky, false, 0.2},
      {"plane stress Hencky", 2, PlanarMode::PlaneStress, MaterialKind::Hencky, false, 0.0},
      {"plane strain small strain", 2, PlanarMode::PlaneStrain, MaterialKind::SmallStrain, false, 0.0},
      {"3D Hencky, stabilised", 3, PlanarMode::None, MaterialKind::Hencky, false, 0.1},
      {"2D stress points", 2, PlanarMode::PlaneStrain, MaterialKind::Hencky, true, 0.0},
      {"3D stress points", 3, PlanarMode::None, MaterialKind::Hencky, true, 0.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Discretization d = testutil::smallLattice(c.dim, c.stressPoints ? 1.015 : 2.015, c.dim == 1 ? 12 : (c.dim == 2 ? 7 : 5));
    const int n = d.size(), D = c.dim;
    const MaterialSpec mat = plastic(c.dim, c.pm, c.kind);
    Model model(mat, localParticles(d, 0, n));
    if (c.stressPoints) model.enableStressPoints(5);
    else model.enableCorrespondence();
    if (c.G > 0) model.enableStabilization({c.G, micromodulusC(mat, d.horizon, d.thickness)});
    ASSERT_TRUE(model.hasHistory());
    ASSERT_EQ(model.stateStride(), Material(mat).stateSize());

    // Commit a plastic state at u1 (stretch 4 yield strains plus noise).
    const auto u1 = field(d, 0.004, 0.0015, 3);
    const std::vector<double> virgin = model.committedStates();
    const Eigen::VectorXd r1 = residual(model, d, u1);
    EXPECT_EQ(model.committedStates(), virgin) << "an evaluation changed the committed state";
    model.commitState(u1);
    int yielded = 0;
    double maxEqps = 0;
    for (const auto& o : model.outputs(u1)) {
      yielded += o.yielded;
      maxEqps = std::max(maxEqps, o.eqps);
    }
    EXPECT_GT(yielded, 0);
    EXPECT_GT(maxEqps, 1e-4);
    // The committed state reproduces the state it was committed at: same forces at u1.
    const Eigen::VectorXd r1c = residual(model, d, u1);
    EXPECT_LE((r1c - r1).cwiseAbs().maxCoeff(), 1e-9 * r1.cwiseAbs().maxCoeff());

    // At u2 (further loading), the tangent from the committed state against central differences.
    const auto u2 = field(d, 0.006, 0.0015, 7);
    DenseSink s(D, n);
    model.evaluate(u2, s, true);
    const double h = 1e-7 * d.dx;
    Eigen::MatrixXd Kfd(n * D, n * D);
    for (int k = 0; k < n * D; ++k) {
      auto up = u2, um = u2;
      up[k] += h;
      um[k] -= h;
      Kfd.col(k) = (residual(model, d, up) - residual(model, d, um)) / (2 * h);
    }
    const double scale = s.K.cwiseAbs().maxCoeff();
    // h moves a strain by ~1e-7 (the yield strain is 1e-3), so no point crosses the surface;
    // truncation is ~h^2 and round-off ~1e-16 |r| / h ~ 1e-9 |K|.
    EXPECT_LE((s.K - Kfd).cwiseAbs().maxCoeff(), 1e-6 * scale);

    // The matrix-free product and the diagonal at u2 against the assembled tangent.
    auto check = [&](const char* what) {
      DenseSink ss(D, n);
      model.evaluate(u2, ss, true);
      const auto v = field(d, 0.0, 1.0, 11);
      Eigen::VectorXd ve = Eigen::Map<const Eigen::VectorXd>(v.data(), n * D);
      const Eigen::VectorXd kv = ss.K * ve;
      for (int rep = 0; rep < 2; ++rep) {  // the second product reads the kept linearisation
        std::vector<double> jv(n * D, 0.0);
        model.applyTangent(u2, v, jv.data());
        EXPECT_LE((Eigen::Map<const Eigen::VectorXd>(jv.data(), n * D) - kv).cwiseAbs().maxCoeff(),
                  1e-12 * kv.cwiseAbs().maxCoeff())
            << what << ", product " << rep;
      }
      std::vector<double> dg(n * D, 0.0);
      model.addJacobianDiagonal(u2, dg.data());
      EXPECT_LE((Eigen::Map<const Eigen::VectorXd>(dg.data(), n * D) - ss.K.diagonal()).cwiseAbs().maxCoeff(),
                1e-12 * ss.K.diagonal().cwiseAbs().maxCoeff())
          << what;
      return ss.K;
    };
    const Eigen::MatrixXd Kbefore = check("before the commit at u2");
    const std::vector<double> s1 = model.committedStates();
    model.commitState(u2);
    const Eigen::MatrixXd Kafter = check("after the commit at u2");
    // Committing changed the tangent at u2 (yielded points moved onto a new surface), so the
    // check after it would have caught a kept, stale linearisation.
    EXPECT_GT((Kafter - Kbefore).cwiseAbs().maxCoeff(), 1e-6 * scale);

    // Restoring the earlier committed state gives back the earlier forces bit for bit.
    const Eigen::VectorXd r2after = residual(model, d, u2);
    model.setCommittedStates(s1);
    EXPECT_EQ(residual(model, d, u2), s.r);
    model.commitState(u2);
    EXPECT_EQ(residual(model, d, u2), r2after);

    // Unloading to u = 0 leaves residual forces (plastic strain is kept); the virgin state has
    // none but the round-off of F = I (sum xi (x) xi K^-1).
    const std::vector<double> zero(n * D, 0.0);
    EXPECT_GT(residual(model, d, zero).cwiseAbs().maxCoeff(), 1e-3 * r1.cwiseAbs().maxCoeff());
    model.setCommittedStates(virgin);
    EXPECT_LE(residual(model, d, zero).cwiseAbs().maxCoeff(), 1e-12 * r1.cwiseAbs().maxCoeff());
    EXPECT_THROW(model.setCommittedStates(std::vector<double>(3, 0.0)), std::invalid_argument);
  }
}

// Elastic materials hold no state: nothing is allocated, commit does nothing.
TEST(ModelPlasticity, ElasticModelHoldsNoState) {
  const Discretization d = testutil::smallLattice(2, 2.015, 6);
  MaterialSpec m = plastic(2, PlanarMode::PlaneStrain, MaterialKind::Hencky);
  m.plastic.enabled = false;
  Model model(m, localParticles(d, 0, d.size()));
  model.enableCorrespondence();
  EXPECT_FALSE(model.hasHistory());
  EXPECT_EQ(model.committedStates().size(), 0u);
  EXPECT_EQ(model.committedState(0), nullptr);
  model.commitState(field(d, 0.01, 0.001, 1));
  EXPECT_EQ(model.committedStates().size(), 0u);
}

// Blocks: a plastic block beside an elastic one; the elastic block's points keep no flow.
TEST(ModelPlasticity, PlasticBlockBesideElasticBlock) {
  const Discretization d = testutil::smallLattice(2, 2.015, 8);
  const int n = d.size();
  MaterialSpec steel = plastic(2, PlanarMode::PlaneStrain, MaterialKind::Hencky);
  MaterialSpec elastic = steel;
  elastic.plastic = PlasticitySpec{};
  auto lp = localParticles(d, 0, n);
  lp.material.resize(lp.X.size());
  for (int l = 0; l < lp.size(); ++l) lp.material[l] = lp.X[l][0] < 0.4 ? 0 : 1;
  Model model(std::vector<MaterialSpec>{steel, elastic}, lp);
  model.enableCorrespondence();
  ASSERT_TRUE(model.hasHistory());
  const auto u = field(d, 0.01, 0.001, 5);
  model.commitState(u);
  const auto out = model.outputs(u);
  int plasticYielded = 0;
  for (int i = 0; i < n; ++i) {
    if (lp.material[i] == 1) {
      EXPECT_FALSE(out[i].yielded);
      EXPECT_EQ(out[i].eqps, 0.0);
    } else {
      plasticYielded += out[i].yielded;
    }
  }
  EXPECT_GT(plasticYielded, 0);
  // The tangent against differences holds across the interface too.
  DenseSink s(2, n);
  const auto u2 = field(d, 0.012, 0.001, 9);
  model.evaluate(u2, s, true);
  const double h = 1e-7 * d.dx;
  double err = 0;
  for (int k = 0; k < 2 * n; ++k) {
    auto up = u2, um = u2;
    up[k] += h;
    um[k] -= h;
    const Eigen::VectorXd col = (residual(model, d, up) - residual(model, d, um)) / (2 * h);
    err = std::max(err, (s.K.col(k) - col).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(err, 1e-6 * s.K.cwiseAbs().maxCoeff());
}

// Ductile failure: after a step, a bond breaks when the mean equivalent plastic strain of its two
// ends (of the trial state at u, nothing committed) reaches the critical value, each bond once,
// and no bond softens by stretch when the stretch criterion is off.
TEST(ModelPlasticity, DuctileCriterionBreaksByPlasticStrain) {
  const Discretization d = testutil::smallLattice(2, 2.015, 8);
  const int n = d.size();
  const MaterialSpec mat = plastic(2, PlanarMode::PlaneStrain, MaterialKind::Hencky);
  auto makeModel = [&](double crit) {
    auto m = std::make_unique<Model>(mat, localParticles(d, 0, n));
    m->enableCorrespondence();
    DamageSpec ds;
    ds.stretchCriterion = false;
    ds.criticalPlasticStrain = crit;
    m->enableDamage(ds);
    return m;
  };
  const auto u = field(d, 0.004, 0.0015, 13);
  auto probe = makeModel(1.0);
  const std::vector<double> committed = probe->committedStates();
  const std::vector<double> eqps = probe->trialPlasticStrain(u);
  EXPECT_EQ(probe->committedStates(), committed) << "trialPlasticStrain committed something";
  const double lo = *std::min_element(eqps.begin(), eqps.end()), hi = *std::max_element(eqps.begin(), eqps.end());
  ASSERT_GT(hi, lo);
  // Stretch softening is off: the forces are those of the model without damage.
  Model plain(mat, localParticles(d, 0, n));
  plain.enableCorrespondence();
  EXPECT_EQ(residual(*probe, d, u), residual(plain, d, u));
  const double crit = 0.5 * (lo + hi);
  long long expected = 0;  // bonds (each once) whose ends' mean reaches crit
  for (int i = 0; i < n; ++i)
    for (auto q = probe->particles().famOffset[i]; q < probe->particles().famOffset[i + 1]; ++q) {
      const int j = probe->particles().famIndex[q];
      if (i < j && 0.5 * (eqps[i] + eqps[j]) >= crit) ++expected;
    }
  ASSERT_GT(expected, 0);
  auto model = makeModel(crit);
  EXPECT_EQ(model->breakBonds(u, eqps), expected);
  EXPECT_EQ(model->breakBonds(u, eqps), 0);  // broken for good, once
  auto none = makeModel(hi * 1.01);
  EXPECT_EQ(none->breakBonds(u, eqps), 0);
  // A ductile law needs a plastic material.
  MaterialSpec elastic = mat;
  elastic.plastic = PlasticitySpec{};
  Model m2(elastic, localParticles(d, 0, n));
  DamageSpec ds;
  ds.criticalPlasticStrain = 0.1;
  EXPECT_THROW(m2.enableDamage(ds), std::invalid_argument);
}

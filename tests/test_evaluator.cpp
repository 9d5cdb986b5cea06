// The assembled Jacobian W of the distributed model evaluator against finite differences of
// its residual, and its symmetry, on 1, 2 or 3 ranks (the same executable runs under each).
// Checks are global (Tpetra vectors), so ghost exchange and Export assembly are exercised.
#include <gtest/gtest.h>

#include <Teuchos_DefaultComm.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Core.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "perinox/evaluator/JacobianOperators.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"

using namespace perinox;
using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;

namespace {

/// With blocks: block 2 (x beyond the middle) with its own material (E x 4, nu 0.2) and G / 2;
/// the stabilisation's C then comes from each block's material.
std::shared_ptr<ProblemSpec> makeProblem(int dim, double factor, double G, bool fictitious, bool blocks = false) {
  auto P = std::make_shared<ProblemSpec>();
  LatticeSpec s;
  s.dim = dim;
  const int n = dim == 2 ? 10 : 6;
  s.counts = {n, dim > 1 ? n - 2 : 1, dim > 2 ? n - 3 : 1};
  s.upper = Vec3(s.counts[0] * 0.2, s.counts[1] * 0.2, dim > 2 ? s.counts[2] * 0.2 : 1.0);
  s.horizonFactor = factor;
  s.thickness = 0.1;
  if (fictitious) s.fictitiousSides = {Side::XMin};
  P->disc = buildLattice(s);
  P->material.dim = dim;
  P->material.planar = dim == 2 ? PlanarMode::PlaneStrain : PlanarMode::None;
  P->material.E = 1.0e3;
  P->material.nu = 0.3;
  if (G > 0) {
    P->stabilization = true;
    P->stab = {G, micromodulusC(P->material, P->disc.horizon, P->disc.thickness)};
  }
  if (blocks) {
    BlockSpec b1, b2;
    b1.id = 1;
    b1.material = P->material;
    b2.id = 2;
    b2.material = P->material;
    b2.material.E *= 4;
    b2.material.nu = 0.2;
    if (G > 0) b2.G = 0.5 * G;
    P->blocks = {b1, b2};
    P->stab.C = StabilizationSpec::kFromMaterial;
    const double mid = 0.5 * (P->disc.boxLower[0] + P->disc.boxUpper[0]);
    for (int p = 0; p < P->disc.size(); ++p) P->disc.block[p] = P->disc.X[p][0] > mid ? 2 : 1;
  }
  const int np = P->disc.size();
  P->fixedMask.assign(np, 0);
  P->prescribed.assign(static_cast<size_t>(np) * dim, 0.0);
  P->bodyForce.assign(static_cast<size_t>(np) * dim, 0.0);
  for (int p = 0; p < np; ++p) {
    const bool left = fictitious ? P->disc.fictitious[p] : P->disc.X[p][0] < 0.2;
    if (left) {
      P->fixedMask[p] = static_cast<std::uint8_t>((1u << dim) - 1);
      for (int c = 0; c < dim; ++c) P->prescribed[p * dim + c] = 0.05 * (c + 1) * P->disc.X[p][1];
    }
    P->bodyForce[p * dim + dim - 1] = -10.0;
  }
  return P;
}

/// Random values on ev's free DOFs, each seeded by the DOF's place among all free DOFs in
/// particle order (what the solution map's numbering was before it followed the ranks), so the
/// same on any rank count and partition, and the same as these tests always had.
void fill(const PeridynamicEvaluator& ev, Thyra::VectorBase<double>& z, unsigned seed, double amp) {
  const ProblemSpec& P = ev.problem();
  std::vector<long long> place(static_cast<std::size_t>(P.disc.size()) * P.dim(), -1);  // a test may hold this
  long long next = 0;
  for (int p = 0; p < P.disc.size(); ++p)
    for (int c = 0; c < P.dim(); ++c)
      if (!P.isFixed(p, c)) place[static_cast<std::size_t>(p) * P.dim() + c] = next++;
  auto values = ev.ownedDofValues(z);
  for (auto& [dof, v] : values) {
    std::mt19937 g(seed * 1000003u + static_cast<unsigned>(place[dof]));
    v = amp * std::uniform_real_distribution<double>(-1, 1)(g);
  }
  ev.setOwnedDofValues(z, values);
}

struct Case {
  int dim;
  double factor;
  double G;
  bool fictitious;
  bool blocks = false;
};

class EvaluatorFD : public ::testing::TestWithParam<Case> {};

/// The evaluator's constructor refuses P with one sentence (no line break) containing part.
void expectRefused(const std::shared_ptr<ProblemSpec>& P, const std::string& part) {
  try {
    PeridynamicEvaluator ev(Teuchos::DefaultComm<int>::getComm(), P);
    ADD_FAILURE() << "accepted; expected a refusal naming " << part;
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(part), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

}  // namespace

// Directional finite differences: (f(x + h v) - f(x - h v)) / 2h = W v + O(h^2). With
// h = 1e-6 relative to |x| and smooth Hencky/stabilisation terms, truncation and round-off stay
// near 1e-9 of |W v|; 1e-6 leaves room and still fails at once for any missing tangent term.
TEST_P(EvaluatorFD, JacobianMatchesDirectionalDifferencesAndIsSymmetric) {
  const Case c = GetParam();
  auto comm = Teuchos::DefaultComm<int>::getComm();
  auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, makeProblem(c.dim, c.factor, c.G, c.fictitious, c.blocks)));
  ev->setLoadFactor(0.7);
  auto space = ev->get_x_space();
  auto x = Thyra::createMember(space), v = Thyra::createMember(space), w = Thyra::createMember(space);
  fill(*ev, *x, 1, 0.03);
  fill(*ev, *v, 2, 1.0);
  fill(*ev, *w, 3, 1.0);

  auto W = ev->create_W_op();
  auto f0 = Thyra::createMember(space);
  auto in = ev->createInArgs();
  in.set_x(x);
  auto out = ev->createOutArgs();
  out.set_f(f0);
  out.set_W_op(W);
  ev->evalModel(in, out);

  auto Wv = Thyra::createMember(space), Ww = Thyra::createMember(space);
  Thyra::apply(*W, Thyra::NOTRANS, *v, Wv.ptr());
  Thyra::apply(*W, Thyra::NOTRANS, *w, Ww.ptr());

  const double h = 1e-6;
  auto xp = x->clone_v(), xm = x->clone_v();
  Thyra::Vp_StV(xp.ptr(), h, *v);
  Thyra::Vp_StV(xm.ptr(), -h, *v);
  auto fp = Thyra::createMember(space), fm = Thyra::createMember(space);
  for (auto [xx, ff] : {std::make_pair(xp, fp), std::make_pair(xm, fm)}) {
    auto i2 = ev->createInArgs();
    i2.set_x(xx);
    auto o2 = ev->createOutArgs();
    o2.set_f(ff);
    ev->evalModel(i2, o2);
  }
  auto fd = Thyra::createMember(space);
  Thyra::V_StVpStV(fd.ptr(), 0.5 / h, *fp, -0.5 / h, *fm);
  Thyra::Vp_StV(fd.ptr(), -1.0, *Wv);
  const double rel = Thyra::norm_2(*fd) / Thyra::norm_2(*Wv);
  EXPECT_LT(rel, 1e-6) << "dim " << c.dim << " horizon " << c.factor << " G " << c.G;
  const double a = Thyra::dot(*w, *Wv), b = Thyra::dot(*v, *Ww);
  EXPECT_LT(std::abs(a - b), 1e-10 * (std::abs(a) + std::abs(b)));
}

INSTANTIATE_TEST_SUITE_P(Cases, EvaluatorFD,
                         ::testing::Values(Case{2, 1.015, 0, false}, Case{2, 2.015, 0, true}, Case{2, 3.015, 0.2, true},
                                           Case{3, 1.015, 0, true}, Case{3, 2.015, 0.5, false},
                                           Case{2, 2.015, 0.2, true, true}, Case{3, 2.015, 0.5, false, true}));

// The matrix-free operators through the Thyra interface, on 1-3 ranks: the analytic product
// equals the assembled W times v to round-off (1e-12: both are exact derivatives, summed in a
// different order, with ghost exchange on both sides); the Jacobian-free difference matches to
// its truncation error (h |v|_inf = 1e-6 of the displacement scale gives about 1e-6 relative;
// 1e-4 leaves room and still fails for any wrong scaling or stale base state). The neighbour
// matrix keeps only couplings within one horizon: fewer entries than the full W.
TEST_P(EvaluatorFD, MatrixFreeProductsMatchAssembledJacobian) {
  const Case c = GetParam();
  auto comm = Teuchos::DefaultComm<int>::getComm();
  auto problem = makeProblem(c.dim, c.factor, c.G, c.fictitious, c.blocks);
  problem->damage = c.G > 0;  // with stabilisation cases, soften bonds too
  problem->damageSpec = DamageSpec{0.004, 0.02, 3.0};
  if (c.blocks && problem->damage) problem->blocks[1].damage = DamageSpec{0.003, 0.015, 2.0, DamageSpec::Softening::Continuous};
  auto assembled = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
  auto space = assembled->get_x_space();
  auto x = Thyra::createMember(space), v = Thyra::createMember(space);
  fill(*assembled, *x, 4, 0.02);
  fill(*assembled, *v, 5, 1.0);
  assembled->setLoadFactor(0.7);
  auto W = assembled->assembledJacobian(*x);
  auto Wt = Thyra::createConstLinearOp<double, LO, GO, Node>(W, space, space);
  auto ref = Thyra::createMember(space);
  Thyra::apply(*Wt, Thyra::NOTRANS, *v, ref.ptr());
  const double refNorm = Thyra::norm_2(*ref);
  ASSERT_GT(refNorm, 0.0);
  for (auto mode : {JacobianMode::MatrixFree, JacobianMode::JacobianFree}) {
    auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
    ev->setJacobian(mode, PreconditionerMatrix::Neighbours, Teuchos::null);
    ev->setLoadFactor(0.7);
    auto op = ev->create_W_op();
    auto in = ev->createInArgs();
    in.set_x(x);
    auto out = ev->createOutArgs();
    out.set_W_op(op);
    ev->evalModel(in, out);
    auto y = Thyra::createMember(space);
    Thyra::apply(*op, Thyra::NOTRANS, *v, y.ptr());
    Thyra::Vp_StV(y.ptr(), -1.0, *ref);
    const double rel = Thyra::norm_2(*y) / refNorm;
    EXPECT_LT(rel, mode == JacobianMode::MatrixFree ? 1e-12 : 1e-4)
        << (mode == JacobianMode::MatrixFree ? "analytic" : "difference") << " product, dim " << c.dim;
    if (mode == JacobianMode::MatrixFree) {
      // Its diagonal, from the element tangents' diagonal blocks alone, is the assembled W's
      // (round-off: the same terms summed in another order).
      auto* own = dynamic_cast<const OperatorDiagonal*>(TOE::getConstTpetraOperator(op).get());
      ASSERT_NE(own, nullptr);
      TMultiVector d(W->getRowMap(), 1);
      own->getDiagonal(d);
      Tpetra::Vector<double, LO, GO> ref(W->getRowMap());
      W->getLocalDiagCopy(ref);
      ref.update(-1.0, *d.getVector(0), 1.0);
      TMultiVector refAgain(W->getRowMap(), 1);
      W->getLocalDiagCopy(*refAgain.getVectorNonConst(0));
      ASSERT_GT(refAgain.getVector(0)->normInf(), 0.0);
      EXPECT_LT(ref.normInf(), 1e-12 * refAgain.getVector(0)->normInf()) << "diagonal, dim " << c.dim;
    }
    auto Wn = ev->assembledJacobian(*x, true);
    EXPECT_LT(Wn->getGlobalNumEntries(), W->getGlobalNumEntries());
  }
}

// The reaction norm kept from the last residual evaluation (displacement-driven: no external
// force, the case in which the convergence test normalises by it) is returned only for that
// state and load factor: every answer equals a fresh evaluator's, which has no cache.
TEST(EvaluatorReaction, KeptNormMatchesFreshEvaluation) {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  auto problem = makeProblem(2, 2.015, 0.0, true);
  std::fill(problem->bodyForce.begin(), problem->bodyForce.end(), 0.0);
  auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
  auto fresh = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
  auto space = ev->get_x_space();
  auto x1 = Thyra::createMember(space), x2 = Thyra::createMember(space), f = Thyra::createMember(space);
  fill(*fresh, *x1, 7, 0.01);
  fill(*fresh, *x2, 8, 0.01);
  auto check = [&](const Thyra::VectorBase<double>& x, const char* what) {
    fresh->setLoadFactor(ev->loadFactor());
    const double want = fresh->reactionNorm(x);
    ASSERT_GT(want, 0.0);
    EXPECT_NEAR(ev->reactionNorm(x), want, 1e-13 * want) << what;
  };
  ev->setLoadFactor(0.7);
  auto in = ev->createInArgs();
  in.set_x(x1);
  auto out = ev->createOutArgs();
  out.set_f(f);
  ev->evalModel(in, out);
  check(*x1, "the evaluated state");
  check(*x2, "another state");
  ev->setLoadFactor(0.3);
  check(*x1, "the evaluated state at another load factor");
}

// A problem built in C++ is checked as a scene is: one sentence naming the field, thrown by the
// evaluator's constructor before any map or graph is built (the same on every rank).
TEST(ProblemValidation, HandBuiltProblemsWithBadFieldsAreRefusedByName) {
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->bodyForce[3] = std::nan("");
    expectRefused(P, "bodyForce[3] = nan is not finite");
  }
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->prescribed.pop_back();
    expectRefused(P, "prescribed has");
  }
  {
    auto P = makeProblem(3, 1.015, 0.1, false);
    P->disc.X[5][1] = std::numeric_limits<double>::infinity();
    expectRefused(P, "disc.X[5] is not finite");
  }
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->material.E = -1;
    expectRefused(P, "material.E = -1");
  }
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->disc.familyOffset.resize(3);
    expectRefused(P, "disc.familyOffset has 3 entries");
  }
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->damage = true;
    P->damageSpec.sMin = 0.003;  // above sCr = 0.002
    expectRefused(P, "0 < sMin < sCr");
  }
  {
    auto P = makeProblem(2, 3.015, 0.0, false);
    P->fixedMask[0] = 4;  // component z in 2D
    expectRefused(P, "fixedMask[0]");
  }
  {
    // Only x prescribed on the left strip: the body can slide in y.
    auto P = makeProblem(2, 3.015, 0.0, false);
    for (auto& m : P->fixedMask) m &= 1u;
    expectRefused(P, "do not prevent rigid-body motion");
  }
  // The unchanged problem is accepted.
  EXPECT_NO_THROW(PeridynamicEvaluator(Teuchos::DefaultComm<int>::getComm(), makeProblem(2, 3.015, 0.1, true)));
}

// The stabilisation's micromodulus is the library's: a ProblemSpec that sets only G gets
// C = 12 k' / (pi t delta^4) (plane strain, k' = E / (2 (1 - nu - 2 nu^2)); Silling 2017), and the
// same residual, bit for bit, as one that gives that C by hand. A C out of range, and a bad G, are
// refused with one sentence.
// Blocks in a hand-built problem: each refusal one sentence naming the field.
TEST(ProblemValidation, BlocksAreCheckedByName) {
  auto refused = [](const std::function<void(ProblemSpec&)>& edit, const std::string& part) {
    auto P = makeProblem(2, 2.015, 0.1, false, true);
    edit(*P);
    expectRefused(P, part);
  };
  refused([](ProblemSpec& P) { P.blocks[1].id = 1; }, "ProblemSpec: blocks[1] (block 1) repeats block id 1");
  refused([](ProblemSpec& P) { P.disc.block[0] = 9; }, "ProblemSpec: particle 0 is in block 9, which has no entry in blocks");
  refused([](ProblemSpec& P) { P.blocks.push_back(P.blocks[0]), P.blocks.back().id = 5; }, "blocks[2] names block 5, which has no particle");
  refused([](ProblemSpec& P) { P.blocks[1].material.nu = 0.5; }, "blocks[1] (block 2).material.nu = 0.5 must satisfy -1 < nu < 0.5");
  refused([](ProblemSpec& P) { P.blocks[1].material.E = 0; }, "blocks[1] (block 2).material.E = 0 must be a positive finite number");
  refused([](ProblemSpec& P) { P.blocks[0].material.dim = 3; }, "blocks[0] (block 1).material.dim = 3 differs from disc.dim = 2");
  refused([](ProblemSpec& P) { P.blocks[1].G = -1.0; }, "blocks[1] (block 2).G = -1 must be finite and >= 0");
  refused([](ProblemSpec& P) { P.stabilization = false; }, "blocks[1] (block 2).G = 0.05 is given but stabilization is off");
  refused([](ProblemSpec& P) { P.blocks[1].damage = DamageSpec{}; }, "blocks[1] (block 2).damage is given but damage is off");
  refused([](ProblemSpec& P) { P.damage = true, P.blocks[1].damage = DamageSpec{0.01, 0.005, 3.0}; }, "blocks[1] (block 2).damage needs 0 < sMin < sCr");
  refused([](ProblemSpec& P) { P.stab.C = 5.0; }, "stab.C is set, but with blocks each block's C applies");
}

TEST(ProblemValidation, StabilizationConstantIsComputedByTheLibrary) {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  auto given = makeProblem(2, 3.015, 0.1, false);  // C = micromodulusC(...), set by hand
  auto computed = std::make_shared<ProblemSpec>(*given);
  computed->stab = StabilizationSpec{};
  computed->stab.G = 0.1;
  const auto& m = given->material;
  const double kp = m.E / (2.0 * (1.0 - m.nu - 2.0 * m.nu * m.nu));
  const double closed = 12.0 * kp / (3.14159265358979323846 * given->disc.thickness * std::pow(given->disc.horizon, 4));
  EXPECT_NEAR(computed->stabilizationSpec().C, closed, 1e-12 * closed);
  EXPECT_EQ(given->stabilizationSpec().C, given->stab.C);  // a given C is kept
  auto residual = [&](const std::shared_ptr<ProblemSpec>& P) {
    auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, P));
    ev->setLoadFactor(0.7);
    auto x = Thyra::createMember(ev->get_x_space()), f = Thyra::createMember(ev->get_x_space());
    fill(*ev, *x, 1, 0.03);
    auto in = ev->createInArgs();
    in.set_x(x);
    auto out = ev->createOutArgs();
    out.set_f(f);
    ev->evalModel(in, out);
    return ev->ownedDofValues(*f);
  };
  EXPECT_EQ(residual(computed), residual(given));
  auto negative = std::make_shared<ProblemSpec>(*computed);
  negative->stab.C = -3.0;
  expectRefused(negative, "ProblemSpec: stab.C = -3 must be finite and >= 0, or left at its default");
  auto badG = std::make_shared<ProblemSpec>(*computed);
  badG->stab.G = std::nan("");
  expectRefused(badG, "stab.G = nan must be finite and >= 0");
}

// The evaluator's own options (getValidParameters): the list picks the Jacobian mode, and a
// misspelt key or an unknown mode is refused with one sentence naming it.
TEST(EvaluatorOptions, ValidatedListSelectsTheJacobian) {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, makeProblem(2, 3.015, 0.1, false)));
  const auto valid = PeridynamicEvaluator::getValidParameters();
  EXPECT_EQ(valid->get<std::string>("Jacobian"), "Assembled");
  Teuchos::ParameterList mf;
  mf.set("Jacobian", "Matrix-Free");
  ev->setJacobian(mf, Teuchos::null);
  EXPECT_EQ(ev->jacobianMode(), JacobianMode::MatrixFree);
  Teuchos::ParameterList jf;
  jf.set("Jacobian", "Jacobian-Free");
  jf.set("Jacobian-Free Lambda", 1e-7);
  ev->setJacobian(jf, Teuchos::null);
  EXPECT_EQ(ev->jacobianMode(), JacobianMode::JacobianFree);
  auto refused = [&](const Teuchos::ParameterList& l, const std::string& part) {
    try {
      ev->setJacobian(l, Teuchos::null);
      ADD_FAILURE() << "accepted; expected " << part;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  Teuchos::ParameterList typo;
  typo.set("Jacobain", "Assembled");
  refused(typo, "Jacobain");
  Teuchos::ParameterList mode;
  mode.set("Jacobian", "Free");
  refused(mode, "Free");
  Teuchos::ParameterList fd;
  fd.set("Jacobian-Free Lambda", -1.0);
  refused(fd, "'Jacobian-Free Lambda' must be positive");
}

// The load factor as the model parameter p(0): an evaluation given p(0) = lambda equals one at
// setLoadFactor(lambda), and DfDp(0) passes a Taylor test in lambda: the remainder
// |f(lambda + h) - f(lambda) - h DfDp| falls like h^2 with prescribed displacements (a smooth, nonlinear
// function of lambda through u) and vanishes to round-off for dead loads (f is affine in lambda).
TEST(LoadFactorParameter, EvaluationWithPAndDfDpTaylorTest) {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  for (const bool prescribed : {true, false}) {
    auto P = makeProblem(2, 3.015, 0.1, false);
    if (!prescribed) std::fill(P->prescribed.begin(), P->prescribed.end(), 0.0);
    auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, P));
    ASSERT_EQ(ev->createInArgs().Np(), 1);
    EXPECT_EQ((*ev->get_p_names(0))[0], "Load Factor");
    auto x = Thyra::createMember(ev->get_x_space());
    fill(*ev, *x, 7, 1e-3);
    auto inAt = [&](double lambda) {
      auto in = ev->createInArgs();
      in.set_x(x);
      auto p = Thyra::createMember(ev->get_p_space(0));
      Thyra::set_ele(0, lambda, p.ptr());
      in.set_p(0, p);
      return in;
    };
    auto residual = [&](double lambda) {
      auto in = inAt(lambda);
      auto out = ev->createOutArgs();
      auto f = Thyra::createMember(ev->get_f_space());
      out.set_f(f);
      ev->evalModel(in, out);
      return f;
    };
    const double lambda = 0.6;
    auto f0 = residual(lambda);
    // The same as setting the load factor on the evaluator (and p set it as the current one).
    EXPECT_DOUBLE_EQ(ev->loadFactor(), lambda);
    {
      ev->setLoadFactor(lambda);
      auto in = ev->createInArgs();
      in.set_x(x);
      auto out = ev->createOutArgs();
      auto f = Thyra::createMember(ev->get_f_space());
      out.set_f(f);
      ev->evalModel(in, out);
      Thyra::Vp_StV(f.ptr(), -1.0, *f0);
      EXPECT_EQ(Thyra::norm_inf(*f), 0.0);
    }
    auto dfdp = Thyra::createMembers(ev->get_f_space(), 1);
    {
      auto in = inAt(lambda);
      auto out = ev->createOutArgs();
      ASSERT_TRUE(out.supports(Thyra::ModelEvaluatorBase::OUT_ARG_DfDp, 0).supports(Thyra::ModelEvaluatorBase::DERIV_MV_BY_COL));
      out.set_DfDp(0, Thyra::ModelEvaluatorBase::Derivative<double>(dfdp, Thyra::ModelEvaluatorBase::DERIV_MV_BY_COL));
      ev->evalModel(in, out);
    }
    const double scale = Thyra::norm_2(*dfdp->col(0));
    ASSERT_GT(scale, 0.0);
    std::vector<double> remainder;
    for (double h : {1e-2, 5e-3, 2.5e-3}) {
      auto fh = residual(lambda + h);
      Thyra::Vp_StV(fh.ptr(), -1.0, *f0);
      Thyra::Vp_StV(fh.ptr(), -h, *dfdp->col(0));
      remainder.push_back(Thyra::norm_2(*fh) / (h * scale));
    }
    if (prescribed) {
      // First-order remainder relative to h |DfDp| halves with h (second order overall).
      EXPECT_GT(remainder[0], 1e-9);
      EXPECT_NEAR(remainder[0] / remainder[1], 2.0, 0.2);
      EXPECT_NEAR(remainder[1] / remainder[2], 2.0, 0.2);
    } else {
      for (double r : remainder) EXPECT_LT(r, 1e-11);
    }
  }
}

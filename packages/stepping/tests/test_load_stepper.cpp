// The load stepper on a model that is not peridynamics: n uncoupled nonlinear springs
//   f_i(x, lambda) = k_i x_i + c x_i^3 - lambda b_i,   W = diag(k_i + 3 c x_i^2),
// a Thyra model with p(0) = lambda and DfDp = -b, solved by Newton (NOX) with a serial dense
// direct solver. Each x_i(lambda) is the unique real root of the cubic, so every answer is known.
// A "damage" policy softens springs stretched past a threshold (k_i -> k_i / 10), which the
// stepper must re-equilibrate; options, cut-backs and observers are checked on the same model.
#include <gtest/gtest.h>

#include <Teuchos_ParameterList.hpp>
#include <Thyra_DefaultSerialDenseLinearOpWithSolveFactory.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_DetachedMultiVectorView.hpp>
#include <Thyra_DetachedVectorView.hpp>
#include <Thyra_MultiVectorStdOps.hpp>
#include <Thyra_StateFuncModelEvaluatorBase.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <cmath>

#include "perinox/stepping/LoadStepper.hpp"

using namespace perinox;
using MEB = Thyra::ModelEvaluatorBase;

namespace {

class Springs : public Thyra::StateFuncModelEvaluatorBase<double> {
 public:
  Springs(std::vector<double> k, double c, std::vector<double> b, int np = 1)
      : k(std::move(k)), c(c), b(std::move(b)), np_(np) {
    space_ = Thyra::defaultSpmdVectorSpace<double>(static_cast<int>(this->k.size()));
    pSpace_ = Thyra::defaultSpmdVectorSpace<double>(1);
    nominal_ = createInArgs();
    auto x0 = Thyra::createMember(space_);
    Thyra::assign(x0.ptr(), 0.0);
    nominal_.set_x(x0);
  }
  std::vector<double> k;
  double c;
  std::vector<double> b;
  int n() const { return static_cast<int>(k.size()); }
  /// A saturating law instead of the cubic (sat > 0): g(x) = sat tanh(k x / sat) + eps k x, a
  /// spring that gives way near the force sat and is then held by eps k alone (perfect
  /// plasticity held by a stabilisation, in one unknown).
  double sat = 0, eps = 0;
  double force(int i, double x) const {
    return sat > 0 ? sat * std::tanh(k[i] * x / sat) + eps * k[i] * x : k[i] * x + c * x * x * x;
  }
  double stiffness(int i, double x) const {
    if (sat > 0) {
      const double ch = std::cosh(k[i] * x / sat);
      return k[i] / (ch * ch) + eps * k[i];
    }
    return k[i] + 3 * c * x * x;
  }
  /// The exact solution of component i at lambda (Newton on the scalar law to round-off).
  double exact(int i, double lambda) const {
    double x = lambda * b[i] / k[i];
    for (int it = 0; it < 200; ++it) x -= (force(i, x) - lambda * b[i]) / stiffness(i, x);
    return x;
  }

  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_x_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_f_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_p_space(int) const override { return pSpace_; }
  Teuchos::RCP<const Teuchos::Array<std::string>> get_p_names(int) const override {
    return Teuchos::rcp(new Teuchos::Array<std::string>(1, "Load Factor"));
  }
  MEB::InArgs<double> getNominalValues() const override { return nominal_; }
  MEB::InArgs<double> createInArgs() const override {
    MEB::InArgsSetup<double> in;
    in.setModelEvalDescription("springs");
    in.set_Np(np_);
    in.setSupports(MEB::IN_ARG_x);
    return in;
  }
  Teuchos::RCP<Thyra::LinearOpBase<double>> create_W_op() const override { return Thyra::createMembers(space_, n()); }
  Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> get_W_factory() const override {
    return Thyra::defaultSerialDenseLinearOpWithSolveFactory<double>();
  }
  mutable int evaluations = 0;

 private:
  MEB::OutArgs<double> createOutArgsImpl() const override {
    MEB::OutArgsSetup<double> out;
    out.setModelEvalDescription("springs");
    out.set_Np_Ng(np_, 0);
    out.setSupports(MEB::OUT_ARG_f);
    out.setSupports(MEB::OUT_ARG_W_op);
    if (np_ > 0) out.setSupports(MEB::OUT_ARG_DfDp, 0, MEB::DerivativeSupport(MEB::DERIV_MV_BY_COL));
    return out;
  }
  void evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const override {
    ++evaluations;
    Thyra::ConstDetachedVectorView<double> x(*in.get_x());
    const double lambda = np_ == 0 || in.get_p(0).is_null() ? 0.0 : Thyra::get_ele(*in.get_p(0), 0);
    if (auto f = out.get_f(); !f.is_null()) {
      Thyra::DetachedVectorView<double> fv(*f);
      for (int i = 0; i < n(); ++i) fv[i] = force(i, x[i]) - lambda * b[i];
    }
    if (auto W = out.get_W_op(); !W.is_null()) {
      auto mv = Teuchos::rcp_dynamic_cast<Thyra::MultiVectorBase<double>>(W, true);
      Thyra::DetachedMultiVectorView<double> Wv(*mv);
      for (int i = 0; i < n(); ++i)
        for (int j = 0; j < n(); ++j) Wv(i, j) = i == j ? stiffness(i, x[i]) : 0.0;
    }
    if (out.Np() > 0) {
      auto dfdp = out.get_DfDp(0).getMultiVector();
      if (!dfdp.is_null()) {
        const auto column = dfdp->col(0);  // the view must not outlive the column
        Thyra::DetachedVectorView<double> d(*column);
        for (int i = 0; i < n(); ++i) d[i] = -b[i];
      }
    }
  }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> space_, pSpace_;
  MEB::InArgs<double> nominal_;
  int np_ = 1;
};

/// The seed's scale for this model: |lambda b|.
class SpringScale : public ResidualScale {
 public:
  SpringScale(const Springs& m, const LoadFactorModel& lm) : m_(m), lm_(lm) {}
  double scale(const Thyra::VectorBase<double>&, bool& reaction) const override {
    reaction = false;
    double s = 0;
    for (double bi : m_.b) s += bi * bi;
    return std::abs(lm_.loadFactor()) * std::sqrt(s);
  }

 private:
  const Springs& m_;
  const LoadFactorModel& lm_;
};

/// Softens spring i (k_i -> k_i / 10) once x_i exceeds the threshold; each spring once.
class Softening : public DamagePolicy {
 public:
  Softening(Springs& m, double threshold) : m_(m), threshold_(threshold), broken_(m.n(), false) {}
  Breaks breakAfterStep(const Thyra::VectorBase<double>& x) override {
    Breaks br;
    Thyra::ConstDetachedVectorView<double> xv(x);
    for (int i = 0; i < m_.n(); ++i)
      if (!broken_[i] && xv[i] > threshold_) {
        broken_[i] = true;
        m_.k[i] /= 10;
        ++br.brokenBonds;
      }
    return br;
  }
  Breaks breakOnStall(const Thyra::VectorBase<double>&, const std::string&) override { return {}; }
  std::vector<bool> broken() const { return broken_; }

 private:
  Springs& m_;
  double threshold_;
  std::vector<bool> broken_;
};

struct Rig {
  Teuchos::RCP<Springs> springs;
  Teuchos::RCP<LoadFactorModel> model;
  Teuchos::RCP<NewtonSolver> newton;
  Rig(std::vector<double> k, double c, std::vector<double> b, int maxIterations = 25) {
    springs = Teuchos::rcp(new Springs(std::move(k), c, std::move(b)));
    model = Teuchos::rcp(new LoadFactorModel(springs));
    NewtonOptions o;
    o.tolerance = 1e-12;
    o.maxIterations = maxIterations;
    newton = Teuchos::rcp(new NewtonSolver(model, Teuchos::rcp(new SpringScale(*springs, *model)), o));
  }
  std::function<NewtonResult(Thyra::VectorBase<double>&)> solve() {
    auto n = newton;
    return [n](Thyra::VectorBase<double>& x) { return n->solve(x); };
  }
};

double maxError(const Springs& m, const Thyra::VectorBase<double>& x, double lambda) {
  Thyra::ConstDetachedVectorView<double> xv(x);
  double e = 0;
  for (int i = 0; i < m.n(); ++i) e = std::max(e, std::abs(xv[i] - m.exact(i, lambda)) / std::abs(m.exact(i, lambda)));
  return e;
}

class Recorder : public StepObserver {
 public:
  std::vector<double> steps;
  std::vector<std::string> notes;
  double vetoAt = 2.0;  // refuse a step whose load factor reaches this
  void note(const std::string& line) override { notes.push_back(line); }
  std::string vet(const StepInfo& s, double) override {
    return s.loadFactor >= vetoAt - 1e-12 ? "vetoed at " + std::to_string(s.loadFactor) : "";
  }
  void accepted(const StepInfo& s) override { steps.push_back(s.loadFactor); }
};

}  // namespace

TEST(LoadStepper, StepsANonPeridynamicModelToItsKnownSolution) {
  Rig s({1.0, 2.0, 4.0}, 0.5, {1.0, 3.0, -2.0});
  LoadStepperOptions o;
  o.loadSteps = 4;
  o.tangentPredictor = true;
  LoadStepper stepper(s.model, s.solve(), o);
  Recorder rec;
  stepper.addObserver(&rec);
  ASSERT_TRUE(stepper.run()) << stepper.failure();
  EXPECT_EQ(stepper.records().size(), 4u);
  EXPECT_EQ(rec.steps, (std::vector<double>{0.25, 0.5, 0.75, 1.0}));
  EXPECT_LT(maxError(*s.springs, stepper.converged(), 1.0), 1e-11);
  // One step in the middle is checked against its own exact state through the previous one.
  EXPECT_LT(maxError(*s.springs, stepper.previous(), 0.75), 1e-11);
  for (const auto& r : stepper.records()) {
    EXPECT_EQ(r.cutbacks, 0);
    EXPECT_GE(r.newtonIterations, 1);
    EXPECT_LE(r.newtonIterations, 6);  // the predictor starts each step near its solution
    EXPECT_EQ(r.linearSolves, r.newtonIterationsAll + (r.step == 1 ? 1 : 0));  // + the tangent predictor
  }
}

TEST(LoadStepper, CutsBackAStepThatFailsAndGrowsAgain) {
  // A stiff cubic from zero in one step: Newton overshoots to lambda b / k and comes back by
  // about a third per iteration; with 7 allowed the full step fails, the halved increments
  // converge (each from the last converged state: no predictor).
  Rig s({1.0, 1.0}, 1.0, {20.0, 15.0}, 7);
  LoadStepperOptions o;
  o.loadSteps = 1;
  o.predictor = false;
  LoadStepper stepper(s.model, s.solve(), o);
  Recorder rec;
  stepper.addObserver(&rec);
  ASSERT_TRUE(stepper.run()) << stepper.failure();
  const int cut = stepper.records().front().cutbacks;
  EXPECT_GT(cut, 0);
  // Easy steps at the reduced increment double it again: fewer steps than 2^cut.
  EXPECT_LT(stepper.records().size(), static_cast<std::size_t>(1) << cut);
  EXPECT_LT(maxError(*s.springs, stepper.converged(), 1.0), 1e-11);
  EXPECT_FALSE(rec.notes.empty());
  EXPECT_NE(rec.notes.front().find("cutting the load increment"), std::string::npos) << rec.notes.front();
  // With no cut-backs allowed the same run stops with one sentence naming the step.
  Rig t({1.0, 1.0}, 1.0, {20.0, 15.0}, 7);
  o.maxCutbacks = 0;
  LoadStepper strict(t.model, t.solve(), o);
  EXPECT_FALSE(strict.run());
  EXPECT_NE(strict.failure().find("load step 1 (load factor 1) failed after 0 cut-back(s)"), std::string::npos) << strict.failure();
}

TEST(LoadStepper, ReequilibratesAfterTheDamagePolicyBreaks) {
  // Springs 0 and 2 pass the threshold 0.6 on the way and soften; spring 1 stays below it.
  Rig s({1.0, 4.0, 1.5}, 0.2, {1.5, 1.0, 1.5});
  Softening policy(*s.springs, 0.6);
  LoadStepperOptions o;
  o.loadSteps = 5;
  LoadStepper stepper(s.model, s.solve(), o);
  stepper.setDamagePolicy(&policy);
  ASSERT_TRUE(stepper.run()) << stepper.failure();
  EXPECT_EQ(policy.broken(), (std::vector<bool>{true, false, true}));
  long long broken = 0;
  int rounds = 0;
  for (const auto& r : stepper.records()) broken += r.brokenBonds, rounds += r.breakRounds;
  EXPECT_EQ(broken, 2);
  EXPECT_GE(rounds, 1);
  // The final state is the equilibrium of the softened springs (k already divided in the model).
  EXPECT_LT(maxError(*s.springs, stepper.converged(), 1.0), 1e-11);
}

TEST(LoadStepper, AnObserverCanStopTheRunAndTheStateIsTheLastAcceptedOne) {
  Rig s({1.0, 2.0}, 0.5, {1.0, 1.0});
  LoadStepperOptions o;
  o.loadSteps = 4;
  LoadStepper stepper(s.model, s.solve(), o);
  Recorder rec;
  rec.vetoAt = 0.75;
  stepper.addObserver(&rec);
  EXPECT_FALSE(stepper.run());
  EXPECT_EQ(stepper.failure(), "vetoed at 0.750000");
  EXPECT_DOUBLE_EQ(stepper.state().loadFactor, 0.5);
  EXPECT_DOUBLE_EQ(s.model->loadFactor(), 0.5);
  EXPECT_LT(maxError(*s.springs, stepper.converged(), 0.5), 1e-11);
}

// The history commit (HistoryCommit): once per accepted step, with the accepted solution, before
// the observers see the step; never for a failed attempt, a cut-back, a damage re-equilibration or
// a vetoed step.
class CommitLog : public StepObserver {
 public:
  std::vector<std::vector<double>> committed;  // x at each commit
  std::vector<std::size_t> commitsSeen;        // commits made when each accepted step was observed
  std::vector<std::vector<double>> observed;
  double vetoAt = 2.0;
  HistoryCommit commit() {
    return [this](const Thyra::VectorBase<double>& x) { committed.push_back(values(x)); };
  }
  std::string vet(const StepInfo& s, double) override {
    return s.loadFactor >= vetoAt - 1e-12 ? "vetoed" : "";
  }
  void accepted(const StepInfo& s) override {
    commitsSeen.push_back(committed.size());
    observed.push_back(values(s.x));
  }
  static std::vector<double> values(const Thyra::VectorBase<double>& x) {
    Thyra::ConstDetachedVectorView<double> v(x);
    return std::vector<double>(v.values(), v.values() + v.subDim());
  }
};

TEST(LoadStepper, CommitsTheHistoryOfEachAcceptedStepOnceBeforeItsObservers) {
  // Cut-backs: the failed full step and its failed halvings commit nothing.
  Rig s({1.0, 1.0}, 1.0, {20.0, 15.0}, 7);
  LoadStepperOptions o;
  o.loadSteps = 1;
  o.predictor = false;
  LoadStepper stepper(s.model, s.solve(), o);
  CommitLog log;
  stepper.setHistoryCommit(log.commit());
  stepper.addObserver(&log);
  ASSERT_TRUE(stepper.run()) << stepper.failure();
  ASSERT_GT(stepper.records().front().cutbacks, 0);
  ASSERT_EQ(log.committed.size(), stepper.records().size());
  EXPECT_EQ(log.committed, log.observed);  // the accepted solution, as the observers see it
  for (std::size_t k = 0; k < log.commitsSeen.size(); ++k) EXPECT_EQ(log.commitsSeen[k], k + 1);
  // Damage: the re-equilibrations after a break are part of one accepted step, one commit.
  Rig d({1.0, 4.0, 1.5}, 0.2, {1.5, 1.0, 1.5});
  Softening policy(*d.springs, 0.6);
  o = LoadStepperOptions{};
  o.loadSteps = 5;
  LoadStepper damaged(d.model, d.solve(), o);
  damaged.setDamagePolicy(&policy);
  CommitLog dlog;
  damaged.setHistoryCommit(dlog.commit());
  damaged.addObserver(&dlog);
  ASSERT_TRUE(damaged.run()) << damaged.failure();
  int rounds = 0;
  for (const auto& r : damaged.records()) rounds += r.breakRounds;
  ASSERT_GE(rounds, 1);
  EXPECT_EQ(dlog.committed.size(), 5u);
  EXPECT_EQ(dlog.committed, dlog.observed);
  // A vetoed step is not committed: the history stays that of the last accepted step.
  Rig v({1.0, 2.0}, 0.5, {1.0, 1.0});
  LoadStepper vetoed(v.model, v.solve(), o);
  CommitLog vlog;
  vlog.vetoAt = 0.6;
  vetoed.setHistoryCommit(vlog.commit());
  vetoed.addObserver(&vlog);
  EXPECT_FALSE(vetoed.run());
  ASSERT_EQ(vlog.committed.size(), 2u);  // load factors 0.2 and 0.4
  EXPECT_EQ(vlog.committed.back(), CommitLog::values(vetoed.converged()));
}

TEST(LoadStepper, OptionsAreValidatedWithOneSentence) {
  Teuchos::ParameterList good;
  good.set("Load Steps", 8);
  good.set("Adaptive Steps", true);
  const auto o = LoadStepperOptions::fromParameterList(good, "host.cpp");
  EXPECT_EQ(o.loadSteps, 8);
  EXPECT_TRUE(o.adaptive);
  EXPECT_EQ(o.maxTotalSteps, 160);
  auto refused = [](Teuchos::ParameterList l, const std::string& part) {
    try {
      LoadStepperOptions::fromParameterList(l, "host.cpp");
      ADD_FAILURE() << "accepted; expected " << part;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  Teuchos::ParameterList typo;
  typo.set("Load Stpes", 3);
  refused(typo, "host.cpp: unknown load-stepping key 'Load Stpes'");
  Teuchos::ParameterList zero;
  zero.set("Load Steps", 0);
  refused(zero, "'Load Steps' must be between 1 and 1000000");
  Teuchos::ParameterList type;
  type.set("Min Increment", 1);
  refused(type, "'Min Increment' must be of type double");
  Teuchos::ParameterList nan;
  nan.set("Max Increment", std::nan(""));
  refused(nan, "'Max Increment' must lie in (0, 1]");
  Teuchos::ParameterList ratio;
  ratio.set("Limit Load Ratio", 0.5);
  refused(ratio, "'Limit Load Ratio' must be 0 (no check) or lie in (1, 1e12]");
  // A model without a load-factor parameter is refused by the wrapper.
  EXPECT_THROW(LoadFactorModel(Teuchos::rcp(new Springs({1.0}, 0.0, {1.0}, 0))), std::invalid_argument);
}

namespace {
/// A stall break that changes the load the body can carry: the first lowers it below the stalled
/// load (a snap-back), the next lifts it (the crack has run through, say).
class SnapBack : public DamagePolicy {
 public:
  SnapBack(double& limit, std::vector<double> limits) : limit_(limit), limits_(std::move(limits)) {}
  Breaks breakAfterStep(const Thyra::VectorBase<double>&) override { return {}; }
  Breaks breakOnStall(const Thyra::VectorBase<double>&, const std::string&) override {
    Breaks b;
    if (next_ < limits_.size()) {
      limit_ = limits_[next_++];
      b.brokenBonds = 1;
    }
    return b;
  }

 private:
  double& limit_;
  std::vector<double> limits_;
  std::size_t next_ = 0;
};
}  // namespace

TEST(LoadStepper, FindsASnapBacksLimitLoadToTheToleranceWithoutTryingALoadThatFailedAgain) {
  // A stand-in for the solve: it converges exactly when the load factor is at most the body's
  // limit, and a failure costs more iterations than a success (as stagnating Newton solves do).
  // The intact body carries 0.5; the stall break there leaves one that carries 0.5 x 0.8731.
  Rig s({1.0}, 0.0, {1.0});
  double limit = 0.5;
  std::vector<std::pair<double, bool>> tried;
  auto solve = [&](Thyra::VectorBase<double>&) {
    NewtonResult r;
    const double lambda = s.model->loadFactor();
    r.converged = lambda <= limit + 1e-12;
    r.iterations = r.work = r.converged ? 2 : 5;
    if (!r.converged) r.failure = "no equilibrium at this load";
    tried.emplace_back(lambda, r.converged);
    return r;
  };
  SnapBack policy(limit, {0.5 * 0.8731, 2.0});
  policy.breakOnStalls = true;
  policy.breakAtSnapBackLimit = true;
  policy.reloadTolerance = 0.02;
  LoadStepperOptions o;
  o.loadSteps = 4;
  o.minIncrement = 0.1;
  LoadStepper stepper(s.model, solve, o);
  stepper.setDamagePolicy(&policy);
  Recorder rec;
  stepper.addObserver(&rec);
  ASSERT_TRUE(stepper.run()) << stepper.failure();
  // The snap-back's step: the load lowered into [limit - tolerance x load, limit].
  const StepRecord* snap = nullptr;
  for (const auto& r : stepper.records())
    if (r.reloadSteps > 0) snap = &r;
  ASSERT_NE(snap, nullptr);
  EXPECT_LE(snap->loadFactor, 0.5 * 0.8731 + 1e-12);
  EXPECT_GT(snap->loadFactor, 0.5 * (0.8731 - 0.02));
  // The reload's sub-steps, after the first that converged (from 0.7 of the load: 0.9 of it
  // fails): none at or above a load that failed before, and the bracket closed in 7 sub-steps
  // (0.9 F, 0.7, 0.775, 0.8875 F, 0.83125, 0.859375, 0.8734375 F of 0.5). Without the bracket
  // the search tried 0.915 after 0.8875 had failed, and needed 12.
  EXPECT_EQ(snap->reloadSteps, 7);
  // The re-equilibration's first solve is the one at the stalled load that fails; its sub-steps follow.
  std::size_t stall = 0;
  while (stall < tried.size() && !(std::abs(tried[stall].first - 0.5) < 1e-12 && !tried[stall].second)) ++stall;
  ASSERT_LT(stall + 7, tried.size());
  std::size_t first = stall + 1;
  while (!tried[first].second) ++first;
  double lowestFailure = 1.0;
  for (std::size_t i = first; i <= stall + 7; ++i) {
    EXPECT_LT(tried[i].first, lowestFailure - 1e-12) << "sub-step " << i << " at " << tried[i].first;
    if (!tried[i].second) lowestFailure = std::min(lowestFailure, tried[i].first);
  }
  EXPECT_LT(lowestFailure, 1.0);
  bool noted = false;
  for (const auto& n : rec.notes) noted = noted || n.find("cannot carry load factor 0.5 (snap-back)") != std::string::npos;
  EXPECT_TRUE(noted);
}

// A load path: the stepper's load factor is a pseudo-time, the model sees the piecewise-linear
// load through 0, 1, 0.25, 1.5 (load, unload, reload past the first peak); steps land on the
// corners, also when adaptive growth would step over one, and each accepted state is the model's
// exact solution at the path's load factor.
TEST(LoadStepper, FollowsALoadPathThroughItsCorners) {
  const std::vector<double> knots{1.0, 0.25, 1.5};
  EXPECT_EQ(loadOnPath(knots, 0.0), 0.0);
  EXPECT_EQ(loadOnPath(knots, 1.0 / 3.0), 1.0);
  EXPECT_EQ(loadOnPath(knots, 2.0 / 3.0), 0.25);
  EXPECT_EQ(loadOnPath(knots, 1.0), 1.5);
  EXPECT_NEAR(loadOnPath(knots, 0.5), 0.625, 1e-15);
  EXPECT_EQ(loadOnPath({}, 0.375), 0.375);
  EXPECT_EQ(LoadFactorModel::pathStops(3), (std::vector<double>{1.0 / 3.0, 2.0 / 3.0}));
  for (const bool adaptive : {false, true}) {
    SCOPED_TRACE(adaptive ? "adaptive" : "fixed steps");
    Rig s({1.0, 2.0}, 0.5, {1.0, -3.0});
    s.model->setLoadPath(knots);
    EXPECT_NEAR(s.model->pathSlope(0.5), 3.0 * (0.25 - 1.0), 1e-15);
    LoadStepperOptions o;
    o.loadSteps = 2 * 3;  // two per segment
    o.stops = LoadFactorModel::pathStops(3);
    o.adaptive = adaptive;
    o.maxIncrement = 0.3;
    o.easyIterations = 10;  // grow after every step: the growth must stop at the corners
    LoadStepper stepper(s.model, s.solve(), o);
    Recorder rec;
    stepper.addObserver(&rec);
    ValueRecorder err([&](const Thyra::VectorBase<double>& x) {
      return std::vector<double>{maxError(*s.springs, x, s.model->loadAt(s.model->loadFactor()))};
    });
    stepper.addObserver(&err);
    ASSERT_TRUE(stepper.run()) << stepper.failure();
    // The records hold the pseudo-time, the observers see the path's load factor.
    std::vector<double> times;
    for (const auto& r : stepper.records()) times.push_back(r.loadFactor);
    for (double stop : o.stops)
      EXPECT_TRUE(std::any_of(times.begin(), times.end(), [&](double v) { return v == stop; }))
          << "no step landed on the corner at pseudo-time " << stop;
    EXPECT_NEAR(times.back(), 1.0, 1e-12);
    ASSERT_EQ(rec.steps.size(), times.size());
    for (std::size_t k = 0; k < times.size(); ++k) EXPECT_EQ(rec.steps[k], loadOnPath(knots, times[k]));
    for (const auto& v : err.values()) EXPECT_LT(v.second.front(), 1e-11) << "at load factor " << v.first;
    if (!adaptive) {
      EXPECT_EQ(times.size(), 6u);
    }
  }
}

TEST(LoadStepper, StopsAtALimitLoadInsteadOfJumpingToAnEquilibriumOnlyTheResidualStiffnessHolds) {
  // One saturating spring (force 1 at most, then eps = 1e-4 of its stiffness): asked for load
  // factor 1.5 in steps of 0.1, Newton would converge past lambda = 1 to x of about 5 000. The
  // stepper finds that the step past the limit moves 100 times more per unit load than the first
  // and cuts it back, and stops with the limit load named.
  auto rig = [] {
    Rig s({1.0}, 0.0, {1.5}, 60);
    s.springs->sat = 1.0;
    s.springs->eps = 1e-4;
    return s;
  };
  LoadStepperOptions o;
  o.loadSteps = 15;
  o.maxCutbacks = 8;
  Rig s = rig();
  LoadStepper stepper(s.model, s.solve(), o);
  EXPECT_FALSE(stepper.run());
  ASSERT_TRUE(std::isfinite(stepper.limitLoad())) << stepper.failure();
  // The tangent compliance reaches 100 times the initial one at g' = k / 100: x = acosh(10),
  // force tanh(acosh(10)) = 0.99499 (+ 3e-4 from eps), lambda = force / 1.5. The step-wise
  // (secant) measure stops there to within the last increment, 0.1 / 2^8 of the path.
  const double atRatio = (std::tanh(std::acosh(10.0)) + 1e-4 * std::acosh(10.0)) / 1.5;
  EXPECT_GT(stepper.limitLoad(), atRatio - 0.02);
  EXPECT_LT(stepper.limitLoad(), 1.0 / 1.5 + 1e-4 * 20);
  EXPECT_NE(stepper.failure().find("reached a limit load at load factor"), std::string::npos) << stepper.failure();
  EXPECT_NE(stepper.failure().find("Limit Load Ratio"), std::string::npos) << stepper.failure();
  // The state kept is the last converged one, exactly on the spring's curve.
  EXPECT_LT(maxError(*s.springs, stepper.converged(), stepper.state().loadFactor), 1e-10);
  Thyra::ConstDetachedVectorView<double> xv(stepper.converged());
  EXPECT_LT(xv[0], 10.0);
  // Without the check the same run converges at every step and ends far away.
  o.limitLoadRatio = 0;
  Rig t = rig();
  LoadStepper free(t.model, t.solve(), o);
  ASSERT_TRUE(free.run()) << free.failure();
  EXPECT_FALSE(std::isfinite(free.limitLoad()));
  Thyra::ConstDetachedVectorView<double> xf(free.converged());
  EXPECT_GT(xf[0], 1000.0);
  EXPECT_LT(maxError(*t.springs, free.converged(), 1.0), 1e-10);
}

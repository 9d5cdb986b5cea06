// Arc-length continuation on a model that is not peridynamics: a two-DOF snap-through
//   f_0(x, lambda) = x_0 exp(-x_0) - lambda b,   f_1 = 2 x_1 - x_0,
//   W = [[(1 - x_0) exp(-x_0), 0], [-1, 2]],     df/dlambda = (-b, 0),
// whose equilibrium path is known in closed form: lambda = x_0 exp(-x_0) / b, x_1 = x_0 / 2. The
// load factor peaks at x_0 = 1 (lambda = 1 / (e b), a limit point) and falls after it; beyond the
// peak there is no equilibrium at all, so load stepping to a larger load factor must fail while
// arc length follows the path over the peak and down the other side.
#include <gtest/gtest.h>

#include <Teuchos_ParameterList.hpp>
#include <Thyra_DefaultSerialDenseLinearOpWithSolveFactory.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_DetachedMultiVectorView.hpp>
#include <Thyra_DetachedVectorView.hpp>
#include <Thyra_StateFuncModelEvaluatorBase.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <cmath>

#include "perinox/stepping/ArcLengthStepper.hpp"

using namespace perinox;
using MEB = Thyra::ModelEvaluatorBase;

namespace {

class SnapThrough : public Thyra::StateFuncModelEvaluatorBase<double> {
 public:
  explicit SnapThrough(double b) : b(b) {
    space_ = Thyra::defaultSpmdVectorSpace<double>(2);
    pSpace_ = Thyra::defaultSpmdVectorSpace<double>(1);
    nominal_ = createInArgs();
    auto x0 = Thyra::createMember(space_);
    Thyra::assign(x0.ptr(), 0.0);
    nominal_.set_x(x0);
  }
  double b;
  /// The load factor on the path at x_0 (closed form).
  double pathLoad(double x0) const { return x0 * std::exp(-x0) / b; }

  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_x_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_f_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_p_space(int) const override { return pSpace_; }
  Teuchos::RCP<const Teuchos::Array<std::string>> get_p_names(int) const override {
    return Teuchos::rcp(new Teuchos::Array<std::string>(1, "Load Factor"));
  }
  MEB::InArgs<double> getNominalValues() const override { return nominal_; }
  MEB::InArgs<double> createInArgs() const override {
    MEB::InArgsSetup<double> in;
    in.setModelEvalDescription("snap-through");
    in.set_Np(1);
    in.setSupports(MEB::IN_ARG_x);
    return in;
  }
  Teuchos::RCP<Thyra::LinearOpBase<double>> create_W_op() const override { return Thyra::createMembers(space_, 2); }
  Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> get_W_factory() const override {
    return Thyra::defaultSerialDenseLinearOpWithSolveFactory<double>();
  }

 private:
  MEB::OutArgs<double> createOutArgsImpl() const override {
    MEB::OutArgsSetup<double> out;
    out.setModelEvalDescription("snap-through");
    out.set_Np_Ng(1, 0);
    out.setSupports(MEB::OUT_ARG_f);
    out.setSupports(MEB::OUT_ARG_W_op);
    out.setSupports(MEB::OUT_ARG_DfDp, 0, MEB::DerivativeSupport(MEB::DERIV_MV_BY_COL));
    return out;
  }
  void evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const override {
    Thyra::ConstDetachedVectorView<double> x(*in.get_x());
    const double lambda = in.get_p(0).is_null() ? 0.0 : Thyra::get_ele(*in.get_p(0), 0);
    const double e = std::exp(-x[0]);
    if (auto f = out.get_f(); !f.is_null()) {
      Thyra::DetachedVectorView<double> fv(*f);
      fv[0] = x[0] * e - lambda * b;
      fv[1] = 2 * x[1] - x[0];
    }
    if (auto W = out.get_W_op(); !W.is_null()) {
      auto mv = Teuchos::rcp_dynamic_cast<Thyra::MultiVectorBase<double>>(W, true);
      Thyra::DetachedMultiVectorView<double> Wv(*mv);
      Wv(0, 0) = (1 - x[0]) * e, Wv(0, 1) = 0.0, Wv(1, 0) = -1.0, Wv(1, 1) = 2.0;
    }
    auto dfdp = out.get_DfDp(0).getMultiVector();
    if (!dfdp.is_null()) {
      const auto column = dfdp->col(0);
      Thyra::DetachedVectorView<double> d(*column);
      d[0] = -b, d[1] = 0.0;
    }
  }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> space_, pSpace_;
  MEB::InArgs<double> nominal_;
};

/// |lambda b|, the external load (the seed's scale).
class LoadScale : public ResidualScale {
 public:
  LoadScale(const SnapThrough& m, const LoadFactorModel& lm) : m_(m), lm_(lm) {}
  double scale(const Thyra::VectorBase<double>&, bool& reaction) const override {
    reaction = false;
    return std::abs(lm_.loadFactor() * m_.b);
  }

 private:
  const SnapThrough& m_;
  const LoadFactorModel& lm_;
};

struct Point {
  double lambda, x0, x1;
};

class PathRecorder : public StepObserver {
 public:
  std::vector<Point> points;
  std::vector<std::string> notes;
  void note(const std::string& line) override { notes.push_back(line); }
  void accepted(const StepInfo& s) override {
    Thyra::ConstDetachedVectorView<double> x(s.x);
    points.push_back({s.loadFactor, x[0], x[1]});
  }
};

struct Rig {
  Teuchos::RCP<SnapThrough> snap;
  Teuchos::RCP<LoadFactorModel> model;
  Teuchos::RCP<LoadScale> scale;
  explicit Rig(double b) {
    snap = Teuchos::rcp(new SnapThrough(b));
    model = Teuchos::rcp(new LoadFactorModel(snap));
    scale = Teuchos::rcp(new LoadScale(*snap, *model));
  }
  Teuchos::RCP<Thyra::VectorBase<double>> zero() const {
    auto x = Thyra::createMember(snap->get_x_space());
    Thyra::assign(x.ptr(), 0.0);
    return x;
  }
};

double x0Of(const Thyra::VectorBase<double>& x) { return Thyra::get_ele(x, 0); }

ArcLengthStepperOptions pathOptions() {
  ArcLengthStepperOptions o;
  o.initialArcLength = 0.05;
  o.maxArcLength = 0.2;
  o.maxSteps = 500;
  o.targetLoadFactor = 10.0;  // never reached: the monitor ends the run
  o.targetMonitor = 3.0;      // x_0 = 3, well past the limit point at x_0 = 1
  o.tolerance = 1e-12;
  o.monitorName = "x0";
  return o;
}

}  // namespace

TEST(ArcLengthStepper, TheFirstTangentIsTheClosedFormOne) {
  // At x = 0, lambda = 0: J = [[1, 0], [-1, 2]], df/dlambda = (-b, 0), so dx/dlambda = (b, b / 2).
  Rig r(0.5);
  ArcLengthCorrector c(r.model, r.scale, pathOptions());
  auto z = r.zero();
  ASSERT_EQ(c.tangent(*r.zero(), 0.0, *z), "");
  EXPECT_NEAR(Thyra::get_ele(*z, 0), 0.5, 1e-15);
  EXPECT_NEAR(Thyra::get_ele(*z, 1), 0.25, 1e-15);
  EXPECT_EQ(c.totalLinear().solves, 1);
}

TEST(ArcLengthStepper, PassesTheLimitPointThatLoadSteppingCannot) {
  // b = 0.5: the path peaks at lambda = 1 / (e b) = 0.7358 < 1.
  const double peak = 1.0 / (std::exp(1.0) * 0.5);
  // Load stepping to lambda = 1 in 10 steps with the given limit-load ratio: whether it got
  // there, the load factor it stopped at, the limit load it names (NaN: none) and its failure.
  struct Stepped {
    bool done;
    double loadFactor, limitLoad;
    std::string failure;
  };
  auto loadStepping = [](double limitLoadRatio) {
    Rig r(0.5);
    NewtonOptions no;
    no.tolerance = 1e-12;
    auto newton = Teuchos::rcp(new NewtonSolver(r.model, r.scale, no));
    LoadStepperOptions lo;
    lo.loadSteps = 10;
    lo.limitLoadRatio = limitLoadRatio;
    LoadStepper stepper(r.model, [newton](Thyra::VectorBase<double>& x) { return newton->solve(x); }, lo);
    const bool done = stepper.run();
    return Stepped{done, stepper.state().loadFactor, stepper.limitLoad(), stepper.failure()};
  };
  {
    const Stepped s = loadStepping(0);  // no limit-load check: Newton fails past the peak
    EXPECT_FALSE(s.done);
    EXPECT_LT(s.loadFactor, peak);
    EXPECT_NE(s.failure.find("failed after"), std::string::npos) << s.failure;
  }
  {
    // With the check (the default) the stepper says it reached a limit load: just below the peak
    // (measured 0.735547 against 0.735759), where the next step would land on the falling branch.
    const Stepped s = loadStepping(LoadStepperOptions().limitLoadRatio);
    EXPECT_FALSE(s.done);
    ASSERT_TRUE(std::isfinite(s.limitLoad)) << s.failure;
    EXPECT_NE(s.failure.find("reached a limit load at load factor"), std::string::npos) << s.failure;
    EXPECT_LT(s.limitLoad, peak);
    EXPECT_GT(s.limitLoad, (1 - 1e-3) * peak);
  }
  Rig r(0.5);
  ArcLengthStepper arc(r.model, r.scale, pathOptions());
  arc.setMonitor(x0Of);
  // The tangent's negative pivots, from its closed form: W_00 < 0 past the peak.
  arc.setStabilityCount([](const Thyra::VectorBase<double>& x) { return x0Of(x) > 1.0 ? 1 : 0; });
  PathRecorder rec;
  arc.addObserver(&rec);
  ASSERT_TRUE(arc.run(*r.zero(), 0.0)) << arc.failure();
  ASSERT_GT(rec.points.size(), 10u);
  ASSERT_EQ(rec.points.size(), arc.records().size());
  for (std::size_t k = 0; k < rec.points.size(); ++k) {
    const Point& p = rec.points[k];
    // Every converged point lies on the closed-form path (corrector tolerance 1e-12 on |f| / |lambda b|).
    EXPECT_NEAR(p.lambda, r.snap->pathLoad(p.x0), 1e-11 * std::max(1.0, p.lambda)) << "step " << k + 1;
    EXPECT_NEAR(p.x1, 0.5 * p.x0, 1e-12) << "step " << k + 1;
    EXPECT_EQ(arc.records()[k].loadFactor, p.lambda);
    EXPECT_EQ(arc.records()[k].negativePivots, p.x0 > 1.0 ? 1 : 0);
  }
  // The path went over the peak and down: one limit point, near the closed-form one.
  ASSERT_EQ(arc.limitPoints().size(), 1u);
  const auto& lp = arc.limitPoints().front();
  EXPECT_LE(lp.loadFactor, peak);
  EXPECT_GT(lp.loadFactor, peak - 0.01);
  EXPECT_NEAR(lp.monitor, 1.0, 0.3);
  EXPECT_EQ(arc.records()[lp.step - 1].loadFactor, lp.loadFactor);
  bool noted = false;
  for (const auto& n : rec.notes) noted = noted || n.find("limit point passed") != std::string::npos;
  EXPECT_TRUE(noted);
  // The last step was shortened to land on x_0 = 3, where lambda = 3 exp(-3) / b.
  EXPECT_NEAR(x0Of(arc.converged()), 3.0, 3e-9);
  EXPECT_NEAR(arc.loadFactor(), r.snap->pathLoad(x0Of(arc.converged())), 1e-12);
  EXPECT_DOUBLE_EQ(r.model->loadFactor(), arc.loadFactor());
  EXPECT_LT(arc.loadFactor(), 0.5 * peak);
}

TEST(ArcLengthStepper, LandsOnATargetLoadFactorBeforeThePeak) {
  Rig r(1.0);
  ArcLengthStepperOptions o = pathOptions();
  o.targetMonitor = 0.0;
  o.targetLoadFactor = 0.25;  // below the peak 1 / e
  ArcLengthStepper arc(r.model, r.scale, o);
  PathRecorder rec;
  arc.addObserver(&rec);
  // The history commit: once per accepted step, with its solution, before the observers see it.
  std::vector<double> committedX0;
  std::vector<std::size_t> commitsWhenObserved;
  struct Seen : StepObserver {
    std::function<void()> f;
    void accepted(const StepInfo&) override { f(); }
  } seen;
  seen.f = [&] { commitsWhenObserved.push_back(committedX0.size()); };
  arc.addObserver(&seen);
  arc.setHistoryCommit([&](const Thyra::VectorBase<double>& x) { committedX0.push_back(x0Of(x)); });
  ASSERT_TRUE(arc.run(*r.zero(), 0.0)) << arc.failure();
  ASSERT_EQ(committedX0.size(), arc.records().size());
  for (std::size_t k = 0; k < rec.points.size(); ++k) {
    EXPECT_EQ(committedX0[k], rec.points[k].x0);
    EXPECT_EQ(commitsWhenObserved[k], k + 1);
  }
  EXPECT_NEAR(arc.loadFactor(), 0.25, 0.25e-9);
  // x_0 exp(-x_0) = 0.25 on the rising branch (x_0 < 1), by Newton on the scalar equation.
  double x0 = 0.25;
  for (int it = 0; it < 60; ++it) x0 -= (x0 * std::exp(-x0) - 0.25) / ((1 - x0) * std::exp(-x0));
  EXPECT_NEAR(x0Of(arc.converged()), x0, 1e-9);
  EXPECT_TRUE(arc.limitPoints().empty());
  for (std::size_t k = 1; k < rec.points.size(); ++k) EXPECT_GT(rec.points[k].lambda, rec.points[k - 1].lambda);
}

TEST(ArcLengthStepper, StopsAtMaxStepsWithOneSentence) {
  Rig r(0.5);
  ArcLengthStepperOptions o = pathOptions();
  o.maxSteps = 3;
  o.keyPrefix = "Arc/";
  ArcLengthStepper arc(r.model, r.scale, o);
  arc.setMonitor(x0Of);
  EXPECT_FALSE(arc.run(*r.zero(), 0.0));
  EXPECT_EQ(arc.records().size(), 3u);
  EXPECT_EQ(arc.failure().rfind("reached 'Arc/Max Steps' = 3 at load factor ", 0), 0u) << arc.failure();
  EXPECT_NE(arc.failure().find("before the target (load factor 10 or x0 3)"), std::string::npos) << arc.failure();
}

TEST(ArcLengthStepper, OptionsAreValidatedWithOneSentence) {
  Teuchos::ParameterList good;
  good.set("Initial Arc Length", 0.1);
  good.set("Max Steps", 40);
  const auto o = ArcLengthStepperOptions::fromParameterList(good, "host.cpp");
  EXPECT_EQ(o.initialArcLength, 0.1);
  EXPECT_EQ(o.maxSteps, 40);
  EXPECT_EQ(o.maxArcLength, ArcLengthStepperOptions().maxArcLength);
  auto refused = [](Teuchos::ParameterList l, const std::string& part) {
    try {
      ArcLengthStepperOptions::fromParameterList(l, "host.cpp");
      ADD_FAILURE() << "accepted; expected " << part;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  Teuchos::ParameterList typo;
  typo.set("Initial Arclength", 0.1);
  refused(typo, "host.cpp: unknown arc-length key 'Initial Arclength' (known: Initial Arc Length, ");
  Teuchos::ParameterList order;
  order.set("Min Arc Length", 0.2);
  refused(order, "host.cpp: 'Initial Arc Length' = 0.05 is below 'Min Arc Length'");
  Teuchos::ParameterList type;
  type.set("Max Steps", 4.0);
  refused(type, "'Max Steps' must be of type int");
  Teuchos::ParameterList nan;
  nan.set("Tolerance", std::nan(""));
  refused(nan, "'Tolerance' must be positive and finite");
  Teuchos::ParameterList negative;
  negative.set("Target Monitor", -1.0);
  refused(negative, "'Target Monitor' must be >= 0");
}

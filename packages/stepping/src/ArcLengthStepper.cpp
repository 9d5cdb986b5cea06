// Pseudo-arc-length continuation (see ArcLengthStepper.hpp). Thyra only: no peridynamics, no NOX;
// the linear solves go through the model's Stratimikos (or any Thyra) factory.
#include "perinox/stepping/ArcLengthStepper.hpp"

#include <Thyra_LinearOpWithSolveBase.hpp>
#include <Thyra_LinearOpWithSolveFactoryHelpers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "perinox/core/EvaluationError.hpp"  // the model could not be evaluated at a state

namespace perinox {

using Vec = Thyra::VectorBase<double>;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string shown(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// f and/or W of the model at x (the model's load factor).
void evaluate(const LoadFactorModel& m, const Vec& x, Vec* f, Thyra::LinearOpBase<double>* W) {
  auto in = m.createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto out = m.createOutArgs();
  if (f) out.set_f(Teuchos::rcpFromRef(*f));
  if (W) out.set_W_op(Teuchos::rcpFromRef(*W));
  m.evalModel(in, out);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Options
// ---------------------------------------------------------------------------------------------

Teuchos::RCP<const Teuchos::ParameterList> ArcLengthStepperOptions::validParameters() {
  static const auto valid = [] {
    auto l = Teuchos::rcp(new Teuchos::ParameterList("Arc Length"));
    const ArcLengthStepperOptions d;
    l->set("Initial Arc Length", d.initialArcLength, "arc of the first step (Min Arc Length <= it <= Max Arc Length)");
    l->set("Min Arc Length", d.minArcLength, "a failing step whose halved arc would fall below this ends the run (> 0)");
    l->set("Max Arc Length", d.maxArcLength, "the arc grows by 1.5 after easy steps up to this");
    l->set("Max Steps", d.maxSteps, "converged steps allowed before the target (1 to 1000000)");
    l->set("Target Load Factor", d.targetLoadFactor, "stop when the load factor reaches it (> 0)");
    l->set("Target Monitor", d.targetMonitor, "stop when |monitor(x)| reaches it (0: off; >= 0)");
    l->set("Max Cutbacks", d.maxCutbacks, "halvings of a failing step's arc (0 to 60)");
    l->set("Easy Iterations", d.easyIterations, "a step of at most this many corrector iterations grows the arc (>= 0)");
    l->set("Tolerance", d.tolerance, "corrector: |f| / scale at convergence (> 0)");
    l->set("Max Iterations", d.maxIterations, "corrector iterations per step (1 to 1000)");
    l->set("Linear Tolerance", d.linearTolerance, "relative residual requested from iterative linear solvers (> 0)");
    return l;
  }();
  return valid;
}

ArcLengthStepperOptions ArcLengthStepperOptions::fromParameterList(const Teuchos::ParameterList& list,
                                                                   const std::string& where) {
  const auto valid = validParameters();
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string& name = list.name(it);
    if (!valid->isParameter(name)) {
      std::string known;
      for (auto v = valid->begin(); v != valid->end(); ++v) known += (known.empty() ? "" : ", ") + valid->name(v);
      throw std::invalid_argument(where + ": unknown arc-length key '" + name + "' (known: " + known + ")");
    }
    if (list.entry(it).getAny(false).type() != valid->getEntry(name).getAny(false).type())
      throw std::invalid_argument(where + ": '" + name + "' must be of type " + valid->getEntry(name).getAny(false).typeName());
  }
  ArcLengthStepperOptions o;
  Teuchos::ParameterList l(list);  // get with a default is not const
  o.initialArcLength = l.get("Initial Arc Length", o.initialArcLength);
  o.minArcLength = l.get("Min Arc Length", o.minArcLength);
  o.maxArcLength = l.get("Max Arc Length", o.maxArcLength);
  o.maxSteps = l.get("Max Steps", o.maxSteps);
  o.targetLoadFactor = l.get("Target Load Factor", o.targetLoadFactor);
  o.targetMonitor = l.get("Target Monitor", o.targetMonitor);
  o.maxCutbacks = l.get("Max Cutbacks", o.maxCutbacks);
  o.easyIterations = l.get("Easy Iterations", o.easyIterations);
  o.tolerance = l.get("Tolerance", o.tolerance);
  o.maxIterations = l.get("Max Iterations", o.maxIterations);
  o.linearTolerance = l.get("Linear Tolerance", o.linearTolerance);
  auto bad = [&](const char* key, const std::string& what) { throw std::invalid_argument(where + ": '" + key + "' " + what); };
  const std::string order = " (0 < Min Arc Length <= Initial Arc Length <= Max Arc Length)";
  if (!(o.minArcLength > 0)) bad("Min Arc Length", "= " + shown(o.minArcLength) + " is not positive" + order);
  if (!(o.initialArcLength >= o.minArcLength))
    bad("Initial Arc Length", "= " + shown(o.initialArcLength) + " is below 'Min Arc Length'" + order);
  if (!(o.maxArcLength >= o.initialArcLength) || !std::isfinite(o.maxArcLength))
    bad("Max Arc Length", "= " + shown(o.maxArcLength) + " is below 'Initial Arc Length' or not finite" + order);
  if (o.maxSteps < 1 || o.maxSteps > 1000000) bad("Max Steps", "must be between 1 and 1000000, not " + std::to_string(o.maxSteps));
  if (!(o.targetLoadFactor > 0) || !std::isfinite(o.targetLoadFactor)) bad("Target Load Factor", "must be positive and finite");
  if (!(o.targetMonitor >= 0) || !std::isfinite(o.targetMonitor)) bad("Target Monitor", "must be >= 0 and finite (0: off)");
  if (o.maxCutbacks < 0 || o.maxCutbacks > 60) bad("Max Cutbacks", "must be between 0 and 60");
  if (o.easyIterations < 0) bad("Easy Iterations", "must be >= 0");
  if (!(o.tolerance > 0) || !std::isfinite(o.tolerance)) bad("Tolerance", "must be positive and finite");
  if (o.maxIterations < 1 || o.maxIterations > 1000) bad("Max Iterations", "must be between 1 and 1000");
  if (!(o.linearTolerance > 0) || !std::isfinite(o.linearTolerance)) bad("Linear Tolerance", "must be positive and finite");
  return o;
}

// ---------------------------------------------------------------------------------------------
// ArcLengthCorrector
// ---------------------------------------------------------------------------------------------

ArcLengthCorrector::ArcLengthCorrector(Teuchos::RCP<LoadFactorModel> model, Teuchos::RCP<const ResidualScale> scale,
                                       const ArcLengthStepperOptions& options)
    : model_(std::move(model)), scale_(std::move(scale)), opt_(options) {
  if (model_.is_null() || scale_.is_null()) throw std::invalid_argument("ArcLengthCorrector: no model or no residual scale given");
}

/// Solves A y = b (y starts at zero); false when the linear solver reports that it did not
/// converge (Belos: iteration limit or breakdown).
bool ArcLengthCorrector::solve(const Thyra::LinearOpWithSolveBase<double>& A, const Vec& b, Vec& y, std::string& why) {
  Thyra::assign(Teuchos::ptrFromRef(y), 0.0);
  Thyra::SolveCriteria<double> crit;
  crit.solveMeasureType = Thyra::SolveMeasureType(Thyra::SOLVE_MEASURE_NORM_RESIDUAL, Thyra::SOLVE_MEASURE_NORM_RHS);
  crit.requestedTol = opt_.linearTolerance;
  const auto st = A.solve(Thyra::NOTRANS, b, Teuchos::ptrFromRef(y), Teuchos::constPtr(crit));
  ++counts_.solves;
  if (!st.extraParameters.is_null()) counts_.krylovIterations += std::max(0, st.extraParameters->get("Iteration Count", 0));
  // Belos can report "unconverged" with an achieved residual far below the request (its
  // loss-of-accuracy check on 2 ranks, measured 1e-20 against 1e-12): the achieved value decides.
  const bool known = st.achievedTol != Thyra::SolveStatus<double>::unknownTolerance();
  if (st.solveStatus == Thyra::SOLVE_STATUS_UNCONVERGED && !(known && st.achievedTol <= opt_.linearTolerance)) {
    std::ostringstream s;
    s << "the linear solver did not converge (achieved relative residual " << (known ? st.achievedTol : NAN)
      << ", requested " << opt_.linearTolerance << ": Krylov iteration limit or breakdown)";
    why = s.str();
    ++counts_.failures;
    return false;
  }
  return true;
}

std::string ArcLengthCorrector::tangent(const Vec& x, double lambda, Vec& z) {
  try {
    auto fl = x.clone_v();
    model_->setLoadFactor(lambda);
    model_->loadDerivative(x, *fl);
    auto W = model_->create_W_op();
    evaluate(*model_, x, nullptr, W.get());
    auto lows = Thyra::linearOpWithSolve(*model_->get_W_factory(), W.getConst());
    Thyra::scale(-1.0, fl.ptr());
    std::string why;
    if (!solve(*lows, *fl, z, why)) return "tangent solve: " + why;
  } catch (const EvaluationError& e) {
    return std::string("model evaluation failed: ") + e.what();
  } catch (const std::exception& e) {
    return std::string("linear solver error in the tangent solve: ") + e.what();
  }
  return "";
}

NewtonResult ArcLengthCorrector::correct(Vec& x, double& lambda, const Vec& tx, double tl, double w, const Vec& xPred,
                                         double lPred) {
  NewtonResult r;
  const double floorAbs = opt_.floorFactor * scale_->roundoff();
  auto f = x.clone_v(), fl = x.clone_v(), a = x.clone_v(), b = x.clone_v(), d = x.clone_v();
  auto W = model_->create_W_op();
  try {
    for (int it = 0;; ++it) {
      model_->setLoadFactor(lambda);
      evaluate(*model_, x, f.get(), W.get());
      const double normF = Thyra::norm_2(*f);
      bool reaction = false;
      double scale = scale_->scale(x, reaction);
      r.reactionNormalised = reaction;
      if (!(scale > 0)) scale = 1.0;  // no load and no reaction: the test is absolute
      const double res = normF / scale;
      r.residuals.push_back(res);
      r.floorNormalised = floorAbs / scale;
      if (!std::isfinite(res)) {
        r.failure = "the residual became NaN or infinite";
        break;
      }
      if (res <= opt_.tolerance || normF <= floorAbs) {
        r.atRoundoffFloor = res > opt_.tolerance;
        r.converged = true;
        r.iterations = it;
        break;
      }
      if (it >= opt_.maxIterations) {
        std::ostringstream s;
        s << "no convergence in " << opt_.maxIterations << " arc-length corrector iterations (last normalised residual "
          << res << ")";
        r.failure = s.str();
        r.iterations = it;
        break;
      }
      const std::string stag = stagnationDiagnosis(r.residuals, opt_.stagnationWindow);
      if (!stag.empty()) {
        r.failure = stag;
        r.iterations = it;
        break;
      }
      // Bordering: J a = -f, J b = df/dlambda.
      ++correctorIterations_;
      model_->loadDerivative(x, *fl);
      auto lows = Thyra::linearOpWithSolve(*model_->get_W_factory(), W.getConst());
      Thyra::scale(-1.0, f.ptr());
      std::string why;
      const bool okA = solve(*lows, *f, *a, why);
      const bool okB = okA && solve(*lows, *fl, *b, why);
      if (!okA || !okB) {
        ++r.linearFailures;
        r.failure = why;
        r.iterations = it + 1;
        break;
      }
      // N at the current iterate: w tx.(x - xPred) + tl (lambda - lPred)
      Thyra::V_VmV(d.ptr(), x, xPred);
      const double N = w * Thyra::dot(tx, *d) + tl * (lambda - lPred);
      const double denom = tl - w * Thyra::dot(tx, *b);
      if (!(std::abs(denom) > 0)) {
        r.failure = "the bordered system is singular (the constraint is tangent to the path)";
        r.iterations = it + 1;
        break;
      }
      const double dl = (-N - w * Thyra::dot(tx, *a)) / denom;
      Thyra::Vp_V(Teuchos::ptrFromRef(x), *a);  // x += a - dl b
      Thyra::Vp_StV(Teuchos::ptrFromRef(x), -dl, *b);
      lambda += dl;
    }
  } catch (const EvaluationError& e) {
    r.failure = std::string("model evaluation failed: ") + e.what();
  } catch (const std::exception& e) {
    r.failure = linearSolverFailure(e);
  }
  if (!r.converged) r.iterations = std::max(r.iterations, static_cast<int>(r.residuals.size()) - 1);
  r.work = r.iterations;
  model_->setLoadFactor(lambda);
  return r;
}

// ---------------------------------------------------------------------------------------------
// ArcLengthStepper
// ---------------------------------------------------------------------------------------------

ArcLengthStepper::ArcLengthStepper(Teuchos::RCP<LoadFactorModel> model, Teuchos::RCP<const ResidualScale> scale,
                                   const ArcLengthStepperOptions& options)
    : model_(model), opt_(options), corrector_(model, std::move(scale), options) {}

void ArcLengthStepper::note(const std::string& line) {
  for (auto* o : observers_) o->note(line);
}

bool ArcLengthStepper::atTarget() const {
  // At the target (a step lands on it to 1e-9, relative) or past it.
  if (lambda_ >= opt_.targetLoadFactor * (1 - 1e-9)) return true;
  return opt_.targetMonitor > 0 && std::abs(monitors_.back()) >= opt_.targetMonitor * (1 - 1e-9);
}

NewtonResult ArcLengthStepper::stepOnce(int step, double& ds, int& cut, Vec& x, double& l) {
  NewtonResult r;
  for (;;) {
    // Predictor: (xConverged, lambda) + ds (tx, tl).
    Thyra::V_StVpStV(Teuchos::ptrFromRef(x), 1.0, *xConverged_, ds, *tx_);
    l = lambda_ + ds * tl_;
    Thyra::copy(x, xPred_.ptr());
    const double lPred = l;
    r = corrector_.correct(x, l, *tx_, tl_, w_, *xPred_, lPred);
    if (r.converged || cut >= opt_.maxCutbacks) break;
    if (0.5 * ds < opt_.minArcLength) {
      r.failure += "; the arc length would fall below '" + opt_.keyPrefix + "Min Arc Length'";
      break;
    }
    ++cut;
    ds *= 0.5;
    std::ostringstream s;
    s << "  step " << step << ": " << r.failure << "; cutting the arc length to " << ds;
    note(s.str());
  }
  return r;
}

// Land on the target rather than pass it: when a converged step crosses the target load factor
// (or monitored value), shorten its arc by secant iteration on the arc length and redo it from
// the same start, until its end is within 1e-9 (relative) of the target. If a shortened step
// fails to converge, the crossing step is kept.
void ArcLengthStepper::landOnTarget(int step, double& ds, Vec& x, double& l, NewtonResult& r) {
  bool byLoad = false;  // the load factor crosses its target (else the monitor)
  double g0 = 0, g1 = 0, target = 0;
  if (lambda_ < opt_.targetLoadFactor && l > opt_.targetLoadFactor) {
    g0 = lambda_, g1 = l, target = opt_.targetLoadFactor, byLoad = true;
  } else if (opt_.targetMonitor > 0 && std::abs(monitors_.back()) < opt_.targetMonitor) {
    const double mn = std::abs(monitorAt(x));
    if (!(mn > opt_.targetMonitor)) return;
    g0 = std::abs(monitors_.back()), g1 = mn, target = opt_.targetMonitor;
  } else {
    return;
  }
  auto xCross = x.clone_v();
  const double lCross = l, dsCross = ds;
  const NewtonResult rCross = r;
  double sA = 0, gA = g0, sB = ds, gB = g1;
  bool landed = false;
  for (int k = 0; k < 10 && !landed; ++k) {
    const double sNew = sB + (target - gB) * (sB - sA) / (gB - gA);
    if (!(sNew > 0) || !(sNew < dsCross)) break;
    ds = sNew;
    Thyra::V_StVpStV(Teuchos::ptrFromRef(x), 1.0, *xConverged_, ds, *tx_);
    l = lambda_ + ds * tl_;
    Thyra::copy(x, xPred_.ptr());
    r = corrector_.correct(x, l, *tx_, tl_, w_, *xPred_, l);
    if (!r.converged) break;
    const double gNew = byLoad ? l : std::abs(monitorAt(x));
    sA = sB, gA = gB, sB = ds, gB = gNew;
    landed = std::abs(gNew - target) <= 1e-9 * std::abs(target);
  }
  if (!r.converged || !landed) {  // keep the crossing step
    Thyra::copy(*xCross, Teuchos::ptrFromRef(x));
    l = lCross, ds = dsCross, r = rCross;
  } else {
    std::ostringstream s;
    s << "  step " << step << ": arc shortened from " << dsCross << " to " << ds << " to land on the target";
    note(s.str());
  }
}

void ArcLengthStepper::accept(StepRecord& rec, const NewtonResult& r, const Vec& x, double l, double tStep) {
  // Secant direction for the next predictor: it continues through limit points, where the load
  // factor turns back, without any sign decision.
  Thyra::V_VmV(tx_.ptr(), x, *xConverged_);
  tl_ = l - lambda_;
  const double n = std::sqrt(w_ * Thyra::dot(*tx_, *tx_) + tl_ * tl_);
  Thyra::scale(1.0 / n, tx_.ptr());
  tl_ /= n;
  Thyra::copy(x, xConverged_.ptr());
  lambda_ = l;
  model_->setLoadFactor(lambda_);
  if (stability_) rec.negativePivots = stability_(*xConverged_);
  rec.elapsed = now() - tStep;  // the stability count included, as observers report it
  path_.push_back(lambda_);
  monitors_.push_back(monitorAt(*xConverged_));
  lambdas_.push_back(lambda_);
  const std::size_t k = lambdas_.size();
  if (k >= 3 && lambdas_[k - 2] > lambdas_[k - 3] && lambdas_[k - 1] < lambdas_[k - 2]) {
    limitPoints_.push_back({rec.step - 1, lambdas_[k - 2], monitors_[k - 2]});
    std::ostringstream s;
    s << std::setprecision(10) << "  limit point passed: the load factor peaked at " << lambdas_[k - 2] << " (step "
      << rec.step - 1 << ", " << opt_.monitorName << " " << monitors_[k - 2] << ") and now decreases";
    note(s.str());
  }
  if (commit_) commit_(*xConverged_);  // the history of the accepted step, before anyone sees it
  const StepInfo info{rec, r, *xConverged_, lambda_};
  for (auto* o : observers_) o->accepted(info);
}

bool ArcLengthStepper::run(const Vec& x0, double lambda0) {
  records_.clear(), path_.clear(), monitors_.clear(), lambdas_.clear(), limitPoints_.clear(), failure_.clear();
  xConverged_ = x0.clone_v();
  lambda_ = lambda0;
  tx_ = x0.clone_v();
  const std::string why = corrector_.tangent(*xConverged_, lambda_, *tx_);
  if (!why.empty()) {
    failure_ = "the initial tangent of the path could not be computed: " + why;
    model_->setLoadFactor(lambda_);
    return false;
  }
  const double zn = Thyra::norm_2(*tx_);
  w_ = zn > 0 ? 1.0 / (zn * zn) : 1.0;
  tl_ = 1.0;
  const double n0 = std::sqrt(w_ * Thyra::dot(*tx_, *tx_) + tl_ * tl_);
  Thyra::scale(1.0 / n0, tx_.ptr());
  tl_ /= n0;
  auto x = x0.clone_v();
  xPred_ = x0.clone_v();
  double ds = opt_.initialArcLength;
  monitors_.push_back(monitorAt(*xConverged_));
  lambdas_.push_back(lambda_);
  for (int step = 1;; ++step) {
    if (atTarget()) return true;
    if (step > opt_.maxSteps) {
      std::ostringstream s;
      s << "reached '" << opt_.keyPrefix << "Max Steps' = " << opt_.maxSteps << " at load factor " << lambda_
        << " before the target (load factor " << opt_.targetLoadFactor;
      if (opt_.targetMonitor > 0) s << " or " << opt_.monitorName << " " << opt_.targetMonitor;
      s << ")";
      failure_ = s.str();
      return false;
    }
    const double tStep = now();
    const LinearSolveCounts before = corrector_.totalLinear();
    const long long correctorsBefore = corrector_.totalCorrectorIterations();
    StepRecord rec;
    rec.step = step;
    int cut = 0;
    double l = lambda_;
    NewtonResult r = stepOnce(step, ds, cut, *x, l);
    if (r.converged) landOnTarget(step, ds, *x, l, r);
    rec.cutbacks = cut;
    rec.loadFactor = l;
    rec.arcLength = ds;
    rec.newtonIterations = r.iterations;
    rec.linearSolves = corrector_.totalLinear().solves - before.solves;
    rec.krylovIterations = corrector_.totalLinear().krylovIterations - before.krylovIterations;
    rec.linearFailures = corrector_.totalLinear().failures - before.failures;
    rec.newtonIterationsAll = corrector_.totalCorrectorIterations() - correctorsBefore;
    rec.residuals = r.residuals;
    rec.reactionNormalised = r.reactionNormalised;
    rec.atRoundoffFloor = r.atRoundoffFloor;
    rec.floor = r.floorNormalised;
    if (!r.converged) {
      rec.elapsed = now() - tStep;
      records_.push_back(rec);
      std::ostringstream s;
      s << "arc-length step " << step << " (from load factor " << lambda_ << ") failed after " << cut
        << " cut-back(s): " << r.failure;
      failure_ = s.str();
      model_->setLoadFactor(lambda_);
      return false;
    }
    records_.push_back(rec);
    accept(records_.back(), r, *x, l, tStep);
    if (r.iterations <= opt_.easyIterations) ds = std::min(opt_.maxArcLength, 1.5 * ds);
  }
}

}  // namespace perinox

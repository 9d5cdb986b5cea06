// Load stepping (see LoadStepper.hpp). Thyra only: no peridynamics, no NOX headers.
#include "perinox/stepping/LoadStepper.hpp"

#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Thyra_DetachedVectorView.hpp>
#include <Thyra_LinearOpWithSolveFactoryHelpers.hpp>
#include <Thyra_MultiVectorBase.hpp>
#include <Thyra_PreconditionerBase.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace perinox {

using MEB = Thyra::ModelEvaluatorBase;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Whether the step's stall break broke something (bonds, or detached particles).
bool stallBroke(const StepRecord& rec) { return rec.stallBrokenBonds > 0 || !rec.detached.empty(); }

std::string shown(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// LoadFactorModel
// ---------------------------------------------------------------------------------------------

LoadFactorModel::LoadFactorModel(const Teuchos::RCP<Thyra::ModelEvaluator<double>>& model) {
  if (model.is_null()) throw std::invalid_argument("LoadFactorModel: no model given");
  if (model->Np() < 1 || model->get_p_space(0)->dim() != 1)
    throw std::invalid_argument("LoadFactorModel: the model needs a parameter p(0) of one value, the load factor (it has " +
                                std::to_string(model->Np()) + " parameter vectors)");
  initialize(model);
}

void LoadFactorModel::setLoadFactor(double lambda) {
  lambda_ = lambda;
  if (listener_) listener_(loadAt(lambda));
}

double loadOnPath(const std::vector<double>& knots, double s) {
  if (knots.empty()) return s;
  const int n = static_cast<int>(knots.size());
  const double t = s * n;
  const double r = std::round(t);
  auto knot = [&](int k) { return k <= 0 ? 0.0 : knots[std::min(k, n) - 1]; };
  if (std::abs(t - r) <= 1e-9) return knot(static_cast<int>(r));  // a corner: exactly its value
  const int k = std::clamp(static_cast<int>(std::floor(t)), 0, n - 1);
  return knot(k) + (t - k) * (knot(k + 1) - knot(k));
}

double LoadFactorModel::pathSlope(double s) const {
  if (path_.empty()) return 1.0;
  const int n = static_cast<int>(path_.size());
  const int k = std::clamp(static_cast<int>(std::floor(s * n + 1e-9)), 0, n - 1);
  return n * (path_[k] - (k == 0 ? 0.0 : path_[k - 1]));
}

std::vector<double> LoadFactorModel::pathStops(int segments) {
  std::vector<double> s;
  for (int k = 1; k < segments; ++k) s.push_back(static_cast<double>(k) / segments);
  return s;
}

void LoadFactorModel::evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const {
  MEB::InArgs<double> args = getUnderlyingModel()->createInArgs();
  args.setArgs(in, true);
  if (args.get_p(0).is_null()) {
    auto p = Thyra::createMember(getUnderlyingModel()->get_p_space(0));
    Thyra::set_ele(0, loadAt(lambda_), p.ptr());
    args.set_p(0, p);
  }
  getUnderlyingModel()->evalModel(args, out);
}

void LoadFactorModel::loadDerivative(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& dfdl) const {
  const auto& m = *getUnderlyingModel();
  auto in = m.createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto p = Thyra::createMember(m.get_p_space(0));
  auto out = m.createOutArgs();
  const double load = loadAt(lambda_);
  if (out.supports(MEB::OUT_ARG_DfDp, 0).supports(MEB::DERIV_MV_BY_COL)) {
    Thyra::set_ele(0, load, p.ptr());
    in.set_p(0, p);
    auto mv = Thyra::createMembers(m.get_f_space(), 1);
    out.set_DfDp(0, MEB::Derivative<double>(mv, MEB::DERIV_MV_BY_COL));
    m.evalModel(in, out);
    Thyra::copy(*mv->col(0), Teuchos::ptrFromRef(dfdl));
  } else {
    const double h = 1e-6 * std::max(1.0, std::abs(load));
    auto fm = dfdl.clone_v();
    for (const double sign : {1.0, -1.0}) {
      Thyra::set_ele(0, load + sign * h, p.ptr());
      in.set_p(0, p);
      auto o = m.createOutArgs();
      o.set_f(sign > 0 ? Teuchos::rcpFromRef(dfdl) : fm);
      m.evalModel(in, o);
    }
    Thyra::Vp_StV(Teuchos::ptrFromRef(dfdl), -1.0, *fm);
    Thyra::scale(0.5 / h, Teuchos::ptrFromRef(dfdl));
  }
  if (!path_.empty()) Thyra::scale(pathSlope(lambda_), Teuchos::ptrFromRef(dfdl));  // df/ds
  if (listener_) listener_(load);  // the model evaluated at other load factors
}

// ---------------------------------------------------------------------------------------------
// Options
// ---------------------------------------------------------------------------------------------

Teuchos::RCP<const Teuchos::ParameterList> LoadStepperOptions::validParameters() {
  static const auto valid = [] {
    auto l = Teuchos::rcp(new Teuchos::ParameterList("Load Stepping"));
    const LoadStepperOptions d;
    l->set("Load Steps", d.loadSteps, "equal load increments to load factor 1 (1 to 1000000)");
    l->set("Max Cutbacks", d.maxCutbacks, "halvings of a failing load step before the run stops (0 to 60)");
    l->set("Min Increment", d.minIncrement, "smallest load increment, as a fraction of the nominal one (0, 1]");
    l->set("Max Total Steps", d.maxTotalSteps, "steps allowed in all, counting reduced ones (0: 20 x Load Steps)");
    l->set("Adaptive Steps", d.adaptive, "grow the increment by 1.5 after steps of at most 'Easy Iterations' iterations");
    l->set("Easy Iterations", d.easyIterations, "adaptive stepping: an easy step needs at most this many iterations");
    l->set("Max Increment", d.maxIncrement, "adaptive stepping: the largest load increment (0, 1]");
    l->set("Predictor", d.predictor, "start each step from the last increment extrapolated");
    l->set("Tangent Predictor", d.tangentPredictor,
           "first step: move with the load along dx/dlambda (J dx/dlambda = -df/dlambda) before Newton");
    l->set("Limit Load Ratio", d.limitLoadRatio,
           "without damage: a converged step whose displacement per unit load exceeds this multiple of the first step's has "
           "jumped past a limit load; it is cut back, and a run that cannot go on stops there, naming the limit load (0: no check)");
    return l;
  }();
  return valid;
}

LoadStepperOptions LoadStepperOptions::fromParameterList(const Teuchos::ParameterList& list, const std::string& where) {
  const auto valid = validParameters();
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string& name = list.name(it);
    if (!valid->isParameter(name))
      throw std::invalid_argument(where + ": unknown load-stepping key '" + name + "' (known: Load Steps, Max Cutbacks, Min "
                                  "Increment, Max Total Steps, Adaptive Steps, Easy Iterations, Max Increment, Predictor, "
                                  "Tangent Predictor, Limit Load Ratio)");
    if (list.entry(it).getAny(false).type() != valid->getEntry(name).getAny(false).type())
      throw std::invalid_argument(where + ": '" + name + "' must be of type " + valid->getEntry(name).getAny(false).typeName());
  }
  LoadStepperOptions o;
  Teuchos::ParameterList l(list);  // get with a default is not const
  o.loadSteps = l.get("Load Steps", o.loadSteps);
  o.maxCutbacks = l.get("Max Cutbacks", o.maxCutbacks);
  o.minIncrement = l.get("Min Increment", o.minIncrement);
  o.maxTotalSteps = l.get("Max Total Steps", o.maxTotalSteps);
  o.adaptive = l.get("Adaptive Steps", o.adaptive);
  o.easyIterations = l.get("Easy Iterations", o.easyIterations);
  o.maxIncrement = l.get("Max Increment", o.maxIncrement);
  o.predictor = l.get("Predictor", o.predictor);
  o.tangentPredictor = l.get("Tangent Predictor", o.tangentPredictor);
  o.limitLoadRatio = l.get("Limit Load Ratio", o.limitLoadRatio);
  auto bad = [&](const char* key, const std::string& what) {
    throw std::invalid_argument(where + ": '" + key + "' " + what);
  };
  if (o.loadSteps < 1 || o.loadSteps > 1000000) bad("Load Steps", "must be between 1 and 1000000, not " + std::to_string(o.loadSteps));
  if (o.maxCutbacks < 0 || o.maxCutbacks > 60) bad("Max Cutbacks", "must be between 0 and 60");
  if (!(o.minIncrement > 0 && o.minIncrement <= 1)) bad("Min Increment", "must lie in (0, 1], not " + shown(o.minIncrement));
  if (o.maxTotalSteps < 0) bad("Max Total Steps", "must be 0 (20 x Load Steps) or positive");
  if (o.easyIterations < 0) bad("Easy Iterations", "must be >= 0");
  if (!(o.maxIncrement > 0 && o.maxIncrement <= 1)) bad("Max Increment", "must lie in (0, 1], not " + shown(o.maxIncrement));
  if (!(o.limitLoadRatio == 0 || (o.limitLoadRatio > 1 && o.limitLoadRatio <= 1e12)))
    bad("Limit Load Ratio", "must be 0 (no check) or lie in (1, 1e12], not " + shown(o.limitLoadRatio));
  if (o.maxTotalSteps == 0) o.maxTotalSteps = static_cast<int>(std::min<long long>(20LL * o.loadSteps, 2000000000LL));
  return o;
}

// ---------------------------------------------------------------------------------------------
// LoadStepper
// ---------------------------------------------------------------------------------------------

std::string DamagePolicy::describeStep(const StepRecord& rec) const {
  std::string s = "    damage: " + std::to_string(rec.brokenBonds) + " bond(s) broken, " + std::to_string(rec.breakRounds) +
                  " re-equilibration(s), " + std::to_string(rec.detached.size()) + " particle(s) detached";
  if (rec.fragmentParticles > 0)
    s += " (" + std::to_string(rec.fragmentParticles) + " in free-floating fragments: frozen where they broke off)";
  return s;
}

LoadStepper::LoadStepper(Teuchos::RCP<LoadFactorModel> model, std::function<NewtonResult(Thyra::VectorBase<double>&)> solve,
                         const LoadStepperOptions& options)
    : model_(std::move(model)), solve_(std::move(solve)), reequilibrate_(solve_), options_(options) {
  if (options_.maxTotalSteps == 0) options_.maxTotalSteps = 20 * options_.loadSteps;
  xConverged_ = Thyra::createMember(model_->get_x_space());
  Thyra::assign(xConverged_.ptr(), 0.0);
  xPrevious_ = xConverged_->clone_v();
  state_.increment = 1.0 / options_.loadSteps;
}

void LoadStepper::resume(const StepperState& state, std::vector<StepRecord> records, std::vector<double> path,
                         const Thyra::VectorBase<double>& x, const Thyra::VectorBase<double>& xPrevious) {
  state_ = state;
  records_ = std::move(records);
  path_ = std::move(path);
  Thyra::copy(x, xConverged_.ptr());
  Thyra::copy(xPrevious, xPrevious_.ptr());
  setLoadFactor(state_.loadFactor);
}

void LoadStepper::note(const std::string& line) {
  for (auto* o : observers_) o->note(line);
}

void LoadStepper::setLoadFactor(double lambda) { model_->setLoadFactor(lambda); }

NewtonResult LoadStepper::counted(const std::function<NewtonResult(Thyra::VectorBase<double>&)>& solve,
                                  Thyra::VectorBase<double>& x) {
  NewtonResult r = solve(x);
  stepWork_ += r.work;
  stepLinear_.solves += r.linear.solves;
  stepLinear_.krylovIterations += r.linear.krylovIterations;
  stepLinear_.failures += r.linear.failures;
  return r;
}

// Re-equilibration after a damage break, at load factor lam. The solve from the state before the
// break first. When the break releases so much that it cannot reach the new equilibrium from
// there (an inverted F on the way, stagnation), the damaged body is reloaded in growing sub-steps
// (the softening law depends only on the current stretch, so the equilibrium with a given set of
// intact bonds does not depend on the path): from the state scaled to 0.9 of the load (a
// snap-back usually lowers it by a few per cent), else 0.7, else half of it, else from zero. If the
// damaged body cannot carry lam (the reload stalls at a limit point: the snap-back of a running
// crack under displacement control), the state at the highest load reached is returned, that load
// found to the policy's reload tolerance, and lam lowered to it; the stepping resumes from there
// (an event-by-event trace of the snap-back). The search keeps the bracket [mu, hi): mu the
// highest load fraction reached, hi the lowest that failed from a state below it. A sub-step never
// tries hi or above again (it would fail again, at several times the cost of a converged one), and
// the search ends once hi - mu is within the tolerance.
NewtonResult LoadStepper::reequilibrate(Thyra::VectorBase<double>& xs, double& lam, StepRecord& rec) {
  auto run = [&](Thyra::VectorBase<double>& x) { return counted(reequilibrate_, x); };
  auto x0 = xs.clone_v();
  NewtonResult first = run(xs);
  if (first.converged || !damage_) return first;
  int iters = first.iterations;
  double bestMu = 0;
  auto xBest = xs.clone_v();
  NewtonResult bestR;
  for (double start : {0.9, 0.7, 0.5, 0.0}) {
    Thyra::V_StV(Teuchos::ptrFromRef(xs), start, *x0);
    double mu = start, inc = 0.25 * (1.0 - start);
    NewtonResult r;
    r.converged = true;  // zero load with zero displacement is an equilibrium
    if (start > 0) {
      setLoadFactor(start * lam);
      r = run(xs);
      iters += r.iterations;
      ++rec.reloadSteps;
      if (!r.converged) continue;
    }
    auto xc = xs.clone_v();
    NewtonResult rc = r;
    double hi = 2.0;  // the lowest fraction that failed (none yet)
    while (mu < 1.0 - 1e-12) {
      const double t = std::min({1.0, mu + inc, 0.5 * (mu + hi)});
      setLoadFactor(t * lam);
      Thyra::copy(*xc, Teuchos::ptrFromRef(xs));
      r = run(xs);
      iters += r.iterations;
      ++rec.reloadSteps;
      if (r.converged) {
        mu = t;
        Thyra::copy(xs, xc.ptr());
        rc = r;
        inc *= 1.5;
      } else {
        hi = t;
        inc = 0.5 * (t - mu);  // halve the sub-step that failed (not the grown one t clamped)
      }
      if (hi - mu <= damage_->reloadTolerance) break;  // the limit load lies in [mu, hi)
    }
    if (mu > bestMu) {
      bestMu = mu;
      Thyra::copy(*xc, xBest.ptr());
      bestR = rc;
    }
    break;  // the sub-stepping ran: its limit is the damaged body's
  }
  if (!(bestMu > 0)) {
    setLoadFactor(lam);
    Thyra::copy(*x0, Teuchos::ptrFromRef(xs));
    first.iterations = iters;
    first.failure += " (reloading the damaged body from 0.9 and half of the load and from zero failed too)";
    return first;
  }
  Thyra::copy(*xBest, Teuchos::ptrFromRef(xs));
  if (bestMu < 1.0) {
    std::ostringstream s;
    s << "    the damaged body cannot carry load factor " << lam << " (snap-back): equilibrium at " << bestMu * lam;
    note(s.str());
    lam *= bestMu;
    state_.atLimit = true;
  }
  setLoadFactor(lam);
  bestR.iterations = iters;
  return bestR;
}

// One load step after another until the load factor reaches 1 or a step fails for good: each
// step is solved with cut-backs (solveWithCutbacks), a step that cannot be converged may be
// rescued by a stall break (breakAtStall), a converged one is broken and re-equilibrated by the
// damage policy (breakAfterConvergence), vetted by the observers and accepted (accept).
bool LoadStepper::run() {
  auto x = xConverged_->clone_v();
  Teuchos::RCP<Thyra::VectorBase<double>> firstTangent;
  failure_.clear();
  while (state_.loadFactor < 1.0 - 1e-12) {
    if (state_.step >= options_.maxTotalSteps) {
      std::ostringstream s;
      s << "reached '" << options_.keyPrefix << "Max Total Steps' = " << options_.maxTotalSteps << " at load factor "
        << state_.loadFactor << " (the load increment had fallen to " << state_.increment
        << "): the solver can no longer advance the load";
      failure_ = s.str();
      break;
    }
    ++state_.step;
    const double tStep = now();
    stepWork_ = 0;
    stepLinear_ = LinearSolveCounts();
    StepRecord rec;
    rec.step = state_.step;
    const double stepIncrement = state_.increment;
    // The first step has no increment to extrapolate. With prescribed motion, starting Newton from
    // the unloaded body puts the whole prescribed jump into the bonds next to the loaded
    // particles; the tangent predictor moves the body with the load first: one linear solve.
    // No free unknown (every displacement prescribed): nothing to predict or solve.
    if (options_.predictor && options_.tangentPredictor && state_.lastIncrement == 0 && state_.step == 1 &&
        xConverged_->space()->dim() > 0)
      firstTangent = firstStepTangent();
    int cut = 0;
    NewtonResult nr;
    const bool atLimit = state_.atLimit;
    state_.atLimit = false;
    if (atLimit && damage_ && damage_->breakOnStalls && damage_->breakAtSnapBackLimit) {
      // The body is at its limit load: any larger load fails (the next step's cut-backs would find
      // that down to Min Increment first), so break at once.
      nr.failure = "at the damaged body's limit load (the snap-back's reload found it)";
      breakAtStall(*x, rec, nr, stepIncrement);
      rec.stallAtLimit = stallBroke(rec);
    }
    if (!rec.stallAtLimit) {
      nr = solveWithCutbacks(*x, rec, cut, firstTangent.get());
      if (!nr.converged && damage_ && damage_->breakOnStalls) {
        breakAtStall(*x, rec, nr, stepIncrement);
        if (!nr.converged && !stallBroke(rec)) retryWithoutPredictor(*x, rec, nr, cut, stepIncrement);
      }
    }
    rec.cutbacks = cut;
    rec.loadFactor = nr.converged ? state_.loadFactor : std::min(1.0, state_.loadFactor + state_.increment);
    rec.newtonIterations = nr.iterations;
    rec.reactionNormalised = nr.reactionNormalised;
    rec.atRoundoffFloor = nr.atRoundoffFloor;
    rec.floor = nr.floorNormalised;
    rec.elapsed = now() - tStep;
    if (!nr.converged) rec.residuals = nr.residuals;
    account(rec);
    records_.push_back(rec);
    if (!nr.converged && rec.pastLimit) {
      // The last attempt converged, but only far away: the body gives way at the last load it
      // held. That is the answer of a load-controlled run past its limit load.
      limitLoad_ = model_->loadAt(state_.loadFactor);
      std::ostringstream s;
      s << "reached a limit load at load factor " << limitLoad_ << " (the last converged step): a step of "
        << std::abs(model_->loadAt(std::min(1.0, state_.loadFactor + state_.increment)) - limitLoad_) << " more, after " << cut
        << " cut-back(s), " << nr.failure << "; Solver/Continuation = Arc Length follows the response past a limit load";
      failure_ = s.str();
      setLoadFactor(state_.loadFactor);
      break;
    }
    if (!nr.converged) {
      std::ostringstream s;
      s << "load step " << state_.step << " (load factor " << rec.loadFactor << ") failed after " << cut
        << " cut-back(s): " << nr.failure;
      failure_ = s.str();
      setLoadFactor(state_.loadFactor);
      break;
    }
    if (damage_ && !breakAfterConvergence(*x, rec, nr, tStep)) break;
    const double previous = records_.size() > 1 ? records_[records_.size() - 2].loadFactor : 0.0;
    if (!vetted(rec, nr, *x, previous)) break;
    accept(*x, rec, nr, previous);
  }
  setLoadFactor(state_.loadFactor);  // the state kept is the last converged one
  return failure_.empty();
}

void LoadStepper::account(StepRecord& rec) const {
  rec.newtonIterationsAll = stepWork_;
  rec.linearSolves = stepLinear_.solves;
  rec.krylovIterations = stepLinear_.krylovIterations;
  rec.linearFailures = stepLinear_.failures;
}

Teuchos::RCP<Thyra::VectorBase<double>> LoadStepper::firstStepTangent() {
  auto z = xConverged_->clone_v();
  const std::string why = tangent(*xConverged_, *z);
  if (why.empty()) return z;
  note("  step 1: no tangent predictor (" + why + "); Newton starts from the unloaded body");
  return Teuchos::null;
}

// The step's solve from the predicted state; a failed solve is retried with half the increment,
// up to Max Cutbacks times and down to Min Increment. On success the load factor is the target.
NewtonResult LoadStepper::solveWithCutbacks(Thyra::VectorBase<double>& x, StepRecord& rec, int& cut,
                                            const Thyra::VectorBase<double>* firstTangent) {
  double& lambda = state_.loadFactor;
  double& increment = state_.increment;
  const double lastIncrement = state_.lastIncrement;
  NewtonResult nr;
  for (;;) {
    double target = std::min(1.0, lambda + increment);
    bool afterStop = false;  // the last converged state is a corner of the load path
    for (double s : options_.stops) {
      if (std::abs(s - lambda) <= 1e-12) afterStop = true;
      if (s > lambda + 1e-12 && s < target - 1e-12) {
        target = s;  // land on the corner
        break;
      }
    }
    setLoadFactor(target);
    Thyra::copy(*xConverged_, Teuchos::ptrFromRef(x));
    if (options_.predictor && lastIncrement > 0 && !afterStop) {
      // x = xConverged + (target - lambda) / lastIncrement * (xConverged - xPrevious)
      const double a = (target - lambda) / lastIncrement;
      Thyra::V_StVpStV(Teuchos::ptrFromRef(x), 1.0 + a, *xConverged_, -a, *xPrevious_);
    } else if (firstTangent && state_.step == 1) {
      Thyra::Vp_StV(Teuchos::ptrFromRef(x), target - lambda, *firstTangent);
    }
    nr = counted(solve_, x);
    rec.residuals.insert(rec.residuals.end(), nr.residuals.begin(), nr.residuals.end());
    if (nr.converged) {
      const std::string past = pastLimitLoad(x, lambda, target);
      if (past.empty()) {
        lambda = target;
        return nr;
      }
      nr.converged = false;
      nr.failure = past;
      rec.pastLimit = true;
    } else {
      rec.pastLimit = false;
    }
    Thyra::copy(*xConverged_, Teuchos::ptrFromRef(x));
    if (cut >= options_.maxCutbacks) return nr;
    if (0.5 * increment < options_.minIncrement / options_.loadSteps) {
      nr.failure += "; the load increment would fall below '" + options_.keyPrefix + "Min Increment'";
      return nr;
    }
    ++cut;
    increment *= 0.5;
    rec.residuals.clear();
    std::ostringstream s;
    s << "  step " << state_.step << ": " << nr.failure << "; cutting the load increment to " << increment;
    note(s.str());
  }
}

// A step that cannot be converged even at the smallest increment (softening bonds snap back
// under displacement control: no equilibrium at a larger load with all of them intact): the
// damage policy breaks at the last converged state, re-equilibrate at the same load, go on.
// The step is recorded at the unchanged load factor.
void LoadStepper::breakAtStall(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, double stepIncrement) {
  if (state_.stallBreaks >= damage_->maxStallBreaks) {
    nr.failure += "; " + damage_->stallLimitReached();
    return;
  }
  Thyra::copy(*xConverged_, Teuchos::ptrFromRef(x));
  setLoadFactor(state_.loadFactor);
  const auto rep = damage_->breakOnStall(x, nr.failure);
  if (rep.brokenBonds == 0 && rep.detached.empty()) {
    nr.failure += "; " + damage_->nothingToBreak();
    return;
  }
  ++state_.stallBreaks;
  rec.stallBrokenBonds = rep.brokenBonds;
  rec.stallStretch = rep.maxStretch;
  rec.brokenBonds += rep.brokenBonds;
  rec.detached.insert(rec.detached.end(), rep.detached.begin(), rep.detached.end());
  rec.fragmentParticles += rep.fragmentParticles;
  note("  step " + std::to_string(state_.step) + ": " + nr.failure);
  if (!rep.note.empty()) note(rep.note);
  const std::string why = nr.failure;
  nr = reequilibrate(x, state_.loadFactor, rec);
  rec.residuals = nr.residuals;
  if (!nr.converged) nr.failure = "re-equilibration after the stall break (" + why + ") failed: " + nr.failure;
  state_.increment = stepIncrement;
}

// A damaged step that failed down to the smallest increment with nothing to break at a stall: the
// secant predictor may be what failed. When the last step broke bonds, its increment holds the
// jump they released; extrapolated, that jump opens the body again by as much, and Newton cannot
// come back from there at any increment (the 60 x 20 plate with a hole at load factor 0.282, where
// 16 bonds had broken in the step before). So the step is tried once more, from the last
// converged state as it is, with the step's first increment and its own cut-backs.
void LoadStepper::retryWithoutPredictor(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, int& cut,
                                        double stepIncrement) {
  if (!options_.predictor || !(state_.lastIncrement > 0)) return;
  note("  step " + std::to_string(state_.step) + ": " + nr.failure +
       "; trying the step again from the last converged state, without the predictor");
  const double lastIncrement = state_.lastIncrement;
  state_.lastIncrement = 0;
  state_.increment = stepIncrement;
  int again = 0;
  NewtonResult retry = solveWithCutbacks(x, rec, again, nullptr);
  cut += again;
  if (retry.converged) {
    nr = retry;
    return;
  }
  state_.lastIncrement = lastIncrement;
  nr.iterations += retry.iterations;
  nr.failure += "; without the predictor: " + retry.failure;
}

// Damage (seed 000, Fig. 8): nothing breaks inside the solve; after convergence, break what the
// criterion says, re-equilibrate at the same load, and repeat until nothing breaks. Only then
// does the load grow. False (failure_ set, the step's record updated) when that fails.
bool LoadStepper::breakAfterConvergence(Thyra::VectorBase<double>& x, StepRecord& rec, NewtonResult& nr, double tStep) {
  double& lambda = state_.loadFactor;
  for (;;) {
    const auto rep = damage_->breakAfterStep(x);
    rec.brokenBonds += rep.brokenBonds;
    rec.detached.insert(rec.detached.end(), rep.detached.begin(), rep.detached.end());
    rec.fragmentParticles += rep.fragmentParticles;
    if (rep.brokenBonds == 0 && rep.detached.empty()) break;
    if (rec.breakRounds >= damage_->maxBreakRounds) {
      nr.converged = false;
      nr.failure = "bonds were still breaking after " + std::to_string(rec.breakRounds) + " re-equilibrations";
      break;
    }
    ++rec.breakRounds;
    const NewtonResult re = reequilibrate(x, lambda, rec);
    rec.newtonIterations += re.iterations;
    rec.residuals.insert(rec.residuals.end(), re.residuals.begin(), re.residuals.end());
    if (!re.converged) {
      nr = re;
      nr.failure = "re-equilibration after breaking " + std::to_string(rep.brokenBonds) + " bond(s) failed: " + re.failure;
      break;
    }
  }
  if (!nr.converged) {
    account(rec);
    records_.back() = rec;
    failure_ = "load step " + std::to_string(state_.step) + " (load factor " + std::to_string(lambda) + "): " + nr.failure;
    return false;
  }
  rec.loadFactor = lambda;  // lowered if the damaged body could not carry the load
  rec.elapsed = now() - tStep;
  account(rec);
  records_.back() = rec;
  if (rec.brokenBonds > 0 || !rec.detached.empty()) note(damage_->describeStep(rec));
  return true;
}

// The observers' veto (a stability check): the run stops at the previous step's state.
bool LoadStepper::vetted(const StepRecord& rec, const NewtonResult& nr, const Thyra::VectorBase<double>& x, double previous) {
  const StepInfo info{rec, nr, x, model_->loadAt(state_.loadFactor)};
  std::string vetoed;
  for (auto* o : observers_)
    if (vetoed.empty()) vetoed = o->vet(info, model_->loadAt(previous));
  if (vetoed.empty()) return true;
  failure_ = vetoed;
  state_.loadFactor = previous;
  setLoadFactor(previous);
  return false;
}

// The step becomes the converged state; the increment grows back after easy steps.
double LoadStepper::compliance(const Thyra::VectorBase<double>& x, double from, double to) const {
  const double dLoad = std::abs(model_->loadAt(to) - model_->loadAt(from));
  if (!(dLoad > 0)) return 0.0;
  auto d = x.clone_v();
  Thyra::Vp_StV(d.ptr(), -1.0, *xConverged_);
  return Thyra::norm_2(*d) / dLoad;
}

std::string LoadStepper::pastLimitLoad(const Thyra::VectorBase<double>& x, double lambda, double target) const {
  const double ref = state_.initialCompliance;
  if (!checksLimitLoad() || !(ref > 0)) return "";
  const double c = compliance(x, lambda, target);
  if (c <= options_.limitLoadRatio * ref) return "";
  std::ostringstream s;
  s << "jumps to an equilibrium whose displacement per unit load is " << std::setprecision(3) << c / ref
    << " times the first step's (above '" << options_.keyPrefix << "Limit Load Ratio' = " << options_.limitLoadRatio << ")";
  return s.str();
}

void LoadStepper::accept(const Thyra::VectorBase<double>& x, const StepRecord& rec, const NewtonResult& nr, double previous) {
  // The first step that moves the load sets the limit-load check's reference (before x becomes
  // the converged state: the compliance is measured from the one before).
  if (checksLimitLoad() && state_.initialCompliance == 0) state_.initialCompliance = compliance(x, previous, state_.loadFactor);
  Thyra::copy(*xConverged_, xPrevious_.ptr());
  Thyra::copy(x, xConverged_.ptr());
  path_.push_back(state_.loadFactor);
  state_.lastIncrement = rec.loadFactor - previous;
  double& increment = state_.increment;
  const double nominal = 1.0 / options_.loadSteps;
  if (options_.adaptive) {
    if (nr.iterations <= options_.easyIterations) increment = std::min(options_.maxIncrement, 1.5 * increment);
  } else if (increment < nominal && nr.iterations <= 6) {
    increment = std::min(nominal, 2 * increment);
  }
  if (commit_) commit_(*xConverged_);  // the history of the accepted step, before anyone sees it
  const StepInfo info{rec, nr, *xConverged_, model_->loadAt(state_.loadFactor)};
  for (auto* o : observers_) o->accepted(info);
}

std::string LoadStepper::tangent(const Thyra::VectorBase<double>& x, Thyra::VectorBase<double>& z) {
  try {
    auto dfdl = x.clone_v();
    model_->loadDerivative(x, *dfdl);
    auto W = model_->create_W_op();
    auto in = model_->createInArgs();
    in.set_x(Teuchos::rcpFromRef(x));
    auto out = model_->createOutArgs();
    out.set_W_op(W);
    // A model that builds its own preconditioner (matrix-free W_op) gives it here as to Newton:
    // without it the Krylov solve of the tangent would run unpreconditioned.
    Teuchos::RCP<Thyra::PreconditionerBase<double>> prec;
    if (out.supports(Thyra::ModelEvaluatorBase::OUT_ARG_W_prec)) prec = model_->create_W_prec();
    if (!prec.is_null()) out.set_W_prec(prec);
    model_->evalModel(in, out);
    Teuchos::RCP<Thyra::LinearOpWithSolveBase<double>> lows;
    if (prec.is_null()) {
      lows = Thyra::linearOpWithSolve(*model_->get_W_factory(), W.getConst());
    } else {
      lows = model_->get_W_factory()->createOp();
      Thyra::initializePreconditionedOp<double>(*model_->get_W_factory(), W.getConst(), prec.getConst(), lows.ptr());
    }
    Thyra::scale(-1.0, dfdl.ptr());
    Thyra::assign(Teuchos::ptrFromRef(z), 0.0);
    Thyra::SolveCriteria<double> crit;
    crit.solveMeasureType = Thyra::SolveMeasureType(Thyra::SOLVE_MEASURE_NORM_RESIDUAL, Thyra::SOLVE_MEASURE_NORM_RHS);
    crit.requestedTol = options_.linearTolerance;
    const auto st = lows->solve(Thyra::NOTRANS, *dfdl, Teuchos::ptrFromRef(z), Teuchos::constPtr(crit));
    ++stepLinear_.solves;
    if (!st.extraParameters.is_null()) stepLinear_.krylovIterations += std::max(0, st.extraParameters->get("Iteration Count", 0));
    const bool known = st.achievedTol != Thyra::SolveStatus<double>::unknownTolerance();
    if (st.solveStatus == Thyra::SOLVE_STATUS_UNCONVERGED && !(known && st.achievedTol <= crit.requestedTol)) {
      ++stepLinear_.failures;
      return "tangent solve: the linear solver did not converge";
    }
  } catch (const std::exception& e) {
    return std::string("tangent solve failed: ") + e.what();
  }
  return "";
}

}  // namespace perinox

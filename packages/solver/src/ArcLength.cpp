// Pseudo-arc-length corrector with a bordering solve (see ArcLength.hpp). Thyra only: the
// linear solves go through the evaluator's Stratimikos factory, like NOX's.
#include "perinox/solver/ArcLength.hpp"

#include <Thyra_LinearOpWithSolveBase.hpp>
#include <Thyra_LinearOpWithSolveFactoryHelpers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/solver/NewtonSolver.hpp"

namespace perinox {

namespace {

using Vec = Thyra::VectorBase<double>;

struct Eval {
  Teuchos::RCP<Vec> f;
  Teuchos::RCP<Thyra::LinearOpBase<double>> W;
};

void evaluate(const PeridynamicEvaluator& ev, const Vec& x, Vec* f, Thyra::LinearOpBase<double>* W) {
  auto in = ev.createInArgs();
  in.set_x(Teuchos::rcpFromRef(x));
  auto out = ev.createOutArgs();
  if (f) out.set_f(Teuchos::rcpFromRef(*f));
  if (W) out.set_W_op(Teuchos::rcpFromRef(*W));
  ev.evalModel(in, out);
}

/// Solves A y = b (y starts at zero); returns false when the linear solver reports that it did
/// not converge (Belos: iteration limit or breakdown).
bool solve(const Thyra::LinearOpWithSolveBase<double>& A, const Vec& b, Vec& y, double tol, std::string& why,
           LinearSolveCounts& counts) {
  Thyra::assign(Teuchos::ptrFromRef(y), 0.0);
  Thyra::SolveCriteria<double> crit;
  crit.solveMeasureType = Thyra::SolveMeasureType(Thyra::SOLVE_MEASURE_NORM_RESIDUAL, Thyra::SOLVE_MEASURE_NORM_RHS);
  crit.requestedTol = tol;
  const auto st = A.solve(Thyra::NOTRANS, b, Teuchos::ptrFromRef(y), Teuchos::constPtr(crit));
  ++counts.solves;
  if (!st.extraParameters.is_null()) counts.krylovIterations += std::max(0, st.extraParameters->get("Iteration Count", 0));
  // Belos can report "unconverged" with an achieved residual far below the request (its
  // loss-of-accuracy check on 2 ranks, measured 1e-20 against 1e-12): the achieved value decides.
  const bool known = st.achievedTol != Thyra::SolveStatus<double>::unknownTolerance();
  if (st.solveStatus == Thyra::SOLVE_STATUS_UNCONVERGED && !(known && st.achievedTol <= tol)) {
    std::ostringstream s;
    s << "the linear solver did not converge (achieved relative residual "
      << (known ? st.achievedTol : NAN)
      << ", requested " << tol << ": Krylov iteration limit or breakdown)";
    why = s.str();
    ++counts.failures;
    return false;
  }
  return true;
}

}  // namespace

ArcLengthSolver::ArcLengthSolver(Teuchos::RCP<PeridynamicEvaluator> evaluator, const ArcLengthOptions& options)
    : ev_(std::move(evaluator)), opt_(options) {}

void ArcLengthSolver::loadDerivative(const Vec& x, double lambda, Vec& fl) const {
  ev_->setLoadFactor(lambda);
  ev_->loadDerivative(x, fl);
}

std::string ArcLengthSolver::tangent(const Vec& x, double lambda, Vec& z) const {
  try {
    auto fl = x.clone_v();
    loadDerivative(x, lambda, *fl);
    auto W = ev_->create_W_op();
    evaluate(*ev_, x, nullptr, W.get());
    auto lows = Thyra::linearOpWithSolve(*ev_->get_W_factory(), W.getConst());
    auto rhs = fl->clone_v();
    Thyra::scale(-1.0, rhs.ptr());
    std::string why;
    if (!solve(*lows, *rhs, z, opt_.linearTolerance, why, counts_)) return "tangent solve: " + why;
  } catch (const EvaluationError& e) {
    return std::string("model evaluation failed: ") + e.what();
  } catch (const std::exception& e) {
    return std::string("linear solver error in the tangent solve: ") + e.what();
  }
  return "";
}

ArcLengthResult ArcLengthSolver::correct(Vec& x, double& lambda, const Vec& tx, double tl, double w,
                                         const Vec& xPred, double lPred) const {
  ArcLengthResult r;
  const double floorAbs = opt_.floorFactor * ev_->roundoffScale();
  auto f = x.clone_v(), fl = x.clone_v(), a = x.clone_v(), b = x.clone_v(), d = x.clone_v();
  auto W = ev_->create_W_op();
  try {
    for (int it = 0;; ++it) {
      ev_->setLoadFactor(lambda);
      evaluate(*ev_, x, f.get(), W.get());
      const double normF = Thyra::norm_2(*f);
      double scale = ev_->externalForceNorm();
      r.reactionNormalised = false;
      if (!(scale > 0)) {
        scale = ev_->reactionNorm(x);
        r.reactionNormalised = true;
      }
      if (!(scale > 0)) scale = 1.0;
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
      loadDerivative(x, lambda, *fl);
      auto lows = Thyra::linearOpWithSolve(*ev_->get_W_factory(), W.getConst());
      Thyra::scale(-1.0, f.ptr());
      std::string why;
      bool okA = solve(*lows, *f, *a, opt_.linearTolerance, why, counts_);
      bool okB = okA && solve(*lows, *fl, *b, opt_.linearTolerance, why, counts_);
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
      // x += a - dl b
      Thyra::Vp_V(Teuchos::ptrFromRef(x), *a);
      Thyra::Vp_StV(Teuchos::ptrFromRef(x), -dl, *b);
      lambda += dl;
    }
  } catch (const EvaluationError& e) {
    r.failure = std::string("model evaluation failed: ") + e.what();
  } catch (const std::exception& e) {
    r.failure = linearSolverFailure(e);
  }
  if (!r.converged) r.iterations = std::max(r.iterations, static_cast<int>(r.residuals.size()) - 1);
  ev_->setLoadFactor(lambda);
  return r;
}

}  // namespace perinox

#include "perinox/solver/AdrSolver.hpp"

#include <Thyra_TpetraThyraWrappers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <cmath>
#include <sstream>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"

namespace perinox {

namespace {
using Node = TMap::node_type;
using TOE = Thyra::TpetraOperatorVectorExtraction<double, LO, GO, Node>;
}  // namespace

AdrResult solveAdr(PeridynamicEvaluator& ev, Thyra::VectorBase<double>& x, const AdrOptions& opt) {
  AdrResult res;
  auto space = ev.get_x_space();
  auto f = Thyra::createMember(space);
  auto eval = [&]() {
    auto in = ev.createInArgs();
    in.set_x(Teuchos::rcpFromRef(x));
    auto out = ev.createOutArgs();
    out.set_f(f);
    ev.evalModel(in, out);
  };
  eval();
  // Fictitious mass from the stiffness bound (stability of the central difference with dt = 1).
  auto A = ev.assembledJacobian(x);
  const size_t n = A->getNodeNumRows();
  std::vector<double> mass(n, 0.0);
  for (size_t r = 0; r < n; ++r) {
    Teuchos::ArrayView<const LO> cols;
    Teuchos::ArrayView<const double> vals;
    A->getLocalRowView(static_cast<LO>(r), cols, vals);
    double s = 0;
    for (double v : vals) s += std::abs(v);
    mass[r] = 0.25 * opt.massSafety * s;
    if (!(mass[r] > 0)) mass[r] = 1.0;
  }
  auto xt = TOE::getTpetraVector(Teuchos::rcpFromRef(x));
  auto ft = TOE::getTpetraVector(f);
  std::vector<double> v(n, 0.0), fPrev(n, 0.0), du(n, 0.0);
  const auto comm = ev.comm();
  auto globalNorm = [&](const std::vector<double>& a) {
    double s = 0, g = 0;
    for (double e : a) s += e * e;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, s, Teuchos::outArg(g));
    return std::sqrt(g);
  };
  const double N = static_cast<double>(ev.numFreeDofs());
  double e1first = -1, e2first = -1;
  for (long long it = 0; it < opt.maxIterations; ++it) {
    if (it > 0) eval();
    auto fd = ft->getData();   // f = f_int - f_ext; the out-of-balance force is -f
    auto xd = xt->getDataNonConst();
    // Damping from Rayleigh's quotient of the local diagonal stiffness.
    double num = 0, den = 0;
    if (it > 0) {
      for (size_t r = 0; r < n; ++r) {
        const double dv = v[r];
        if (dv != 0.0) {
          const double k = ((-fd[r]) / mass[r] - (-fPrev[r]) / mass[r]) / (-dv);
          num += xd[r] * k * xd[r];
        }
        den += xd[r] * xd[r];
      }
    }
    double sums[2] = {num, den}, g[2] = {0, 0};
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, 2, sums, g);
    const double c = (g[1] > 0 && g[0] > 0) ? 2.0 * std::sqrt(g[0] / g[1]) : 0.0;
    std::vector<double> L(n);
    for (size_t r = 0; r < n; ++r) {
      const double force = -fd[r];
      L[r] = force;
      const double vNew = it == 0 ? 0.5 * force / mass[r] : ((2.0 - c) * v[r] + 2.0 * force / mass[r]) / (2.0 + c);
      v[r] = vNew;
      du[r] = vNew;
      xd[r] += vNew;
      fPrev[r] = fd[r];
    }
    xd = Teuchos::null;
    fd = Teuchos::null;
    const double e1 = globalNorm(L) / N, e2 = globalNorm(du) / N;
    if (!std::isfinite(e1) || !std::isfinite(e2)) {
      res.failure = "dynamic relaxation produced a non-finite residual";
      res.iterations = it + 1;
      return res;
    }
    if (e1first < 0) {
      e1first = e1 > 0 ? e1 : 1.0;
      e2first = e2 > 0 ? e2 : 1.0;
    }
    res.e1 = e1 / e1first;
    res.e2 = e2 / e2first;
    res.iterations = it + 1;
    if (res.e1 < opt.tolerance && res.e2 < opt.tolerance) {
      res.converged = true;
      return res;
    }
  }
  std::ostringstream s;
  s << "dynamic relaxation did not reach e1, e2 < " << opt.tolerance << " in " << opt.maxIterations
    << " iterations (e1 = " << res.e1 << ", e2 = " << res.e2 << ")";
  res.failure = s.str();
  return res;
}

}  // namespace perinox

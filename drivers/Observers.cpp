// The driver's step observers (Observers.hpp).
#include "Observers.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace perinox {

double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string probeKey(const ProbeDef& probe) {
  return probe.quantity == "Reaction" ? "reaction" : probe.quantity == "Plastic Strain" ? "plastic_strain" : "displacement";
}

std::vector<std::string> probeComponents(const ProbeDef& probe, int dim) {
  if (probe.quantity == "Plastic Strain") return {"max", "mean"};
  std::vector<std::string> c;
  for (int k = 0; k < dim; ++k) c.push_back(std::string(1, "xyz"[k]));
  return c;
}

std::vector<double> probeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe,
                               const Thyra::VectorBase<double>& x, const std::vector<double>& uOwned,
                               const std::vector<ParticleOutput>* outs) {
  const int D = ev.problem().dim();
  if (probe.quantity == "Reaction") return ev.reactionOn(x, probe.particles);
  if (probe.quantity == "Plastic Strain") {
    // The committed equivalent plastic strain: its largest value and its mean over the region.
    std::vector<ParticleOutput> computed;
    if (!outs) outs = &(computed = ev.ownedOutputs(x));
    double mx = 0.0, sum[2] = {0.0, 0.0}, all[2] = {0.0, 0.0};
    for (int p : probe.particles)
      if (const int l = ev.ownedIndex(p); l >= 0) {
        mx = std::max(mx, (*outs)[l].eqps);
        sum[0] += (*outs)[l].eqps;
        sum[1] += 1;
      }
    double gmax = 0.0;
    Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_MAX, mx, Teuchos::outArg(gmax));
    Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, 2, sum, all);
    return {gmax, all[0] / all[1]};
  }
  std::vector<double> s(D + 1, 0.0), g(D + 1, 0.0);
  for (int p : probe.particles)
    if (const int l = ev.ownedIndex(p); l >= 0) {
      for (int c = 0; c < D; ++c) s[c] += uOwned[static_cast<std::size_t>(l) * D + c];
      s[D] += 1;
    }
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, D + 1, s.data(), g.data());
  std::vector<double> v(D);
  for (int c = 0; c < D; ++c) v[c] = g[c] / g[D];
  return v;
}

std::vector<double> referenceProbeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe, const ReferenceDef& ref) {
  const int D = ev.problem().dim();
  std::vector<double> s(D + 1, 0.0), g(D + 1, 0.0);
  for (int p : probe.particles)
    if (ev.ownedIndex(p) >= 0) {
      const Vec3& X = ev.problem().disc.X[ev.problem().index(p)];
      for (int c = 0; c < D; ++c) s[c] += ref.displacement(X, c);
      s[D] += 1;
    }
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, D + 1, s.data(), g.data());
  std::vector<double> v(D);
  for (int c = 0; c < D; ++c) v[c] = g[c] / g[D];
  return v;
}

/// e_u = sum_i |u_i - u_ref,i| / |u_ref,i| V_i / sum_i V_i over real particles with u_ref != 0.
double displacementError(const PeridynamicEvaluator& ev, const ReferenceDef& ref, const std::vector<double>& uOwned) {
  const auto& d = ev.problem().disc;
  const int D = ev.problem().dim();
  double s[2] = {0, 0}, g[2] = {0, 0};
  for (std::size_t l = 0; l < ev.ownedParticles().size(); ++l) {
    const int p = ev.problem().index(ev.ownedParticles()[l]);  // index in the discretisation
    if (d.fictitious[p]) continue;
    Eigen::VectorXd ur(D), u(D);
    for (int c = 0; c < D; ++c) {
      ur[c] = ref.displacement(d.X[p], c);
      u[c] = uOwned[l * D + c];
    }
    if (ur.stableNorm() <= 1e-14 * d.dx) continue;
    s[0] += (u - ur).stableNorm() / ur.stableNorm() * d.volume[p];  // stable: no overflow of the squares
    s[1] += d.volume[p];
  }
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, 2, s, g);
  return g[1] > 0 ? g[0] / g[1] : 0.0;
}

void ConsoleLines::accepted(const StepInfo& s) {
  if (!speak_) return;
  CoutFormat keep;
  const auto& nr = s.result;
  const auto& rec = s.record;
  std::cout << "step " << std::setw(3) << rec.step << "  load " << std::fixed << std::setprecision(4) << s.loadFactor
            << (adr_ ? "  adr " : "  newton ") << std::setw(2) << nr.iterations
            << (adr_ ? "  e1, e2 " : (nr.reactionNormalised ? "  |R|/|reaction| " : "  |R|/|f_ext| "))
            << std::scientific << std::setprecision(3)
            << (nr.residuals.empty() ? 0.0 : (adr_ ? nr.residuals.front() : nr.residuals.back())) << (adr_ ? ", " : "")
            << (adr_ ? std::to_string(nr.residuals.back()) : std::string())
            << (rec.krylovIterations > 0 ? "  krylov " + std::to_string(rec.krylovIterations) : std::string())
            << (rec.linearFailures > 0 ? "  unconverged linear solves " + std::to_string(rec.linearFailures) : std::string())
            << "  " << std::fixed << std::setprecision(2) << rec.elapsed << " s"
            << (nr.atRoundoffFloor ? "  (at the round-off floor)" : "") << std::endl;  // flushed: a log can be followed
}

std::string StabilityCheck::vet(const StepInfo& s, double previous) {
  const int neg = ev_.negativePivots(s.x);
  if (neg == 0) return "";
  std::ostringstream m;
  if (neg > 0)
    m << "loss of stability: the equilibrium found at load factor " << s.loadFactor << " is unstable (the tangent has "
      << neg << " negative pivot(s)): the path passed a bifurcation or limit point between load factors " << previous
      << " and " << s.loadFactor << "; the last stable state is written";
  else
    m << "stability check impossible at load factor " << s.loadFactor << ": the tangent is not symmetric or its LDL^T failed";
  return m.str();
}

void ArcConsole::accepted(const StepInfo& s) {
  if (!speak_) return;
  CoutFormat keep;
  const auto& rec = s.record;
  std::cout << "step " << std::setw(3) << rec.step << "  load " << std::fixed << std::setprecision(6) << s.loadFactor
            << "  arc " << std::scientific << std::setprecision(3) << rec.arcLength << "  corrector " << std::setw(2)
            << s.result.iterations << "  residual " << s.result.residuals.back()
            << (deflection_ ? "  deflection " + std::to_string(arc_.monitorHistory().back()) : std::string())
            << (rec.negativePivots >= 0 ? "  negative pivots " + std::to_string(rec.negativePivots) : "") << "  "
            << std::fixed << std::setprecision(2) << rec.elapsed << " s" << std::endl;
}

}  // namespace perinox

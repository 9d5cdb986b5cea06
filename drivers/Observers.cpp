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

std::vector<double> probeValue(const PeridynamicEvaluator& ev, const ProbeDef& probe,
                               const Thyra::VectorBase<double>& x, const std::vector<double>& uOwned) {
  const int D = ev.problem().dim();
  if (probe.quantity == "Reaction") return ev.reactionOn(x, probe.particles);
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

/// e_u = sum_i |u_i - u_ref,i| / |u_ref,i| V_i / sum_i V_i over real particles with u_ref != 0.
double displacementError(const PeridynamicEvaluator& ev, const ReferenceDef& ref, const std::vector<double>& uOwned) {
  const auto& d = ev.problem().disc;
  const int D = ev.problem().dim();
  double s[2] = {0, 0}, g[2] = {0, 0};
  for (std::size_t l = 0; l < ev.ownedParticles().size(); ++l) {
    const long long p = ev.ownedParticles()[l];
    if (d.fictitious[p]) continue;
    Eigen::VectorXd ur(D), u(D);
    for (int c = 0; c < D; ++c) {
      ur[c] = ref.displacement(d.X[p], c);
      u[c] = uOwned[l * D + c];
    }
    if (ur.norm() <= 1e-14 * d.dx) continue;
    s[0] += (u - ur).norm() / ur.norm() * d.volume[p];
    s[1] += d.volume[p];
  }
  Teuchos::reduceAll(*ev.comm(), Teuchos::REDUCE_SUM, 2, s, g);
  return g[1] > 0 ? g[0] / g[1] : 0.0;
}

}  // namespace perinox

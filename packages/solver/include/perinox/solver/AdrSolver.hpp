#pragma once
// Explicit adaptive dynamic relaxation (Kilic & Madenci 2010; seed 001, section 4): the
// baseline both seeds compare the implicit solver with. It needs only residuals (plus one
// assembled tangent at the start of each load step for the fictitious diagonal mass).
#include <Teuchos_RCP.hpp>
#include <Thyra_VectorBase.hpp>
#include <string>
#include <vector>

namespace perinox {

class PeridynamicEvaluator;

struct AdrOptions {
  double tolerance = 1e-6;      // both e1 and e2 below this (seed 001)
  long long maxIterations = 2000000;
  double massSafety = 1.0;      // multiplies the Gershgorin stiffness bound m_i = 1/4 sum_j |K_ij|
};

struct AdrResult {
  bool converged = false;
  long long iterations = 0;
  double e1 = 0, e2 = 0;
  std::string failure;
};

/// Relaxes x to static equilibrium at the evaluator's current load factor.
AdrResult solveAdr(PeridynamicEvaluator& ev, Thyra::VectorBase<double>& x, const AdrOptions& opt);

}  // namespace perinox

#pragma once
// Output for host programs that drive the evaluator themselves (examples/): the particle fields
// as VTU pieces with a PVTU index, and the probes in summary.json's layout, which
// tests/compare_runs.py compares with a driver run. The driver's own output (fields, CSV, plots,
// the output-folder policy) is in drivers/Simulation.cpp.
#include <Thyra_VectorBase.hpp>
#include <string>
#include <utility>
#include <vector>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"

namespace perinox {

/// A probe's history: load factor -> value (a displacement or a reaction, per component).
struct ProbeHistory {
  std::string name;
  std::string quantity = "displacement";  // "displacement" or "reaction" (compare_runs.py's keys)
  std::vector<std::pair<double, std::vector<double>>> values;
};

/// Writes dir/fields_<rank>.vtu (this rank's particles at their reference positions with the
/// displacement, the Cauchy stress and, with damage, the damage index) and, on rank 0,
/// dir/fields.pvtu; makes dir. Collective.
void writeParticleFields(const std::string& dir, const PeridynamicEvaluator& evaluator, const Thyra::VectorBase<double>& x);

/// Rank 0 writes file (its folder made) as {"ranks": N, <extra>, "probes": {name: [{"load_factor": l,
/// quantity: [...]}, ...]}} with 17 digits; extra is a JSON fragment such as "\"newton_iterations\": 4"
/// (or empty). Throws std::runtime_error if the file cannot be written.
void writeProbeSummary(const std::string& file, const Teuchos::Comm<int>& comm, const std::vector<ProbeHistory>& probes,
                       const std::string& extra = "");

}  // namespace perinox

#pragma once
// For host programs that drive the evaluator themselves (examples/): a main() with MPI, options
// and one-sentence errors; the particle fields as VTU pieces with a PVTU index, and the probes in
// summary.json's layout, which tests/compare_runs.py compares with a driver run. The driver's own output (fields, CSV, plots,
// the output-folder policy) is in drivers/Simulation.cpp.
#include <Teuchos_Comm.hpp>
#include <Thyra_VectorBase.hpp>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/Output.hpp"

namespace perinox {

/// A host program's options: "--key value" pairs, each key from the program's list.
using HostOptions = std::map<std::string, std::string>;

/// The body of a host program: it gets the world communicator and the options, returns the exit code.
using HostBody = std::function<int(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const HostOptions& options)>;

/// A host program's main(): starts MPI and Kokkos (Tpetra::ScopeGuard), reads "--key value" options
/// (the keys of defaults, which holds their default values) and runs body. An unknown key or a key
/// without a value prints the usage line on rank 0 and returns 2; an exception thrown by body
/// (perinox's are one sentence) is printed on rank 0 as "name: sentence" and returns 1.
int hostMain(int argc, char** argv, const std::string& name, HostOptions defaults, const HostBody& body);

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

/// The fields of the materials' history for a problem with a plastic material (none otherwise):
/// equivalent_plastic_strain and yielded (1 where the last committed step flowed), one value per
/// output. Both field writers (this one and the driver's) add them.
std::vector<PointField> historyFields(const ProblemSpec& problem, const std::vector<ParticleOutput>& outputs);

/// Rank 0 writes file (its folder made) as {"ranks": N, <extra>, "probes": {name: [{"load_factor": l,
/// quantity: [...]}, ...]}} with 17 digits; extra is a JSON fragment such as "\"newton_iterations\": 4"
/// (or empty). Throws std::runtime_error if the file cannot be written.
void writeProbeSummary(const std::string& file, const Teuchos::Comm<int>& comm, const std::vector<ProbeHistory>& probes,
                       const std::string& extra = "");

}  // namespace perinox

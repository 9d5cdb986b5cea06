// Output for host programs (see HostOutput.hpp).
#include "perinox/io/HostOutput.hpp"

#include <Teuchos_DefaultComm.hpp>
#include <Tpetra_Core.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <stdexcept>

#include "perinox/io/Output.hpp"

namespace perinox {

int hostMain(int argc, char** argv, const std::string& name, HostOptions options, const HostBody& body) {
  Tpetra::ScopeGuard mpi(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const bool root = comm->getRank() == 0;
  for (int i = 1; i < argc; i += 2) {
    const std::string key = std::string(argv[i]).rfind("--", 0) == 0 ? std::string(argv[i]).substr(2) : "";
    if (i + 1 == argc || !options.count(key)) {
      if (root) {
        std::cerr << "usage: " << name;
        for (const auto& [k, v] : options) std::cerr << " [--" << k << " VALUE (default " << (v.empty() ? "none" : v) << ")]";
        std::cerr << "\n";
      }
      return 2;
    }
    options[key] = argv[i + 1];
  }
  try {
    return body(comm, options);
  } catch (const std::exception& e) {
    if (root) std::cerr << name << ": " << e.what() << "\n";
    return 1;
  }
}

void writeParticleFields(const std::string& dir, const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x) {
  const auto& d = ev.problem().disc;
  const int D = ev.problem().dim();
  const int rank = ev.comm()->getRank(), ranks = ev.comm()->getSize();
  const auto u = ev.ownedDisplacements(x);
  const auto outs = ev.ownedOutputs(x);
  std::vector<Eigen::Vector3d> points;
  PointField displacement{"displacement", 3, {}}, stress{"cauchy_stress", 9, {}};
  for (std::size_t l = 0; l < ev.ownedParticles().size(); ++l) {
    const long long p = ev.ownedParticles()[l];
    points.push_back(d.X[ev.problem().index(p)]);
    for (int c = 0; c < 3; ++c) displacement.values.push_back(c < D ? u[l * D + c] : 0.0);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) stress.values.push_back(outs[l].cauchy(r, c));
  }
  std::vector<PointField> fields{displacement, stress};
  if (ev.problem().damage) fields.push_back({"damage", 1, ev.ownedDamage()});
  for (auto& f : historyFields(ev.problem(), outs)) fields.push_back(std::move(f));
  if (rank == 0) std::filesystem::create_directories(dir);
  ev.comm()->barrier();  // the folder exists before any rank writes into it
  writeVtu(dir + "/fields_" + std::to_string(rank) + ".vtu", points, fields);
  if (rank == 0) {
    std::vector<std::string> pieces;
    for (int r = 0; r < ranks; ++r) pieces.push_back("fields_" + std::to_string(r) + ".vtu");
    writePvtu(dir + "/fields.pvtu", pieces, fields);
  }
}

std::vector<PointField> historyFields(const ProblemSpec& problem, const std::vector<ParticleOutput>& outputs) {
  if (!problem.plastic()) return {};
  PointField eqps{"equivalent_plastic_strain", 1, {}}, yielded{"yielded", 1, {}};
  for (const ParticleOutput& o : outputs) {
    eqps.values.push_back(o.eqps);
    yielded.values.push_back(o.yielded ? 1.0 : 0.0);
  }
  return {eqps, yielded};
}

void writeProbeSummary(const std::string& file, const Teuchos::Comm<int>& comm, const std::vector<ProbeHistory>& probes,
                       const std::string& extra) {
  if (comm.getRank() != 0) return;
  const auto folder = std::filesystem::path(file).parent_path();
  if (!folder.empty()) std::filesystem::create_directories(folder);
  std::ofstream f(file);
  f << std::setprecision(17) << "{\"ranks\": " << comm.getSize() << (extra.empty() ? "" : ", ") << extra
    << ",\n \"probes\": {";
  for (std::size_t k = 0; k < probes.size(); ++k) {
    f << (k ? ",\n  " : "") << "\"" << probes[k].name << "\": [";
    const auto& v = probes[k].values;
    for (std::size_t s = 0; s < v.size(); ++s) {
      f << (s ? ", " : "") << "{\"load_factor\": " << v[s].first << ", \"" << probes[k].quantity << "\": [";
      for (std::size_t c = 0; c < v[s].second.size(); ++c) f << (c ? ", " : "") << v[s].second[c];
      f << "]}";
    }
    f << "]";
  }
  f << "}}\n";
  if (!f) throw std::runtime_error("cannot write '" + file + "'");
}

}  // namespace perinox

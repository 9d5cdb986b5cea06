// Exodus II results per converged step (drivers/ExodusResults.hpp, docs/exodus.md).
#include "ExodusResults.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <mpi.h>

#include <algorithm>
#include <stdexcept>

#include "Observers.hpp"  // probeKey, probeComponents
#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/ExodusOutput.hpp"

namespace perinox {

namespace {

// Per particle: displacement (3), Cauchy stress (6: xx yy zz xy yz zx), damage; with a plastic
// material also the equivalent plastic strain and the yield flag of the last step.
std::vector<std::string> nodalNames(bool plastic) {
  std::vector<std::string> n{"displacement_x", "displacement_y", "displacement_z", "stress_xx", "stress_yy",
                             "stress_zz",      "stress_xy",      "stress_yz",      "stress_zx", "damage"};
  if (plastic) {
    n.push_back("equivalent_plastic_strain");
    n.push_back("yielded");
  }
  return n;
}

/// Runs f on the ranks that write (rank 0, or every rank when each writes its own file); if it
/// throws anywhere, every rank throws the lowest failing rank's sentence (no rank is left
/// waiting in a collective).
template <class F>
void writeAgreed(const Teuchos::Comm<int>& comm, bool writes, F&& f) {
  std::string msg;
  if (writes) try {
      f();
    } catch (const std::exception& e) {
      msg = e.what();
      if (msg.empty()) msg = "unknown error";
    }
  msg = lowestRankMessage(comm, msg);
  if (!msg.empty()) throw std::runtime_error("writing the Exodus results failed: " + msg);
}

MPI_Comm rawComm(const Teuchos::Comm<int>& comm) {
  const auto* mpi = dynamic_cast<const Teuchos::MpiComm<int>*>(&comm);
  if (!mpi) throw std::logic_error("ExodusRecorder needs an MPI communicator");
  return (*mpi->getRawMpiComm())();
}

}  // namespace

ExodusRecorder::ExodusRecorder(const PeridynamicEvaluator& ev, const Scene& scene, const RunResult& res,
                               const std::string& dir)
    : ev_(ev), scene_(scene), res_(res) {
  const auto& d = ev.problem().disc;
  std::vector<std::string> globals{"load_factor"};
  for (const auto& p : scene.probes) {
    if (p.quantity == "Profile") continue;
    std::string what = probeKey(p);
    std::replace(what.begin(), what.end(), '_', ' ');
    for (const std::string& c : probeComponents(p, d.dim)) globals.push_back(what + " " + p.name + " " + c);
  }
  const auto& comm = *ev.comm();
  perRank_ = ev.problem().distributed && comm.getSize() > 1;
  if (!perRank_) {
    writeAgreed(comm, comm.getRank() == 0, [&] {
      writer_ = std::make_unique<ExodusWriter>(dir + "/fields.e", d.dim, d.thickness, d.X, d.volume, d.block,
                                               scene.regions, nodalNames(ev.problem().plastic()), globals);
    });
    return;
  }
  // One file per rank of its owned particles (no rank holds the whole body): node and element
  // maps of their ids, the regions' owned members as node sets.
  const auto& owned = ev.ownedParticles();
  std::vector<Eigen::Vector3d> X;
  std::vector<double> volume;
  std::vector<int> block;
  for (long long g : owned) {
    const int k = ev.problem().index(g);
    X.push_back(d.X[k]);
    volume.push_back(d.volume[k]);
    block.push_back(d.block[k]);
  }
  std::map<std::string, std::vector<int>> sets;
  for (const auto& [name, ids] : scene.regions) {
    auto& local = sets[name];
    for (int g : ids) {
      const auto it = std::lower_bound(owned.begin(), owned.end(), static_cast<long long>(g));
      if (it != owned.end() && *it == g) local.push_back(static_cast<int>(it - owned.begin()));
    }
    std::sort(local.begin(), local.end());
  }
  writeAgreed(comm, true, [&] {
    writer_ = std::make_unique<ExodusWriter>(dir + "/" + exodusPieceName(comm.getSize(), comm.getRank()), d.dim,
                                             d.thickness, X, volume, block, sets, nodalNames(ev.problem().plastic()), globals, owned);
  });
}

std::string exodusPieceName(int ranks, int rank) {
  const std::string p = std::to_string(ranks), r = std::to_string(rank);
  return "fields.e." + p + "." + std::string(p.size() > r.size() ? p.size() - r.size() : 0, '0') + r;
}

ExodusRecorder::~ExodusRecorder() = default;

void ExodusRecorder::record(const Thyra::VectorBase<double>& x, double lambda) {
  const auto& comm = *ev_.comm();
  const int D = ev_.problem().dim();
  const auto u = ev_.ownedDisplacements(x);
  const auto outs = ev_.ownedOutputs(x);
  const std::vector<double> damage = ev_.problem().damage ? ev_.ownedDamage() : std::vector<double>(outs.size(), 0.0);
  const int n = static_cast<int>(ev_.ownedParticles().size());
  const bool plastic = ev_.problem().plastic();
  const int kPerParticle = plastic ? 12 : 10;
  std::vector<double> mine(static_cast<std::size_t>(n) * kPerParticle, 0.0);
  for (int i = 0; i < n; ++i) {
    double* v = &mine[static_cast<std::size_t>(i) * kPerParticle];
    for (int c = 0; c < D; ++c) v[c] = u[static_cast<std::size_t>(i) * D + c];
    const auto& s = outs[i].cauchy;
    v[3] = s(0, 0), v[4] = s(1, 1), v[5] = s(2, 2), v[6] = s(0, 1), v[7] = s(1, 2), v[8] = s(2, 0);
    v[9] = damage[i];
    if (plastic) {
      v[10] = outs[i].eqps;
      v[11] = outs[i].yielded ? 1.0 : 0.0;
    }
  }
  std::vector<double> globals{lambda};
  for (std::size_t k = 0; k < scene_.probes.size(); ++k) {
    if (scene_.probes[k].quantity == "Profile") continue;
    const auto& hist = k < res_.probes.size() ? res_.probes[k].second : decltype(res_.probes[k].second){};
    const int nc = static_cast<int>(probeComponents(scene_.probes[k], D).size());
    for (int c = 0; c < nc; ++c)
      globals.push_back(!hist.empty() && static_cast<int>(hist.back().second.size()) > c ? hist.back().second[c] : 0.0);
  }
  if (perRank_) {  // this rank's file: its particles in owned order
    writeAgreed(comm, true, [&] {
      std::vector<std::vector<double>> nodal(kPerParticle, std::vector<double>(static_cast<std::size_t>(n)));
      for (int p = 0; p < n; ++p)
        for (int v = 0; v < kPerParticle; ++v) nodal[v][p] = mine[static_cast<std::size_t>(p) * kPerParticle + v];
      writer_->writeStep(lambda, nodal, globals);
    });
    ++steps_;
    return;
  }
  // Rank 0 receives every rank's values and particle ids and puts them in id order (the
  // partition decides which ids a rank owns). (MPI itself: Teuchos::gatherv has no case for
  // double in Trilinos 13.2, docs/exodus.md.)
  const int ranks = comm.getSize();
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(ranks, 0), displs(ranks, 0);
  const MPI_Comm raw = rawComm(comm);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, raw);
  int total = 0;
  for (int r = 0; r < ranks; ++r) displs[r] = total, total += counts[r];
  std::vector<double> all(comm.getRank() == 0 ? total : 0);
  MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, raw);
  for (int r = 0; r < ranks; ++r) counts[r] /= kPerParticle, displs[r] /= kPerParticle;
  std::vector<long long> ids(comm.getRank() == 0 ? total / kPerParticle : 0);
  MPI_Gatherv(ev_.ownedParticles().data(), n, MPI_LONG_LONG, ids.data(), counts.data(), displs.data(), MPI_LONG_LONG,
              0, raw);
  writeAgreed(comm, comm.getRank() == 0, [&] {
    const std::size_t np = static_cast<std::size_t>(total / kPerParticle);
    std::vector<std::vector<double>> nodal(kPerParticle, std::vector<double>(np));
    for (std::size_t p = 0; p < np; ++p)
      for (int v = 0; v < kPerParticle; ++v) nodal[v][static_cast<std::size_t>(ids[p])] = all[p * kPerParticle + v];
    writer_->writeStep(lambda, nodal, globals);
  });
  ++steps_;
}

void ExodusRecorder::close() {
  writeAgreed(*ev_.comm(), writer_ != nullptr || perRank_, [&] {
    if (writer_) writer_->close();
  });
}

}  // namespace perinox

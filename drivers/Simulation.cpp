#include "Simulation.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <mpi.h>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <iomanip>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>  // environ (GNU)
#include <fcntl.h>

#include "ExodusResults.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/Output.hpp"
#include "perinox/io/OutputFolder.hpp"
#include "perinox/solver/AdrSolver.hpp"
#include "perinox/solver/AuxiliaryOperators.hpp"
#include "perinox/solver/LinearSolver.hpp"
#include "perinox/solver/LinearSolverValidation.hpp"
#include "perinox/solver/NewtonSolver.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"
#include "perinox/stepping/ArcLengthStepper.hpp"
#include "perinox/stepping/LoadStepper.hpp"
#include "perinox/stepping/PeridynamicDamage.hpp"

namespace perinox {

namespace fs = std::filesystem;

namespace {

/// Progress lines set fixed or scientific formats and precisions on std::cout; this restores the
/// stream's format when the line's scope ends, so no line inherits another's (a load factor
/// printed after the "2 decimals" of an elapsed time read 0.24 for 0.2442).
class CoutFormat {
 public:
  CoutFormat() : flags_(std::cout.flags()), precision_(std::cout.precision()) {}
  ~CoutFormat() {
    std::cout.flags(flags_);
    std::cout.precision(precision_);
  }
  CoutFormat(const CoutFormat&) = delete;
  CoutFormat& operator=(const CoutFormat&) = delete;

 private:
  std::ios_base::fmtflags flags_;
  std::streamsize precision_;
};

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Runs f on every rank (f may do nothing on some). If it throws on any rank, every rank throws
/// the same OutputPathError (the sentence of the lowest failing rank) once all have finished f,
/// so no rank is left waiting in a collective for one that threw. For work done by some ranks
/// only between collectives: writing files, making folders.
template <class F>
void agreed(const Teuchos::Comm<int>& comm, F&& f) {
  std::string msg;
  try {
    f();
  } catch (const fs::filesystem_error& e) {
    msg = e.code().message() + " at '" + e.path1().string() + "'";
  } catch (const std::exception& e) {
    msg = e.what();
    if (msg.empty()) msg = "unknown error";
  }
  const int rank = comm.getRank(), size = comm.getSize();
  int mine = msg.empty() ? size : rank, first = size;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(first));
  if (first == size) return;
  int length = static_cast<int>(msg.size());
  Teuchos::broadcast(comm, first, Teuchos::outArg(length));
  msg.resize(length);
  if (length > 0) Teuchos::broadcast(comm, first, length, msg.data());
  if (msg.rfind("--", 0) == 0) throw OutputPathError(msg);  // already names its option
  throw OutputPathError("writing the results failed" + (size > 1 ? " on rank " + std::to_string(first) : std::string()) +
                        ": " + msg);
}

/// Tests only: PERINOX_FAULT_WRITE_RANK=r makes rank r's field writer fail, as a full disk or a
/// vanished folder would, to check that every rank ends with the same sentence.
void injectedWriteFault(int rank, const std::string& file) {
  const char* f = std::getenv("PERINOX_FAULT_WRITE_RANK");
  if (f && *f && std::atoi(f) == rank) throw std::runtime_error("cannot write '" + file + "' (fault injected by PERINOX_FAULT_WRITE_RANK)");
}

/// Runs a program with arguments (no shell: nothing in them is interpreted), its output into
/// logFile; returns its exit status (-1 when it could not be started).
int runProgram(const std::vector<std::string>& argv, const std::string& logFile) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, logFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Mean displacement of a probe's particles, or the summed reaction, at state x.
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

void writeFields(const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x, const std::string& dir,
                 bool vtk, int rank, int nranks) {
  const auto& d = ev.problem().disc;
  const int D = ev.problem().dim();
  const auto u = ev.ownedDisplacements(x);
  const auto outs = ev.ownedOutputs(x);
  const std::size_t n = ev.ownedParticles().size();
  std::vector<Eigen::Vector3d> pts(n);
  PointField disp{"displacement", 3, std::vector<double>(3 * n, 0.0)};
  PointField stress{"cauchy_stress", 9, std::vector<double>(9 * n, 0.0)};
  PointField fict{"fictitious", 1, std::vector<double>(n, 0.0)};
  PointField rk{"rank", 1, std::vector<double>(n, static_cast<double>(rank))};
  const bool damage = ev.problem().damage;
  PointField dmg{"damage", 1, damage ? ev.ownedDamage() : std::vector<double>(n, 0.0)};
  std::ostringstream csv;
  csv << std::setprecision(12);
  for (std::size_t i = 0; i < n; ++i) {
    const long long p = ev.ownedParticles()[i];
    pts[i] = d.X[p];
    for (int c = 0; c < D; ++c) disp.values[3 * i + c] = u[i * D + c];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) stress.values[9 * i + 3 * r + c] = outs[i].cauchy(r, c);
    fict.values[i] = d.fictitious[p];
    csv << p << ',' << d.X[p][0] << ',' << d.X[p][1] << ',' << d.X[p][2] << ',' << disp.values[3 * i] << ','
        << disp.values[3 * i + 1] << ',' << disp.values[3 * i + 2] << ',' << outs[i].cauchy(0, 0) << ','
        << outs[i].cauchy(1, 1) << ',' << outs[i].cauchy(2, 2) << ',' << outs[i].cauchy(0, 1) << ','
        << static_cast<int>(d.fictitious[p]) << ',' << dmg.values[i] << '\n';
  }
  std::vector<PointField> fields{disp, stress, fict, rk};
  if (damage) fields.push_back(dmg);  // only where the effect is on
  injectedWriteFault(rank, dir + "/fields_" + std::to_string(rank) + ".vtu");
  if (vtk) {
    const std::string piece = "fields_" + std::to_string(rank) + ".vtu";
    writeVtu(dir + "/" + piece, pts, fields);
    if (rank == 0) {
      std::vector<std::string> pieces;
      for (int r = 0; r < nranks; ++r) pieces.push_back("fields_" + std::to_string(r) + ".vtu");
      writePvtu(dir + "/fields.pvtu", pieces, fields);
    }
  }
  writeFileAtomic(dir + "/fields_" + std::to_string(rank) + ".csv.part", csv.str());
}

/// The residual history up to its first NaN or infinity (JSON has no such numbers; a step whose
/// residual became non-finite says so with "residual_not_finite").
std::vector<double> finitePrefix(const std::vector<double>& r) {
  return {r.begin(), std::find_if(r.begin(), r.end(), [](double v) { return !std::isfinite(v); })};
}

/// One step's record as summary.json writes it (and a checkpoint keeps it).
nlohmann::json stepJson(const StepRecord& s, bool damage, bool arcLength) {
  nlohmann::json j = {{"step", s.step},
                      {"load_factor", s.loadFactor},
                      {"newton_iterations", s.newtonIterations},
                      {"newton_iterations_all_attempts", s.newtonIterationsAll},
                      {"linear_solves", s.linearSolves},
                      {"krylov_iterations", s.krylovIterations},
                      {"linear_failures", s.linearFailures},
                      {"residuals", finitePrefix(s.residuals)},
                      {"normalised_by", s.reactionNormalised ? "reaction" : "external force"},
                      {"cutbacks", s.cutbacks},
                      {"converged_at_roundoff_floor", s.atRoundoffFloor},
                      {"roundoff_floor", s.floor},
                      {"broken_bonds", s.brokenBonds},
                      {"break_rounds", s.breakRounds},
                      {"detached", s.detached},
                      {"time_s", s.elapsed}};
  if (finitePrefix(s.residuals).size() < s.residuals.size()) j["residual_not_finite"] = true;
  if (arcLength) j["arc_length"] = s.arcLength;
  if (s.negativePivots >= -1) j["negative_pivots"] = s.negativePivots;
  if (damage) {
    j["stall_broken_bonds"] = s.stallBrokenBonds;
    j["reload_steps"] = s.reloadSteps;
    j["fragment_particles"] = s.fragmentParticles;
    if (s.stallBrokenBonds > 0) j["stall_max_stretch"] = s.stallStretch;
  }
  return j;
}

/// The sentence a run that converged with unconverged linear solves ends with ("" when none did).
std::string inexactSolvesWarning(const std::vector<StepRecord>& steps) {
  long long unconverged = 0, solves = 0;
  for (const auto& st : steps) unconverged += st.linearFailures, solves += st.linearSolves;
  if (unconverged == 0) return "";
  return std::to_string(unconverged) + " of " + std::to_string(solves) +
         " linear solves did not converge (Krylov iteration limit or breakdown); Newton went on with inexact "
         "directions, which costs Newton iterations (linear_failures per step): raise the Krylov limit or choose a "
         "stronger preconditioner";
}

StepRecord stepFromJson(const nlohmann::json& j) {
  StepRecord s;
  s.step = j.at("step");
  s.loadFactor = j.at("load_factor");
  s.newtonIterations = j.at("newton_iterations");
  s.newtonIterationsAll = j.at("newton_iterations_all_attempts");
  s.linearSolves = j.at("linear_solves");
  s.krylovIterations = j.at("krylov_iterations");
  s.linearFailures = j.value("linear_failures", 0LL);  // absent in checkpoints of older versions
  s.residuals = j.at("residuals").get<std::vector<double>>();
  s.reactionNormalised = j.at("normalised_by") == "reaction";
  s.cutbacks = j.at("cutbacks");
  s.atRoundoffFloor = j.at("converged_at_roundoff_floor");
  s.floor = j.at("roundoff_floor");
  s.brokenBonds = j.at("broken_bonds");
  s.breakRounds = j.at("break_rounds");
  s.detached = j.at("detached").get<std::vector<long long>>();
  s.elapsed = j.at("time_s");
  s.arcLength = j.value("arc_length", 0.0);
  s.negativePivots = j.value("negative_pivots", -2);
  s.stallBrokenBonds = j.value("stall_broken_bonds", 0LL);
  s.reloadSteps = j.value("reload_steps", 0);
  s.fragmentParticles = j.value("fragment_particles", 0LL);
  s.stallStretch = j.value("stall_max_stretch", 0.0);
  return s;
}

std::string resolvedSceneText(const Scene& scene) {
  std::ostringstream s;
  Teuchos::writeParameterListToXmlOStream(*scene.resolved, s);
  return s.str();
}

/// Everything a load-stepping run needs to go on from a converged step. Vectors, bonds and
/// frozen DOFs are by global id, so a checkpoint can be resumed on any number of ranks.
/// Files: state.json (rank 0: counters, step records, probes) and rank_R.txt per writing rank
/// (lines "x GID X XPREV", "bond GID_I GID_J", "frozen GID VALUE"; doubles in hexadecimal, so a
/// resumed run starts from bit-identical numbers).
struct Checkpoint {
  nlohmann::json state;
  std::vector<std::pair<long long, double>> x, xPrevious, frozen;
  std::vector<std::pair<long long, long long>> broken;
};

void writeCheckpoint(const FolderPlan& plan, const nlohmann::json& state, const PeridynamicEvaluator& ev,
                     const Thyra::VectorBase<double>& x, const Thyra::VectorBase<double>& xPrevious,
                     const Teuchos::Comm<int>& comm) {
  const int rank = comm.getRank();
  agreed(comm, [&] {
    if (rank == 0) openStaging(plan);
  });
  agreed(comm, [&] {
    std::ostringstream out;
    out << std::hexfloat;
    const auto xv = ev.ownedFreeValues(x), pv = ev.ownedFreeValues(xPrevious);
    for (std::size_t k = 0; k < xv.size(); ++k) out << "x " << xv[k].first << ' ' << xv[k].second << ' ' << pv[k].second << '\n';
    for (const auto& [a, b] : ev.ownedBrokenBonds()) out << "bond " << a << ' ' << b << '\n';
    for (const auto& [g, v] : ev.ownedFrozenDofs()) out << "frozen " << g << ' ' << v << '\n';
    writeFileAtomic(plan.staging + "/rank_" + std::to_string(rank) + ".txt", out.str());
  });
  agreed(comm, [&] {
    if (rank != 0) return;
    nlohmann::json st = state;
    st["ranks"] = comm.getSize();
    writeFileAtomic(plan.staging + "/state.json", st.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
    // Replace the previous checkpoint only once the new one is complete; the old one is moved
    // aside first, so a job killed in between leaves DIR.old or DIR, never neither.
    commitFolder(plan);
  });
}

/// Reads a checkpoint written for this scene (freeDofs unknowns); throws std::invalid_argument
/// naming the problem.
Checkpoint readCheckpoint(const std::string& dir, const Scene& scene, long long freeDofs, long long particles) {
  Checkpoint c;
  const std::string where = "checkpoint '" + dir + "'";
  std::ifstream sj(dir + "/state.json");
  if (!sj)
    throw std::invalid_argument(where + ": no state.json there (not a checkpoint" +
                                (fs::exists(dir + ".old/state.json") ? std::string(": the job was killed while replacing it; the previous one is '") + dir + ".old'" : std::string()) +
                                ")");
  try {
    c.state = nlohmann::json::parse(sj);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(where + ": state.json is truncated or damaged (not valid JSON at byte " +
                                std::to_string(e.byte) + ")");
  }
  if (c.state.value("format", 0) != 1 || !c.state.contains("scene") || !c.state.contains("ranks"))
    throw std::invalid_argument(where + ": state.json is not a perinox checkpoint (format 1)");
  // Run controls may change between the segments of a run (limits that stopped it, the linear
  // solver, NOX's verbosity, the output options); everything else must be the checkpoint's.
  auto physics = [&](const std::string& xml) {
    Teuchos::RCP<Teuchos::ParameterList> pl;
    try {
      pl = Teuchos::getParametersFromXmlString(xml);
    } catch (const std::exception&) {
      throw std::invalid_argument(where + ": the scene kept in its state.json is not readable XML (damaged checkpoint)");
    }
    if (pl->isSublist("Solver")) {
      auto& so = pl->sublist("Solver");
      for (const char* k : {"Max Total Steps", "Linear Solver Preset", "Linear Solver", "Verbosity"}) so.remove(k, false);
    }
    if (pl->isSublist("Damage")) pl->sublist("Damage").remove("Max Stall Breaks", false);
    if (pl->isSublist("Discretization")) pl->sublist("Discretization").remove("Partition", false);
    pl->remove("Output", false);
    // "Sublist/Key" -> value: the order of the keys and whether a value came from the scene
    // file, a --set or a default does not matter, only the values.
    std::map<std::string, std::pair<std::string, std::string>> values;  // exact, shown
    std::function<void(const Teuchos::ParameterList&, const std::string&)> walk =
        [&](const Teuchos::ParameterList& l, const std::string& prefix) {
          for (auto it = l.begin(); it != l.end(); ++it) {
            const std::string key = prefix + l.name(it);
            const auto& e = l.entry(it);
            if (e.isList()) {
              walk(Teuchos::getValue<Teuchos::ParameterList>(e), key + "/");
            } else {
              std::ostringstream exact, shown;
              exact << std::setprecision(17) << e.getAny(false);
              shown << e.getAny(false);
              values[key] = {exact.str(), shown.str()};
            }
          }
        };
    walk(*pl, "");
    return values;
  };
  const auto mine = physics(resolvedSceneText(scene)), theirs = physics(c.state["scene"].get<std::string>());
  if (mine != theirs) {
    std::string what;
    for (const auto& [k, v] : mine) {
      const auto t = theirs.find(k);
      if (t == theirs.end()) {
        what = "'" + k + "' = " + v.second + " now, not in the checkpoint's scene";
        break;
      }
      if (t->second.first != v.first) {
        what = "'" + k + "' = " + v.second + " now, " + t->second.second + " in the checkpoint";
        break;
      }
    }
    if (what.empty())
      for (const auto& [k, v] : theirs)
        if (!mine.count(k)) {
          what = "'" + k + "' = " + v.second + " in the checkpoint, not in this scene";
          break;
        }
    throw std::invalid_argument(where + " is for another scene: " + what + " (only run controls may differ, README)");
  }
  // Everything the loop will read, checked now, before any output exists.
  try {
    for (const char* k : {"step", "lambda", "increment", "last_increment", "stall_breaks", "elapsed_s", "segment"}) {
      const double v = c.state.at(k).get<double>();
      if (!std::isfinite(v)) throw std::runtime_error(std::string("'") + k + "' is not a finite number");
    }
    // Values a run could have written: a counter is a whole number within its range, a load
    // factor lies in [0, 1], an increment in (0, 1].
    auto whole = [&](const char* k, long long lo, long long hi) {
      const double v = c.state.at(k).get<double>();
      if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
        throw std::runtime_error(std::string("'") + k + "' = " + c.state.at(k).dump() + " is not a whole number in [" +
                                 std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    auto within = [&](const char* k, double lo, double hi, bool openLow) {
      const double v = c.state.at(k).get<double>();
      if (v > hi || v < lo || (openLow && v == lo))
        throw std::runtime_error(std::string("'") + k + "' = " + c.state.at(k).dump() + " lies outside " +
                                 (openLow ? "(" : "[") + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    whole("step", 0, 2000000000);
    whole("stall_breaks", 0, 2000000000);
    whole("segment", 1, 1000000000);
    within("lambda", 0.0, 1.0, false);
    within("increment", 0.0, 1.0, true);
    within("last_increment", 0.0, 1.0, false);
    within("elapsed_s", 0.0, 1e12, false);
    if (c.state.at("steps").size() != c.state.at("step").get<std::size_t>())
      throw std::runtime_error("it records " + std::to_string(c.state.at("steps").size()) + " steps, not 'step' = " +
                               c.state.at("step").dump());
    for (const auto& sj : c.state.at("steps")) (void)stepFromJson(sj);
    (void)c.state.at("path_load_factors").get<std::vector<double>>();
    for (long long id : c.state.at("detached").get<std::vector<long long>>())
      if (id < 0 || id >= particles)
        throw std::runtime_error("detached particle " + std::to_string(id) + " is not one of the " +
                                 std::to_string(particles) + " particles");
    const auto& probes = c.state.at("probes");
    if (probes.size() != scene.probes.size()) throw std::runtime_error("probe histories do not match the scene's probes");
    for (const auto& p : probes) (void)p.get<std::vector<std::pair<double, std::vector<double>>>>();
  } catch (const std::exception& e) {
    throw std::invalid_argument(where + ": state.json is incomplete or damaged (" + e.what() + ")");
  }
  const int ranks = c.state["ranks"];
  for (int r = 0; r < ranks; ++r) {
    const std::string f = dir + "/rank_" + std::to_string(r) + ".txt";
    std::ifstream in(f);
    if (!in) throw std::invalid_argument(where + ": " + f + " is missing");
    std::string line, kind;
    // A number as written (hexadecimal floating point), finite, with nothing after it.
    auto number = [&](const std::string& t, bool& ok) {
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      ok = ok && end && *end == '\0' && end != t.c_str() && std::isfinite(v);
      return v;
    };
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      ls >> kind;
      long long g = 0, h = 0;
      std::string v1, v2;
      bool ok = true;
      if (kind == "x") {
        ok = static_cast<bool>(ls >> g >> v1 >> v2);
        if (ok) {
          c.x.emplace_back(g, number(v1, ok));
          c.xPrevious.emplace_back(g, number(v2, ok));
        }
      } else if (kind == "bond") {
        ok = static_cast<bool>(ls >> g >> h) && g >= 0 && h >= 0 && g < particles && h < particles && g != h;
        if (ok) c.broken.emplace_back(g, h);
      } else if (kind == "frozen") {
        ok = static_cast<bool>(ls >> g >> v1) && g >= 0 && g < freeDofs;
        if (ok) c.frozen.emplace_back(g, number(v1, ok));
      } else {
        ok = false;
      }
      if (!ok) throw std::invalid_argument(where + ": unreadable line in " + f + ": '" + line + "'");
    }
  }
  std::vector<long long> ids;
  for (const auto& e : c.x) ids.push_back(e.first);
  std::sort(ids.begin(), ids.end());
  const bool complete = static_cast<long long>(ids.size()) == freeDofs &&
                        std::adjacent_find(ids.begin(), ids.end()) == ids.end() &&
                        (ids.empty() || (ids.front() == 0 && ids.back() == freeDofs - 1));
  if (!complete)
    throw std::invalid_argument(where + " holds " + std::to_string(ids.size()) + " displacement values for " +
                                std::to_string(freeDofs) + " free DOFs (damaged or from another discretisation)");
  return c;
}

/// The scene's probes, recorded at every accepted step (collective: every rank).
class ProbeRecorder final : public StepObserver {
 public:
  ProbeRecorder(const PeridynamicEvaluator& ev, const Scene& scene, RunResult& res) : ev_(ev), scene_(scene), res_(res) {}
  void accepted(const StepInfo& s) override {
    const auto u = ev_.ownedDisplacements(s.x);
    for (std::size_t k = 0; k < scene_.probes.size(); ++k)
      if (scene_.probes[k].quantity != "Profile")
        res_.probes[k].second.push_back({s.loadFactor, probeValue(ev_, scene_.probes[k], s.x, u)});
  }

 private:
  const PeridynamicEvaluator& ev_;
  const Scene& scene_;
  RunResult& res_;
};

/// The console: one line per accepted step (load factor, iterations, residual, time) and the
/// stepper's notes (cut-backs, stalls, damage), on rank 0 unless quiet.
class ConsoleLines final : public StepObserver {
 public:
  ConsoleLines(const Scene& scene, bool speak) : adr_(scene.solver.method == "ADR"), speak_(speak) {}
  void note(const std::string& line) override {
    if (speak_) std::cout << line << "\n";
  }
  void accepted(const StepInfo& s) override {
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

 private:
  bool adr_, speak_;
};

/// 'Solver/Stability Check': the tangent's negative pivots at each converged step; an unstable
/// equilibrium stops the run, the last stable state kept.
class StabilityCheck final : public StepObserver {
 public:
  explicit StabilityCheck(PeridynamicEvaluator& ev) : ev_(ev) {}
  std::string vet(const StepInfo& s, double previous) override {
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

 private:
  PeridynamicEvaluator& ev_;
};

/// Checkpoints after accepted steps, every --checkpoint-steps steps and/or --checkpoint-seconds.
class CheckpointWriter final : public StepObserver {
 public:
  CheckpointWriter(const RunOptions& options, const FolderPlan& folder, const Scene& scene, const PeridynamicEvaluator& ev,
                   const Teuchos::Comm<int>& comm, const LoadStepper& stepper, const RunResult& res, double t0,
                   double elapsedBefore, int segment)
      : options_(options), folder_(folder), scene_(scene), ev_(ev), comm_(comm), stepper_(stepper), res_(res), t0_(t0),
        elapsedBefore_(elapsedBefore), segment_(segment), last_(now()) {}
  void accepted(const StepInfo& s) override {
    const auto& state = stepper_.state();
    int due = (options_.checkpointSteps > 0 && state.step % options_.checkpointSteps == 0) ||
              (options_.checkpointSeconds > 0 && now() - last_ >= options_.checkpointSeconds);
    Teuchos::broadcast(comm_, 0, Teuchos::outArg(due));  // clocks differ between ranks
    if (!due) return;
    nlohmann::json st;
    st["format"] = 1;
    st["scene"] = resolvedSceneText(scene_);
    st["step"] = state.step;
    st["lambda"] = state.loadFactor;
    st["increment"] = state.increment;
    st["last_increment"] = state.lastIncrement;
    st["stall_breaks"] = state.stallBreaks;
    st["elapsed_s"] = now() - t0_ + elapsedBefore_;
    st["segment"] = segment_;
    nlohmann::json steps = nlohmann::json::array();
    for (const auto& sr : stepper_.records()) steps.push_back(stepJson(sr, true, false));
    st["steps"] = steps;
    st["path_load_factors"] = stepper_.path();
    nlohmann::json probes = nlohmann::json::array();
    for (const auto& pr : res_.probes) probes.push_back(pr.second);
    st["probes"] = probes;
    st["detached"] = ev_.detachedParticles();
    writeCheckpoint(folder_, st, ev_, s.x, stepper_.previous(), comm_);
    last_ = now();
    if (comm_.getRank() == 0 && !options_.quiet)
      std::cout << "  checkpoint after step " << state.step << " in " << folder_.target << std::endl;
  }

 private:
  const RunOptions& options_;
  const FolderPlan& folder_;
  const Scene& scene_;
  const PeridynamicEvaluator& ev_;
  const Teuchos::Comm<int>& comm_;
  const LoadStepper& stepper_;
  const RunResult& res_;
  double t0_, elapsedBefore_;
  int segment_;
  double last_;
};

/// What summary.json reports beyond the run's result: where it ran and what it held.
struct RunFacts {
  int ranks = 1;
  int segment = 1;                 // 1, or the runs a checkpointed run was split into
  nlohmann::json resumedFrom;      // null unless resumed
  std::vector<std::string> effects;
  long long matrixBytes = 0;       // sparse matrices held, all ranks
  double rssMax = 0, rssSum = 0;   // peak resident memory, MiB: the largest rank's and the sum
  std::vector<long long> detached;
  // Wall times (rank 0's clock after barriers): the set-up (evaluator, maps, before the first
  // solve), the solve (every load step), and one residual evaluation at the final state (median
  // of three), the unit of the machine-independent cost ratios in docs/performance.md.
  double setupSeconds = 0, solveSeconds = 0, residualSeconds = 0;
  TwoStageStatistics twoStage;     // the Two-Stage preconditioner's set-ups (zeros for others)
  nlohmann::json partition;        // the partition: method, owned and ghost particles per rank
};

/// The per-rank particle CSVs gathered into fields.csv (for plotting) in particle id order
/// (a rank's particles are the partition's choice), the parts removed.
void gatherFieldsCsv(const std::string& staging, int nranks) {
  std::vector<std::pair<long long, std::string>> rows;
  for (int r = 0; r < nranks; ++r) {
    const std::string part = staging + "/fields_" + std::to_string(r) + ".csv.part";
    std::ifstream in(part);
    for (std::string line; std::getline(in, line);) rows.emplace_back(std::stoll(line), std::move(line));
    in.close();
    fs::remove(part);
  }
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::ofstream all(staging + "/fields.csv");
  all << "id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,fictitious,damage\n";
  for (const auto& row : rows) all << row.second << '\n';
  if (!all) throw std::runtime_error("cannot write '" + staging + "/fields.csv'");
}

/// Profiles: the final state of every particle of a region (e.g. u_x along an axis).
void writeProfiles(const Scene& scene, const std::string& staging) {
  for (const auto& probe : scene.probes) {
    if (probe.quantity != "Profile") continue;
    std::ifstream in(staging + "/fields.csv");
    std::ostringstream out;
    std::string line;
    std::getline(in, line);
    out << line << '\n';
    while (std::getline(in, line)) {
      const long long id = std::stoll(line.substr(0, line.find(',')));
      if (std::binary_search(probe.particles.begin(), probe.particles.end(), static_cast<int>(id))) out << line << '\n';
    }
    std::string fname = probe.name;
    std::replace(fname.begin(), fname.end(), ' ', '_');
    writeFileAtomic(staging + "/profile_" + fname + ".csv", out.str());
  }
}

/// summary.json: the run, its steps and totals, the probes, the errors against the reference.
nlohmann::json summaryJson(const Scene& scene, const RunResult& res, const RunFacts& facts) {
  using nlohmann::json;
  const bool arcLength = scene.solver.continuation == "Arc Length";
  json j;
  j["scene"] = scene.file;
  j["title"] = scene.title;
  j["ranks"] = facts.ranks;
  j["particles"] = res.particles;
  j["dofs"] = res.dofs;
  j["converged"] = res.converged;
  if (!res.converged) j["failure"] = res.failure;
  j["wall_time_s"] = res.wallTime;
  j["run_segments"] = facts.segment;
  if (!facts.resumedFrom.is_null()) j["resumed_from"] = facts.resumedFrom;
  j["effects"] = facts.effects;
  j["linear_solver"] = scene.solver.linearSolverName;
  j["jacobian"] = scene.solver.jacobian;
  if (scene.solver.jacobian != "Assembled") j["preconditioner_matrix"] = scene.solver.preconditionerMatrix;
  j["matrix_bytes"] = facts.matrixBytes;
  j["peak_rss_mib_max_rank"] = facts.rssMax;
  j["peak_rss_mib_all_ranks"] = facts.rssSum;
  j["partition"] = facts.partition;
  j["method"] = scene.solver.method;
  j["tolerance"] = scene.solver.tolerance;
  json steps = json::array();
  for (const auto& s : res.steps) steps.push_back(stepJson(s, scene.problem->damage, arcLength));
  j["steps"] = steps;
  // The run's totals, one pass over the steps: the whole work (Newton iterations of every
  // attempt, ADR's iterations for ADR; linear solves; Krylov iterations, 0 with a direct
  // solver) and, with damage, the bonds broken, the stall events and the fragment particles.
  long long newtonAll = 0, solves = 0, krylov = 0, linearFailures = 0, broken = 0, stallBonds = 0, fragments = 0;
  int stallSteps = 0;
  for (const auto& s : res.steps) {
    newtonAll += s.newtonIterationsAll;
    solves += s.linearSolves;
    krylov += s.krylovIterations;
    linearFailures += s.linearFailures;
    broken += s.brokenBonds;
    stallBonds += s.stallBrokenBonds;
    stallSteps += s.stallBrokenBonds > 0;
    fragments += s.fragmentParticles;
  }
  j["newton_iterations_total"] = newtonAll;
  const long long newtonTotal = newtonAll;
  j["timing"] = {{"setup_s", facts.setupSeconds},
                 {"solve_s", facts.solveSeconds},
                 {"residual_evaluation_s", facts.residualSeconds},
                 {"solve_in_residuals", facts.residualSeconds > 0 ? facts.solveSeconds / facts.residualSeconds : 0.0},
                 {"newton_iteration_in_residuals",
                  facts.residualSeconds > 0 && newtonTotal > 0 ? facts.solveSeconds / facts.residualSeconds / newtonTotal : 0.0}};
  j["linear_solves_total"] = solves;
  if (facts.twoStage.setups > 0)
    j["preconditioner"] = {{"type", "Two-Stage"},
                           {"setups", facts.twoStage.setups},
                           {"hierarchies_built", facts.twoStage.hierarchiesBuilt},
                           {"levels", facts.twoStage.levels}};
  j["krylov_iterations_total"] = krylov;
  j["linear_failures_total"] = linearFailures;
  const std::string inexact = inexactSolvesWarning(res.steps);  // "" unless a linear solve failed
  if (!inexact.empty()) j["warnings"] = {inexact};
  if (scene.problem->damage) {
    j["broken_bonds_total"] = broken;
    j["stall_broken_bonds_total"] = stallBonds;
    j["stall_breaks"] = stallSteps;
    j["detached_particles"] = facts.detached;
    j["fragment_particles_total"] = fragments;  // of the detached: cut off from every prescribed DOF
  }
  json probes = json::object();
  for (std::size_t k = 0; k < res.probes.size(); ++k) {
    if (scene.probes[k].quantity == "Profile") continue;
    json list = json::array();
    const std::string key = scene.probes[k].quantity == "Reaction" ? "reaction" : "displacement";
    for (const auto& [lf, v] : res.probes[k].second) list.push_back({{"load_factor", lf}, {key, v}});
    probes[res.probes[k].first] = list;
  }
  j["probes"] = probes;
  j["continuation"] = scene.solver.continuation;
  if (arcLength) {
    json lp = json::array();
    for (const auto& l : res.limitPoints)
      lp.push_back({{"step", l.step}, {"load_factor", l.loadFactor}, {"deflection", l.deflection}});
    j["limit_points"] = lp;
  }
  if (res.hasError) j["errors"] = {{"e_u", res.errorU}, {"reference", scene.reference.type}};
  return j;
}

/// path.csv: the load factor and every probe at every converged step.
std::string pathCsv(const Scene& scene, const RunResult& res) {
  std::ostringstream path;
  path << "step,load_factor";
  const char* comp = "xyz";
  for (std::size_t k = 0; k < res.probes.size(); ++k)
    if (scene.probes[k].quantity != "Profile")
      for (int c = 0; c < scene.problem->dim(); ++c) {
        std::string name = res.probes[k].first;
        std::replace(name.begin(), name.end(), ' ', '_');
        path << ',' << name << '_' << comp[c];
      }
  path << '\n' << std::setprecision(15);
  for (std::size_t i = 0; i < res.pathLoadFactors.size(); ++i) {
    path << i + 1 << ',' << res.pathLoadFactors[i];
    for (std::size_t k = 0; k < res.probes.size(); ++k)
      if (scene.probes[k].quantity != "Profile")
        for (double v : res.probes[k].second[i].second) path << ',' << v;
    path << '\n';
  }
  return path.str();
}

/// newton.csv: every step's normalised residual per iteration.
std::string newtonCsv(const RunResult& res) {
  std::ostringstream csv;
  csv << std::setprecision(6) << std::scientific << "step,iteration,residual\n";
  for (const auto& s : res.steps)
    for (std::size_t it = 0; it < s.residuals.size(); ++it) csv << s.step << ',' << it << ',' << s.residuals[it] << '\n';
  return csv.str();
}

/// The residual table of seed 000's Tables 2-4: one column per step, one row per iteration.
void printResidualTable(const RunResult& res) {
  CoutFormat keep;
  std::size_t rows = 0;
  for (const auto& s : res.steps) rows = std::max(rows, s.residuals.size());
  std::cout << "\nNewton residuals (normalised) per load step:\n   iter";
  for (const auto& s : res.steps) std::cout << std::setw(11) << ("step " + std::to_string(s.step));
  std::cout << "\n";
  for (std::size_t it = 0; it < rows; ++it) {
    std::cout << std::setw(7) << it;
    for (const auto& s : res.steps) {
      if (it < s.residuals.size())
        std::cout << std::setw(11) << std::scientific << std::setprecision(3) << s.residuals[it];
      else
        std::cout << std::setw(11) << "-";
    }
    std::cout << "\n";
  }
}

/// PNGs by the plot script, run without a shell (the paths go to python as they are).
void drawPlots(const std::string& staging, const RunOptions& options) {
  // Debian's python3 carries python3-matplotlib; another python3 earlier on PATH may not.
  const char* py = std::getenv("PERINOX_PYTHON");
  const std::string python = py && *py ? py : (fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3");
  if (runProgram({python, options.plotScript, staging}, staging + "/plot.log") != 0 && !options.quiet)
    std::cout << "note: plots were not drawn (see plot.log; python3-matplotlib missing?)\n";
}

/// Rank 0: everything the output folder holds besides the per-rank fields, into the staging folder.
void writeResults(const Scene& scene, const RunResult& res, const RunFacts& facts, const RunOptions& options,
                  const std::string& staging, int nranks) {
  gatherFieldsCsv(staging, nranks);
  writeProfiles(scene, staging);
  writeFileAtomic(staging + "/path.csv", pathCsv(scene, res));
  writeFileAtomic(staging + "/summary.json",
                  summaryJson(scene, res, facts).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  writeFileAtomic(staging + "/newton.csv", newtonCsv(res));
  if (!options.quiet) printResidualTable(res);
  if (scene.output.plots && !options.plotScript.empty()) drawPlots(staging, options);
}

/// The scene's evaluator with its linear solver (the list checked first: a misspelt Belos,
/// Ifpack2 or MueLu key would be ignored by Trilinos) and Jacobian mode.
Teuchos::RCP<PeridynamicEvaluator> buildEvaluator(const Scene& scene, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  validateLinearSolverList(*scene.solver.linearSolver, scene.solver.linearSolverName == "custom"
                                                           ? std::string()
                                                           : "preset '" + scene.solver.linearSolverName + "'");
  auto evaluator = Teuchos::rcp(new PeridynamicEvaluator(comm, scene.problem));
  const auto linearParams = Teuchos::rcp(new Teuchos::ParameterList(*scene.solver.linearSolver));
  // The two-stage preconditioner (preset scalable) gets its auxiliary operator from the model.
  std::shared_ptr<AuxiliarySource> auxiliary;
  if (linearParams->get<std::string>("Preconditioner Type", "None") == twoStageName())
    auxiliary = makeAuxiliarySource(evaluator, linearParams->sublist("Preconditioner Types").sublist(twoStageName()));
  if (scene.solver.jacobian == "Assembled" || scene.solver.method != "Newton") {
    evaluator->set_W_factory(buildLinearSolverFactory(linearParams, comm->getSize(), auxiliary));
  } else {
    // Matrix-free: Belos without a preconditioner of its own; the model builds the
    // preconditioner from the matrix the scene names.
    auto split = buildSplitLinearSolver(linearParams, comm->getSize(), auxiliary);
    evaluator->set_W_factory(split.krylov);
    evaluator->setJacobian(scene.solver.jacobian == "Matrix-Free" ? JacobianMode::MatrixFree : JacobianMode::JacobianFree,
                           scene.solver.preconditionerMatrix == "Assembled" ? PreconditionerMatrix::Assembled
                                                                            : PreconditionerMatrix::Neighbours,
                           split.preconditioner, scene.solver.jfnkLambda);
  }
  return evaluator;
}

/// Wall time of one residual evaluation at x (median of three, after barriers).
double residualSeconds(const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x) {
  auto f = Thyra::createMember(ev.get_f_space());
  std::vector<double> t;
  for (int r = 0; r < 3; ++r) {
    auto in = ev.createInArgs();
    in.set_x(Teuchos::rcpFromRef(x));
    auto out = ev.createOutArgs();
    out.set_f(f);
    ev.comm()->barrier();
    const double a = now();
    ev.evalModel(in, out);
    ev.comm()->barrier();
    t.push_back(now() - a);
  }
  std::sort(t.begin(), t.end());
  return t[1];
}

/// Peak resident memory (the largest rank's and the sum, MiB) and the sparse matrices held.
void measureFootprint(const PeridynamicEvaluator& ev, const Teuchos::Comm<int>& comm, RunFacts& facts) {
  double rss = 0;
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) == 0) rss = ru.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, rss, Teuchos::outArg(facts.rssMax));
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, rss, Teuchos::outArg(facts.rssSum));
  long long bytes = static_cast<long long>(ev.matrixBytes());
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, bytes, Teuchos::outArg(facts.matrixBytes));
  // Per rank: owned and ghost particles (what each halo exchange brings in) and peak memory.
  const LocalParticles& lp = ev.model().particles();
  const double mine[3] = {static_cast<double>(lp.numOwned), static_cast<double>(lp.size() - lp.numOwned), rss};
  double most[3], least[3], sum[3];
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, 3, mine, most);
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MIN, 3, mine, least);
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, 3, mine, sum);
  facts.partition = {{"method", partitionName(ev.problem().partition)},
                     {"owned_max", most[0]}, {"owned_min", least[0]},
                     {"ghosts_max", most[1]}, {"ghosts_min", least[1]}, {"ghosts_mean", sum[1] / comm.getSize()},
                     {"peak_rss_mib_min_rank", least[2]}};
}

/// The solve's outcome: the last converged state and its load factor.
/// The arc-length console: one line per converged point (load factor, arc, corrector iterations,
/// residual, deflection, negative pivots, time) and the stepper's notes, on rank 0 unless quiet.
class ArcConsole final : public StepObserver {
 public:
  ArcConsole(const ArcLengthStepper& arc, bool deflection, bool speak) : arc_(arc), deflection_(deflection), speak_(speak) {}
  void note(const std::string& line) override {
    if (speak_) std::cout << line << "\n";
  }
  void accepted(const StepInfo& s) override {
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

 private:
  const ArcLengthStepper& arc_;
  bool deflection_, speak_;
};

/// 'Solver/Continuation = Arc Length': the stepping layer's ArcLengthStepper over the load-factor
/// model from the unloaded state (x, lambda), with the scene's deflection probe as its monitor, the
/// stability check as its pivot count, and the probes and the console as observers. Fills res
/// (steps, path, limit points, failure); x and lambda receive the last converged point.
bool arcLengthContinuation(const Scene& scene, const Teuchos::RCP<PeridynamicEvaluator>& ev,
                           const Teuchos::RCP<LoadFactorModel>& model, StepObserver& probes, Thyra::VectorBase<double>& x,
                           double& lambda, RunResult& res, bool quiet, int rank) {
  const auto& A = scene.solver.arc;
  ArcLengthStepperOptions ao;
  ao.initialArcLength = A.initial;
  ao.minArcLength = A.minimum;
  ao.maxArcLength = A.maximum;
  ao.maxSteps = A.maxSteps;
  ao.targetLoadFactor = A.targetLoadFactor;
  ao.targetMonitor = A.targetDeflection;
  ao.maxCutbacks = scene.solver.maxCutbacks;
  ao.easyIterations = scene.solver.easyIterations;
  ao.tolerance = scene.solver.tolerance;
  ao.maxIterations = scene.solver.maxIterations;
  ao.floorFactor = scene.solver.floorFactor;
  ao.keyPrefix = "Solver/Arc Length/";
  ao.monitorName = "deflection";
  ArcLengthStepper arc(model, Teuchos::rcp(new EvaluatorResidualScale(ev)), ao);
  int deflProbe = -1;
  for (std::size_t k = 0; k < scene.probes.size(); ++k)
    if (scene.probes[k].name == A.deflectionProbe) deflProbe = static_cast<int>(k);
  if (deflProbe >= 0)
    arc.setMonitor([&, deflProbe](const Thyra::VectorBase<double>& state) {
      const auto u = ev->ownedDisplacements(state);
      return probeValue(*ev, scene.probes[deflProbe], state, u)[A.deflectionComponent];
    });
  if (scene.solver.stabilityCheck) arc.setStabilityCount([&](const Thyra::VectorBase<double>& s) { return ev->negativePivots(s); });
  ArcConsole console(arc, deflProbe >= 0, rank == 0 && !quiet);
  arc.addObserver(&probes);
  arc.addObserver(&console);
  const bool ok = arc.run(x, lambda);
  res.steps = arc.records();
  res.pathLoadFactors = arc.path();
  res.failure = arc.failure();
  for (const auto& lp : arc.limitPoints()) res.limitPoints.push_back({lp.step, lp.loadFactor, lp.monitor});
  Thyra::copy(arc.converged(), Teuchos::ptrFromRef(x));
  lambda = arc.loadFactor();
  return ok;
}

struct Solved {
  Teuchos::RCP<Thyra::VectorBase<double>> x;
  double loadFactor = 0.0;
  bool converged = false;
  double elapsedBefore = 0.0;  // wall time of the earlier segments of a resumed run
  int segment = 1;             // 1, or the runs a checkpointed run was split into
};

/// Load stepping (LoadStepper with perinox's damage policy and observers) or arc-length
/// continuation from zero load or a checkpoint; fills res's steps, probes and path.
Solved solveScene(const Scene& scene, const Teuchos::RCP<PeridynamicEvaluator>& evaluator, const RunOptions& options,
                  const FolderPlan& checkpointFolder, const std::optional<Checkpoint>& resume, RunResult& res, double t0,
                  StepObserver* exodus = nullptr) {
  const auto comm = evaluator->comm();
  const int rank = comm->getRank(), nranks = comm->getSize();
  const bool checkpoints = options.checkpointSteps > 0 || options.checkpointSeconds > 0;
  NewtonOptions nopt;
  nopt.tolerance = scene.solver.tolerance;
  nopt.maxIterations = scene.solver.maxIterations;
  nopt.lineSearch = scene.solver.lineSearch;
  nopt.verbosity = scene.solver.verbosity;
  nopt.floorFactor = scene.solver.floorFactor;
  nopt.stagnationStop = scene.solver.stagnationStop;
  // The load factor is the evaluator's parameter p(0): the stepper's wrapper passes it to every
  // evaluation, and keeps the evaluator's own (its diagnostics, damage and outputs use it).
  auto model = Teuchos::rcp(new LoadFactorModel(evaluator));
  model->onLoadFactor([ev = evaluator.get()](double lambda) { ev->setLoadFactor(lambda); });
  auto newton = Teuchos::rcp(new NewtonSolver(model, Teuchos::rcp(new EvaluatorResidualScale(evaluator)), nopt));
  auto newtonSolve = [newton](Thyra::VectorBase<double>& xs) { return newton->solve(xs); };
  auto adrSolve = [&](Thyra::VectorBase<double>& xs) {
    AdrOptions ao;
    ao.tolerance = scene.solver.adrTolerance;
    ao.maxIterations = scene.solver.adrMaxIterations;
    ao.massSafety = scene.solver.adrMassSafety;
    AdrResult ar;
    try {
      ar = solveAdr(*evaluator, xs, ao);
    } catch (const EvaluationError& e) {
      ar.failure = std::string("dynamic relaxation reached an invalid state: ") + e.what();
    }
    NewtonResult nr;
    nr.converged = ar.converged;
    nr.iterations = static_cast<int>(std::min<long long>(ar.iterations, 2000000000));
    nr.work = ar.iterations;
    nr.residuals = {ar.e1, ar.e2};
    nr.failure = ar.failure;
    return nr;
  };
  const bool adr = scene.solver.method == "ADR";

  LoadStepperOptions so;
  so.loadSteps = scene.solver.loadSteps;
  so.maxCutbacks = scene.solver.maxCutbacks;
  so.minIncrement = scene.solver.minIncrement;
  so.maxTotalSteps = scene.solver.maxTotalSteps;
  so.adaptive = scene.solver.adaptive;
  so.easyIterations = scene.solver.easyIterations;
  so.maxIncrement = scene.solver.maxIncrement;
  so.predictor = scene.solver.predictor;
  // The first step with prescribed motion starts along the tangent dx/dlambda (at 150 x 50 on the
  // damaged plate, starting from the unloaded body put stretch 0.0067 into the bonds next to the
  // loaded particles, past s_cr; the first step stagnated). Dead loads do not need it (it equals
  // Newton's first iteration there).
  so.tangentPredictor = !adr && (scene.problem->rotates() || scene.problem->prescribesDisplacement());
  so.keyPrefix = "Solver/";
  LoadStepper stepper(model, adr ? std::function<NewtonResult(Thyra::VectorBase<double>&)>(adrSolve)
                                 : std::function<NewtonResult(Thyra::VectorBase<double>&)>(newtonSolve),
                      so);
  stepper.setReequilibrationSolve(newtonSolve);
  std::unique_ptr<PeridynamicDamage> damage;
  if (scene.problem->damage) {
    PeridynamicDamageOptions d;
    d.maxBreakRounds = scene.maxBreakRounds;
    d.breakOnStalls = scene.stallBreak;
    d.maxStallBreaks = scene.maxStallBreaks;
    d.stallBreakTolerance = scene.stallBreakTolerance;
    d.reloadTolerance = scene.reloadTolerance;
    damage = std::make_unique<PeridynamicDamage>(*evaluator, d);
    stepper.setDamagePolicy(damage.get());
  }

  res.probes.resize(scene.probes.size());
  for (std::size_t k = 0; k < scene.probes.size(); ++k) res.probes[k].first = scene.probes[k].name;

  if (rank == 0 && !options.quiet)
    std::cout << "perinox: " << scene.title << " | " << res.particles << " particles, " << res.dofs
              << " free DOFs, " << nranks << " rank(s), linear solver " << scene.solver.linearSolverName << std::endl;
  double elapsedBefore = 0;  // wall time of the earlier segments of a resumed run
  int segment = 1;
  if (resume) {
    const auto& st = resume->state;
    StepperState ss;
    ss.step = st.at("step");
    ss.loadFactor = st.at("lambda");
    ss.increment = st.at("increment");
    ss.lastIncrement = st.at("last_increment");
    ss.stallBreaks = st.at("stall_breaks");
    elapsedBefore = st.at("elapsed_s");
    segment = st.at("segment").get<int>() + 1;
    std::vector<StepRecord> records;
    for (const auto& sj : st.at("steps")) records.push_back(stepFromJson(sj));
    for (std::size_t k = 0; k < res.probes.size(); ++k)
      res.probes[k].second = st.at("probes").at(k).get<std::vector<std::pair<double, std::vector<double>>>>();
    evaluator->restoreDamage(resume->broken, st.at("detached").get<std::vector<long long>>(), resume->frozen);
    auto xc = Thyra::createMember(evaluator->get_x_space()), xp = Thyra::createMember(evaluator->get_x_space());
    evaluator->setOwnedFreeValues(*xc, resume->x);
    evaluator->setOwnedFreeValues(*xp, resume->xPrevious);
    stepper.resume(ss, std::move(records), st.at("path_load_factors").get<std::vector<double>>(), *xc, *xp);
    if (rank == 0 && !options.quiet)
      std::cout << "resumed from " << options.restartFrom << " after step " << ss.step << " at load factor "
                << ss.loadFactor << " (" << evaluator->detachedParticles().size() << " detached particle(s))" << std::endl;
  }

  // What each accepted step is seen by: the probes, the console, the stability check, checkpoints.
  ProbeRecorder probes(*evaluator, scene, res);
  ConsoleLines console(scene, rank == 0 && !options.quiet);
  StabilityCheck stability(*evaluator);
  CheckpointWriter checkpointer(options, checkpointFolder, scene, *evaluator, *comm, stepper, res, t0, elapsedBefore, segment);
  stepper.addObserver(&probes);
  stepper.addObserver(&console);
  if (scene.solver.stabilityCheck) stepper.addObserver(&stability);
  if (checkpoints) stepper.addObserver(&checkpointer);
  if (exodus) stepper.addObserver(exodus);  // after the probes: it writes their values

  Solved out;
  out.x = Thyra::createMember(evaluator->get_x_space());
  out.elapsedBefore = elapsedBefore;
  out.segment = segment;
  if (scene.solver.continuation == "Arc Length") {
    Thyra::assign(out.x.ptr(), 0.0);
    out.converged = arcLengthContinuation(scene, evaluator, model, probes, *out.x, out.loadFactor, res, options.quiet, rank);
  } else {
    out.converged = stepper.run();
    res.steps = stepper.records();
    res.pathLoadFactors = stepper.path();
    res.failure = stepper.failure();
    out.loadFactor = stepper.state().loadFactor;
    Thyra::copy(stepper.converged(), out.x.ptr());
  }
  return out;
}

}  // namespace

RunResult runScene(const Scene& scene, const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                   const RunOptions& options) {
  const double t0 = now();
  const int rank = comm->getRank(), nranks = comm->getSize();
  RunResult res;
  res.outputDir = options.outputDir;
  const bool arcLength = scene.solver.continuation == "Arc Length";
  const bool checkpoints = options.checkpointSteps > 0 || options.checkpointSeconds > 0;
  if (arcLength && (checkpoints || !options.restartFrom.empty()))
    throw std::invalid_argument("checkpoints and restarts belong to load stepping: arc-length continuation "
                                "('Solver/Continuation = Arc Length') cannot be checkpointed or resumed");

  // Where the results and checkpoints go, checked first (README, "Output folders"): a folder that
  // is not perinox's, the scene, the checkpoint being resumed, '.', a file or a device is refused
  // before any work, on every rank with rank 0's sentence.
  const FolderPlan output = folderNames(options.outputDir, FolderKind::Output, "--output");
  const std::string checkpointOption = options.checkpointDir.empty() ? "the checkpoint folder" : "--checkpoint-dir";
  const FolderPlan checkpointFolder = folderNames(
      options.checkpointDir.empty() ? output.target + ".checkpoint" : options.checkpointDir, FolderKind::Checkpoint, checkpointOption);
  agreed(*comm, [&] {
    if (rank != 0) return;
    std::vector<ProtectedPath> keep{{scene.file, "the scene file"}, {options.restartFrom, "the checkpoint to resume from"}};
    planFolder(options.outputDir, FolderKind::Output, "--output", keep);
    if (checkpoints) {
      checkDistinct(output, planFolder(checkpointFolder.target, FolderKind::Checkpoint, checkpointOption, {keep[0]}));
    }
  });

  // Everything that can reject the set-up happens before the output folder exists: the linear
  // solver's list first (a misspelt Belos, Ifpack2 or MueLu key would be ignored by Trilinos).
  auto evaluator = buildEvaluator(scene, comm);
  res.particles = scene.problem->disc.size();
  res.dofs = evaluator->numFreeDofs();
  std::optional<Checkpoint> resume;
  if (!options.restartFrom.empty()) resume = readCheckpoint(options.restartFrom, scene, res.dofs, res.particles);

  const std::string staging = output.staging;
  // A run that ends with an error leaves no half-written folder: the staging folder goes with it
  // (unless it holds finished results that could not be moved into place).
  bool keepStaging = false;
  struct StagingGuard {
    const std::string& path;
    const bool& keep;
    bool active;
    ~StagingGuard() {
      std::error_code ec;
      if (active && !keep && fs::is_directory(fs::symlink_status(path, ec))) fs::remove_all(path, ec);
    }
  } stagingGuard{staging, keepStaging, rank == 0};
  agreed(*comm, [&] {
    if (rank != 0) return;
    openStaging(output);
    std::ostringstream xml;
    Teuchos::writeParameterListToXmlOStream(*scene.resolved, xml);
    writeFileAtomic(staging + "/scene.resolved.xml", xml.str());
  });

  // Output/Format = Exodus or Both: fields.e in the staging folder, a time step per converged step.
  std::unique_ptr<ExodusRecorder> exodus;
  if (scene.output.format != "VTU") exodus = std::make_unique<ExodusRecorder>(*evaluator, scene, res, staging);
  comm->barrier();
  const double tSolve = now();
  const Solved solved = solveScene(scene, evaluator, options, checkpointFolder, resume, res, t0, exodus.get());
  comm->barrier();
  const double solveSeconds = now() - tSolve;
  const auto& xConverged = solved.x;
  const double lambda = solved.loadFactor, elapsedBefore = solved.elapsedBefore;
  const int segment = solved.segment;
  const bool ok = solved.converged;
  res.converged = ok;
  evaluator->setLoadFactor(lambda);  // the state written is the last converged one

  // Output of the last converged state.
  const auto u = evaluator->ownedDisplacements(*xConverged);
  if (scene.reference.type != "None") {
    res.hasError = true;
    res.errorU = displacementError(*evaluator, scene.reference, u);
  }
  const bool vtu = scene.output.vtk && scene.output.format != "Exodus";
  agreed(*comm, [&] { writeFields(*evaluator, *xConverged, staging, vtu, rank, nranks); });
  if (exodus) {
    // Arc-length continuation (no load-stepping observers) or no accepted step: the state written.
    if (exodus->steps() == 0) exodus->record(*xConverged, lambda);
    exodus->close();
  }
  res.wallTime = now() - t0 + elapsedBefore;
  RunFacts facts;
  facts.setupSeconds = tSolve - t0;
  facts.solveSeconds = solveSeconds;
  facts.residualSeconds = residualSeconds(*evaluator, *xConverged);
  if (auto wf = evaluator->get_W_factory())
    if (auto pf = wf->getPreconditionerFactory()) facts.twoStage = twoStageStatistics(*pf);
  measureFootprint(*evaluator, *comm, facts);
  facts.ranks = nranks;
  facts.segment = segment;
  if (resume) facts.resumedFrom = {{"checkpoint", options.restartFrom}, {"step", resume->state.at("step")}};
  facts.effects = evaluator->model().effectNames();
  facts.detached = evaluator->detachedParticles();
  agreed(*comm, [&] {
    if (rank != 0) return;
    writeResults(scene, res, facts, options, staging, nranks);
    try {
      commitFolder(output);
    } catch (const OutputPathError&) {
      keepStaging = true;  // the results are complete: the message says where they are
      throw;
    }
    stagingGuard.active = false;
    if (!options.quiet) {
      CoutFormat keep;
      const std::string inexact = inexactSolvesWarning(res.steps);
      if (res.hasError) std::cout << "displacement error e_u = " << res.errorU << " against " << scene.reference.type << "\n";
      if (!inexact.empty()) std::cout << "note: " << inexact << "\n";
      std::cout << (res.converged ? "converged" : "FAILED: " + res.failure) << "; results in " << options.outputDir
                << " (" << std::fixed << std::setprecision(2) << res.wallTime << " s)\n";
    }
  });
  return res;
}

}  // namespace perinox

// The output folder's contents (RunOutput.hpp).
#include "RunOutput.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>  // environ (GNU)

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <queue>
#include <sstream>

#include "Observers.hpp"
#include "perinox/io/HostOutput.hpp"  // historyFields
#include "perinox/io/Output.hpp"
#include "perinox/io/OutputFolder.hpp"

namespace perinox {

namespace fs = std::filesystem;

namespace {

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

/// The residual history up to its first NaN or infinity (JSON has no such numbers; a step whose
/// residual became non-finite says so with "residual_not_finite").
std::vector<double> finitePrefix(const std::vector<double>& r) {
  return {r.begin(), std::find_if(r.begin(), r.end(), [](double v) { return !std::isfinite(v); })};
}

/// fields.csv's columns; with a plastic material also the equivalent plastic strain and the
/// yield flag of the last step (only the effects a scene has get columns).
std::string fieldsHeader(bool plastic) {
  return std::string("id,x,y,z,ux,uy,uz,sxx,syy,szz,sxy,fictitious,damage") + (plastic ? ",eqps,yielded" : "");
}

/// A profile's file name part: its probe's name with spaces as underscores.
std::string profileName(const ProbeDef& probe) {
  std::string fname = probe.name;
  std::replace(fname.begin(), fname.end(), ' ', '_');
  return fname;
}

/// Merges files of rows sorted by their leading id into `out` (under `header` unless empty), in
/// id order, and removes them. One row of each part is held, never the whole body.
void mergeGroup(const std::vector<std::string>& parts, const std::string& header, const std::string& out) {
  std::vector<std::ifstream> in;
  std::vector<std::string> row(parts.size());
  using Head = std::pair<long long, std::size_t>;
  std::priority_queue<Head, std::vector<Head>, std::greater<Head>> next;
  auto advance = [&](std::size_t k) {
    if (std::getline(in[k], row[k]) && !row[k].empty()) next.emplace(std::stoll(row[k]), k);
  };
  for (const auto& p : parts) in.emplace_back(p);
  for (std::size_t k = 0; k < parts.size(); ++k) advance(k);
  std::ofstream o(out);
  if (!header.empty()) o << header << '\n';
  while (!next.empty()) {
    const std::size_t k = next.top().second;
    next.pop();
    o << row[k] << '\n';
    advance(k);
  }
  o.close();
  if (!o) throw std::runtime_error("cannot write '" + out + "'");
  for (std::size_t k = 0; k < parts.size(); ++k) in[k].close(), fs::remove(parts[k]);
}

/// mergeGroup for any number of parts: at most 64 files open at once (groups of 64 merged into
/// intermediate parts first, as many rounds as needed).
void mergeSortedParts(std::vector<std::string> parts, const std::string& header, const std::string& out) {
  constexpr std::size_t kOpen = 64;
  for (int round = 0; parts.size() > kOpen; ++round) {
    std::vector<std::string> merged;
    for (std::size_t g = 0; g < parts.size(); g += kOpen) {
      const std::vector<std::string> group(parts.begin() + g, parts.begin() + std::min(g + kOpen, parts.size()));
      merged.push_back(out + ".round" + std::to_string(round) + "_" + std::to_string(merged.size()) + ".part");
      mergeGroup(group, "", merged.back());
    }
    parts = std::move(merged);
  }
  mergeGroup(parts, header, out);
}

/// The per-rank particle CSVs merged into fields.csv (for plotting) in particle id order, and
/// each Profile probe's per-rank rows into profile_<name>.csv; the parts removed.
void mergeFieldParts(const Scene& scene, const std::string& staging, int nranks) {
  auto partsOf = [&](const std::string& stem) {
    std::vector<std::string> parts;
    for (int r = 0; r < nranks; ++r) parts.push_back(staging + "/" + stem + "_" + std::to_string(r) + ".csv.part");
    return parts;
  };
  const std::string header = fieldsHeader(scene.problem->plastic());
  mergeSortedParts(partsOf("fields"), header, staging + "/fields.csv");
  for (const auto& probe : scene.probes)
    if (probe.quantity == "Profile")
      mergeSortedParts(partsOf("profile_" + profileName(probe)), header,
                       staging + "/profile_" + profileName(probe) + ".csv");
}

/// path.csv: the load factor and every probe at every converged step.
std::string pathCsv(const Scene& scene, const RunResult& res) {
  std::ostringstream path;
  path << "step,load_factor";
  for (std::size_t k = 0; k < res.probes.size(); ++k)
    if (scene.probes[k].quantity != "Profile")
      for (const std::string& c : probeComponents(scene.probes[k], scene.problem->dim())) {
        std::string name = res.probes[k].first;
        std::replace(name.begin(), name.end(), ' ', '_');
        path << ',' << name << '_' << c;
      }
  path << '\n' << std::setprecision(15);
  for (std::size_t i = 0; i < res.pathLoadFactors.size(); ++i) {
    path << i + 1 << ',' << loadOnPath(scene.solver.loadPath, res.pathLoadFactors[i]);
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

}  // namespace

void writeFields(const PeridynamicEvaluator& ev, const Thyra::VectorBase<double>& x, const std::string& dir,
                 bool vtk, int rank, int nranks, const std::vector<ProbeDef>& probes) {
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
  const bool plastic = ev.problem().plastic();
  std::vector<std::string> rows(n);  // this rank's fields.csv rows
  for (std::size_t i = 0; i < n; ++i) {
    const long long p = ev.ownedParticles()[i];
    const int k = ev.problem().index(p);  // its index in the discretisation (p unless distributed)
    pts[i] = d.X[k];
    for (int c = 0; c < D; ++c) disp.values[3 * i + c] = u[i * D + c];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) stress.values[9 * i + 3 * r + c] = outs[i].cauchy(r, c);
    fict.values[i] = d.fictitious[k];
    std::ostringstream csv;
    csv << std::setprecision(12);
    csv << p << ',' << d.X[k][0] << ',' << d.X[k][1] << ',' << d.X[k][2] << ',' << disp.values[3 * i] << ','
        << disp.values[3 * i + 1] << ',' << disp.values[3 * i + 2] << ',' << outs[i].cauchy(0, 0) << ','
        << outs[i].cauchy(1, 1) << ',' << outs[i].cauchy(2, 2) << ',' << outs[i].cauchy(0, 1) << ','
        << static_cast<int>(d.fictitious[k]) << ',' << dmg.values[i];
    if (plastic) csv << ',' << outs[i].eqps << ',' << (outs[i].yielded ? 1 : 0);
    csv << '\n';
    rows[i] = csv.str();
  }
  std::vector<PointField> fields{disp, stress, fict, rk};
  if (damage) fields.push_back(dmg);  // only where the effect is on
  for (auto& f : historyFields(ev.problem(), outs)) fields.push_back(std::move(f));
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
  // The rows in id order (ownedParticles is sorted; the merge on rank 0 relies on it), and each
  // Profile probe's rows of this rank's particles in the region.
  const auto& owned = ev.ownedParticles();
  if (!std::is_sorted(owned.begin(), owned.end())) throw std::logic_error("writeFields: the owned particles are not sorted");
  std::string all;
  for (const auto& r : rows) all += r;
  writeFileAtomic(dir + "/fields_" + std::to_string(rank) + ".csv.part", all);
  for (const auto& probe : probes) {
    if (probe.quantity != "Profile") continue;
    std::vector<int> members(probe.particles);
    std::sort(members.begin(), members.end());
    std::string part;
    for (std::size_t i = 0; i < n; ++i)
      if (std::binary_search(members.begin(), members.end(), static_cast<int>(owned[i]))) part += rows[i];
    writeFileAtomic(dir + "/profile_" + profileName(probe) + "_" + std::to_string(rank) + ".csv.part", part);
  }
}

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
    if (s.stallAtLimit) j["stall_at_limit"] = true;
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
  s.stallAtLimit = j.value("stall_at_limit", false);
  return s;
}

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
  if (std::isfinite(res.limitLoad)) j["limit_load_factor"] = res.limitLoad;
  j["wall_time_s"] = res.wallTime;
  j["run_segments"] = facts.segment;
  if (!facts.resumedFrom.is_null()) j["resumed_from"] = facts.resumedFrom;
  j["effects"] = facts.effects;
  j["linear_solver"] = scene.solver.linearSolverName;
  j["forcing_term"] = scene.solver.forcingTerm;
  if (scene.solver.automatic)
    j["linear_solver_auto"] = {{"preset", scene.solver.linearSolverName}, {"jacobian", scene.solver.jacobian},
                               {"forcing_term", scene.solver.forcingTerm}, {"reason", scene.solver.autoReason}};
  j["jacobian"] = scene.solver.jacobian;
  if (scene.solver.jacobian != "Assembled") j["preconditioner_matrix"] = scene.solver.preconditionerMatrix;
  j["matrix_bytes"] = facts.matrixBytes;
  j["peak_rss_mib_max_rank"] = facts.rssMax;
  j["peak_rss_mib_all_ranks"] = facts.rssSum;
  j["partition"] = facts.partition;
  j["method"] = scene.solver.method;
  j["tolerance"] = scene.solver.tolerance;
  json steps = json::array();
  for (const auto& s : res.steps) {
    steps.push_back(stepJson(s, scene.problem->damage, arcLength));
    if (!scene.solver.loadPath.empty()) {  // the stepper's load factor is the path's pseudo-time
      steps.back()["pseudo_time"] = s.loadFactor;
      steps.back()["load_factor"] = loadOnPath(scene.solver.loadPath, s.loadFactor);
    }
  }
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
  // The cost of a Newton iteration in residual evaluations: Newton's own time (its Jacobians,
  // linear solves and residuals) per iteration; and the whole solve's time per iteration, which
  // also carries the tangent predictor's solve, the first assembly's graph and the output.
  const bool perIteration = facts.residualSeconds > 0 && newtonTotal > 0;
  j["timing"] = {{"setup_s", facts.setupSeconds},
                 {"solve_s", facts.solveSeconds},
                 {"newton_s", facts.newtonSeconds},
                 {"residual_evaluation_s", facts.residualSeconds},
                 {"solve_in_residuals", facts.residualSeconds > 0 ? facts.solveSeconds / facts.residualSeconds : 0.0},
                 {"solve_per_newton_iteration_in_residuals",
                  perIteration ? facts.solveSeconds / facts.residualSeconds / newtonTotal : 0.0}};
  // Absent where no Newton iteration was timed (ADR, arc length, a load reached without one):
  // summary.json holds no null, NaN or infinity.
  if (perIteration && facts.newtonSeconds > 0)
    j["timing"]["newton_iteration_in_residuals"] = facts.newtonSeconds / facts.residualSeconds / newtonTotal;
  j["linear_solves_total"] = solves;
  if (facts.twoStage.setups > 0)
    j["preconditioner"] = {{"type", "Two-Stage"},
                           {"setups", facts.twoStage.setups},
                           {"hierarchies_built", facts.twoStage.hierarchiesBuilt},
                           {"eigenvalue_products", facts.twoStage.eigenvalueProducts},
                           {"operator_diagonals", facts.twoStage.operatorDiagonals},
                           {"levels", facts.twoStage.levels},
                           {"fine_smoothed_hierarchies", facts.twoStage.fineSmoothedHierarchies},
                           {"coarse_entry_hierarchies", facts.twoStage.coarseEntryHierarchies}};
  if (facts.mumps.setups > 0)
    j["preconditioner"] = {{"type", "MUMPS"}, {"setups", facts.mumps.setups}, {"factorizations", facts.mumps.factorizations},
                           {"factorizations_during_solves", facts.mumps.factorizationsDuringSolves},
                           {"self_assembled", facts.mumps.selfAssembled},
                           {"factor_precision", facts.mumps.bytesPerEntry == 4 ? "single" : "double"},
                           {"factor_bytes", facts.mumps.factorBytes},
                           {"double_precision_fallbacks", facts.mumps.doublePrecisionFallbacks},
                           {"factorization_s", facts.mumps.factorSeconds},
                           {"solves", facts.mumps.solves},
                           {"solve_s", facts.mumps.solveSeconds}};
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
    const std::string key = probeKey(scene.probes[k]);
    for (const auto& [lf, v] : res.probes[k].second) list.push_back({{"load_factor", lf}, {key, v}});
    probes[res.probes[k].first] = list;
  }
  j["probes"] = probes;
  if (!res.probeReferences.empty()) {
    json refs = json::object();
    for (const auto& [name, v] : res.probeReferences)
      refs[name] = {{"load_factor", 1.0}, {"displacement", v}, {"reference", scene.reference.type}};
    j["probe_references"] = refs;
  }
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

void writeResults(const Scene& scene, const RunResult& res, const RunFacts& facts, const RunOptions& options,
                  const std::string& staging, int nranks) {
  mergeFieldParts(scene, staging, nranks);
  writeFileAtomic(staging + "/path.csv", pathCsv(scene, res));
  writeFileAtomic(staging + "/summary.json",
                  summaryJson(scene, res, facts).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  writeFileAtomic(staging + "/newton.csv", newtonCsv(res));
  if (!options.quiet) printResidualTable(res);
  if (scene.output.plots && !options.plotScript.empty()) drawPlots(staging, options);
}

}  // namespace perinox

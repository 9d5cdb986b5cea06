// One run of a scene (Simulation.hpp) as a list of verbs over the library: plan the folders,
// build the evaluator, read a checkpoint, open the output, solve (load stepping or arc-length
// continuation, with the driver's observers), write the results and move them into place.
#include "Simulation.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <sys/resource.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "Agreed.hpp"
#include "Checkpoint.hpp"
#include "ExodusResults.hpp"
#include "Observers.hpp"
#include "RunOutput.hpp"
#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/Output.hpp"
#include "perinox/io/OutputFolder.hpp"
#include "perinox/solver/AdrSolver.hpp"
#include "perinox/solver/EvaluatorSetup.hpp"
#include "perinox/solver/NewtonSolver.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"
#include "perinox/stepping/ArcLengthStepper.hpp"
#include "perinox/stepping/LoadStepper.hpp"
#include "perinox/stepping/PeridynamicDamage.hpp"

namespace perinox {

namespace fs = std::filesystem;

namespace {

using StepSolve = std::function<NewtonResult(Thyra::VectorBase<double>&)>;

/// The scene's evaluator with its linear solver and Jacobian mode (EvaluatorSetup.hpp).
Teuchos::RCP<PeridynamicEvaluator> buildEvaluator(const Scene& scene, const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  const auto& s = scene.solver;
  JacobianChoice jacobian;
  if (s.jacobian != "Assembled" && s.method == "Newton") {
    jacobian.mode = s.jacobian == "Matrix-Free" ? JacobianMode::MatrixFree : JacobianMode::JacobianFree;
    jacobian.matrix = s.preconditionerMatrix == "Assembled"    ? PreconditionerMatrix::Assembled
                      : s.preconditionerMatrix == "Neighbours" ? PreconditionerMatrix::Neighbours
                                                               : PreconditionerMatrix::None;
    jacobian.jacobianFreeLambda = s.jfnkLambda;
  }
  return evaluatorWithSolver(comm, scene.problem, *s.linearSolver,
                             s.linearSolverName == "custom" ? std::string() : "preset '" + s.linearSolverName + "'", jacobian);
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
    const double a = wallSeconds();
    ev.evalModel(in, out);
    ev.comm()->barrier();
    t.push_back(wallSeconds() - a);
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
  // Family entries the rank holds (the model's, the families as built, and any global family
  // array of the discretisation: none in a scene's run), against its share: at most twice the
  // owned and ghost particles times the largest family, whatever the body's size.
  const LocalFamilies& F = ev.localFamilies();
  const long long global = static_cast<long long>(ev.problem().disc.familyIndex.size());
  const long long held = global + static_cast<long long>(lp.famIndex.size() + F.ownedIndex.size() + F.ghostMembers.size());
  long long largest = 0;
  for (int l = 0; l < lp.numOwned; ++l) largest = std::max<long long>(largest, F.ownedOffset[l + 1] - F.ownedOffset[l]);
  for (std::size_t k = 0; k + 1 < F.ghostOffset.size(); ++k) largest = std::max<long long>(largest, F.ghostOffset[k + 1] - F.ghostOffset[k]);
  const long long counts[3] = {global, held, held <= 2 * static_cast<long long>(lp.size()) * largest ? 0 : 1};
  long long countsMax[3];
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, 3, counts, countsMax);
  // Particles the rank's discretisation holds: the whole body (Construction = Replicated) or its
  // share (Distributed): the owned particles and those within two horizons of the owned box, i.e.
  // the ghost layer (one horizon), a second layer about as wide, and the box's corners; measured
  // at most 2.7 x the ghosts beyond the owned on every paper scene. A rank above 3 x holds more
  // than its share (on 2 or more ranks, a replicated discretisation does).
  long long heldParticles = ev.problem().disc.size(), heldMax = 0;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, heldParticles, Teuchos::outArg(heldMax));
  const long long beyondShare = heldParticles > lp.numOwned + 3LL * (lp.size() - lp.numOwned) ? 1 : 0;
  long long ranksBeyondShare = 0;
  Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, beyondShare, Teuchos::outArg(ranksBeyondShare));
  facts.partition = {{"method", partitionName(ev.problem().partition)},
                     {"construction", ev.problem().distributed ? "Distributed" : "Replicated"},
                     {"particles_held_max", heldMax}, {"particles", ev.problem().particleCount()},
                     {"ranks_beyond_particle_share", ranksBeyondShare},
                     {"owned_max", most[0]}, {"owned_min", least[0]},
                     {"ghosts_max", most[1]}, {"ghosts_min", least[1]}, {"ghosts_mean", sum[1] / comm.getSize()},
                     {"peak_rss_mib_min_rank", least[2]},
                     {"global_family_entries_max", countsMax[0]}, {"family_entries_max", countsMax[1]},
                     {"ranks_beyond_family_share", countsMax[2]}};
}

/// The scene's Newton controls.
NewtonOptions newtonOptions(const SolverSettings& s) {
  NewtonOptions o;
  o.tolerance = s.tolerance;
  o.maxIterations = s.maxIterations;
  o.lineSearch = s.lineSearch;
  o.verbosity = s.verbosity;
  o.floorFactor = s.floorFactor;
  o.stagnationStop = s.stagnationStop;
  o.forcingTerm = s.forcingTerm;
  o.linearTolerance = s.linearTolerance;
  return o;
}

/// Solver/Method = ADR as a step solve: explicit dynamic relaxation, reported as a Newton result.
StepSolve adrStepSolve(const Scene& scene, const Teuchos::RCP<PeridynamicEvaluator>& evaluator) {
  AdrOptions ao;
  ao.tolerance = scene.solver.adrTolerance;
  ao.maxIterations = scene.solver.adrMaxIterations;
  ao.massSafety = scene.solver.adrMassSafety;
  return [evaluator, ao](Thyra::VectorBase<double>& xs) {
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
}

/// The scene's load-stepping controls, through the stepper's validated list (the tangent
/// predictor when the evaluator prescribes motion on any rank).
LoadStepperOptions loadSteppingOptions(const Scene& scene, const PeridynamicEvaluator& ev) {
  const auto& s = scene.solver;
  const bool adr = s.method == "ADR";
  Teuchos::ParameterList l("Load Stepping");
  const int segments = std::max<int>(1, static_cast<int>(s.loadPath.size()));
  l.set("Load Steps", s.loadSteps * segments);  // the stepper's steps span the whole path
  l.set("Max Cutbacks", s.maxCutbacks);
  l.set("Limit Load Ratio", s.limitLoadRatio);
  l.set("Min Increment", s.minIncrement);
  l.set("Max Total Steps", s.maxTotalSteps);
  l.set("Adaptive Steps", s.adaptive);
  l.set("Easy Iterations", s.easyIterations);
  l.set("Max Increment", s.maxIncrement);
  l.set("Predictor", s.predictor);
  // The first step with prescribed motion starts along the tangent dx/dlambda (at 150 x 50 on the
  // damaged plate, starting from the unloaded body put stretch 0.0067 into the bonds next to the
  // loaded particles, past s_cr; the first step stagnated). Dead loads do not need it (it equals
  // Newton's first iteration there).
  l.set("Tangent Predictor", !adr && (scene.problem->rotates() || ev.prescribesDisplacement()));
  LoadStepperOptions o = LoadStepperOptions::fromParameterList(l, scene.file);
  o.keyPrefix = "Solver/";
  if (!s.loadPath.empty()) o.stops = LoadFactorModel::pathStops(segments);
  // The tangent predictor's system is a starting guess: with the Eisenstat-Walker forcing term it
  // is solved as loosely as Newton's first system may be (1e-3), else to the Linear Tolerance.
  // (1e-2 cost the block of 51 200 particles a fourth Newton iteration; 1e-3 and 1e-12 give three.)
  o.linearTolerance = s.forcingTerm == "Eisenstat-Walker" ? std::max(s.linearTolerance, 1e-3) : s.linearTolerance;
  return o;
}

/// The scene's arc-length controls, through the stepper's validated list.
ArcLengthStepperOptions arcLengthOptions(const Scene& scene) {
  const auto& s = scene.solver;
  Teuchos::ParameterList l("Arc Length");
  l.set("Initial Arc Length", s.arc.initial);
  l.set("Min Arc Length", s.arc.minimum);
  l.set("Max Arc Length", s.arc.maximum);
  l.set("Max Steps", s.arc.maxSteps);
  l.set("Target Load Factor", s.arc.targetLoadFactor);
  l.set("Target Monitor", s.arc.targetDeflection);
  l.set("Max Cutbacks", s.maxCutbacks);
  l.set("Easy Iterations", s.easyIterations);
  l.set("Tolerance", s.tolerance);
  l.set("Max Iterations", s.maxIterations);
  ArcLengthStepperOptions o = ArcLengthStepperOptions::fromParameterList(l, scene.file);
  o.floorFactor = s.floorFactor;
  o.keyPrefix = "Solver/Arc Length/";
  o.monitorName = "deflection";
  return o;
}

/// perinox's damage as the stepper's policy, with the scene's Damage controls.
std::unique_ptr<PeridynamicDamage> damagePolicy(const Scene& scene, PeridynamicEvaluator& evaluator) {
  if (!scene.problem->damage) return nullptr;
  PeridynamicDamageOptions d;
  d.maxBreakRounds = scene.maxBreakRounds;
  d.breakOnStalls = scene.stallBreak;
  d.maxStallBreaks = scene.maxStallBreaks;
  d.stallBreakTolerance = scene.stallBreakTolerance;
  d.reloadTolerance = scene.reloadTolerance;
  d.breakAtSnapBackLimit = scene.breakAtSnapBackLimit;
  return std::make_unique<PeridynamicDamage>(evaluator, d);
}

/// The stepper goes on from a checkpoint: its counters, records, probes, damage and states.
/// Returns the wall time of the earlier segments and this segment's number.
std::pair<double, int> resumeFrom(const Checkpoint& resume, PeridynamicEvaluator& evaluator, LoadStepper& stepper,
                                  RunResult& res, const RunOptions& options) {
  const auto& st = resume.state;
  StepperState ss;
  ss.step = st.at("step");
  ss.loadFactor = st.at("lambda");
  ss.increment = st.at("increment");
  ss.lastIncrement = st.at("last_increment");
  ss.stallBreaks = st.at("stall_breaks");
  ss.atLimit = st.value("at_limit", false);
  ss.initialCompliance = st.value("initial_compliance", 0.0);
  std::vector<StepRecord> records;
  for (const auto& sj : st.at("steps")) records.push_back(stepFromJson(sj));
  for (std::size_t k = 0; k < res.probes.size(); ++k)
    res.probes[k].second = st.at("probes").at(k).get<std::vector<std::pair<double, std::vector<double>>>>();
  evaluator.restoreDamage(resume.broken, st.at("detached").get<std::vector<long long>>(), resume.frozen);
  evaluator.restoreHistory(resume.history);
  auto xc = Thyra::createMember(evaluator.get_x_space()), xp = Thyra::createMember(evaluator.get_x_space());
  evaluator.setOwnedDofValues(*xc, resume.x);
  evaluator.setOwnedDofValues(*xp, resume.xPrevious);
  stepper.resume(ss, std::move(records), st.at("path_load_factors").get<std::vector<double>>(), *xc, *xp);
  if (evaluator.comm()->getRank() == 0 && !options.quiet)
    std::cout << "resumed from " << options.restartFrom << " after step " << ss.step << " at load factor "
              << ss.loadFactor << " (" << evaluator.detachedParticles().size() << " detached particle(s))" << std::endl;
  return {st.at("elapsed_s").get<double>(), st.at("segment").get<int>() + 1};
}

struct Solved {
  Teuchos::RCP<Thyra::VectorBase<double>> x;
  double loadFactor = 0.0;
  bool converged = false;
  double elapsedBefore = 0.0;  // wall time of the earlier segments of a resumed run
  int segment = 1;             // 1, or the runs a checkpointed run was split into
  double newtonSeconds = 0.0;  // wall time inside Newton's solves (not the predictor, output, ...)
};

/// Everything a solve of the scene is given: the evaluator, the load-factor model around it, the
/// driver's options and folders, and the observers every continuation shares.
struct SolveContext {
  const Scene& scene;
  Teuchos::RCP<PeridynamicEvaluator> evaluator;
  Teuchos::RCP<LoadFactorModel> model;
  const RunOptions& options;
  const FolderPlan& checkpointFolder;
  StepObserver& probes;
  StepObserver* exodus;
  bool speak;  // rank 0 and not quiet
};

/// Load stepping: LoadStepper with Newton (or ADR), perinox's damage policy and the driver's
/// observers (probes, console, stability check, checkpoints, Exodus), from zero load or a checkpoint.
Solved loadStepping(const SolveContext& c, const std::optional<Checkpoint>& resume, RunResult& res, double t0) {
  const Scene& scene = c.scene;
  auto newton = Teuchos::rcp(new NewtonSolver(c.model, Teuchos::rcp(new EvaluatorResidualScale(c.evaluator)),
                                              newtonOptions(scene.solver)));
  // Newton's own wall time (Jacobians, linear solves, residuals of its iterations), the numerator
  // of the cost of a Newton iteration in residual evaluations (summary.json "timing").
  auto newtonSeconds = std::make_shared<double>(0.0);
  const StepSolve newtonSolve = [newton, newtonSeconds](Thyra::VectorBase<double>& xs) {
    const double a = wallSeconds();
    NewtonResult r = newton->solve(xs);
    *newtonSeconds += wallSeconds() - a;
    return r;
  };
  LoadStepper stepper(c.model, scene.solver.method == "ADR" ? adrStepSolve(scene, c.evaluator) : newtonSolve,
                      loadSteppingOptions(scene, *c.evaluator));
  stepper.setReequilibrationSolve(newtonSolve);
  if (c.evaluator->hasHistory()) {
    const auto ev = c.evaluator;
    stepper.setHistoryCommit([ev](const Thyra::VectorBase<double>& x) { ev->commitHistory(x); });
  }
  const auto damage = damagePolicy(scene, *c.evaluator);
  if (damage) stepper.setDamagePolicy(damage.get());
  Solved out;
  if (resume) std::tie(out.elapsedBefore, out.segment) = resumeFrom(*resume, *c.evaluator, stepper, res, c.options);

  // What each accepted step is seen by: the probes, the console, the stability check, checkpoints.
  ConsoleLines console(scene, c.speak);
  StabilityCheck stability(*c.evaluator);
  CheckpointWriter checkpointer(c.options, c.checkpointFolder, scene, *c.evaluator, *c.evaluator->comm(), stepper, res,
                                t0, out.elapsedBefore, out.segment);
  stepper.addObserver(&c.probes);
  stepper.addObserver(&console);
  if (scene.solver.stabilityCheck) stepper.addObserver(&stability);
  if (c.options.checkpointSteps > 0 || c.options.checkpointSeconds > 0) stepper.addObserver(&checkpointer);
  if (c.exodus) stepper.addObserver(c.exodus);  // after the probes: it writes their values

  out.converged = stepper.run();
  res.steps = stepper.records();
  res.pathLoadFactors = stepper.path();
  res.failure = stepper.failure();
  res.limitLoad = stepper.limitLoad();
  out.loadFactor = stepper.state().loadFactor;
  out.x = Thyra::createMember(c.evaluator->get_x_space());
  Thyra::copy(stepper.converged(), out.x.ptr());
  out.newtonSeconds = *newtonSeconds;
  return out;
}

/// 'Solver/Continuation = Arc Length': the stepping layer's ArcLengthStepper over the load-factor
/// model from the unloaded state, with the scene's deflection probe as its monitor, the stability
/// check as its pivot count, and the probes and the console as observers.
Solved arcLengthContinuation(const SolveContext& c, RunResult& res) {
  const Scene& scene = c.scene;
  const auto& ev = c.evaluator;
  const auto& A = scene.solver.arc;
  ArcLengthStepper arc(c.model, Teuchos::rcp(new EvaluatorResidualScale(ev)), arcLengthOptions(scene));
  int deflProbe = -1;
  for (std::size_t k = 0; k < scene.probes.size(); ++k)
    if (scene.probes[k].name == A.deflectionProbe) deflProbe = static_cast<int>(k);
  if (deflProbe >= 0)
    arc.setMonitor([&, deflProbe](const Thyra::VectorBase<double>& state) {
      const auto u = ev->ownedDisplacements(state);
      return probeValue(*ev, scene.probes[deflProbe], state, u)[A.deflectionComponent];
    });
  if (scene.solver.stabilityCheck) arc.setStabilityCount([&](const Thyra::VectorBase<double>& s) { return ev->negativePivots(s); });
  if (ev->hasHistory()) arc.setHistoryCommit([ev](const Thyra::VectorBase<double>& x) { ev->commitHistory(x); });
  ArcConsole console(arc, deflProbe >= 0, c.speak);
  arc.addObserver(&c.probes);
  arc.addObserver(&console);
  Solved out;
  out.x = Thyra::createMember(ev->get_x_space());
  Thyra::assign(out.x.ptr(), 0.0);
  out.converged = arc.run(*out.x, out.loadFactor);
  res.steps = arc.records();
  res.pathLoadFactors = arc.path();
  res.failure = arc.failure();
  for (const auto& lp : arc.limitPoints()) res.limitPoints.push_back({lp.step, lp.loadFactor, lp.monitor});
  Thyra::copy(arc.converged(), out.x.ptr());
  out.loadFactor = arc.loadFactor();
  return out;
}

/// The solve: load stepping or arc-length continuation over the evaluator as a load-factor model;
/// fills res's steps, probes and path.
Solved solveScene(const Scene& scene, const Teuchos::RCP<PeridynamicEvaluator>& evaluator, const RunOptions& options,
                  const FolderPlan& checkpointFolder, const std::optional<Checkpoint>& resume, RunResult& res, double t0,
                  StepObserver* exodus) {
  const auto comm = evaluator->comm();
  const bool speak = comm->getRank() == 0 && !options.quiet;
  // The load factor is the evaluator's parameter p(0): the stepper's wrapper passes it to every
  // evaluation, and keeps the evaluator's own (its diagnostics, damage and outputs use it).
  auto model = Teuchos::rcp(new LoadFactorModel(evaluator));
  model->setLoadPath(scene.solver.loadPath);
  model->onLoadFactor([ev = evaluator.get()](double lambda) { ev->setLoadFactor(lambda); });
  res.probes.resize(scene.probes.size());
  for (std::size_t k = 0; k < scene.probes.size(); ++k) res.probes[k].first = scene.probes[k].name;
  if (speak)
    std::cout << "perinox: " << scene.title << " | " << res.particles << " particles, " << res.dofs << " free DOFs, "
              << comm->getSize() << " rank(s), linear solver " << linearSolverPhrase(scene.solver) << std::endl;
  ProbeRecorder probes(*evaluator, scene, res);
  const SolveContext context{scene, evaluator, model, options, checkpointFolder, probes, exodus, speak};
  if (scene.solver.continuation == "Arc Length") return arcLengthContinuation(context, res);
  return loadStepping(context, resume, res, t0);
}

/// The output and checkpoint folders, checked before any work (README, "Output folders"): a
/// folder that is not perinox's, the scene, the checkpoint being resumed, '.', a file or a device
/// is refused on every rank with rank 0's sentence.
struct RunFolders {
  FolderPlan output, checkpoint;
};
RunFolders planRunFolders(const Scene& scene, const RunOptions& options, const Teuchos::Comm<int>& comm) {
  const bool checkpoints = options.checkpointSteps > 0 || options.checkpointSeconds > 0;
  if (scene.solver.continuation == "Arc Length" && (checkpoints || !options.restartFrom.empty()))
    throw std::invalid_argument("checkpoints and restarts belong to load stepping: arc-length continuation "
                                "('Solver/Continuation = Arc Length') cannot be checkpointed or resumed");
  RunFolders f;
  f.output = folderNames(options.outputDir, FolderKind::Output, "--output");
  const std::string checkpointOption = options.checkpointDir.empty() ? "the checkpoint folder" : "--checkpoint-dir";
  f.checkpoint = folderNames(options.checkpointDir.empty() ? f.output.target + ".checkpoint" : options.checkpointDir,
                             FolderKind::Checkpoint, checkpointOption);
  agreed(comm, [&] {
    if (comm.getRank() != 0) return;
    std::vector<ProtectedPath> keep{{scene.file, "the scene file"}, {options.restartFrom, "the checkpoint to resume from"}};
    planFolder(options.outputDir, FolderKind::Output, "--output", keep);
    if (checkpoints) checkDistinct(f.output, planFolder(f.checkpoint.target, FolderKind::Checkpoint, checkpointOption, {keep[0]}));
  });
  return f;
}

/// A run that ends with an error leaves no half-written folder: the staging folder goes with it
/// (unless it holds finished results that could not be moved into place: keep).
struct StagingGuard {
  std::string path;
  bool active;
  bool keep = false;
  ~StagingGuard() {
    std::error_code ec;
    if (active && !keep && fs::is_directory(fs::symlink_status(path, ec))) fs::remove_all(path, ec);
  }
};

/// What summary.json reports about the run beyond its steps.
RunFacts runFacts(const PeridynamicEvaluator& evaluator, const Thyra::VectorBase<double>& x, const Solved& solved,
                  const std::optional<Checkpoint>& resume, const RunOptions& options) {
  RunFacts facts;
  facts.residualSeconds = residualSeconds(evaluator, x);
  forPreconditionerFactories(evaluator, [&](const Thyra::PreconditionerFactoryBase<double>& pf) {
    facts.twoStage = twoStageStatistics(pf);
    facts.mumps = mumpsPreconditionerStatistics(pf);
  });
  measureFootprint(evaluator, *evaluator.comm(), facts);
  facts.ranks = evaluator.comm()->getSize();
  facts.segment = solved.segment;
  if (resume) facts.resumedFrom = {{"checkpoint", options.restartFrom}, {"step", resume->state.at("step")}};
  facts.effects = evaluator.model().effectNames();
  facts.detached = evaluator.detachedParticles();
  return facts;
}

/// Rank 0: the results into the staging folder, the folder into place, the closing lines.
void commitResults(const Scene& scene, const RunResult& res, const RunFacts& facts, const RunOptions& options,
                   const FolderPlan& output, StagingGuard& staging, const Teuchos::Comm<int>& comm) {
  agreed(comm, [&] {
    if (comm.getRank() != 0) return;
    writeResults(scene, res, facts, options, output.staging, comm.getSize());
    try {
      commitFolder(output);
    } catch (const OutputPathError&) {
      staging.keep = true;  // the results are complete: the message says where they are
      throw;
    }
    staging.active = false;
    if (options.quiet) return;
    CoutFormat keep;
    const std::string inexact = inexactSolvesWarning(res.steps);
    if (res.hasError) std::cout << "displacement error e_u = " << res.errorU << " against " << scene.reference.type << "\n";
    if (!inexact.empty()) std::cout << "note: " << inexact << "\n";
    const std::string end = res.converged ? "converged" : std::isfinite(res.limitLoad) ? "STOPPED: " + res.failure : "FAILED: " + res.failure;
    std::cout << end << "; results in " << options.outputDir << " ("
              << std::fixed << std::setprecision(2) << res.wallTime << " s)\n";
  });
}

}  // namespace

RunResult runScene(const Scene& scene, const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const RunOptions& options) {
  const double t0 = wallSeconds();
  const int rank = comm->getRank();
  const RunFolders folders = planRunFolders(scene, options, *comm);

  // Everything that can reject the set-up happens before the output folder exists.
  auto evaluator = buildEvaluator(scene, comm);
  RunResult res;
  res.outputDir = options.outputDir;
  res.particles = scene.problem->particleCount();
  res.dofs = evaluator->numFreeDofs();
  std::optional<Checkpoint> resume;
  if (!options.restartFrom.empty())
    resume = readCheckpoint(options.restartFrom, scene, res.dofs, res.particles,
                            evaluator->hasHistory() ? evaluator->model().stateDoublesPerParticle() : 0,
                            evaluator->ownedParticles(), *comm);

  const std::string& staging = folders.output.staging;
  StagingGuard stagingGuard{staging, rank == 0};
  agreed(*comm, [&] {
    if (rank != 0) return;
    openStaging(folders.output);
    writeFileAtomic(staging + "/scene.resolved.xml", resolvedSceneText(scene));
  });
  // Output/Format = Exodus or Both: fields.e in the staging folder, a time step per converged step.
  std::unique_ptr<ExodusRecorder> exodus;
  if (scene.output.format != "VTU") exodus = std::make_unique<ExodusRecorder>(*evaluator, scene, res, staging);

  comm->barrier();
  const double tSolve = wallSeconds();
  const Solved solved = solveScene(scene, evaluator, options, folders.checkpoint, resume, res, t0, exodus.get());
  comm->barrier();
  const double solveSeconds = wallSeconds() - tSolve;
  res.converged = solved.converged;
  evaluator->setLoadFactor(solved.loadFactor);  // the state written is the last converged one

  // Output of the last converged state.
  const auto& x = *solved.x;
  if (scene.reference.type != "None") {
    res.hasError = true;
    res.errorU = displacementError(*evaluator, scene.reference, evaluator->ownedDisplacements(x));
    for (const ProbeDef& probe : scene.probes)
      if (probe.quantity == "Displacement")
        res.probeReferences.emplace_back(probe.name, referenceProbeValue(*evaluator, probe, scene.reference));
  }
  const bool vtu = scene.output.vtk && scene.output.format != "Exodus";
  agreed(*comm, [&] { writeFields(*evaluator, x, staging, vtu, rank, comm->getSize(), scene.probes); });
  if (exodus) {
    // Arc-length continuation (no load-stepping observers) or no accepted step: the state written.
    if (exodus->steps() == 0) exodus->record(x, solved.loadFactor);
    exodus->close();
  }
  res.wallTime = wallSeconds() - t0 + solved.elapsedBefore;
  RunFacts facts = runFacts(*evaluator, x, solved, resume, options);
  facts.setupSeconds = tSolve - t0;
  facts.solveSeconds = solveSeconds;
  facts.newtonSeconds = solved.newtonSeconds;
  commitResults(scene, res, facts, options, folders.output, stagingGuard, *comm);
  return res;
}

}  // namespace perinox

// perinox: solve a quasi-static peridynamics scene.
//
// Sample runs:
//   perinox run xml/cantilever.xml
//   perinox run xml/cantilever.xml --set Discretization/Horizon\ Factor=2.015 --output out/c2
//   mpirun -np 2 perinox run xml/hydrostatic.xml
//   perinox schema [--json]   (every scene key with its default and meaning; --json: for programs, with allowed values)
//
// Exit codes: 0 converged; 2 invalid input (nothing written); 3 a load step failed for good
// (the last converged state is written, with the reason in summary.json); 1 internal error.
#include <Teuchos_DefaultComm.hpp>
#include <Tpetra_Core.hpp>
#include <mpi.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "Simulation.hpp"
#include "perinox/io/OutputFolder.hpp"
#include "perinox/io/PeridigmDeck.hpp"
#include "perinox/io/Scene.hpp"
#include "perinox/solver/AutoLinearSolver.hpp"
#include "perinox/model/Model.hpp"

namespace {

int usage(int code) {
  (code == 0 ? std::cout : std::cerr)
      << "usage: perinox run SCENE.xml [--set Sublist/Key=value]... [--output DIR] [--quiet]\n"
         "                  [--checkpoint-steps N] [--checkpoint-seconds S] [--checkpoint-dir DIR]\n"
         "                  [--restart CHECKPOINT_DIR]\n"
         "       perinox check SCENE.xml [--set Sublist/Key=value]...  validate the scene (mesh, regions, conditions,\n"
         "                  rigid-body modes, solver keys) and say what it holds, without solving or writing\n"
         "       perinox convert DECK [--out SCENE.xml]  write the scene a Peridigm deck (XML or YAML) makes\n"
         "                  (default: beside the deck, DECK's name with .scene.xml); run and check take decks too\n"
         "       perinox schema     every scene key with its default and meaning (--json: as JSON, with allowed values)\n"
         "       perinox --help\n"
         "checkpoints (load stepping): after a converged step, every N steps and/or S seconds, into\n"
         "DIR (default: the output folder + .checkpoint), each replacing the last when complete;\n"
         "--restart resumes from one with the same scene and --set options, on any number of ranks\n"
         "exit codes: 0 converged; 2 invalid input (nothing written); 3 a step failed for good\n"
         "(last converged state written, reason in summary.json); 1 internal error\n";
  return code;
}

/// A message as one line: line breaks and runs of blanks become one space, at most 500 characters (messages are written to stay near 300 with their paths)
/// (a message is one sentence; this guards against a library's multi-line text).
std::string oneLine(const std::string& text) {
  std::string s;
  for (char c : text) {
    const bool blank = c == '\n' || c == '\r' || c == '\t' || c == ' ';
    if (blank) {
      if (!s.empty() && s.back() != ' ') s += ' ';
    } else {
      s += c;
    }
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s.size() > 500 ? s.substr(0, 497) + "..." : s;
}

std::string envOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

/// The scenes and linear-solver presets: $PERINOX_XML_DIR, else <exe dir>/../share/perinox/xml
/// (an installed driver), else the source tree this driver was built from.
std::string xmlDirectory() {
  std::error_code ec;
  const auto installed = std::filesystem::read_symlink("/proc/self/exe", ec).parent_path() / "../share/perinox/xml";
  const bool useInstalled = !ec && std::filesystem::is_directory(installed, ec);
  return envOr("PERINOX_XML_DIR", useInstalled ? installed.lexically_normal().string() : PERINOX_SOURCE_DIR "/xml");
}

/// Before MPI and Kokkos see the arguments: --help (Kokkos answers it with its own options) and
/// Kokkos' own options, refused (perinox runs Kokkos' Serial back end and takes none of them;
/// Kokkos would otherwise act on them, or print pages of help, before perinox could say
/// anything). MPI is not up yet, so the launcher's rank decides who speaks. -1: go on.
int beforeMpi(int argc, char** argv) {
  const char* launcherRank = std::getenv("OMPI_COMM_WORLD_RANK");
  const bool speaker = !launcherRank || std::string(launcherRank) == "0";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") return speaker ? usage(0) : 0;
    for (const char* k : {"--kokkos", "--threads", "--numa", "--device-id", "--num-devices", "--tune-internals",
                          "--disable-warnings", "--tools-"})
      if (a.rfind(k, 0) == 0) {
        if (speaker)
          std::cerr << "perinox: '" << oneLine(a.substr(0, 60)) << "' is a Kokkos option, which perinox does not take "
                    << "(it runs Kokkos' Serial back end; perinox --help lists its options)\n";
        return 2;
      }
  }
  return -1;
}

/// What `perinox run` was asked to do.
struct RunCommand {
  std::string scenePath;
  std::vector<std::string> overrides;
  perinox::RunOptions options;
};

/// --checkpoint-steps N or --checkpoint-seconds S into the options; "" or the refusal.
std::string checkpointInterval(const std::string& flag, const std::string& text, perinox::RunOptions& opt) {
  std::size_t used = 0;
  double v = -1;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const bool steps = flag == "--checkpoint-steps";
  if (used != text.size() || !(v > 0) || !std::isfinite(v) || (steps && (v > 1e9 || v != static_cast<int>(v))))
    return flag + " needs a positive " + (steps ? "whole number" : "number") + ", not '" + text.substr(0, 40) + "'";
  if (steps)
    opt.checkpointSteps = static_cast<int>(v);
  else
    opt.checkpointSeconds = v;
  return "";
}

/// `run SCENE [options]` (args[0] is "run"): "" or the sentence refusing them.
std::string parseRun(const std::vector<std::string>& args, RunCommand& cmd) {
  if (args.size() < 2) return "'perinox run' needs a scene file: perinox run SCENE.xml [options]";
  cmd.scenePath = args[1];
  perinox::RunOptions& opt = cmd.options;
  opt.outputDir = "";
  for (std::size_t i = 2; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool valued = a == "--set" || a == "--output" || a == "--checkpoint-dir" || a == "--restart" ||
                        a == "--checkpoint-steps" || a == "--checkpoint-seconds";
    if (a == "--quiet") {
      opt.quiet = true;
    } else if (valued && i + 1 == args.size()) {
      return a + " needs a value";
    } else if (!valued) {
      return "unknown argument '" + a.substr(0, 60) + "' (perinox --help lists the options)";
    } else if (a == "--set") {
      cmd.overrides.push_back(args[++i]);
    } else if (a == "--output") {
      opt.outputDir = args[++i];
    } else if (a == "--checkpoint-dir") {
      opt.checkpointDir = args[++i];
    } else if (a == "--restart") {
      opt.restartFrom = args[++i];
    } else if (const std::string bad = checkpointInterval(a, args[i + 1], opt); !bad.empty()) {
      return bad;
    } else {
      ++i;
    }
  }
  if (opt.outputDir.empty()) {
    std::string stem = cmd.scenePath.substr(cmd.scenePath.find_last_of('/') + 1);
    stem = stem.substr(0, stem.rfind('.'));
    opt.outputDir = "out/" + stem;
  }
  // PERINOX_PLOT_SCRIPT set and empty: no plots (the tests' setting).
  const char* plotScript = std::getenv("PERINOX_PLOT_SCRIPT");
  opt.plotScript = plotScript ? plotScript : PERINOX_SOURCE_DIR "/drivers/plot_result.py";
  return "";
}

/// Runs the scene and writes its folder; the exit code. Errors of the set-up and the agreed ones
/// (every rank throws the same sentence) end every rank with one sentence; anything else on one
/// rank alone could leave the others waiting in a collective, so it ends the whole job.
template <class Refuse>
int runAndWrite(const perinox::Scene& scene, const RunCommand& cmd, const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
                const Refuse& refuse) {
  try {
    return perinox::runScene(scene, comm, cmd.options).converged ? 0 : 3;
  } catch (const perinox::OutputPathError& e) {
    return refuse(std::string("error: ") + e.what());
  } catch (const perinox::EvaluationError& e) {
    return refuse("error in " + cmd.scenePath + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    return refuse("error in " + cmd.scenePath + ": " + e.what());
  } catch (const std::exception& e) {
    std::cerr << "perinox: internal error" << (comm->getSize() > 1 ? " on rank " + std::to_string(comm->getRank()) : std::string())
              << ": " << oneLine(e.what()) << "\n";
    if (comm->getSize() > 1) MPI_Abort(MPI_COMM_WORLD, 1);
    return 1;
  }
}

/// The scene schema as JSON, for programs (the fuzzers, documentation tables): one object per key,
/// "Sublist/Key" (a named sublist's template as "*": "Regions/*/Type") -> type, default, doc and,
/// for an enumerated key, its values. The presets are the files of xml/solvers and "custom".
nlohmann::json schemaJson(const Teuchos::ParameterList& list, const std::string& prefix, const std::string& presetDir) {
  nlohmann::json out = nlohmann::json::object();
  for (auto it = list.begin(); it != list.end(); ++it) {
    const std::string name = list.name(it) == "<name>" ? "*" : list.name(it);
    const Teuchos::ParameterEntry& e = list.entry(it);
    if (e.isList()) {
      out.update(schemaJson(Teuchos::getValue<Teuchos::ParameterList>(e), prefix + name + "/", presetDir));
      continue;
    }
    nlohmann::json k = {{"type", e.getAny(false).typeName()}, {"default", Teuchos::toString(e.getAny(false))},
                        {"doc", e.docString()}};
    if (e.validator() != Teuchos::null && e.validator()->validStringValues() != Teuchos::null)
      k["values"] = std::vector<std::string>(e.validator()->validStringValues()->begin(), e.validator()->validStringValues()->end());
    out[prefix + name] = k;
  }
  if (prefix.empty() && out.contains("Solver/Linear Solver Preset")) {
    std::vector<std::string> presets{"auto", "custom"};
    std::error_code ec;
    for (const auto& f : std::filesystem::directory_iterator(presetDir, ec))
      if (f.path().extension() == ".xml") presets.push_back(f.path().stem().string());
    std::sort(presets.begin(), presets.end());
    out["Solver/Linear Solver Preset"]["values"] = presets;
  }
  return out;
}

/// perinox check's estimate of the run's cost with its linear solver (estimateRun: rough power
/// laws, docs/choosing-a-solver.md "Estimates"). Collective.
std::string estimateLine(const perinox::Scene& scene, const perinox::ProblemSpec& P, const Teuchos::Comm<int>& comm) {
  const perinox::SolverSettings& s = scene.solver;
  if (s.method == "ADR") return "  estimate: ADR (no estimate; docs/performance.md, \"Implicit against explicit\")";
  const perinox::SolverFeatures f = perinox::solverFeatures(comm, P, scene.inputFile.empty(), false, false);
  const perinox::RunEstimate e = perinox::estimateRun(f, {s.linearSolverName, s.jacobian, s.forcingTerm, ""});
  const long long steps = s.continuation == "Arc Length" ? s.arc.maxSteps : static_cast<long long>(s.loadSteps) *
                                                                                   std::max<std::size_t>(1, s.loadPath.size());
  std::ostringstream os;
  os << "  estimate (rough, one core; docs/choosing-a-solver.md): peak memory about " << std::fixed << std::setprecision(0) << e.peakMiB
     << " MiB, a Newton iteration about " << std::defaultfloat << std::setprecision(2) << e.secondsPerNewton << " s; "
     << steps << (s.continuation == "Arc Length" ? " arc-length steps at most" : " load steps") << " at 2-6 iterations each: "
     << std::setprecision(2) << 2.0 * steps * e.secondsPerNewton << " to " << 6.0 * steps * e.secondsPerNewton << " s";
  return os.str();
}

/// `perinox check SCENE [--set ...]`: reads and validates the scene as `run` does (the mesh or
/// particle file, regions, conditions, rigid-body modes, solver keys), prints what it holds, and
/// solves nothing and writes nothing. Exit 0, or 2 with the sentence `run` would give.
template <class Refuse>
int checkScene(const std::vector<std::string>& args, const Teuchos::RCP<const Teuchos::Comm<int>>& comm,
               const Refuse& refuse) {
  if (args.size() < 2) return refuse("'perinox check' needs a scene file: perinox check SCENE.xml [--set Sublist/Key=value]...");
  std::vector<std::string> overrides;
  for (std::size_t i = 2; i < args.size(); ++i) {
    if (args[i] != "--set") return refuse("unknown argument '" + args[i].substr(0, 60) + "' (perinox check takes --set Sublist/Key=value)");
    if (i + 1 == args.size()) return refuse("--set needs a value");
    overrides.push_back(args[++i]);
  }
  perinox::Scene scene;
  try {
    scene = perinox::loadScene(args[1], overrides, xmlDirectory() + "/solvers", comm);
  } catch (const std::exception& e) {
    return refuse(std::string("error: ") + e.what());
  }
  const perinox::ProblemSpec& P = *scene.problem;
  const int dim = P.disc.dim;
  // Counts over the ranks: owned particles only (a distributed share also holds ghosts).
  auto sum = [&](long long v) {
    long long total = v;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, v, Teuchos::outArg(total));
    return total;
  };
  const long long fixedDofs = perinox::prescribedDofCount(*comm, P);
  long long fictitious = 0;
  for (int i = 0; i < P.disc.size(); ++i) fictitious += P.owns(P.distributed ? P.globalId[i] : i) && P.disc.fictitious[i] != 0;
  fictitious = sum(fictitious);
  std::vector<std::pair<std::string, long long>> regions;
  for (const auto& [name, ids] : scene.regions) {
    long long n = 0;
    for (int g : ids) n += P.owns(g);
    regions.emplace_back(name, sum(n));
  }
  const std::string estimate = estimateLine(scene, P, *comm);  // collective
  if (comm->getRank() != 0) return 0;
  const long long particles = P.particleCount();
  std::cout << "perinox check: " << args[1] << " is a valid scene (nothing solved, nothing written)\n"
            << "  title: " << scene.title << "\n"
            << "  " << dim << "D, " << particles << " particles (" << fictitious << " fictitious), horizon " << P.disc.horizon
            << ", spacing " << P.disc.dx << "\n"
            << "  unknowns: " << particles * dim - fixedDofs << " free, " << fixedDofs << " prescribed"
            << "; the conditions leave no rigid-body motion free\n"
            << "  effects: " << (P.plastic() ? "plasticity" : "elastic") << (P.damage ? ", damage" : "")
            << (P.blocks.empty() ? "" : ", " + std::to_string(P.blocks.size()) + " blocks") << "\n"
            << "  solver: " << scene.solver.method << ", " << scene.solver.continuation << ", linear solver "
            << linearSolverPhrase(scene.solver) << "\n"
            << estimate << "\n"
            << "  regions (particles):";
  for (const auto& [name, n] : regions) std::cout << " '" << name << "' " << n << ";";
  std::cout << "\n";
  return 0;
}

/// `perinox convert DECK [--out SCENE.xml]`: the scene a Peridigm deck makes, written through a
/// temporary file beside it and renamed into place when complete (rank 0). Nothing is solved and
/// the mesh is not read (its existence is checked). Exit 0, or 2 with one sentence.
template <class Refuse>
int convertDeck(const std::vector<std::string>& args, const Teuchos::RCP<const Teuchos::Comm<int>>& comm, const Refuse& refuse) {
  namespace fs = std::filesystem;
  if (args.size() < 2) return refuse("'perinox convert' needs a Peridigm deck: perinox convert DECK [--out SCENE.xml]");
  const std::string deck = args[1];
  std::string out;
  for (std::size_t i = 2; i < args.size(); ++i) {
    if (args[i] != "--out") return refuse("unknown argument '" + args[i].substr(0, 60) + "' (perinox convert takes --out SCENE.xml)");
    if (i + 1 == args.size()) return refuse("--out needs a value");
    out = args[++i];
  }
  if (out.empty() && args.size() > 3) return refuse("--out is empty; give the scene's path");
  if (out.empty()) {
    const fs::path d(deck);
    out = (d.parent_path() / d.stem()).string() + ".scene.xml";
  }
  Teuchos::ParameterList scene;
  try {
    const Teuchos::ParameterList pl = perinox::readSceneList(deck);
    if (!perinox::isPeridigmDeck(pl))
      return refuse(deck + ": is a perinox scene, not a Peridigm deck (perinox convert translates Peridigm decks)");
    const perinox::PeridigmScene made = perinox::sceneFromPeridigmDeck(pl, deck);
    if (made.kinematicOnly)
      return refuse(deck + " (a Peridigm deck): 'Solver/Verlet' is explicit dynamics; perinox runs such a deck only when every "
                           "displacement is prescribed, which it checks on the mesh: use perinox run or check on the deck itself");
    scene = made.scene;
  } catch (const std::exception& e) {
    return refuse(std::string("error: ") + e.what());
  }
  std::error_code ec;
  if (fs::is_directory(out, ec)) return refuse("--out " + out.substr(0, 200) + " is a folder; give the scene file's path");
  if (fs::exists(out, ec) && fs::equivalent(out, deck, ec)) return refuse("--out " + out.substr(0, 200) + " is the deck itself");
  // An existing file is replaced only if it is a scene perinox convert wrote (a user's file never).
  if (fs::exists(out, ec)) {
    std::ifstream old(out, std::ios::binary);
    std::string head(std::size_t(16) << 20, '\0');  // a scene's size limit
    old.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(old.gcount()));
    if (head.rfind("<ParameterList name=\"perinox\">", 0) != 0 || head.find("value=\"Translated from the Peridigm deck ") == std::string::npos)
      return refuse("--out " + out.substr(0, 200) + " exists and is not a scene perinox convert wrote; name a new file or move it");
  }
  const fs::path parent = fs::absolute(out, ec).parent_path();
  if (!fs::is_directory(parent, ec)) return refuse("--out " + out.substr(0, 200) + ": its folder does not exist");
  if (comm->getRank() != 0) return 0;
  const std::string tmp = out + ".partial";
  {
    std::ofstream f(tmp, std::ios::binary);
    f << perinox::sceneXml(scene);
    if (!f.flush()) {
      fs::remove(tmp, ec);
      return refuse("cannot write the scene " + out.substr(0, 200));
    }
  }
  fs::rename(tmp, out, ec);
  if (ec) {
    fs::remove(tmp, ec);
    return refuse("cannot write the scene " + out.substr(0, 200));
  }
  auto count = [&](const char* list) { return scene.isSublist(list) ? scene.sublist(list).numParams() : 0; };
  std::cout << "perinox convert: wrote " << out << " (" << scene.get<std::string>("Title") << "): " << count("Regions") << " regions, "
            << count("Boundary Conditions") << " conditions, " << count("Loads") << " loads, " << count("Probes") << " probes"
            << (count("Blocks") ? ", " + std::to_string(count("Blocks")) + " blocks with their own materials" : std::string()) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (const int early = beforeMpi(argc, argv); early >= 0) return early;
  Tpetra::ScopeGuard mpi(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const bool root = comm->getRank() == 0;
  const std::vector<std::string> args(argv + 1, argv + argc);
  auto refuse = [&](const std::string& msg) {
    if (root) std::cerr << "perinox: " << oneLine(msg) << "\n";
    return 2;
  };
  const std::string usageLine = "usage: perinox run SCENE.xml [options] (perinox --help lists them)";
  if (args.empty()) return refuse("no command given; " + usageLine);
  if (args[0] == "schema") {
    if (args.size() > 2 || (args.size() == 2 && args[1] != "--json"))
      return refuse("usage: perinox schema [--json]");
    if (!root) return 0;
    if (args.size() == 2)
      std::cout << schemaJson(*perinox::sceneSchema(), "", xmlDirectory() + "/solvers").dump(1) << "\n";
    else
      perinox::sceneSchema()->print(std::cout, Teuchos::ParameterList::PrintOptions().showDoc(true).indent(2).showTypes(true));
    return 0;
  }
  if (args[0] == "check") return checkScene(args, comm, refuse);
  if (args[0] == "convert") return convertDeck(args, comm, refuse);
  if (args[0] != "run") return refuse("unknown command '" + args[0].substr(0, 60) + "'; " + usageLine);

  // Set up: the command line, then the scene (validated completely before any work).
  RunCommand cmd;
  if (const std::string bad = parseRun(args, cmd); !bad.empty()) return refuse(bad);
  perinox::Scene scene;
  try {
    scene = perinox::loadScene(cmd.scenePath, cmd.overrides, xmlDirectory() + "/solvers", comm);
  } catch (const std::exception& e) {
    return refuse(std::string("error: ") + e.what());
  }
  // Run and write.
  return runAndWrite(scene, cmd, comm, refuse);
}

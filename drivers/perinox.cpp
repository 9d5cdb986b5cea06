// perinox: solve a quasi-static peridynamics scene.
//
// Sample runs:
//   perinox run xml/cantilever.xml
//   perinox run xml/cantilever.xml --set Discretization/Horizon\ Factor=2.015 --output out/c2
//   mpirun -np 2 perinox run xml/hydrostatic.xml
//   perinox schema            (every scene key with its default and meaning)
//
// Exit codes: 0 converged; 2 invalid input (nothing written); 3 a load step failed for good
// (the last converged state is written, with the reason in summary.json); 1 internal error.
#include <Teuchos_DefaultComm.hpp>
#include <Tpetra_Core.hpp>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "Simulation.hpp"
#include "perinox/model/Model.hpp"

namespace {

int usage(int code) {
  (code == 0 ? std::cout : std::cerr)
      << "usage: perinox run SCENE.xml [--set Sublist/Key=value]... [--output DIR] [--quiet]\n"
         "                  [--checkpoint-steps N] [--checkpoint-seconds S] [--checkpoint-dir DIR]\n"
         "                  [--restart CHECKPOINT_DIR]\n"
         "       perinox schema     every scene key with its default and meaning\n"
         "       perinox --help\n"
         "checkpoints (load stepping): after a converged step, every N steps and/or S seconds, into\n"
         "DIR (default: the output folder + .checkpoint), each replacing the last when complete;\n"
         "--restart resumes from one with the same scene and --set options, on any number of ranks\n"
         "exit codes: 0 converged; 2 invalid input (nothing written); 3 a step failed for good\n"
         "(last converged state written, reason in summary.json); 1 internal error\n";
  return code;
}

std::string envOr(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

}  // namespace

int main(int argc, char** argv) {
  // Before Kokkos sees the arguments: it answers --help with its own options.
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return usage(0);
  Tpetra::ScopeGuard mpi(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const bool root = comm->getRank() == 0;
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return root ? usage(2) : 2;
  if (args[0] == "schema") {
    if (root) perinox::sceneSchema()->print(std::cout, Teuchos::ParameterList::PrintOptions().showDoc(true).indent(2).showTypes(true));
    return 0;
  }
  if (args[0] != "run" || args.size() < 2) return root ? usage(2) : 2;

  std::string scenePath = args[1];
  std::vector<std::string> overrides;
  perinox::RunOptions opt;
  opt.outputDir = "";
  for (std::size_t i = 2; i < args.size(); ++i) {
    if (args[i] == "--set" && i + 1 < args.size()) {
      overrides.push_back(args[++i]);
    } else if (args[i] == "--output" && i + 1 < args.size()) {
      opt.outputDir = args[++i];
    } else if (args[i] == "--quiet") {
      opt.quiet = true;
    } else if ((args[i] == "--checkpoint-steps" || args[i] == "--checkpoint-seconds") && i + 1 < args.size()) {
      const std::string flag = args[i], text = args[++i];
      std::size_t used = 0;
      double v = -1;
      try {
        v = std::stod(text, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      const bool steps = flag == "--checkpoint-steps";
      if (used != text.size() || !(v > 0) || (steps && v != static_cast<int>(v))) {
        if (root) std::cerr << "perinox: " << flag << " needs a positive " << (steps ? "whole number" : "number")
                            << ", not '" << text << "'\n";
        return 2;
      }
      if (steps)
        opt.checkpointSteps = static_cast<int>(v);
      else
        opt.checkpointSeconds = v;
    } else if (args[i] == "--checkpoint-dir" && i + 1 < args.size()) {
      opt.checkpointDir = args[++i];
    } else if (args[i] == "--restart" && i + 1 < args.size()) {
      opt.restartFrom = args[++i];
    } else {
      if (root) std::cerr << "perinox: unknown argument '" << args[i] << "'\n";
      return root ? usage(2) : 2;
    }
  }
  if (opt.outputDir.empty()) {
    std::string stem = scenePath.substr(scenePath.find_last_of('/') + 1);
    stem = stem.substr(0, stem.rfind('.'));
    opt.outputDir = "out/" + stem;
  }
  const std::string xmlDir = envOr("PERINOX_XML_DIR", PERINOX_SOURCE_DIR "/xml");
  opt.plotScript = envOr("PERINOX_PLOT_SCRIPT", PERINOX_SOURCE_DIR "/drivers/plot_result.py");

  perinox::Scene scene;
  try {
    scene = perinox::loadScene(scenePath, overrides, xmlDir + "/solvers");
  } catch (const std::exception& e) {
    if (root) std::cerr << "perinox: error: " << e.what() << "\n";
    return 2;
  }
  try {
    const auto r = perinox::runScene(scene, comm, opt);
    return r.converged ? 0 : 3;
  } catch (const perinox::EvaluationError& e) {
    if (root) std::cerr << "perinox: error in " << scenePath << ": " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    if (root) std::cerr << "perinox: error in " << scenePath << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    if (root) std::cerr << "perinox: internal error: " << e.what() << "\n";
    return 1;
  }
}

#pragma once
// Scene files: a Teuchos XML parameter list describing one problem. This module validates a
// scene completely before any work (unknown keys, wrong types, malformed numbers, impossible
// values, references to undefined regions, no constraint against rigid motion) and turns it
// into a ProblemSpec plus solver, probe and output settings.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_Comm.hpp>
#include <Teuchos_RCP.hpp>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "perinox/evaluator/Problem.hpp"

namespace perinox {

/// A problem with the input: the message names the file and the key.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ProbeDef {
  std::string name;
  std::string quantity;          // "Displacement" (mean over the region) or "Reaction" (sum)
  std::vector<int> particles;
};

/// An analytic reference displacement u_ref(X) = H (X - center).
struct ReferenceDef {
  std::string type = "None";     // "None", "Hydrostatic Hencky", "Uniform Stretch", "Affine"
  double stretch = 1.0;          // x = l / l0 (Hydrostatic Hencky, Uniform Stretch)
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Vec3 center = Vec3::Zero();
  double barAlpha = 0, barBeta = 0, barLength = 1;  // Seed001 Bar: u(x) of seed 001 eq. 19

  /// The reference displacement at X (component c).
  double displacement(const Vec3& X, int c) const {
    if (type == "Seed001 Bar") {
      const double xr = X[0] / barLength;
      return barAlpha * X[0] + (xr > 0.5 ? barBeta * barLength * std::sqrt(xr - 0.5) : 0.0);
    }
    return (H.row(c) * (X - center))(0);
  }
};

struct SolverSettings {
  std::string method = "Newton";     // "Newton" or "ADR"
  double adrTolerance = 1e-6;
  long long adrMaxIterations = 2000000;
  double adrMassSafety = 4.0;
  int loadSteps = 10;                // per segment of the load path
  std::vector<double> loadPath;      // load factors after 0 (empty: 0 -> 1); LoadFactorModel::setLoadPath
  double tolerance = 1e-10;
  int maxIterations = 25;
  std::string lineSearch = "Full Step";
  int maxCutbacks = 4;
  double limitLoadRatio = 100;  // LoadStepperOptions::limitLoadRatio
  int maxTotalSteps = 200;           // including reduced steps
  double minIncrement = 1e-6;        // fraction of the nominal increment
  bool predictor = true;
  bool adaptive = false;             // grow increments after easy steps
  int easyIterations = 4;
  double maxIncrement = 0.25;
  bool stabilityCheck = false;       // negative pivots of the tangent after each step
  double floorFactor = 2.0;          // see NewtonOptions::floorFactor             // extrapolate the previous increment to start each step
  int verbosity = 0;
  int stagnationStop = 0;            // > 0: stop a Newton solve whose residual has not halved in this many iterations
  std::string forcingTerm = "Constant";  // NewtonOptions::forcingTerm
  double linearTolerance = 1e-12;    // NewtonOptions::linearTolerance
  std::string continuation = "Load Stepping";  // or "Arc Length"
  struct ArcLength {
    double initial = 0.05;           // arc length of the first step (metric: see Scene.cpp)
    double minimum = 1e-4;
    double maximum = 0.5;
    int maxSteps = 100;
    double targetLoadFactor = 1.0;   // stop when the load factor reaches it
    double targetDeflection = 0.0;   // stop when |deflection| reaches it (0: off)
    std::string deflectionProbe;     // Displacement probe giving the deflection
    int deflectionComponent = 1;
  } arc;
  Teuchos::RCP<Teuchos::ParameterList> linearSolver;  // Stratimikos list
  std::string linearSolverName;                       // preset name or "custom" (auto: the preset it chose)
  bool automatic = false;                             // Linear Solver Preset = auto (AutoLinearSolver.hpp)
  std::string autoReason, autoJacobian, autoForcingTerm;  // auto's choice and why
  std::string jacobian = "Assembled";                 // Assembled, Matrix-Free, Jacobian-Free
  std::string preconditionerMatrix = "Neighbours";    // matrix-free: Assembled or Neighbours
  double jfnkLambda = 1e-6;
};

/// The linear solver in a phrase: "auto: scalable, Matrix-Free Jacobian, Eisenstat-Walker forcing
/// (why)", or the preset or custom list named with its Jacobian.
std::string linearSolverPhrase(const SolverSettings& s);


struct OutputSettings {
  bool vtk = true;                   // VTU files (with format VTU or Both)
  std::string format = "VTU";        // "VTU", "Exodus" (fields.e, every converged step) or "Both"
  bool plots = true;
};

struct Scene {
  std::string file;
  std::string inputFile;  // the particle file or Exodus mesh read (path as opened); empty for a lattice
  std::string title;
  std::shared_ptr<ProblemSpec> problem;
  std::map<std::string, std::vector<int>> regions;  // global particle ids (distributed: those of the rank's share)
  std::vector<ProbeDef> probes;
  ReferenceDef reference;
  SolverSettings solver;
  OutputSettings output;
  int maxBreakRounds = 50;                        // damage: break/re-equilibrate rounds per step
  bool stallBreak = false;                        // damage: On Stall = Break Most Stretched
  double stallBreakTolerance = 1e-6;              // damage: stretch window of that break, relative to s_cr - s_min
  int maxStallBreaks = 200;                       // damage: stall breaks allowed in a run
  double reloadTolerance = 0.01;                  // damage: a snap-back's load found to this fraction
  bool breakAtSnapBackLimit = false;              // damage: 'After Snap-Back' = Break Most Stretched
  Teuchos::RCP<Teuchos::ParameterList> resolved;  // the scene with every default filled in
};

/// Reads, overrides (each "Sublist/Key=value"), validates and builds a scene.
/// presetDir is where "Linear Solver Preset" names are looked up (xml/solvers). Every rank of
/// comm (default: Teuchos' default communicator) builds it; with `Discretization/Construction` =
/// Distributed each builds only its share (collective), and the regions are lists of global ids
/// in either case (a distributed scene's: the particles of the rank's share).
Scene loadScene(const std::string& path, const std::vector<std::string>& overrides,
                const std::string& presetDir, const Teuchos::RCP<const Teuchos::Comm<int>>& comm = Teuchos::null);

/// The same from an in-memory list (tests). `file` is only used in messages.
Scene buildScene(Teuchos::ParameterList pl, const std::string& file, const std::string& presetDir,
                 const Teuchos::RCP<const Teuchos::Comm<int>>& comm = Teuchos::null);

/// The schema with defaults and documentation, for --help and docs.
Teuchos::RCP<const Teuchos::ParameterList> sceneSchema();

/// The list a scene file holds, parsed and checked as text, before any key is looked at: XML
/// (strictly typed, no duplicate keys), or a YAML file (read as a Peridigm deck only). Throws
/// SceneError naming the file.
Teuchos::ParameterList readSceneList(const std::string& path);

/// A scene list as the text of a scene file (ParameterList and Parameter elements with their
/// name, type and value only), which readSceneList and loadScene read back.
std::string sceneXml(const Teuchos::ParameterList& scene);
/// The schema's entry (default and documentation) for a resolved scene's key "Sublist/Key"
/// ("Regions/left/Side": a named sublist's entries are its template's), or null if it has none.
const Teuchos::ParameterEntry* sceneSchemaEntry(const std::string& key);

}  // namespace perinox

// Checkpoints of load stepping (Checkpoint.hpp).
#include "Checkpoint.hpp"

#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "Agreed.hpp"
#include "Observers.hpp"
#include "RunOutput.hpp"
#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/evaluator/Partitioner.hpp"
#include "perinox/io/Output.hpp"
#include "perinox/solver/MumpsSolver.hpp"

namespace perinox {

namespace fs = std::filesystem;

std::string resolvedSceneText(const Scene& scene) { return sceneXml(*scene.resolved); }

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
    const auto xv = ev.ownedDofValues(x), pv = ev.ownedDofValues(xPrevious);
    for (std::size_t k = 0; k < xv.size(); ++k) out << "x " << xv[k].first << ' ' << xv[k].second << ' ' << pv[k].second << '\n';
    for (const auto& [a, b] : ev.ownedBrokenBonds()) out << "bond " << a << ' ' << b << '\n';
    for (const auto& [g, v] : ev.ownedFrozenDofs()) out << "frozen " << g << ' ' << v << '\n';
    for (const auto& [g, values] : ev.ownedHistory()) {
      out << "state " << g;
      for (double v : values) out << ' ' << v;
      out << '\n';
    }
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

std::string inputFileHash(const Scene& scene) {
  if (scene.inputFile.empty()) return "";
  std::ifstream in(scene.inputFile, std::ios::binary);
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a, 64 bits: a content check, not a cryptographic one
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    for (std::streamsize k = 0; k < in.gcount(); ++k) {
      h ^= static_cast<unsigned char>(buf[static_cast<std::size_t>(k)]);
      h *= 1099511628211ull;
    }
  }
  std::ostringstream s;
  s << std::hex << std::setw(16) << std::setfill('0') << h;
  return s.str();
}

namespace {

/// state.json, parsed, with the keys every checkpoint has.
nlohmann::json readState(const std::string& dir, const std::string& where) {
  std::ifstream sj(dir + "/state.json");
  if (!sj)
    throw std::invalid_argument(where + ": no state.json there (not a checkpoint" +
                                (fs::exists(dir + ".old/state.json") ? std::string(": the job was killed while replacing it; the previous one is '") + dir + ".old'" : std::string()) +
                                ")");
  nlohmann::json state;
  try {
    state = nlohmann::json::parse(sj);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(where + ": state.json is truncated or damaged (not valid JSON at byte " +
                                std::to_string(e.byte) + ")");
  }
  if (!state.is_object()) throw std::invalid_argument(where + ": state.json is not a perinox checkpoint (not a JSON object)");
  for (const char* k : {"format", "ranks"})
    if (state.contains(k) && !state[k].is_number_integer())
      throw std::invalid_argument(where + ": state.json is damaged ('" + k + "' is not a whole number)");
  if (state.contains("scene") && !state["scene"].is_string())
    throw std::invalid_argument(where + ": state.json is damaged ('scene' is not the scene's text)");
  if (state.value("format", 0) == 1)
    throw std::invalid_argument(where + ": a checkpoint of format 1 (keyed by free-DOF numbers, written by an older perinox), "
                                        "which this perinox does not read; rerun from the start or with the perinox that wrote it");
  if (state.value("format", 0) != 2 || !state.contains("scene") || !state.contains("ranks"))
    throw std::invalid_argument(where + ": state.json is not a perinox checkpoint (format 2)");
  if (state["ranks"].get<long long>() < 1 || state["ranks"].get<long long>() > 1000000)
    throw std::invalid_argument(where + ": state.json is damaged ('ranks' = " + state["ranks"].dump() + " is not in [1, 1000000])");
  return state;
}

/// A resolved scene's physics as "Sublist/Key" -> (exact value, value as shown): the run controls,
/// which may change between the segments of a run (limits that stopped it, the linear solver,
/// NOX's verbosity, the output options), left out; the order of the keys and whether a value came
/// from the scene file, a --set or a default do not matter, only the values.
std::map<std::string, std::pair<std::string, std::string>> physicsValues(const std::string& xml, const std::string& where) {
  Teuchos::RCP<Teuchos::ParameterList> pl;
  try {
    pl = Teuchos::getParametersFromXmlString(xml);
  } catch (const std::exception&) {
    throw std::invalid_argument(where + ": the scene kept in its state.json is not readable XML (damaged checkpoint)");
  }
  if (pl->isSublist("Solver")) {
    auto& so = pl->sublist("Solver");
    for (const char* k : {"Max Total Steps", "Linear Solver Preset", "Linear Solver", "Verbosity", "Forcing Term",
                          "Linear Tolerance"})
      so.remove(k, false);
  }
  if (pl->isSublist("Damage")) pl->sublist("Damage").remove("Max Stall Breaks", false);
  if (pl->isSublist("Discretization"))
    for (const char* k : {"Partition", "Construction"}) pl->sublist("Discretization").remove(k, false);
  pl->remove("Output", false);
  std::map<std::string, std::pair<std::string, std::string>> values;
  std::function<void(const Teuchos::ParameterList&, const std::string&)> walk = [&](const Teuchos::ParameterList& l,
                                                                                    const std::string& prefix) {
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
}

/// Whether "Sublist/Key" holds the scene schema's default (exactly, as physicsValues prints it).
bool atSchemaDefault(const std::string& key, const std::string& exact) {
  const Teuchos::ParameterEntry* e = sceneSchemaEntry(key);
  if (e == nullptr || e->isList()) return false;
  std::ostringstream d;
  d << std::setprecision(17) << e->getAny(false);
  return d.str() == exact;
}

/// Refuses a checkpoint of another scene, naming the first differing key and both values.
void checkSameScene(const Scene& scene, const nlohmann::json& state, const std::string& where) {
  auto mine = physicsValues(resolvedSceneText(scene), where), theirs = physicsValues(state["scene"].get<std::string>(), where);
  // A checkpoint that holds its input file's hash is tied to what the file holds (checked after
  // this), not to where it lies: the resolved scene names the file by its absolute path.
  if (state.contains("input_hash"))
    for (const char* k : {"Discretization/Mesh File", "Discretization/Particle File"}) mine.erase(k), theirs.erase(k);
  if (mine == theirs) return;
  std::string what;
  for (const auto& [k, v] : mine) {
    const auto t = theirs.find(k);
    if (t == theirs.end()) {
      // A key newer than the checkpoint (a perinox that did not know it wrote it) at its default
      // means what the older perinox did.
      if (atSchemaDefault(k, v.first)) continue;
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
  if (what.empty()) return;  // only keys newer than the checkpoint, at their defaults
  throw std::invalid_argument(where + " is for another scene: " + what + " (only run controls may differ, README)");
}

/// Everything the loop will read from state.json, checked now, before any output exists: values a
/// run could have written (a counter a whole number within its range, a load factor in [0, 1], an
/// increment in (0, 1]), the step records, the detached particles and the probe histories.
void checkStateValues(const nlohmann::json& state, const Scene& scene, long long particles, const std::string& where) {
  try {
    for (const char* k : {"step", "lambda", "increment", "last_increment", "stall_breaks", "elapsed_s", "segment"}) {
      const double v = state.at(k).get<double>();
      if (!std::isfinite(v)) throw std::runtime_error(std::string("'") + k + "' is not a finite number");
    }
    auto whole = [&](const char* k, long long lo, long long hi) {
      const double v = state.at(k).get<double>();
      if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
        throw std::runtime_error(std::string("'") + k + "' = " + state.at(k).dump() + " is not a whole number in [" +
                                 std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    auto within = [&](const char* k, double lo, double hi, bool openLow) {
      const double v = state.at(k).get<double>();
      if (v > hi || v < lo || (openLow && v == lo))
        throw std::runtime_error(std::string("'") + k + "' = " + state.at(k).dump() + " lies outside " +
                                 (openLow ? "(" : "[") + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    whole("step", 0, 2000000000);
    whole("stall_breaks", 0, 2000000000);
    whole("segment", 1, 1000000000);
    within("lambda", 0.0, 1.0, false);
    within("increment", 0.0, 1.0, true);
    within("last_increment", -1.0, 1.0, false);  // negative after a snap-back lowered the load
    within("elapsed_s", 0.0, 1e12, false);
    if (state.contains("initial_compliance")) within("initial_compliance", 0.0, 1e300, false);  // absent before the limit-load check
    if (state.contains("at_limit") && !state.at("at_limit").is_boolean())
      throw std::runtime_error("'at_limit' = " + state.at("at_limit").dump() + " is not true or false");
    if (state.at("steps").size() != state.at("step").get<std::size_t>())
      throw std::runtime_error("it records " + std::to_string(state.at("steps").size()) + " steps, not 'step' = " +
                               state.at("step").dump());
    // The records are steps 1, 2, ... and the state's load factor is the last one's: a state.json
    // whose counters and records disagree was not written by a run.
    std::vector<double> recordedPath;  // the records' load factors
    for (const auto& sj : state.at("steps")) {
      const StepRecord r = stepFromJson(sj);
      if (r.step != static_cast<int>(recordedPath.size()) + 1)
        throw std::runtime_error("step record " + std::to_string(recordedPath.size() + 1) + " says step " + std::to_string(r.step));
      if (!(r.loadFactor >= -1.0 && r.loadFactor <= 1.0))
        throw std::runtime_error("step " + std::to_string(r.step) + " records the load factor " + sj.at("load_factor").dump());
      recordedPath.push_back(r.loadFactor);
    }
    const double recorded = recordedPath.empty() ? 0.0 : recordedPath.back();
    if (state.at("lambda").get<double>() != recorded)
      throw std::runtime_error("'lambda' = " + state.at("lambda").dump() + " is not the load factor " + std::to_string(recorded) +
                               " of its last step record");
    if (state.at("path_load_factors").get<std::vector<double>>() != recordedPath)
      throw std::runtime_error("'path_load_factors' does not list the load factors of its step records");
    if (!scene.problem->damage && !state.at("detached").empty())
      throw std::runtime_error("it lists detached particles, but the scene has no damage");
    for (long long id : state.at("detached").get<std::vector<long long>>())
      if (id < 0 || id >= particles)
        throw std::runtime_error("detached particle " + std::to_string(id) + " is not one of the " +
                                 std::to_string(particles) + " particles");
    const auto& probes = state.at("probes");
    if (probes.size() != scene.probes.size()) throw std::runtime_error("probe histories do not match the scene's probes");
    for (const auto& p : probes) {
      // A probe's history has a value per accepted step, at its load factor (or none: a profile);
      // the records hold the stepper's load factor, the pseudo-time of a load path.
      const auto history = p.get<std::vector<std::pair<double, std::vector<double>>>>();
      if (!history.empty() && (history.size() != recordedPath.size() ||
                               !std::equal(history.begin(), history.end(), recordedPath.begin(),
                                           [&](const auto& h, double l) { return h.first == loadOnPath(scene.solver.loadPath, l); })))
        throw std::runtime_error("a probe history does not follow the step records");
    }
  } catch (const std::exception& e) {
    // nlohmann's sentences start with their own tag ("[json.exception.type_error.302] "): cut it.
    std::string why = e.what();
    if (why.rfind("[json.exception", 0) == 0 && why.find("] ") != std::string::npos) why = why.substr(why.find("] ") + 2);
    throw std::invalid_argument(where + ": state.json is incomplete or damaged (" + why + ")");
  }
}

/// One rank file's lines ("x DOF X XPREV", "bond GID_I GID_J", "frozen DOF VALUE") into c; a DOF
/// must be a free DOF of the scene (particle * dim + component).
void readRankFile(const std::string& f, const ProblemSpec& P, int stateDoubles, Checkpoint& c, const std::string& where) {
  const long long particles = P.particleCount();
  const int D = P.dim();
  auto freeDof = [&](long long g) {
    if (g < 0 || g >= particles * D) return false;
    // A distributed problem knows its share only: another rank's DOF is checked by that rank.
    if (!P.holds(g / D)) return true;
    return !P.isFixed(g / D, static_cast<int>(g % D));
  };
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
  long long lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    std::istringstream ls(line);
    ls >> kind;
    long long g = 0, h = 0;
    std::string v1, v2;
    bool ok = true;
    if (kind == "x") {
      ok = static_cast<bool>(ls >> g >> v1 >> v2) && freeDof(g);
      if (ok) {
        c.x.emplace_back(g, number(v1, ok));
        c.xPrevious.emplace_back(g, number(v2, ok));
      }
    } else if (kind == "bond") {
      ok = P.damage && static_cast<bool>(ls >> g >> h) && g >= 0 && h >= 0 && g < particles && h < particles && g != h;
      if (ok) c.broken.emplace_back(g, h);
    } else if (kind == "frozen") {
      ok = P.damage && static_cast<bool>(ls >> g >> v1) && freeDof(g);
      if (ok) c.frozen.emplace_back(g, number(v1, ok));
    } else if (kind == "state") {
      if (stateDoubles == 0)
        throw std::invalid_argument(where + ": " + f + " holds material states, but no material of the scene has history");
      ok = static_cast<bool>(ls >> g) && g >= 0 && g < particles;
      std::vector<double> values;
      while (ok && ls >> v1) values.push_back(number(v1, ok));
      if (ok && static_cast<int>(values.size()) != stateDoubles)
        throw std::invalid_argument(where + ": the state of particle " + std::to_string(g) + " in " + f + " has " +
                                    std::to_string(values.size()) + " values, the scene's materials keep " +
                                    std::to_string(stateDoubles) + " (another material or model)");
      if (ok) c.history.emplace_back(g, std::move(values));
    } else {
      ok = false;
    }
    if (!ok && !P.damage && (kind == "bond" || kind == "frozen"))
      throw std::invalid_argument(where + ": " + f + " holds broken bonds or frozen values, but the scene has no damage");
    if (!ok) throw std::invalid_argument(where + ": unreadable line " + std::to_string(lineNo) + " in " + f);
  }
}

/// A checkpoint record as it travels: kind, the particle whose owner receives it, and three values
/// (x: DOF, X, XPREV; frozen: DOF, VALUE, 0; bond: GID_I, GID_J, 0; state: GID, index, value, one
/// record per value). Ids are below 2^53 (the scene's particle limit is 5e7), so a double carries
/// them exactly.
constexpr int kRecord = 5;
enum RecordKind { kX = 0, kFrozen = 1, kBond = 2, kState = 3 };

/// c's values and bonds sent to the owners of their particles (collective): first to the id slab
/// of the particle (idSlabOf), which has learned from every rank which of its slab's particles
/// that rank owns, then on to the owner. Returns what this rank owns.
Checkpoint routeToOwners(const Checkpoint& c, const ProblemSpec& P, const Teuchos::Comm<int>& comm) {
  const int ranks = comm.getSize(), D = P.dim();
  const long long n = P.particleCount();
  // The directory: owner of each particle of this rank's id slab.
  const long long begin = partitionBegin(n, ranks, comm.getRank()), end = partitionBegin(n, ranks, comm.getRank() + 1);
  std::vector<double> mine;
  std::vector<int> to;
  for (long long g : P.owned) {
    mine.push_back(static_cast<double>(g));
    mine.push_back(static_cast<double>(comm.getRank()));
    to.push_back(idSlabOf(g, n, ranks));
  }
  std::vector<int> owner(static_cast<std::size_t>(end - begin), -1);
  const std::vector<double> owners = exchangeRecords(comm, mine, 2, to);
  for (std::size_t k = 0; k < owners.size(); k += 2) owner[static_cast<long long>(owners[k]) - begin] = static_cast<int>(owners[k + 1]);
  std::vector<double> recs;
  to.clear();
  auto send = [&](RecordKind kind, long long key, double a, double b, double v) {
    const double r[kRecord] = {static_cast<double>(kind), static_cast<double>(key), a, b, v};
    recs.insert(recs.end(), r, r + kRecord);
    to.push_back(idSlabOf(key, n, ranks));
  };
  for (std::size_t k = 0; k < c.x.size(); ++k)
    send(kX, c.x[k].first / D, static_cast<double>(c.x[k].first), c.x[k].second, c.xPrevious[k].second);
  for (const auto& [g, v] : c.frozen) send(kFrozen, g / D, static_cast<double>(g), v, 0.0);
  for (const auto& [a, b] : c.broken) {
    send(kBond, a, static_cast<double>(a), static_cast<double>(b), 0.0);
    send(kBond, b, static_cast<double>(a), static_cast<double>(b), 0.0);
  }
  for (const auto& [g, values] : c.history)
    for (std::size_t k = 0; k < values.size(); ++k) send(kState, g, static_cast<double>(g), static_cast<double>(k), values[k]);
  const std::vector<double> atSlab = exchangeRecords(comm, recs, kRecord, to);
  to.clear();
  for (std::size_t k = 0; k < atSlab.size(); k += kRecord) to.push_back(owner[static_cast<long long>(atSlab[k + 1]) - begin]);
  const std::vector<double> atOwner = exchangeRecords(comm, atSlab, kRecord, to);
  Checkpoint out;
  std::map<long long, std::vector<double>> states;
  for (std::size_t k = 0; k < atOwner.size(); k += kRecord) {
    const double* r = &atOwner[k];
    const long long a = static_cast<long long>(r[2]);
    if (r[0] == kState) {
      auto& v = states[a];
      const std::size_t i = static_cast<std::size_t>(r[3]);
      if (v.size() <= i) v.resize(i + 1, 0.0);
      v[i] = r[4];
    } else if (r[0] == kX) {
      out.x.emplace_back(a, r[3]);
      out.xPrevious.emplace_back(a, r[4]);
    } else if (r[0] == kFrozen) {
      out.frozen.emplace_back(a, r[3]);
    } else {
      out.broken.emplace_back(a, static_cast<long long>(r[3]));
    }
  }
  for (auto& [g, v] : states) out.history.emplace_back(g, std::move(v));
  return out;
}

/// The number of values in x, and whether any DOF has two (those of one DOF all reach one rank).
std::pair<long long, bool> countValues(const Checkpoint& c) {
  std::vector<long long> ids;
  for (const auto& e : c.x) ids.push_back(e.first);
  std::sort(ids.begin(), ids.end());
  return {static_cast<long long>(ids.size()), std::adjacent_find(ids.begin(), ids.end()) != ids.end()};
}

}  // namespace

Checkpoint readCheckpoint(const std::string& dir, const Scene& scene, long long freeDofs, long long particles,
                          int stateDoubles, const std::vector<long long>& owned, const Teuchos::Comm<int>& comm) {
  const std::string where = "checkpoint '" + dir + "'";
  const ProblemSpec& P = *scene.problem;
  const bool share = P.distributed && comm.getSize() > 1;
  Checkpoint c;
  int ranks = 0;
  // Every rank reads state.json (the same on all, so they fail alike).
  throwAgreed<std::invalid_argument>(comm, [&] {
    c.state = readState(dir, where);
    checkSameScene(scene, c.state, where);
    checkStateValues(c.state, scene, particles, where);
    // The particle file or mesh by content: another file with the same counts is another body.
    // (A checkpoint of a perinox that did not record it is taken as it is.)
    if (c.state.contains("input_hash") &&
        (!c.state["input_hash"].is_string() || c.state["input_hash"].get<std::string>() != inputFileHash(scene)))
      throw std::invalid_argument(where + " is for another body: '" + fs::path(scene.inputFile).filename().string() +
                                  "' is not the file it was written with (its content differs)");
    ranks = c.state["ranks"];
  });
  throwAgreed<std::invalid_argument>(comm, [&] {
    for (int r = 0; r < ranks; ++r)
      if (!share || r % comm.getSize() == comm.getRank())
        readRankFile(dir + "/rank_" + std::to_string(r) + ".txt", P, stateDoubles, c, where);
  });
  if (share) {
    Checkpoint routed = routeToOwners(c, P, comm);
    routed.state = std::move(c.state);
    c = std::move(routed);
    // The owner checks what its share's DOFs received: a value for a prescribed DOF is damaged.
    throwAgreed<std::invalid_argument>(comm, [&] {
      const int D = P.dim();
      for (const auto* values : {&c.x, &c.frozen})
        for (const auto& e : *values)
          if (P.isFixed(e.first / D, static_cast<int>(e.first % D)))
            throw std::invalid_argument(where + " holds a value for the prescribed DOF " + std::to_string(e.first) +
                                        " (damaged or from another discretisation)");
    });
  }
  // Every value is of a free DOF: with as many values as free DOFs and none twice, every free DOF
  // has one (summed over the ranks when each holds its share).
  auto [count, twice] = countValues(c);
  if (share) {
    long long total = 0;
    int anyTwice = 0, mineTwice = twice;
    Teuchos::reduceAll(comm, Teuchos::REDUCE_SUM, count, Teuchos::outArg(total));
    Teuchos::reduceAll(comm, Teuchos::REDUCE_MAX, mineTwice, Teuchos::outArg(anyTwice));
    count = total, twice = anyTwice != 0;
  }
  if (count != freeDofs || twice)
    throw std::invalid_argument(where + " holds " + std::to_string(count) + " displacement values for " +
                                std::to_string(freeDofs) + " free DOFs (damaged or from another discretisation)");
  // With history, every owned particle has its committed state (once).
  throwAgreed<std::invalid_argument>(comm, [&] {
    if (stateDoubles == 0) return;
    std::vector<long long> have;
    for (const auto& e : c.history)
      if (std::binary_search(owned.begin(), owned.end(), e.first)) have.push_back(e.first);
    std::sort(have.begin(), have.end());
    if (std::adjacent_find(have.begin(), have.end()) != have.end())
      throw std::invalid_argument(where + " holds two states for particle " +
                                  std::to_string(*std::adjacent_find(have.begin(), have.end())));
    for (long long g : owned)
      if (!std::binary_search(have.begin(), have.end(), g))
        throw std::invalid_argument(where + " holds no material state for particle " + std::to_string(g) +
                                    " (written before the scene's material had history, or damaged)");
  });
  return c;
}

void forPreconditionerFactories(const PeridynamicEvaluator& ev,
                                const std::function<void(const Thyra::PreconditionerFactoryBase<double>&)>& f) {
  if (auto wf = ev.get_W_factory())
    if (auto pf = wf->getPreconditionerFactory()) f(*pf);
  if (auto pf = ev.preconditionerFactory()) f(*pf);
}

void CheckpointWriter::accepted(const StepInfo& s) {
  const auto& state = stepper_.state();
  int due = (options_.checkpointSteps > 0 && state.step % options_.checkpointSteps == 0) ||
            (options_.checkpointSeconds > 0 && wallSeconds() - last_ >= options_.checkpointSeconds);
  Teuchos::broadcast(comm_, 0, Teuchos::outArg(due));  // clocks differ between ranks
  if (!due) return;
  nlohmann::json st;
  st["format"] = 2;
  st["scene"] = resolvedSceneText(scene_);
  st["step"] = state.step;
  st["lambda"] = state.loadFactor;
  st["increment"] = state.increment;
  st["last_increment"] = state.lastIncrement;
  st["stall_breaks"] = state.stallBreaks;
  st["at_limit"] = state.atLimit;
  st["initial_compliance"] = state.initialCompliance;
  st["elapsed_s"] = wallSeconds() - t0_ + elapsedBefore_;
  st["segment"] = segment_;
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& sr : stepper_.records()) steps.push_back(stepJson(sr, true, false));
  st["steps"] = steps;
  st["path_load_factors"] = stepper_.path();
  nlohmann::json probes = nlohmann::json::array();
  for (const auto& pr : res_.probes) probes.push_back(pr.second);
  st["probes"] = probes;
  st["detached"] = ev_.detachedParticles();
  if (!inputHash_) inputHash_ = comm_.getRank() == 0 ? inputFileHash(scene_) : std::string();
  if (!inputHash_->empty()) st["input_hash"] = *inputHash_;
  writeCheckpoint(folder_, st, ev_, s.x, stepper_.previous(), comm_);
  // A run resumed from here starts without the MUMPS preconditioner's kept factors (gmres-mumps);
  // dropping them here too makes this run factorise at the same set-up: both go on bit for bit.
  forPreconditionerFactories(ev_, [](const Thyra::PreconditionerFactoryBase<double>& pf) { renewKeptFactors(pf); });
  last_ = wallSeconds();
  if (comm_.getRank() == 0 && !options_.quiet)
    std::cout << "  checkpoint after step " << state.step << " in " << folder_.target << std::endl;
}

}  // namespace perinox

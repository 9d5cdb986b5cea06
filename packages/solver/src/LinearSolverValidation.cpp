// Validation of Stratimikos linear-solver lists against Trilinos' own valid-parameter lists (see
// LinearSolverValidation.hpp). What each package checks by itself in Trilinos 13.2, and when:
//  - Stratimikos' builder checks its top-level names and the names of the strategy sublists only
//    (the strategy sublists are marked "no recursive validation");
//  - Thyra's Belos adapter checks its own level and the names under 'Solver Types' when the
//    strategy is created, but not the keys inside 'Solver Types/<solver>' (a typo is ignored and
//    the tolerance silently becomes -1); Belos' solver managers do not validate either;
//  - Thyra's Ifpack2 adapter checks 'Ifpack2 Settings' against the union of all Ifpack2 keys when
//    the strategy is created; 'Prec Type' is checked only when the first preconditioner is built,
//    and only Relaxation / BlockRelaxation then check their own keys;
//  - Thyra's MueLu adapter checks nothing; MueLu checks the names and types of its simple list
//    (and 'level N' sublists) against its master list when the first hierarchy is built;
//  - Thyra's Amesos2 adapter checks its level when the strategy is created, with a Teuchos
//    internal exception for an unknown 'Solver Type'.
// All of these are checked here up front, with one sentence each.
#include "perinox/solver/LinearSolverValidation.hpp"

#include "perinox/solver/LinearSolver.hpp"
#include "perinox/solver/TwoStagePreconditioner.hpp"

#include <Ifpack2_BlockRelaxation_decl.hpp>
#include <Ifpack2_Details_Factory.hpp>
#include <Ifpack2_Relaxation_decl.hpp>
#include <MueLu_MasterList.hpp>
#include <Teuchos_Array.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Thyra_Amesos2Types.hpp>
#include <Tpetra_Map_decl.hpp>
#include <Tpetra_RowMatrix_decl.hpp>

#include <algorithm>
#include <cctype>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace perinox {

namespace {

using Teuchos::ParameterEntry;
using Teuchos::ParameterList;
using Node = Tpetra::Map<int, long long>::node_type;
using RowMatrix = Tpetra::RowMatrix<double, int, long long, Node>;

const char* const kRoot = "Solver/Linear Solver";
const std::size_t kMaxMessage = 300;

// Stratimikos' built-in strategies that need Epetra operators: on perinox's Tpetra operators they
// throw a bad cast at the first solve.
bool epetraOnly(const std::string& name) { return name == "Amesos" || name == "Ifpack" || name == "ML"; }

// Not suggested in messages: the Epetra-only ones, and AztecOO (it runs on a Tpetra operator
// through an Epetra copy of every vector and reports an unknown convergence status).
bool notSuggested(const std::string& name) { return epetraOnly(name) || name == "AztecOO"; }

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Edit distance ignoring case, a swap of two neighbouring letters counting as one edit.
std::size_t editDistance(const std::string& a, const std::string& b) {
  auto low = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (low(a[i - 1]) == low(b[j - 1]) ? 0 : 1)});
      if (i > 1 && j > 1 && low(a[i - 1]) == low(b[j - 2]) && low(a[i - 2]) == low(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// The closest candidate when it is close enough to be a likely typo (case is ignored), else "".
std::string closest(const std::string& name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t bestD = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = editDistance(name, c);
    if (d < bestD) bestD = d, best = c;
  }
  return (bestD <= 3 && 3 * bestD <= name.size()) ? best : std::string();
}

bool xmlType(const ParameterEntry& e) {
  if (e.isList()) return true;
  const auto& t = e.getAny(false).type();
  return t == typeid(std::string) || t == typeid(int) || t == typeid(double) || t == typeid(bool) ||
         t == typeid(long long) || t == typeid(float) || t == typeid(Teuchos::Array<int>) ||
         t == typeid(Teuchos::Array<double>) || t == typeid(Teuchos::Array<std::string>);
}

std::string typeName(const ParameterEntry& e) {
  if (e.isList()) return "sublist";
  const auto& t = e.getAny(false).type();
  if (t == typeid(std::string)) return "string";
  if (t == typeid(double)) return "double";
  if (t == typeid(int)) return "int";
  if (t == typeid(bool)) return "bool";
  if (t == typeid(long long)) return "long long";
  if (t == typeid(float)) return "float";
  if (t == typeid(Teuchos::Array<int>)) return "Array(int)";
  if (t == typeid(Teuchos::Array<double>)) return "Array(double)";
  if (t == typeid(Teuchos::Array<std::string>)) return "Array(string)";
  return e.getAny(false).typeName();
}

std::string valueText(const ParameterEntry& e) {
  std::ostringstream s;
  if (e.isType<std::string>()) return "'" + Teuchos::getValue<std::string>(e) + "'";
  if (e.isType<bool>()) return Teuchos::getValue<bool>(e) ? "true" : "false";
  e.getAny(false).print(s);
  return s.str();
}

// Names a user could give at this level (entries of types an XML file can hold).
std::vector<std::string> namesOf(const ParameterList& l) {
  std::vector<std::string> n;
  for (auto it = l.begin(); it != l.end(); ++it)
    if (xmlType(l.entry(it))) n.push_back(l.name(it));
  return n;
}

std::vector<std::string> toVector(const Teuchos::RCP<const Teuchos::Array<std::string>>& a) {
  return a.is_null() ? std::vector<std::string>() : std::vector<std::string>(a->begin(), a->end());
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

class Checker {
 public:
  explicit Checker(const std::string& where) : prefix_(where.empty() ? "" : where + ": ") {}

  [[noreturn]] void fail(const std::string& sentence) const { throw std::invalid_argument(prefix_ + sentence); }

  // "sentence (did you mean 'x'?)" when a candidate is close, else "sentence (label: a, b, ...)"
  // with as many candidates as fit in the message length.
  [[noreturn]] void failWithHint(const std::string& sentence, const std::string& given,
                                 const std::vector<std::string>& candidates, const std::string& label) const {
    const std::string best = closest(given, candidates);
    if (!best.empty()) fail(sentence + " (did you mean '" + best + "'?)");
    std::string list;
    const std::size_t room = kMaxMessage > prefix_.size() + sentence.size() + label.size() + 5
                                 ? kMaxMessage - prefix_.size() - sentence.size() - label.size() - 5
                                 : 0;
    for (const auto& c : candidates) {
      const std::string piece = (list.empty() ? "" : ", ") + c;
      if (list.size() + piece.size() + 5 > room) {
        if (!list.empty()) list += ", ...";
        break;
      }
      list += piece;
    }
    fail(list.empty() ? sentence : sentence + " (" + label + ": " + list + ")");
  }

  // One entry against its valid counterpart: sublist or not, type, Trilinos validator.
  // 'noun' describes an acceptable value in messages ("a Belos solver type").
  void checkEntry(const ParameterEntry& e, const ParameterEntry& v, const std::string& name,
                  const std::string& key, const std::string& owner, const std::string& noun = "") const {
    if (v.isList() != e.isList()) {
      if (v.isList()) fail("'" + key + "' must be a sublist, not a parameter");
      fail("'" + key + "' must be a parameter of type " + typeName(v) + ", not a sublist");
    }
    if (e.isList()) {
      const auto& validSub = Teuchos::getValue<ParameterList>(v);
      // An empty valid sublist is free-form (passed on to another package unchecked).
      if (validSub.numParams() > 0) checkList(Teuchos::getValue<ParameterList>(e), validSub, key, owner);
      return;
    }
    const auto validator = v.validator();
    const bool anyNumber =
        dynamic_cast<const Teuchos::AnyNumberParameterEntryValidator*>(validator.get()) != nullptr;
    if (!anyNumber && e.getAny(false).type() != v.getAny(false).type())
      fail("'" + key + "' must be of type " + typeName(v) + ", not " + typeName(e));
    if (validator.is_null()) return;
    try {
      validator->validate(e, name, key);
    } catch (const std::exception&) {
      const auto values = toVector(validator->validStringValues());
      if (!values.empty() && e.isType<std::string>())
        failWithHint("'" + key + "' = " + valueText(e) + " is not " + (noun.empty() ? "an allowed value" : noun),
                     Teuchos::getValue<std::string>(e), values, "allowed");
      if (auto d = dynamic_cast<const Teuchos::EnhancedNumberValidator<double>*>(validator.get())) {
        std::ostringstream s;
        s << "'" << key << "' = " << valueText(e) << " is outside [" << d->getMin() << ", " << d->getMax() << "]";
        fail(s.str());
      }
      if (auto i = dynamic_cast<const Teuchos::EnhancedNumberValidator<int>*>(validator.get())) {
        std::ostringstream s;
        s << "'" << key << "' = " << valueText(e) << " is outside [" << i->getMin() << ", " << i->getMax() << "]";
        fail(s.str());
      }
      fail("'" + key + "' = " + valueText(e) + " is not an allowed value");
    }
  }

  // Every entry of 'user' must exist in 'valid' (recursively). owner: "a Belos parameter".
  void checkList(const ParameterList& user, const ParameterList& valid, const std::string& path,
                 const std::string& owner) const {
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const std::string key = path + "/" + name;
      if (!valid.isParameter(name)) failWithHint("'" + key + "' is not " + owner, name, namesOf(valid), "known here");
      checkEntry(user.entry(it), valid.getEntry(name), name, key, owner);
    }
  }

  void top(const ParameterList& user, const ParameterList& valid) const {
    const std::string path = kRoot;
    std::vector<std::string> topNames = namesOf(valid);
    for (const auto& own : presetOwnKeys()) topNames.push_back(own.first);
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const ParameterEntry& e = user.entry(it);
      const std::string key = path + "/" + name;
      const auto own = std::find_if(presetOwnKeys().begin(), presetOwnKeys().end(),
                                    [&](const auto& k) { return k.first == name; });
      if (own != presetOwnKeys().end()) {  // perinox's own keys (Scene.cpp)
        if (!e.isType<std::string>()) fail("'" + key + "' must be of type string, not " + typeName(e));
        const std::vector<std::string>& allowed = own->second;
        const std::string& value = Teuchos::getValue<std::string>(e);
        if (std::find(allowed.begin(), allowed.end(), value) == allowed.end())
          failWithHint("'" + key + "' = '" + value + "' is not one of " + joined(allowed), value, allowed, "allowed");
        continue;
      }
      if (!valid.isParameter(name)) failWithHint("'" + key + "' is not a Stratimikos parameter", name, topNames, "known here");
      if (name == "Linear Solver Types" && e.isList()) {
        strategies(Teuchos::getValue<ParameterList>(e), valid.sublist(name), key, true);
      } else if (name == "Preconditioner Types" && e.isList()) {
        strategies(Teuchos::getValue<ParameterList>(e), valid.sublist(name), key, false);
      } else if ((name == "Linear Solver Type" || name == "Preconditioner Type") && e.isType<std::string>()) {
        // The builder's validator also lists the Epetra-only strategies: name the usable ones.
        const bool isSolver = name == "Linear Solver Type";
        const ParameterList& types = valid.sublist(isSolver ? "Linear Solver Types" : "Preconditioner Types");
        const std::string& value = Teuchos::getValue<std::string>(e);
        if (!types.isSublist(value) && (isSolver || value != "None")) {
          std::vector<std::string> known = tpetraNameList(types);
          if (!isSolver) known.insert(known.begin(), "None");
          failWithHint("'" + key + "' = '" + value + "' is not " + (isSolver ? "a linear solver type" : "a preconditioner type"),
                       value, known, "known");
        }
      } else {
        checkEntry(e, valid.getEntry(name), name, key, "a Stratimikos parameter");
      }
    }
    // Stratimikos' defaults for missing types are Amesos and Ifpack, which need Epetra.
    const std::string solverKey = path + "/Linear Solver Type", precKey = path + "/Preconditioner Type";
    const std::string tpetraSolvers = tpetraNames(valid.sublist("Linear Solver Types"));
    const std::string tpetraPrecs = "None, " + tpetraNames(valid.sublist("Preconditioner Types"));
    if (!user.isParameter("Linear Solver Type"))
      fail("'" + solverKey + "' is missing (Stratimikos' default, Amesos, needs Epetra): give one of " + tpetraSolvers);
    const std::string solver = user.get<std::string>("Linear Solver Type");
    if (epetraOnly(solver))
      fail("'" + solverKey + "' = '" + solver + "' works on Epetra matrices only; perinox's are Tpetra: use " + tpetraSolvers);
    if (solver == "Belos" && !user.isParameter("Preconditioner Type"))
      fail("'" + precKey + "' is missing (Stratimikos' default, Ifpack, needs Epetra): give one of " + tpetraPrecs);
    const std::string prec = user.isParameter("Preconditioner Type") ? user.get<std::string>("Preconditioner Type") : "None";
    if (epetraOnly(prec))
      fail("'" + precKey + "' = '" + prec + "' works on Epetra matrices only; perinox's are Tpetra: use " + tpetraPrecs);
  }

 private:
  static std::vector<std::string> tpetraNameList(const ParameterList& types) {
    std::vector<std::string> n;
    for (auto it = types.begin(); it != types.end(); ++it)
      if (!notSuggested(types.name(it))) n.push_back(types.name(it));
    return n;
  }
  static std::string tpetraNames(const ParameterList& types) { return joined(tpetraNameList(types)); }

  void strategies(const ParameterList& user, const ParameterList& valid, const std::string& path, bool solvers) const {
    const std::vector<std::string> known = tpetraNameList(valid);
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const std::string key = path + "/" + name;
      if (!valid.isSublist(name))
        failWithHint("'" + key + "' is not " + (solvers ? "a linear solver type" : "a preconditioner type"), name, known,
                     "known");
      if (!user.entry(it).isList()) fail("'" + key + "' must be a sublist, not a parameter");
      const ParameterList& sub = user.sublist(name);
      const ParameterList& validSub = valid.sublist(name);
      if (name == "Belos") {
        belos(sub, validSub, key);
      } else if (name == "Amesos2") {
        amesos2(sub, validSub, key);
      } else if (name == "Ifpack2") {
        ifpack2(sub, validSub, key);
      } else if (name == "MueLu") {
        muelu(sub, key);
      } else if (name == twoStageName()) {
        twoStage(sub, validSub, key);
      } else {
        const bool vowel = std::string("AEIOUaeiou").find(name.empty() ? 'x' : name[0]) != std::string::npos;
        checkList(sub, validSub, key, (vowel ? "an " : "a ") + name + " parameter");
      }
    }
  }

  void belos(const ParameterList& user, const ParameterList& valid, const std::string& path) const {
    const ParameterList& validTypes = valid.sublist("Solver Types");
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const ParameterEntry& e = user.entry(it);
      const std::string key = path + "/" + name;
      if (name == "Solver Types" && e.isList()) {
        const ParameterList& types = Teuchos::getValue<ParameterList>(e);
        for (auto t = types.begin(); t != types.end(); ++t) {
          const std::string& solver = types.name(t);
          const std::string solverKey = key + "/" + solver;
          if (!validTypes.isSublist(solver))
            failWithHint("'" + solverKey + "' is not a Belos solver type", solver, namesOf(validTypes), "known");
          if (!types.entry(t).isList()) fail("'" + solverKey + "' must be a sublist, not a parameter");
          const ParameterList& s = types.sublist(solver);
          belosNumbers(s, solverKey);
          checkList(s, validTypes.sublist(solver), solverKey, "a Belos " + solver + " parameter");
        }
        continue;
      }
      if (!valid.isParameter(name)) failWithHint("'" + key + "' is not a Belos parameter", name, namesOf(valid), "known here");
      checkEntry(e, valid.getEntry(name), name, key, "a Belos parameter", name == "Solver Type" ? "a Belos solver type" : "");
    }
  }

  void belosNumbers(const ParameterList& s, const std::string& path) const {
    if (s.isType<double>("Convergence Tolerance")) {
      const double tol = s.get<double>("Convergence Tolerance");
      if (!(tol > 0)) {
        std::ostringstream m;
        m << "'" << path << "/Convergence Tolerance' must be positive (got " << tol << ")";
        fail(m.str());
      }
    }
    for (const char* k : {"Maximum Iterations", "Num Blocks", "Block Size"}) {
      if (s.isType<int>(k) && s.get<int>(k) <= 0)
        fail("'" + path + "/" + k + "' must be positive (got " + std::to_string(s.get<int>(k)) + ")");
    }
  }

  void amesos2(const ParameterList& user, const ParameterList& valid, const std::string& path) const {
    checkList(user, valid, path, "an Amesos2 parameter");
    // Stratimikos' Amesos2 adapter maps these names itself (Thyra::Amesos2): Amesos2::query() knows
    // more solvers (Tacho) than the adapter offers.
    auto names = [](const char* const* n, int count) { return std::vector<std::string>(n, n + count); };
    const std::vector<std::string> solverNames = names(Thyra::Amesos2::solverTypeNames, Thyra::Amesos2::numSolverTypes);
    const std::vector<std::string> policyNames =
        names(Thyra::Amesos2::refactorizationPolicyNames, Thyra::Amesos2::numRefactorizationPolices);
    if (user.isType<std::string>("Solver Type")) {
      const std::string& s = user.get<std::string>("Solver Type");
      if (std::find(solverNames.begin(), solverNames.end(), s) == solverNames.end())
        failWithHint("'" + path + "/Solver Type' = '" + s + "' is not an Amesos2 solver that Stratimikos offers in this Trilinos build",
                     s, solverNames, "available");
    }
    if (user.isType<std::string>("Refactorization Policy")) {
      const std::string& s = user.get<std::string>("Refactorization Policy");
      if (std::find(policyNames.begin(), policyNames.end(), s) == policyNames.end())
        failWithHint("'" + path + "/Refactorization Policy' = '" + s + "' is not an Amesos2 refactorization policy", s,
                     policyNames, "allowed");
    }
  }

  void ifpack2(const ParameterList& user, const ParameterList& valid, const std::string& path) const {
    checkList(user, valid, path, "an Ifpack2 parameter");
    Ifpack2::Details::Factory<double, int, long long, Node> factory;
    const std::string type = user.isType<std::string>("Prec Type") ? user.get<std::string>("Prec Type")
                                                                  : valid.get<std::string>("Prec Type");
    if (!factory.isSupported(type)) {
      // Ifpack2 has no list of its names; these (canonical spellings) only feed the hint, each
      // shown only if this build supports it.
      std::vector<std::string> known;
      for (const char* n : {"RILUK", "ILUT", "RELAXATION", "CHEBYSHEV", "SCHWARZ", "DIAGONAL", "BLOCK_RELAXATION",
                            "BANDED_RELAXATION", "TRIDI_RELAXATION", "DENSE_BLOCK_RELAXATION",
                            "SPARSE_BLOCK_RELAXATION", "RBILUK", "AMESOS2", "FAST_ILU", "FAST_IC", "FAST_ILDL",
                            "DENSE", "IDENTITY", "HIPTMAIR", "HYPRE"})
        if (factory.isSupported(n)) known.push_back(n);
      failWithHint("'" + path + "/Prec Type' = '" + type + "' is not an Ifpack2 preconditioner type", type, known, "e.g.");
    }
    // Relaxation and BlockRelaxation refuse keys of other preconditioners when they are set up;
    // their own lists are available from an instance without a matrix.
    if (!user.isSublist("Ifpack2 Settings") || upper(type).find("RELAXATION") == std::string::npos) return;
    Teuchos::RCP<const ParameterList> own;
    try {
      auto prec = factory.create(type, Teuchos::RCP<const RowMatrix>());
      if (auto r = dynamic_cast<const Ifpack2::Relaxation<RowMatrix>*>(prec.get())) own = r->getValidParameters();
      if (auto b = dynamic_cast<const Ifpack2::BlockRelaxation<RowMatrix>*>(prec.get())) own = b->getValidParameters();
    } catch (const std::exception&) {
      return;  // no per-type list: the union check above stands
    }
    if (own.is_null()) return;
    const ParameterList& settings = user.sublist("Ifpack2 Settings");
    const std::string settingsPath = path + "/Ifpack2 Settings";
    for (auto it = settings.begin(); it != settings.end(); ++it) {
      const std::string& name = settings.name(it);
      const std::string key = settingsPath + "/" + name;
      if (!own->isParameter(name))
        failWithHint("'" + key + "' is not a parameter of Ifpack2 Prec Type " + type, name, namesOf(*own), "known for it");
      checkEntry(settings.entry(it), own->getEntry(name), name, key, "an Ifpack2 " + type + " parameter");
    }
  }

  // perinox's two-stage preconditioner: its own keys, and MueLu's list for the auxiliary
  // hierarchy; the fine smoother's Ifpack2 list is passed on (Ifpack2 checks it at set-up).
  void twoStage(const ParameterList& user, const ParameterList& valid, const std::string& path) const {
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const ParameterEntry& e = user.entry(it);
      const std::string key = path + "/" + name;
      if (!valid.isParameter(name))
        failWithHint("'" + key + "' is not a Two-Stage parameter", name, namesOf(valid), "known here");
      if (name == "MueLu" && e.isList()) {
        muelu(Teuchos::getValue<ParameterList>(e), key);
      } else if (name == "Fine Smoother Parameters" && e.isList()) {
        continue;
      } else {
        checkEntry(e, valid.getEntry(name), name, key, "a Two-Stage parameter");
      }
    }
  }

  // MueLu's simple parameter list, as MueLu::ParameterListInterpreter::Validate checks it: the
  // main list and 'level N' sublists (N < 100), names and types only (depth 0), after moving
  // non-serializable data ('user data', matrices and vectors in level lists) out of the way.
  void muelu(const ParameterList& user, const std::string& path) const {
    if (user.isSublist("Hierarchy") || user.isParameter("MueLu preconditioner") ||
        (user.isType<std::string>("parameterlist: syntax") && user.get<std::string>("parameterlist: syntax") == "ml"))
      return;  // factory-style, facade or ML-syntax lists: no list of valid keys
    const ParameterList& master = *MueLu::MasterList::List();
    const std::vector<std::string> masterNames = namesOf(master);
    auto levelList = [](const std::string& n) {
      if (n.rfind("level ", 0) != 0 || n.size() < 7 || n.size() > 8) return false;
      const std::string d = n.substr(6);
      if (!std::all_of(d.begin(), d.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) return false;
      return d.size() == 1 || d[0] != '0';
    };
    auto checkFlat = [&](const ParameterList& l, const std::string& p, bool level) {
      for (auto it = l.begin(); it != l.end(); ++it) {
        const std::string& name = l.name(it);
        const ParameterEntry& e = l.entry(it);
        const std::string key = p + "/" + name;
        if (level && (name == "A" || name == "P" || name == "R" || name == "M" || name == "Mdiag" || name == "K" ||
                      name == "Nullspace" || name == "Coordinates" || name == "Node Comm" ||
                      name == "DualNodeID2PrimalNodeID" || name == "pcoarsen: element to node map"))
          continue;
        if (!master.isParameter(name)) failWithHint("'" + key + "' is not a MueLu parameter", name, masterNames, "known here");
        const ParameterEntry& v = master.getEntry(name);
        if (v.isList() != e.isList()) {
          if (v.isList()) fail("'" + key + "' must be a sublist, not a parameter");
          fail("'" + key + "' must be a parameter of type " + typeName(v) + ", not a sublist");
        }
        if (!e.isList() && e.getAny(false).type() != v.getAny(false).type())
          fail("'" + key + "' must be of type " + typeName(v) + ", not " + typeName(e));
      }
    };
    ParameterList main;
    for (auto it = user.begin(); it != user.end(); ++it) {
      const std::string& name = user.name(it);
      const ParameterEntry& e = user.entry(it);
      if (e.isList() && levelList(name)) {
        checkFlat(user.sublist(name), path + "/" + name, true);
      } else if (e.isList() && name == "user data") {
        continue;  // user data for the hierarchy
      } else if ((name == "Nullspace" || name == "Coordinates") && !xmlType(e)) {
        continue;  // set by perinox's evaluator (rigid-body modes); Thyra's adapter moves it to 'user data'
      } else {
        main.setEntry(name, e);
      }
    }
    checkFlat(main, path, false);
  }

  std::string prefix_;
};

}  // namespace

void validateLinearSolverList(const Teuchos::ParameterList& stratimikos, const std::string& where) {
  // Stratimikos' valid list with perinox's strategies (Ifpack2, MueLu, MUMPS) registered, built
  // afresh (about a millisecond) so that no Trilinos object outlives the caller's MPI environment (MPI_Finalize).
  const Teuchos::RCP<const Teuchos::ParameterList> valid = validLinearSolverParameters();
  Checker(where).top(stratimikos, *valid);
  // A MUMPS preconditioner that renews its factors during a solve changes between Krylov
  // iterations: only flexible GMRES builds its solution from the preconditioned vectors it kept.
  auto text = [](const Teuchos::ParameterList& l, const std::string& key) {
    return l.isType<std::string>(key) ? l.get<std::string>(key) : std::string();
  };
  if (text(stratimikos, "Preconditioner Type") != "MUMPS" || !stratimikos.isSublist("Preconditioner Types")) return;
  const auto& types = stratimikos.sublist("Preconditioner Types");
  if (!types.isSublist("MUMPS")) return;
  const auto& mumps = types.sublist("MUMPS");
  if (!mumps.isType<int>("Refactor Within A Solve Above") || mumps.get<int>("Refactor Within A Solve Above") <= 0) return;
  bool flexible = false;
  if (text(stratimikos, "Linear Solver Type") == "Belos" && stratimikos.isSublist("Linear Solver Types") &&
      stratimikos.sublist("Linear Solver Types").isSublist("Belos")) {
    const auto& belos = stratimikos.sublist("Linear Solver Types").sublist("Belos");
    const std::string type = text(belos, "Solver Type");
    if (type == "Block GMRES" && belos.isSublist("Solver Types") && belos.sublist("Solver Types").isSublist(type)) {
      const auto& gmres = belos.sublist("Solver Types").sublist(type);
      flexible = gmres.isType<bool>("Flexible Gmres") && gmres.get<bool>("Flexible Gmres");
    }
  }
  if (!flexible)
    Checker(where).fail("'Preconditioner Types/MUMPS/Refactor Within A Solve Above' > 0 changes the preconditioner within a "
                        "solve; it needs Belos 'Block GMRES' with 'Flexible Gmres' = true");
}

const std::vector<std::pair<std::string, std::vector<std::string>>>& presetOwnKeys() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> keys = {
      {"Jacobian", {"Assembled", "Matrix-Free", "Jacobian-Free"}},
      {"Preconditioner Matrix", {"Assembled", "Neighbours", "None"}},
      {"Forcing Term", {"Constant", "Eisenstat-Walker"}}};
  return keys;
}

}  // namespace perinox

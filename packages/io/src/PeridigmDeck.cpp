// Peridigm decks translated into scenes (PeridigmDeck.hpp; docs/peridigm.md, key by key).
#include "perinox/io/PeridigmDeck.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <vector>

#include "SceneText.hpp"
#include "perinox/core/InputFile.hpp"
#include "perinox/io/Scene.hpp"

namespace perinox {
namespace {

using Teuchos::ParameterList;

constexpr std::size_t kMaxExpression = 1000;  // characters of a Value expression
constexpr int kMaxDepth = 50;                 // levels of parentheses and signs in it
constexpr int kMaxLoadSteps = 1000000;        // Solver/Load Steps' bound
constexpr double kAgreement = 1e-6;           // three or four elastic constants must agree to this

/// v with 17 significant digits: read back, the same double.
std::string roundTrip(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

/// The deck being read: its file (for messages) and the refusal.
struct Deck {
  std::string file;
  [[noreturn]] void refuse(const std::string& msg) const { throw SceneError(file + " (a Peridigm deck): " + msg); }
};

/// "path/key" ("key" at the top level).
std::string joined(const std::string& path, const std::string& key) { return path.empty() ? key : path + "/" + key; }

/// What a Teuchos entry holds, for a message.
std::string described(const Teuchos::ParameterEntry& e) {
  if (e.isList()) return "a list";
  if (e.isType<std::string>()) return "the text " + quote(e.getValue<std::string>(static_cast<std::string*>(nullptr)), 60);
  if (e.isType<double>()) return "the number " + roundTrip(e.getValue<double>(static_cast<double*>(nullptr)));
  if (e.isType<int>()) return "the number " + std::to_string(e.getValue<int>(static_cast<int*>(nullptr)));
  if (e.isType<bool>()) return std::string("the boolean ") + (e.getValue<bool>(static_cast<bool*>(nullptr)) ? "true" : "false");
  return "a value of type " + e.getAny().typeName();
}

/// A list of the deck and its path; each accessor refuses a missing or ill-typed key by naming
/// it ('Materials/Steel/Bulk Modulus').
struct Section {
  const Deck& deck;
  const ParameterList& pl;
  std::string path;

  bool has(const std::string& k) const { return pl.isParameter(k); }
  std::string key(const std::string& k) const { return "'" + joined(path, k) + "'"; }

  const Teuchos::ParameterEntry& entry(const std::string& k) const {
    const Teuchos::ParameterEntry* e = pl.getEntryPtr(k);
    if (!e) deck.refuse(key(k) + " is missing");
    return *e;
  }
  Section sub(const std::string& k) const {
    const Teuchos::ParameterEntry& e = entry(k);
    if (!e.isList()) deck.refuse(key(k) + " is " + described(e) + ", not a list");
    return Section{deck, pl.sublist(k), joined(path, k)};
  }
  std::string text(const std::string& k) const {
    const Teuchos::ParameterEntry& e = entry(k);
    if (!e.isType<std::string>()) deck.refuse(key(k) + " is " + described(e) + ", not a text");
    const std::string v = e.getValue<std::string>(static_cast<std::string*>(nullptr));
    if (v.find_first_not_of(" \t") == std::string::npos) deck.refuse(key(k) + " is empty");
    return v;
  }
  std::string text(const std::string& k, const std::string& otherwise) const { return has(k) ? text(k) : otherwise; }
  /// A finite number (a double, an int, or a text holding a decimal number) for which ok holds;
  /// `rule` says which, for the message.
  template <class Ok>
  double number(const std::string& k, const std::string& rule, Ok ok) const {
    const Teuchos::ParameterEntry& e = entry(k);
    double v = NAN;
    bool read = true;
    if (e.isType<double>()) {
      v = e.getValue<double>(static_cast<double*>(nullptr));
    } else if (e.isType<int>()) {
      v = e.getValue<int>(static_cast<int*>(nullptr));
    } else if (e.isType<std::string>()) {  // blanks around it allowed; out of double's range: not read
      const std::string s = e.getValue<std::string>(static_cast<std::string*>(nullptr));
      const std::size_t b = s.find_first_not_of(" \t"), end = s.find_last_not_of(" \t");
      const std::string t = b == std::string::npos ? "" : s.substr(b, end - b + 1);
      char* stop = nullptr;
      errno = 0;
      if (decimalCharacters(t)) v = std::strtod(t.c_str(), &stop);
      read = decimalCharacters(t) && *stop == '\0' && errno != ERANGE;
    } else {
      read = false;
    }
    if (!read) deck.refuse(key(k) + " is " + described(e) + "; it must be " + rule);
    if (!std::isfinite(v) || !ok(v)) deck.refuse(key(k) + " is " + roundTrip(v) + "; it must be " + rule);
    return v;
  }
  template <class Ok>
  double number(const std::string& k, const std::string& rule, Ok ok, double otherwise) const {
    return has(k) ? number(k, rule, ok) : otherwise;
  }
  /// The names of the entries, in the deck's order.
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (auto it = pl.begin(); it != pl.end(); ++it) n.push_back(pl.name(it));
    return n;
  }
};

// ---------------------------------------------------------------------------------------------
// Value expressions: numbers, x, y, z, t, + - * / and parentheses, read by recursive descent
// (never by a general evaluator), then checked to be t (a + b x + c y + d z).
//
//   expression := term { ("+" | "-") term }      term := factor { ("*" | "/") factor }
//   factor     := ("+" | "-") factor | number | "x" | "y" | "z" | "t" | "(" expression ")"
// ---------------------------------------------------------------------------------------------

struct Node {
  char op;  // 'n' number, 'v' variable, '~' negation, '+', '-', '*', '/'
  double value = 0;
  int var = 0;
  std::unique_ptr<Node> a, b;
};

class ExpressionParser {
 public:
  explicit ExpressionParser(const std::string& s) : s_(s) {}
  std::unique_ptr<Node> parse() {
    auto n = expression(0);
    skip();
    if (i_ < s_.size()) fail("has " + quote(s_.substr(i_, 1), 10) + " at character " + std::to_string(i_ + 1) +
                             " where an operator or the end was expected");
    return n;
  }
  std::string error;

 private:
  struct Failed {};
  [[noreturn]] void fail(const std::string& why) {
    error = why;
    throw Failed{};
  }
  void skip() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\n' || s_[i_] == '\r')) ++i_;
  }
  bool take(char c) {
    skip();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  static std::unique_ptr<Node> join(char op, std::unique_ptr<Node> a, std::unique_ptr<Node> b) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->a = std::move(a);
    n->b = std::move(b);
    return n;
  }
  std::unique_ptr<Node> expression(int depth) {
    auto n = term(depth);
    for (;;) {
      skip();
      if (take('+')) n = join('+', std::move(n), term(depth));
      else if (take('-')) n = join('-', std::move(n), term(depth));
      else return n;
    }
  }
  std::unique_ptr<Node> term(int depth) {
    auto n = factor(depth);
    for (;;) {
      skip();
      if (i_ + 1 < s_.size() && s_[i_] == '*' && s_[i_ + 1] == '*')
        fail("has '**' at character " + std::to_string(i_ + 1) + "; powers are not taken");
      if (take('*')) n = join('*', std::move(n), factor(depth));
      else if (take('/')) n = join('/', std::move(n), factor(depth));
      else return n;
    }
  }
  std::unique_ptr<Node> factor(int depth) {
    if (depth >= kMaxDepth) fail("nests parentheses and signs more than " + std::to_string(kMaxDepth) + " deep");
    skip();
    if (i_ >= s_.size()) fail("ends where a number, x, y, z, t or '(' was expected");
    const char c = s_[i_];
    const std::size_t at = i_;
    if (c == '+' || c == '-') {
      ++i_;
      auto inner = factor(depth + 1);
      if (c == '+') return inner;
      auto n = std::make_unique<Node>();
      n->op = '~';
      n->a = std::move(inner);
      return n;
    }
    if (c == '(') {
      ++i_;
      auto inner = expression(depth + 1);
      if (!take(')')) {
        skip();
        fail(i_ >= s_.size() ? std::string("has the end where ')' was expected")
                             : "has " + quote(s_.substr(i_, 1), 10) + " at character " + std::to_string(i_ + 1) + " where ')' was expected");
      }
      return inner;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      std::size_t j = i_;
      while (j < s_.size() && std::isdigit(static_cast<unsigned char>(s_[j]))) ++j;
      if (j < s_.size() && s_[j] == '.') ++j;
      while (j < s_.size() && std::isdigit(static_cast<unsigned char>(s_[j]))) ++j;
      if (j < s_.size() && (s_[j] == 'e' || s_[j] == 'E')) {
        std::size_t k = j + 1;
        if (k < s_.size() && (s_[k] == '+' || s_[k] == '-')) ++k;
        if (k < s_.size() && std::isdigit(static_cast<unsigned char>(s_[k]))) {
          while (k < s_.size() && std::isdigit(static_cast<unsigned char>(s_[k]))) ++k;
          j = k;
        }
      }
      const std::string word = s_.substr(i_, j - i_);
      if (word == ".") fail("has '.' at character " + std::to_string(at + 1) + ", which is not a number");
      const double v = std::strtod(word.c_str(), nullptr);
      const std::string mantissa = word.substr(0, word.find_first_of("eE"));
      if (!std::isfinite(v) || (v == 0 && mantissa.find_first_of("123456789") != std::string::npos))
        fail("has the number " + quote(word, 20) + ", which is out of the range of double precision");
      i_ = j;
      auto n = std::make_unique<Node>();
      n->op = 'n';
      n->value = v;
      return n;
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t j = i_;
      while (j < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[j])) || s_[j] == '_')) ++j;
      const std::string word = s_.substr(i_, j - i_);
      static const std::map<std::string, int> vars{{"x", 0}, {"y", 1}, {"z", 2}, {"t", 3}};
      const auto v = vars.find(word);
      if (v == vars.end())
        fail("uses the name " + quote(word, 20) + " at character " + std::to_string(at + 1) +
             "; only x, y, z and t are known (no functions or constants)");
      i_ = j;
      auto n = std::make_unique<Node>();
      n->op = 'v';
      n->var = v->second;
      return n;
    }
    fail("has " + quote(s_.substr(i_, 1), 10) + " at character " + std::to_string(at + 1) +
         ", which expressions do not take (only numbers, x, y, z, t, + - * / and parentheses)");
  }

  const std::string& s_;
  std::size_t i_ = 0;
};

/// The tree's value at p = (x, y, z, t); false on a division by zero.
bool evaluate(const Node& n, const std::array<double, 4>& p, double& out) {
  double a = 0, b = 0;
  switch (n.op) {
    case 'n': out = n.value; return true;
    case 'v': out = p[n.var]; return true;
    case '~':
      if (!evaluate(*n.a, p, a)) return false;
      out = -a;
      return true;
    default: break;
  }
  if (!evaluate(*n.a, p, a) || !evaluate(*n.b, p, b)) return false;
  switch (n.op) {
    case '+': out = a + b; break;
    case '-': out = a - b; break;
    case '*': out = a * b; break;
    default:
      if (b == 0) return false;
      out = a / b;
  }
  return true;
}

/// {a, b, c, d} with value(x, y, z, t) = t (a + b x + c y + d z), checked at 20 points; refuses
/// anything else naming the key and the expression.
std::array<double, 4> linearInT(const Deck& deck, const std::string& where, const Teuchos::ParameterEntry& e) {
  std::string expr;
  if (e.isType<std::string>()) expr = e.getValue<std::string>(static_cast<std::string*>(nullptr));
  else if (e.isType<double>()) expr = roundTrip(e.getValue<double>(static_cast<double*>(nullptr)));
  else if (e.isType<int>()) expr = std::to_string(e.getValue<int>(static_cast<int*>(nullptr)));
  else deck.refuse(where + " is " + described(e) + ", not an expression");
  const std::string shown = quote(expr, 60);
  if (expr.size() > kMaxExpression)
    deck.refuse(where + " is an expression of " + std::to_string(expr.size()) + " characters (" + shown + "); at most " +
                std::to_string(kMaxExpression) + " are read");
  if (expr.find_first_not_of(" \t\r\n") == std::string::npos) deck.refuse(where + " is empty");
  ExpressionParser parser(expr);
  std::unique_ptr<Node> tree;
  try {
    tree = parser.parse();
  } catch (...) {
    deck.refuse(where + ": " + shown + " " + parser.error);
  }
  const std::string form = " is not of the form t (a + b x + c y + d z), which perinox's conditions take";
  auto at = [&](double x, double y, double z, double t) {
    double v = 0;
    std::ostringstream pt;
    pt << "x = " << x << ", y = " << y << ", z = " << z << ", t = " << t;
    if (!evaluate(*tree, {x, y, z, t}, v)) deck.refuse(where + ": " + shown + " divides by zero at " + pt.str() + ", so it" + form);
    if (!std::isfinite(v)) deck.refuse(where + ": " + shown + " is not finite at " + pt.str() + ", so it" + form);
    return v;
  };
  const double a = at(0, 0, 0, 1);
  std::array<double, 4> c{a, at(1, 0, 0, 1) - a, at(0, 1, 0, 1) - a, at(0, 0, 1, 1) - a};
  double scale = 1 + std::abs(a);
  for (int i = 1; i < 4; ++i) scale += 3 * std::abs(c[i]);
  if (!std::isfinite(scale)) deck.refuse(where + ": " + shown + " has coefficients beyond double precision");
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int k = 0; k < 20; ++k) {
    const double x = u(rng), y = u(rng), z = u(rng), t = u(rng);
    const double want = t * (c[0] + c[1] * x + c[2] * y + c[3] * z);
    if (!(std::abs(at(x, y, z, t) - want) <= 1e-12 * (scale + std::abs(want)))) deck.refuse(where + ": " + shown + form);
  }
  for (double& v : c) v += 0.0;  // no -0 in the scene
  return c;
}

// ---------------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------------

struct DeckMaterial {
  double E = 0, nu = 0, K = 0, G = 0, hourglass = 0;
  std::string from;          // the two constants used
  bool plastic = false;
  double yieldStress = 0, hardening = 0;
};

DeckMaterial readMaterial(const Section& m) {
  const std::string model = m.text("Material Model");
  DeckMaterial mat;
  if (model == "Elastic Plastic Correspondence") mat.plastic = true;
  else if (model != "Elastic Correspondence")
    m.deck.refuse(m.key("Material Model") + " is " + quote(model) +
                  "; perinox translates Elastic Correspondence and Elastic Plastic Correspondence (its materials are correspondence materials)");
  const std::array<std::string, 4> names{"Young's Modulus", "Poisson's Ratio", "Bulk Modulus", "Shear Modulus"};
  std::map<std::string, double> given;
  for (const auto& k : names) {
    if (!m.has(k)) continue;
    if (k == "Poisson's Ratio") given[k] = m.number(k, "a number between -1 and 0.5 (both excluded)", [](double v) { return v > -1 && v < 0.5; });
    else given[k] = m.number(k, "a finite number above 0", [](double v) { return v > 0; });
  }
  if (given.size() < 2)
    m.deck.refuse("material " + quote(m.path, 60) + " gives " + (given.empty() ? std::string("none") : "only " + given.begin()->first) +
                  " of the elastic constants; give two of Young's Modulus, Poisson's Ratio, Bulk Modulus, Shear Modulus");
  static const std::array<std::array<int, 2>, 6> pairs{{{0, 1}, {2, 3}, {0, 3}, {0, 2}, {2, 1}, {3, 1}}};
  std::array<int, 2> pair{};
  for (const auto& p : pairs)
    if (given.count(names[p[0]]) && given.count(names[p[1]])) {
      pair = p;
      break;
    }
  const double a = given[names[pair[0]]], b = given[names[pair[1]]];
  double E = 0, nu = 0;
  if (pair == std::array<int, 2>{0, 1}) E = a, nu = b;
  else if (pair == std::array<int, 2>{2, 3}) E = 9 * a * b / (3 * a + b), nu = (3 * a - 2 * b) / (2 * (3 * a + b));
  else if (pair == std::array<int, 2>{0, 3}) E = a, nu = a / (2 * b) - 1;
  else if (pair == std::array<int, 2>{0, 2}) E = a, nu = (3 * b - a) / (6 * b);
  else if (pair == std::array<int, 2>{2, 1}) E = 3 * a * (1 - 2 * b), nu = b;
  else E = 2 * a * (1 + b), nu = b;
  const std::string both = m.key(names[pair[0]]) + " and '" + names[pair[1]] + "'";
  if (!std::isfinite(E) || !std::isfinite(nu)) m.deck.refuse(both + " are too large to convert to Young's modulus and Poisson's ratio");
  if (!(nu > -1 && nu < 0.5))
    m.deck.refuse(both + " give Poisson's ratio " + roundTrip(nu) + ", outside -1 < nu < 0.5 (K and G must be above 0)");
  mat.E = E;
  mat.nu = nu;
  mat.K = E / (3 * (1 - 2 * nu));
  mat.G = E / (2 * (1 + nu));
  const std::map<std::string, double> derived{{names[0], E}, {names[1], nu}, {names[2], mat.K}, {names[3], mat.G}};
  for (const auto& [k, v] : given) {
    if (k == names[pair[0]] || k == names[pair[1]]) continue;
    const double d = derived.at(k);
    const double off = k == names[1] ? std::abs(v - d) : std::abs(v - d) / std::max(std::abs(v), std::abs(d));
    if (!(off <= kAgreement))
      m.deck.refuse(m.key(k) + " is " + roundTrip(v) + " but " + names[pair[0]] + " and " + names[pair[1]] + " give " + roundTrip(d) +
                    " (they differ by more than 1e-6); give two elastic constants, or ones that agree");
  }
  mat.from = names[pair[0]] + " and " + names[pair[1]];
  if (m.has("Density")) m.number("Density", "a finite number above 0", [](double v) { return v > 0; });
  mat.hourglass = m.number("Hourglass Coefficient", "a finite number, 0 or above", [](double v) { return v >= 0; }, 0.0);
  if (mat.plastic) {
    mat.yieldStress = m.number("Yield Stress", "a finite number above 0", [](double v) { return v > 0; });
    mat.hardening = m.number("Hardening Modulus", "a finite number, 0 or above", [](double v) { return v >= 0; }, 0.0);
  }
  return mat;
}

Teuchos::Array<double> array3(double a, double b, double c) {
  Teuchos::Array<double> v(3);
  v[0] = a, v[1] = b, v[2] = c;
  return v;
}

/// N of "block_N", or -1.
long long blockId(const std::string& name) {
  if (name.rfind("block_", 0) != 0 || name.size() == 6 || name.size() > 15) return -1;
  const std::string digits = name.substr(6);
  if (digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stoll(digits);
}

void setMaterial(ParameterList& ml, const DeckMaterial& m) {
  ml.set("Young's Modulus", m.E);
  ml.set("Poisson's Ratio", m.nu);
  ml.set("Plasticity", std::string(m.plastic ? "J2" : "None"));
  if (m.plastic) {
    ml.set("Yield Stress", m.yieldStress);
    ml.set("Hardening Modulus", m.hardening);
  }
}

std::string absolutePath(const std::string& deckPath, const std::string& rel) {
  namespace fs = std::filesystem;
  fs::path p(rel);
  std::error_code ec;
  if (p.is_relative()) p = fs::absolute(fs::path(deckPath), ec).parent_path() / p;
  return p.lexically_normal().string();
}

}  // namespace

bool isPeridigmDeck(const ParameterList& pl) {
  return pl.isSublist("Materials") || pl.isSublist("Compute Class Parameters") ||
         (pl.isSublist("Discretization") && pl.sublist("Discretization").isParameter("Input Mesh File"));
}

PeridigmScene sceneFromPeridigmDeck(const ParameterList& deckList, const std::string& deckPath) {
  const Deck deck{deckPath};
  const Section p{deck, deckList, ""};
  PeridigmScene out;
  ParameterList& sc = out.scene;
  std::ostringstream notes;

  static const std::set<std::string> known{"Verbose", "Discretization", "Materials", "Blocks", "Boundary Conditions", "Solver",
                                           "Compute Class Parameters"};
  for (const std::string& k : p.names())
    if (!known.count(k) && k.rfind("Output", 0) != 0)
      deck.refuse("has '" + k + "', which perinox does not translate (it reads Discretization, Materials, Blocks, Boundary Conditions, "
                  "Solver, Compute Class Parameters and Output lists)");
  // Discretization: an Exodus mesh or a text file ("x y z block volume" lines).
  const Section disc = p.sub("Discretization");
  const std::string dtype = disc.text("Type");
  if (dtype != "Exodus" && dtype != "Text File")
    deck.refuse(disc.key("Type") + " is " + quote(dtype) + "; perinox translates Exodus meshes and text files (Type Exodus or Text File)");
  const bool textFile = dtype == "Text File";
  const std::string meshGiven = disc.text("Input Mesh File"), mesh = absolutePath(deckPath, meshGiven);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(mesh, ec))
    deck.refuse(disc.key("Input Mesh File") + " is " + quote(meshGiven, 80) + ", which " +
                (std::filesystem::exists(mesh, ec) ? "is not a file" : "does not exist") + " (looked for " + quote(mesh, 200) + ")");
  for (const std::string& k : disc.names())
    if (k != "Type" && k != "Input Mesh File" && k != "Omit Bonds Between Blocks" && k != "Verbose")
      deck.refuse(disc.key(k) + " is not translated (perinox reads Type and Input Mesh File)");
  if (disc.has("Omit Bonds Between Blocks") && disc.text("Omit Bonds Between Blocks") != "None")
    deck.refuse(disc.key("Omit Bonds Between Blocks") + " is " + quote(disc.text("Omit Bonds Between Blocks"), 40) +
                "; perinox keeps the bonds between blocks (None)");

  // Materials and blocks.
  const Section mats = p.sub("Materials");
  std::map<std::string, DeckMaterial> materials;
  for (const std::string& name : mats.names()) materials.emplace(name, readMaterial(mats.sub(name)));
  if (materials.empty()) deck.refuse("'Materials' is empty: the deck has no materials");
  const Section blocks = p.sub("Blocks");
  struct BlockUse {
    std::string name;
    long long id;
    const DeckMaterial* mat;
  };
  std::vector<BlockUse> uses;
  std::map<long long, std::string> listedBy;
  double horizon = -1;
  std::string horizonFrom;
  for (const std::string& bname : blocks.names()) {
    const Section b = blocks.sub(bname);
    if (b.has("Damage Model")) deck.refuse(b.key("Damage Model") + " is given; perinox does not translate Peridigm's damage models");
    const std::string mname = b.text("Material");
    const auto m = materials.find(mname);
    if (m == materials.end()) deck.refuse(b.key("Material") + " is " + quote(mname) + ", which 'Materials' does not define");
    const double h = b.number("Horizon", "a finite number above 0", [](double v) { return v > 0; });
    if (horizon < 0) horizon = h, horizonFrom = b.key("Horizon");
    else if (h != horizon)
      deck.refuse(b.key("Horizon") + " is " + roundTrip(h) + " but " + horizonFrom + " is " + roundTrip(horizon) +
                  "; perinox uses one horizon for all blocks, and these blocks' horizons differ");
    std::istringstream names(b.text("Block Names"));
    for (std::string n; names >> n;) {
      const long long id = blockId(n);
      if (id < 0) deck.refuse(b.key("Block Names") + " lists " + quote(n) + "; perinox translates Peridigm's block_<id> names");
      if (listedBy.count(id)) deck.refuse(b.key("Block Names") + " lists " + n + ", which block " + quote(listedBy[id]) + " lists too");
      listedBy[id] = bname;
      uses.push_back({n, id, &m->second});
    }
  }
  if (uses.empty()) deck.refuse("'Blocks' is empty: the deck has no blocks");

  // Solver: quasi-static load steps, or Verlet on a kinematic (fully prescribed) deck.
  const Section solver = p.sub("Solver");
  solver.number("Initial Time", "0 (perinox's load factor is t / Final Time)", [](double v) { return v == 0; }, 0.0);
  const double finalTime = solver.number("Final Time", "a finite number above 0", [](double v) { return v > 0; });
  int steps = 1, maxIterations = 25;
  std::string solverName;
  for (const std::string s : {"QuasiStatic", "NOXQuasiStatic", "Verlet"}) {
    if (!solver.has(s)) continue;
    if (!solverName.empty()) deck.refuse("'Solver' has both " + solverName + " and " + s + "; give one");
    solverName = s;
  }
  for (const std::string& k : solver.names())
    if (solver.pl.isSublist(k) && k != solverName)
      deck.refuse(solver.key(k) + " is not translated: perinox runs QuasiStatic and NOXQuasiStatic decks (and Verlet decks whose every displacement is prescribed)");
  if (solverName.empty()) deck.refuse("'Solver' has no QuasiStatic, NOXQuasiStatic or Verlet list");
  const Section qs = solver.sub(solverName);
  const std::string stepRule = "a whole number from 1 to " + std::to_string(kMaxLoadSteps);
  auto whole = [](double v) { return v == std::floor(v) && v >= 1 && v <= kMaxLoadSteps; };
  if (solverName == "Verlet") {
    const double dt = qs.number("Fixed dt", "a finite number above 0", [](double v) { return v > 0; });
    const double n = std::round(finalTime / dt);
    if (!whole(n) || std::abs(n * dt - finalTime) > 1e-9 * finalTime)
      deck.refuse(qs.key("Fixed dt") + " is " + roundTrip(dt) + ", which does not divide 'Solver/Final Time' into " + stepRule + " of steps");
    steps = static_cast<int>(n);
    out.kinematicOnly = true;
    notes << "Verlet with every displacement prescribed: its " << steps << " time steps are load steps. ";
  } else {
    steps = static_cast<int>(qs.number("Number of Load Steps", stepRule, whole, 1.0));
    maxIterations = static_cast<int>(qs.number("Maximum Solver Iterations", "a whole number from 1 to 1000",
                                               [](double v) { return v == std::floor(v) && v >= 1 && v <= 1000; }, 25.0));
    if (qs.has("Absolute Tolerance")) {
      qs.number("Absolute Tolerance", "a finite number above 0", [](double v) { return v > 0; });
      notes << "Peridigm's Absolute Tolerance (a force-density norm) is not translated: perinox stops at |R| / |reaction| below "
               "Solver/Tolerance. ";
    }
  }

  // Boundary conditions on node sets (the mesh's, or defined in the deck by numbers or a file):
  // prescribed displacements, and body forces as loads.
  ParameterList& regions = sc.sublist("Regions");
  ParameterList& conditions = sc.sublist("Boundary Conditions");
  std::map<std::pair<std::string, std::string>, std::array<double, 4>> prescribed;
  if (p.has("Boundary Conditions")) {
    const Section bcs = p.sub("Boundary Conditions");
    // Peridigm's names compare upper-cased with blanks as underscores ("Node Set One" = "node_set_one").
    auto tidy = [](std::string n) {
      const std::size_t b = n.find_first_not_of(' '), e = n.find_last_not_of(' ');
      n = b == std::string::npos ? "" : n.substr(b, e - b + 1);
      for (char& ch : n) ch = ch == ' ' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      return n;
    };
    // Node sets the deck defines: a key holding NODE_SET whose value lists numbers (an int, or a
    // text with blanks or a leading number) or names a file (relative to the deck's folder).
    std::map<std::string, std::string> definedSets;  // tidy name -> region name
    for (const std::string& name : bcs.names()) {
      const Teuchos::ParameterEntry& e = bcs.entry(name);
      if (e.isList()) continue;
      if (tidy(name).find("NODE_SET") == std::string::npos)
        deck.refuse(bcs.key(name) + " is " + described(e) + ", not a list (a boundary condition) nor a node set (a key with 'Node Set' in its name)");
      if (!definedSets.emplace(tidy(name), name).second)
        deck.refuse(bcs.key(name) + " defines a node set whose name another node set has (Peridigm compares names upper-cased)");
      ParameterList& r = regions.sublist(name);
      r.set("Type", std::string("Ids"));
      if (e.isType<int>()) {
        r.set("Ids", Teuchos::Array<int>(1, e.getValue<int>(static_cast<int*>(nullptr))));
        continue;
      }
      const std::string v = bcs.text(name);
      const std::size_t b = v.find_first_not_of(" \t"), end = v.find_last_not_of(" \t");
      const std::string t = v.substr(b, end - b + 1);
      const bool list = t.find_first_of(" \t") != std::string::npos || std::isdigit(static_cast<unsigned char>(t[0])) || t[0] == '-' ||
                        t[0] == '+';
      if (!list) {
        const std::string file = absolutePath(deckPath, t);
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec))
          deck.refuse(bcs.key(name) + " names the node-set file " + quote(t, 80) + ", which " +
                      (std::filesystem::exists(file, ec) ? "is not a file" : "does not exist") + " (looked for " + quote(file, 200) + ")");
        r.set("Ids File", file);
        continue;
      }
      Teuchos::Array<int> ids;
      std::istringstream in(t);
      std::string tok;
      while (in >> tok) {
        char* stop = nullptr;
        errno = 0;
        const long long id = std::strtoll(tok.c_str(), &stop, 10);
        if (*stop != '\0' || errno == ERANGE || id < 1 || id > INT_MAX)
          deck.refuse(bcs.key(name) + " lists " + quote(tok, 40) + "; node numbers are whole numbers from 1");
        ids.push_back(static_cast<int>(id));
      }
      r.set("Ids", ids);
    }
    for (const std::string& name : bcs.names()) {
      if (!bcs.entry(name).isList()) continue;
      const Section bc = bcs.sub(name);
      const std::string type = bc.text("Type");
      if (type != "Prescribed Displacement" && type != "Body Force")
        deck.refuse(bc.key("Type") + " is " + quote(type) + "; perinox translates Prescribed Displacement and Body Force");
      const std::string ns = bc.text("Node Set");
      const std::string comp = bc.text("Coordinate");
      if (comp != "x" && comp != "y" && comp != "z") deck.refuse(bc.key("Coordinate") + " is " + quote(comp) + "; it must be x, y or z");
      std::array<double, 4> c = linearInT(deck, bc.key("Value"), bc.entry("Value"));
      for (double& v : c) v *= finalTime;  // t = load factor x Final Time
      std::string region = ns;
      if (const auto def = definedSets.find(tidy(ns)); def != definedSets.end()) {
        region = def->second;
      } else if (textFile) {
        deck.refuse(bc.key("Node Set") + " is " + quote(ns, 60) + ", which the deck does not define (a text-file mesh has no node sets "
                    "of its own: define it in 'Boundary Conditions' by numbers or a file)");
      } else if (!regions.isSublist(ns)) {
        ParameterList& r = regions.sublist(ns);
        r.set("Type", std::string("Node Set"));
        r.set("Name", ns);
      }
      const int axis = comp[0] - 'x';
      if (type == "Body Force") {  // a force per volume on the node set's particles
        if (c[1] != 0 || c[2] != 0 || c[3] != 0)
          deck.refuse(bc.key("Value") + " varies with x, y or z; perinox's body forces are uniform over their region (t times a number)");
        ParameterList& ld = sc.sublist("Loads").sublist(name);
        ld.set("Region", region);
        ld.set("Type", std::string("Body Force"));
        ld.set("Value", array3(axis == 0 ? c[0] : 0.0, axis == 1 ? c[0] : 0.0, axis == 2 ? c[0] : 0.0));
        continue;
      }
      const auto [it, fresh] = prescribed.emplace(std::make_pair(region, comp), c);
      if (!fresh && it->second != c)
        deck.refuse("boundary condition " + quote(name) + " prescribes " + comp + " on " + quote(ns) + " differently from another condition");
      ParameterList& cl = conditions.sublist(name);
      cl.set("Region", region);
      cl.set("Component", comp);
      cl.set("Value", c[0]);
      if (c[1] != 0 || c[2] != 0 || c[3] != 0) cl.set("Gradient", array3(c[1], c[2], c[3]));
    }
  }

  // Compute classes: Block_Data force sums as reactions, Nearest_Point_Data displacements.
  ParameterList& probes = sc.sublist("Probes");
  if (p.has("Compute Class Parameters")) {
    const Section ccp = p.sub("Compute Class Parameters");
    for (const std::string& name : ccp.names()) {
      const Section c = ccp.sub(name);
      const std::string cls = c.text("Compute Class");
      const std::string variable = c.text("Variable", "");
      std::string region, quantity;
      if (cls == "Block_Data" && variable == "Force" && c.text("Calculation Type", "") == "Sum") {
        const std::string block = c.text("Block");
        const long long id = blockId(block);
        if (id < 0) deck.refuse(c.key("Block") + " is " + quote(block) + "; perinox translates Peridigm's block_<id> names");
        region = block;
        if (!regions.isSublist(region)) {
          ParameterList& r = regions.sublist(region);
          r.set("Type", std::string("Block"));
          r.set("Id", static_cast<int>(id));
        }
        quantity = "Reaction";
      } else if (cls == "Nearest_Point_Data" && variable == "Displacement") {
        auto any = [](double) { return true; };
        const Teuchos::Array<double> at = array3(c.number("X", "a finite number", any), c.number("Y", "a finite number", any),
                                                 c.number("Z", "a finite number", any));
        region = "near " + name;
        ParameterList& r = regions.sublist(region);
        r.set("Type", std::string("Nearest"));
        r.set("Point", at);
        quantity = "Displacement";
      } else {
        notes << "Compute class " << quote(name) << " (" << cls << ") has no perinox probe: skipped. ";
        continue;
      }
      const std::string label = c.text("Output Label");
      if (probes.isSublist(label)) deck.refuse(c.key("Output Label") + " is " + quote(label) + ", which another compute class uses too");
      ParameterList& pr = probes.sublist(label);
      pr.set("Region", region);
      pr.set("Quantity", quantity);
    }
  }

  // The scene.
  const std::string deckName = std::filesystem::path(deckPath).filename().string();
  sc.set("Title", "Peridigm deck " + deckName);
  ParameterList& d = sc.sublist("Discretization");
  d.set("Dimension", 3);
  if (textFile) {
    d.set("Type", std::string("Particle File"));
    d.set("Particle File", mesh);
    d.set("Particle File Columns", std::string("x y z block volume"));
  } else {
    d.set("Type", std::string("Exodus"));
    d.set("Mesh File", mesh);
  }
  d.set("Horizon", horizon);
  const DeckMaterial& first = *uses.front().mat;
  ParameterList& ml = sc.sublist("Material");
  ml.set("Model", std::string("Hencky"));
  setMaterial(ml, first);
  bool stabilised = false, oneMaterial = true;
  for (const auto& u : uses) {
    stabilised = stabilised || u.mat->hourglass > 0;
    oneMaterial = oneMaterial && u.mat == &first;
  }
  if (stabilised) {
    sc.sublist("Model").set("Stabilization", std::string("Silling"));
    sc.sublist("Model").set("G", first.hourglass);
    sc.sublist("Model").set("G Form", std::string("Peridigm Hourglass"));
  }
  if (!oneMaterial) {
    ParameterList& bl = sc.sublist("Blocks");
    for (const auto& u : uses) {
      ParameterList& b = bl.sublist(u.name);
      b.set("Id", static_cast<int>(u.id));
      setMaterial(b.sublist("Material"), *u.mat);
      if (stabilised) b.sublist("Stabilization").set("G", u.mat->hourglass);
    }
  }
  ParameterList& so = sc.sublist("Solver");
  so.set("Load Steps", steps);
  so.set("Max Newton Iterations", maxIterations);
  // The linear solver is left to auto (AutoLinearSolver.hpp): Peridigm's tensile deck gets the
  // matrix-free scalable solver (12 s; the former default, assembled GMRES + ILU, had not converged
  // its first step after 7 minutes), a small deck a direct solve.
  so.set("Linear Solver Preset", std::string("auto"));
  sc.sublist("Output").set("Format", std::string("Exodus"));

  std::ostringstream what;
  what << "Translated from the Peridigm deck " << deckPath << ". ";
  for (const auto& [name, m] : materials)
    what << "material " << quote(name, 60) << ": K = " << roundTrip(m.K) << ", G = " << roundTrip(m.G) << ", E = " << roundTrip(m.E)
         << ", nu = " << roundTrip(m.nu) << " (from " << m.from
         << "), Hencky (Peridigm's correspondence material is a hypoelastic rate form: the two agree to the order of the strain), "
         << (m.hourglass > 0 ? "hourglass coefficient " + roundTrip(m.hourglass) +
                                   " (Model/G Form = Peridigm Hourglass: each particle's Silling G gives the family Peridigm's stabilising stiffness)"
                             : std::string("no hourglass control"))
         << (m.plastic ? ", J2 plasticity with linear hardening" : "") << ". ";
  what << "Linear solver: auto, chosen from the problem (--set Solver/Linear Solver Preset=... to choose). ";
  what << "Displacements: t = load factor x Final Time (" << roundTrip(finalTime)
       << "). Node sets select the elements touching their nodes, as in Peridigm. A Block_Data force sum is a Reaction probe: "
          "the force the supports exert, Peridigm's sum with the opposite sign. "
       << notes.str();
  sc.set("Description", what.str());
  return out;
}

}  // namespace perinox

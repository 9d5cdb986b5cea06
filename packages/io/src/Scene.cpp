// Scene parsing and validation. Every check here exists so that a user's mistake gives one
// sentence naming the file (or --set argument) and key, before any particle is built.
#include "perinox/io/Scene.hpp"

#include <Teuchos_Array.hpp>
#include <Teuchos_CommHelpers.hpp>
#include <Teuchos_DefaultComm.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Teuchos_StrUtils.hpp>
#include <Teuchos_StringInputSource.hpp>
#include <Teuchos_XMLObject.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Teuchos_XMLParameterListReader.hpp>
#include <Teuchos_XMLParameterListWriter.hpp>
#include <Teuchos_YamlParameterListCoreHelpers.hpp>
#include <dirent.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <type_traits>

#include "SceneText.hpp"
#include "perinox/core/ExodusMesh.hpp"
#include "perinox/core/InputFile.hpp"
#include "perinox/io/PeridigmDeck.hpp"
#include "perinox/evaluator/LowestRankMessage.hpp"
#include "perinox/evaluator/Partitioner.hpp"
#include "perinox/evaluator/Problem.hpp"
#include "perinox/model/Partition.hpp"
#include "perinox/solver/AutoLinearSolver.hpp"

namespace perinox {

namespace {

using Teuchos::Array;
using Teuchos::ParameterList;

template <class T>
Array<T> arr(std::initializer_list<T> v) {
  return Array<T>(std::vector<T>(v));
}

// Upper bounds on the work a scene may ask for (each stated in its key's documentation).
constexpr int kMaxLoadSteps = 1000000;
constexpr int kMaxTotalSteps = 20 * kMaxLoadSteps;  // the default, 20 x Load Steps, always fits
constexpr int kMaxArcSteps = 1000000;
constexpr int kMaxNewtonIterations = 1000;
constexpr int kMaxCutbacks = 60;                    // 2^-60 of an increment is below round-off
constexpr double kMaxHorizonFactor = 50.0;          // horizon / spacing
constexpr std::size_t kMaxMessage = 300;            // characters of a message after the file name

std::string joinKey(const std::string& path, const std::string& name) {
  return path.empty() ? name : path + "/" + name;
}

std::string orList(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i == 0 ? "" : i + 1 == v.size() ? " or " : ", ") + v[i];
  return s;
}

std::string number(double v) { return messageNumber(v); }

/// One line, at most kMaxMessage characters: a message never grows with the user's input.
std::string failMessage(const std::string& file, std::string msg) {
  std::replace_if(msg.begin(), msg.end(), [](char c) { return c == '\n' || c == '\r' || c == '\t'; }, ' ');
  if (msg.size() > kMaxMessage) msg = msg.substr(0, kMaxMessage - 3) + "...";
  return file + ": " + msg;
}

[[noreturn]] void fail(const std::string& file, std::string msg) { throw SceneError(failMessage(file, std::move(msg))); }

// ---------------------------------------------------------------------------------------------
// Schema: every key with its default, its meaning and, where the value is restricted, a Teuchos
// validator holding the allowed values (StringToIntegralParameterEntryValidator) or the range
// (an EnhancedNumberValidator): written once, they give the documentation, the checks and the
// messages.
// ---------------------------------------------------------------------------------------------

/// Sublists whose children are user-named entries validated against one template.
const std::map<std::string, std::string>& namedSublists() {
  static const std::map<std::string, std::string> m{{"Regions", "region"},
                                                    {"Boundary Conditions", "condition"},
                                                    {"Loads", "load"},
                                                    {"Probes", "probe"},
                                                    {"Holes", "hole"},
                                                    {"Blocks", "block"}};
  return m;
}

/// The allowed values of an enumerated key, matched exactly, each with the value E the scene's
/// builder reads (getIntegralValue). Its documentation is the key's own: it lists the values.
template <class E>
class Choices final : public Teuchos::StringToIntegralParameterEntryValidator<E> {
 public:
  using Teuchos::StringToIntegralParameterEntryValidator<E>::StringToIntegralParameterEntryValidator;
  void printDoc(const std::string& doc, std::ostream& out) const override { Teuchos::StrUtils::printLines(out, "# ", doc); }
};

/// The allowed values of each entry of an array of strings (Fictitious Sides); documented by the key.
class ChoiceList final : public Teuchos::ArrayStringValidator {
 public:
  using Teuchos::ArrayStringValidator::ArrayStringValidator;
  void printDoc(const std::string& doc, std::ostream& out) const override { Teuchos::StrUtils::printLines(out, "# ", doc); }
};

/// A number's allowed range, each end closed, open or absent; its phrase ("from 1 to 60", "in (0,
/// 1]", "positive", ">= 0") ends the key's documentation and the message refusing a value outside
/// it, with an optional note on why.
enum class End { Closed, Open, None };
template <class T>
class Range final : public Teuchos::EnhancedNumberValidator<T> {
 public:
  Range(End loEnd, T lo, T hi, End hiEnd, std::string note = "")
      : Teuchos::EnhancedNumberValidator<T>(loEnd == End::None ? std::numeric_limits<T>::lowest() : lo,
                                            hiEnd == End::None ? std::numeric_limits<T>::max() : hi),
        loEnd_(loEnd), hiEnd_(hiEnd), lo_(lo), hi_(hi), note_(std::move(note)) {}
  bool holds(T v) const {
    if (loEnd_ != End::None && (v < lo_ || (loEnd_ == End::Open && v == lo_))) return false;
    return hiEnd_ == End::None || (v < hi_ || (hiEnd_ == End::Closed && v == hi_));
  }
  std::string phrase() const {
    if (std::is_integral<T>::value)
      return hiEnd_ == End::None ? "at least " + shown(lo_) : "from " + shown(lo_) + " to " + shown(hi_);
    if (hiEnd_ == End::None) {
      if (lo_ == 0) return loEnd_ == End::Open ? "positive" : ">= 0";
      return (loEnd_ == End::Open ? "greater than " : "at least ") + shown(lo_);
    }
    return std::string("in ") + (loEnd_ == End::Open ? "(" : "[") + shown(lo_) + ", " + shown(hi_) + (hiEnd_ == End::Open ? ")" : "]");
  }
  const std::string& note() const { return note_; }
  void validate(const Teuchos::ParameterEntry& entry, const std::string& name, const std::string& sublist) const override {
    Teuchos::EnhancedNumberValidator<T>::validate(entry, name, sublist);
    if (!holds(Teuchos::getValue<T>(entry)))
      throw Teuchos::Exceptions::InvalidParameterValue("'" + sublist + "/" + name + "' must be " + phrase());
  }
  void printDoc(const std::string& doc, std::ostream& out) const override { Teuchos::StrUtils::printLines(out, "# ", doc); }

 private:
  static std::string shown(T v) { return number(static_cast<double>(v)); }
  End loEnd_, hiEnd_;
  T lo_, hi_;
  std::string note_;
};

Teuchos::RCP<const Range<int>> ints(int lo, int hi = INT_MAX) {
  return Teuchos::rcp(new Range<int>(End::Closed, lo, hi, hi == INT_MAX ? End::None : End::Closed));
}
Teuchos::RCP<const Range<double>> reals(End loEnd, double lo, double hi, End hiEnd, const std::string& note = "") {
  return Teuchos::rcp(new Range<double>(loEnd, lo, hi, hiEnd, note));
}
Teuchos::RCP<const Range<double>> positive(const std::string& note = "") { return reals(End::Open, 0, 0, End::None, note); }
Teuchos::RCP<const Range<double>> nonNegative(const std::string& note = "") { return reals(End::Closed, 0, 0, End::None, note); }

/// A number key with its range: the range's phrase ends the documentation. The validator is
/// attached without checking the default (a default such as Young's Modulus 0 means "not given").
template <class T>
void setNumber(ParameterList& l, const std::string& key, T def, const std::string& doc, const Teuchos::RCP<const Range<T>>& range) {
  l.set(key, def, doc + " (" + range->phrase() + (range->note().empty() ? "" : "; " + range->note()) + ")");
  l.getEntryRCP(key)->setValidator(range);
}

template <class E>
struct Choice {
  std::string value;
  E e;
  std::string meaning;
};

/// An enumerated string key: matched exactly; its documentation lists the values.
template <class E>
void setChoice(ParameterList& l, const std::string& key, const std::string& def, const std::vector<Choice<E>>& choices,
               const std::string& lead = "", const std::string& tail = "") {
  std::vector<std::string> values, described, docs;
  std::vector<E> es;
  for (const auto& c : choices) {
    values.push_back(c.value);
    docs.push_back(c.meaning);
    es.push_back(c.e);
    described.push_back(c.meaning.empty() ? c.value : c.value + " (" + c.meaning + ")");
  }
  l.set(key, def, lead + orList(described) + tail,
        Teuchos::rcp(new Choices<E>(Teuchos::arrayViewFromVector(values), Teuchos::arrayViewFromVector(docs),
                                    Teuchos::arrayViewFromVector(es), key)));
}

/// A choice whose builder reads the string itself (its position in the list is its value).
void setChoice(ParameterList& l, const std::string& key, const std::string& def,
               const std::vector<std::pair<std::string, std::string>>& choices, const std::string& lead = "",
               const std::string& tail = "") {
  std::vector<Choice<int>> c;
  for (const auto& [value, meaning] : choices) c.push_back({value, static_cast<int>(c.size()), meaning});
  setChoice(l, key, def, c, lead, tail);
}

/// The value E of the enumerated key `key` of the user's list l, through the schema's validator.
template <class E>
E choice(const ParameterList& l, const ParameterList& schema, const std::string& key) {
  const auto v = Teuchos::rcp_dynamic_cast<const Teuchos::StringToIntegralParameterEntryValidator<E>>(
      schema.getEntry(key).validator(), true);
  return v->getIntegralValue(l.get<std::string>(key), key, l.name());
}

std::vector<Choice<Side>> sideChoices() {
  std::vector<Choice<Side>> c;
  for (int s = 0; s < 6; ++s) c.push_back({sideName(static_cast<Side>(s)), static_cast<Side>(s), ""});
  return c;
}

// Vector keys are known to the checks by pattern: the key with the user's name of a named
// sublist's entry replaced by '*' ("Regions/*/Point"). The setter records, for each, the array
// length the scene's dimension fixes.
enum class Length { Dim, DimOrEmpty, DimSquaredOrEmpty, Three };
std::map<std::string, Length>& lengthTable() {
  static std::map<std::string, Length> t;
  return t;
}

std::string lengthRule(Length r) {
  switch (r) {
    case Length::Dim: return "Dimension entries";
    case Length::DimOrEmpty: return "none, or Dimension entries";
    case Length::DimSquaredOrEmpty: return "none, or Dimension x Dimension entries";
    default: return "3 entries";
  }
}

/// An array key whose length the scene's dimension fixes (stated in its documentation).
template <class T>
void setVector(ParameterList& l, const std::string& pattern, const std::string& key, const Array<T>& def,
               const std::string& doc, Length rule) {
  lengthTable()[joinKey(pattern, key)] = rule;
  l.set(key, def, doc + " (" + lengthRule(rule) + ")");
}

ParameterList holeTemplate() {
  const std::string p = "Discretization/Holes/*";
  ParameterList h("hole");
  setChoice<Hole::Kind>(h, "Shape", "Circle", {{"Circle", Hole::Kind::Circle, "disc; cylinder along z in 3D"}, {"Rectangle", Hole::Kind::Rectangle, ""}});
  setVector(h, p, "Center", arr<double>({0, 0, 0}), "centre of the hole", Length::Dim);
  setNumber(h, "Radius", 0.0, "radius of a Circle", positive());
  setVector(h, p, "Half Widths", arr<double>({0, 0, 0}), "half extents of a Rectangle per axis (each > 0)", Length::Dim);
  return h;
}

ParameterList regionTemplate() {
  const std::string p = "Regions/*";
  ParameterList r("region");
  setChoice(r, "Type", "Box",
            {{"Box", ""}, {"Side Layer", ""}, {"Fictitious Side", ""}, {"Nearest", ""},
             {"All Fictitious", "needs 'Discretization/Fictitious Sides'"}, {"All Real", ""},
             {"Node Set", "Exodus mesh: the particles of the elements touching the set's nodes (Peridigm's rule)"},
             {"Side Set", "Exodus mesh: the particles of the elements whose sides are listed"},
             {"Block", "the particles of a block (particle file: 5th column; Exodus: element block)"},
             {"Ids", "particle file or Exodus mesh: particles by number, 1-based (Peridigm's node numbers): a particle file's n-th "
                     "particle line (comments and blank lines not counted), an Exodus mesh's element with id n in its element number "
                     "map (n-th element when it has none)"}});
  setVector(r, p, "Lower", arr<double>({0, 0, 0}), "Box: lower corner", Length::Dim);
  setVector(r, p, "Upper", arr<double>({0, 0, 0}), "Box: upper corner", Length::Dim);
  setChoice<Population>(r, "Population", "Real",
                        {{"Real", Population::Real, ""}, {"Fictitious", Population::Fictitious, ""}, {"All", Population::All, "every particle"}},
                        "Box/Nearest: ");
  setChoice(r, "Side", "xmin", sideChoices(), "Side Layer / Fictitious Side: ", " (a side of the body's dimension)");
  setNumber(r, "Thickness", 0.0, "Side Layer: layer thickness", nonNegative("0: one particle spacing"));
  setVector(r, p, "Point", arr<double>({0, 0, 0}), "Nearest: the point; particles equally near (to 1e-9) tie, and a tie goes to the smallest x, then y, then z (not to the particle order or the ranks)", Length::Dim);
  r.set("Name", "", "Node Set / Side Set / Block: the set's or Exodus block's name in the mesh (give Name or Id)");
  r.set("Id", -1, "Node Set / Side Set / Block: the set's or block's id (>= 0; -1: none, give Name)");
  r.set("Ids", arr<int>({}), "Ids: the numbers (give Ids or Ids File)");
  r.set("Ids File", "", "Ids: path (relative to the scene) of a file of numbers, separated by spaces or lines; a line starting "
                        "with '#', '/' or '*' is a comment (Peridigm's node-set files)");
  return r;
}

/// The start of a template for an entry that acts on a region.
ParameterList onRegion(const std::string& what, const std::string& regionDoc) {
  ParameterList l(what);
  l.set("Region", "", regionDoc);
  return l;
}

ParameterList conditionTemplate() {
  const std::string p = "Boundary Conditions/*";
  ParameterList c = onRegion("condition", "name of the region whose particles are constrained");
  setChoice<int>(c, "Component", "all", {{"x", 0, ""}, {"y", 1, ""}, {"z", 2, ""}, {"all", -1, ""}}, "",
                 "; a component of a particle prescribed by two conditions must get the same value from both");
  c.set("Value", 0.0, "prescribed displacement at load factor 1");
  setVector(c, p, "Gradient", arr<double>({}), "optional: u = Value + Gradient . X", Length::DimOrEmpty);
  return c;
}

ParameterList loadTemplate() {
  const std::string p = "Loads/*";
  ParameterList l = onRegion("load", "name of the region carrying the load");
  setChoice(l, "Type", "Total Force",
            {{"Total Force", "spread over the region by volume"}, {"Traction", "force per area on a Side Layer"},
             {"Body Force", "force per volume"},
             {"Radial Force", "a total force of Magnitude spread over the region by volume, each particle's share pointing away from Center "
                              "(3D with Axis: away from the axis through Center); a pressure p on a bore of area A is Magnitude = p A"}});
  setVector(l, p, "Value", arr<double>({0, 0, 0}), "the load vector at load factor 1 (not with Radial Force)", Length::Dim);
  l.set("Magnitude", 0.0, "Radial Force: the total force at load factor 1, summed as magnitudes (negative: towards Center)");
  setVector(l, p, "Center", arr<double>({}), "Radial Force: the point the forces point away from", Length::DimOrEmpty);
  setVector(l, p, "Axis", arr<double>({}), "Radial Force, 3D: the forces point away from the line through Center along Axis (none: from the point)", Length::DimOrEmpty);
  return l;
}

ParameterList probeTemplate() {
  ParameterList r = onRegion("probe", "region to probe");
  setChoice(r, "Quantity", "Displacement",
            {{"Displacement", "mean over the region, per step"}, {"Reaction", "sum of reaction forces, per step"},
             {"Profile", "every particle of the region at the end, to profile_<name>.csv"},
             {"Plastic Strain", "the largest and the mean equivalent plastic strain over the region, per step (needs a plastic material)"}});
  return r;
}

enum class PlasticityChoice { None, J2 };
enum class HardeningChoice { Linear, Voce };

void materialKeys(ParameterList& m, const std::string& lead = "") {
  setChoice<MaterialKind>(m, "Model", "Hencky", {{"Hencky", MaterialKind::Hencky, "finite deformation"}, {"Small Strain", MaterialKind::SmallStrain, ""}}, lead.empty() ? "" : lead + "model: ");
  setChoice<PlanarMode>(m, "Plane", "Plane Strain", {{"Plane Strain", PlanarMode::PlaneStrain, ""}, {"Plane Stress", PlanarMode::PlaneStress, ""}}, lead.empty() ? "2D: " : lead + "plane (2D): ");
  setNumber(m, "Young's Modulus", 0.0, lead + "E, in the scene's stress units", positive());
  setNumber(m, "Poisson's Ratio", 0.0, lead + "nu", reals(End::Open, -1, 0.5, End::Open, "nu = 0.5 is incompressible: the Lame constant lambda is infinite"));
  setChoice<PlasticityChoice>(m, "Plasticity", "None",
                  {{"None", PlasticityChoice::None, "elastic"},
                   {"J2", PlasticityChoice::J2, "von Mises plasticity with isotropic hardening (docs/plasticity.md); Hencky: finite strain, F = Fe Fp; Small Strain: additive"}},
                  lead.empty() ? "" : lead + "plasticity: ");
  setNumber(m, "Yield Stress", 0.0, lead + "initial yield stress sigma_y0 (J2), in the scene's stress units; must be positive with Plasticity = J2", nonNegative());
  setNumber(m, "Hardening Modulus", 0.0, lead + "linear isotropic hardening modulus H (J2): sigma_y grows by H per unit equivalent plastic strain; 0 with Hardening = Linear is perfect plasticity", nonNegative());
  setChoice<HardeningChoice>(m, "Hardening", "Linear",
                  {{"Linear", HardeningChoice::Linear, "sigma_y = sigma_y0 + H alpha"},
                   {"Voce", HardeningChoice::Voce, "sigma_y = sigma_y0 + H alpha + (sigma_inf - sigma_y0) (1 - exp(-delta alpha))"}},
                  lead.empty() ? "" : lead + "hardening: ");
  setNumber(m, "Saturation Stress", 0.0, lead + "sigma_inf of Voce hardening (at least the Yield Stress)", nonNegative());
  setNumber(m, "Saturation Rate", 0.0, lead + "delta of Voce hardening (positive; dimensionless, per unit equivalent plastic strain)", nonNegative());
}

enum class BreakCriterion { Stretch, PlasticStrain, Either };

void damageLawKeys(ParameterList& dm, const std::string& lead = "") {
  dm.set("Critical Stretch", 0.002, lead + "s_cr: bonds with stretch >= s_cr carry no force and break after the step");
  dm.set("Softening Start", 0.0015, lead + "s_min: bond forces soften from here (0 < s_min < s_cr)");
  setNumber(dm, "Beta", 3.0, lead + "steepness of the tanh softening", positive());
  setChoice<DamageSpec::Softening>(dm, "Softening", "Paper",
            {{"Paper", DamageSpec::Softening::Paper, "seed 000 eq. 48: T_s jumps by 1/2 (1 - tanh beta) at s_min and s_cr"},
             {"Continuous", DamageSpec::Softening::Continuous, "the tanh rescaled to be exactly 1 at s_min and 0 at s_cr"}}, lead.empty() ? "" : lead + "softening: ");
  setChoice<BreakCriterion>(dm, "Criterion", "Stretch",
            {{"Stretch", BreakCriterion::Stretch, "bonds soften from Softening Start and break at Critical Stretch"},
             {"Plastic Strain", BreakCriterion::PlasticStrain, "ductile: a bond breaks when the mean equivalent plastic strain of its ends reaches Critical Plastic Strain (no softening)"},
             {"Either", BreakCriterion::Either, "both criteria"}}, lead.empty() ? "" : lead + "criterion: ");
  setNumber(dm, "Critical Plastic Strain", 0.0, lead + "the ductile criterion's equivalent plastic strain (Criterion = Plastic Strain or Either)", nonNegative());
}

/// One entry of Blocks: a block's own material, G and damage law (each key not given takes the
/// top-level list's value: Material/..., Model/G, Damage/...).
ParameterList blockTemplate() {
  const std::string p = "Blocks/*";
  ParameterList b("block");
  b.set("Id", -1, "the block's id (particle file: 5th column; Exodus: element block id; lattice: the id the Box gives, others are block 1); -1: give Name");
  b.set("Name", "", "Exodus: the element block's name (give Name or Id)");
  setVector(b, p, "Box Min", arr<double>({}), "Lattice: the block is the particles (fictitious ones included) in [Box Min, Box Max]; particles in no box are block 1", Length::DimOrEmpty);
  setVector(b, p, "Box Max", arr<double>({}), "Lattice: upper corner of the block's box", Length::DimOrEmpty);
  materialKeys(b.sublist("Material", false, "the block's material; a key not given takes the top-level Material's"), "the block's ");
  setNumber(b.sublist("Stabilization", false, "the block's Silling stabilisation (needs Model/Stabilization = Silling)"), "G", 0.0,
            "the block's G (not given: Model/G); C is the micromodulus of the block's material", nonNegative());
  damageLawKeys(b.sublist("Damage", false, "the block's damage law (needs Damage/Enabled); a key not given takes the top-level Damage's; a bond between two blocks takes the law with the smaller Critical Stretch"),
                "the block's ");
  return b;
}

const ParameterList& templateFor(const std::string& sub) {
  static const std::map<std::string, ParameterList> t{{"Regions", regionTemplate()}, {"Blocks", blockTemplate()},
                                                      {"Boundary Conditions", conditionTemplate()},
                                                      {"Loads", loadTemplate()},
                                                      {"Probes", probeTemplate()},
                                                      {"Holes", holeTemplate()}};
  return t.at(sub);
}

void discretizationSchema(ParameterList& d) {
  const std::string dp = "Discretization";
  setChoice(d, "Type", "Lattice", {{"Lattice", ""}, {"Particle File", ""},
            {"Exodus", "an Exodus II mesh: a particle per element at its centroid with its volume (docs/exodus.md)"}});
  d.set("Dimension", 2, "1, 2 or 3; every vector key (corners, points, centres, load values) then takes exactly this many entries (an absent key's 3-entry default counts only its first Dimension entries)");
  setVector(d, dp, "Lower Corner", arr<double>({0, 0, 0}), "Lattice: lower corner of the body", Length::Dim);
  setVector(d, dp, "Upper Corner", arr<double>({1, 1, 1}), "Lattice: upper corner of the body", Length::Dim);
  setVector(d, dp, "Particles", arr<int>({}),
            "Lattice: particles per axis, each >= 1, at most " + std::to_string(kMaxParticles) + " lattice sites in all with the fictitious layers; or give Spacing",
            Length::DimOrEmpty);
  d.set("Spacing", 0.0, "Lattice: spacing instead of Particles (must divide the box evenly); Particle File: nominal spacing (0: the median particle's, volume^(1/3), 2D (volume / Thickness)^(1/2), 1D volume / Thickness); Exodus: nominal spacing (0: the median element's edge, volume^(1/3), 2D (area)^(1/2))");
  d.set("Horizon Factor", 3.015, "horizon delta = factor * spacing (1 <= factor <= " + number(kMaxHorizonFactor) + ")");
  d.set("Horizon", 0.0, "Particle File, Exodus: absolute horizon (overrides Horizon Factor when > 0; spacing <= horizon <= " + number(kMaxHorizonFactor) + " x spacing)");
  setNumber(d, "Thickness", 1.0, "2D: out-of-plane thickness h; 1D: cross-section area A", positive());
  std::vector<std::string> sides;
  for (const auto& c : sideChoices()) sides.push_back(c.value);
  d.set("Fictitious Sides", arr<std::string>({}), "sides with a fictitious Dirichlet layer of width delta, each " + orList(sides),
        Teuchos::rcp(new ChoiceList(Teuchos::rcp(new Teuchos::StringValidator(Teuchos::Array<std::string>(sides))))));
  d.set("Particle File", "", "Particle File: path (relative to the scene) of 'x y z volume [block]' lines");
  setChoice(d, "Particle File Columns", "x y z volume [block]",
            {{"x y z volume [block]", "perinox's particle files"},
             {"x y z block volume", "Peridigm's text-file discretisations: exactly these five; lines starting with '#', '/' or '*' are comments"}},
            "Particle File: the columns of each line: ");
  d.set("Mesh File", "", "Exodus: path (relative to the scene) of the Exodus II mesh (hex, tet, wedge, sphere in 3D; quad, tri, sphere in 2D, areas x Thickness)");
  setNumber(d, "Jitter", 0.0, "random shift of real particles, fraction of the spacing", reals(End::Closed, 0, 1, End::Open));
  setNumber(d, "Jitter Seed", 12345, "seed of the jitter", ints(0));
  d.sublist("Holes", false, "named holes (Shape, Center, Radius / Half Widths)");
  setChoice<PartitionMethod>(d, "Partition", partitionName(PartitionMethod::Rcb),
                             {{partitionName(PartitionMethod::Rcb), PartitionMethod::Rcb, "Zoltan2 recursive coordinate bisection of the reference positions"},
                              {partitionName(PartitionMethod::MultiJagged), PartitionMethod::MultiJagged, "Zoltan2 multi-jagged"},
                              {partitionName(PartitionMethod::Slabs), PartitionMethod::Slabs, "contiguous particle-id ranges, lattice rows; for tests"}},
                             "how particles are split among MPI ranks: ");
  setChoice(d, "Construction", "Distributed",
            {{"Distributed", "each rank generates (a lattice) or reads (its slice of a particle file's bytes, its range of an "
                             "Exodus mesh's elements) only its part and keeps its owned particles and those within two horizons of them; "
                             "regions, boundary conditions and loads are found rank by rank (docs/architecture.md, \"Distribution\")"},
             {"Replicated", "every rank builds the whole discretisation (its positions, loads and regions) and keeps its particles' "
                            "families; for comparisons (the same answers)"}},
            "how the discretisation is built on MPI ranks: ");
}

void materialSchema(ParameterList& m) {
  materialKeys(m);
  setChoice(m, "Modulus Field", "Uniform",
            {{"Uniform", ""}, {"Seed001 Bar", "E(x) of seed 001 eq. 18: E on the left half, softer to the right"}});
  setNumber(m, "Field Alpha", 0.001, "Seed001 Bar: alpha of eqs 18-20", reals(End::Open, 0, 1, End::Closed, "a strain"));
  setNumber(m, "Field Beta", 0.0056568542494923801, "Seed001 Bar: beta of eqs 18-20 (default 0.004 sqrt 2)",
            reals(End::Open, 0, 1, End::Closed, "a strain"));
  setNumber(m, "Field Length", 1.0, "Seed001 Bar: L_tot (x measured from 0)", positive());
}

void modelSchema(ParameterList& mo) {
  setChoice(mo, "Stabilization", "None", {{"None", ""}, {"Silling", ""}});
  setNumber(mo, "G", 0.0, "Silling stabilisation parameter (dimensionless)", nonNegative());
  setChoice(mo, "G Form", "Silling",
            {{"Silling", "T_z = (G C / w0_i) z"},
             {"Peridigm Hourglass", "G (and each block's G) is Peridigm's Hourglass Coefficient: each particle's Silling G is "
                                    "G delta S_i / (3 V_i), S_i = sum_j V_j / |xi_ij|, the same trace of stabilising stiffness "
                                    "over its family as Peridigm's hourglass force (docs/peridigm.md)"}});
  setChoice(mo, "Zero-Energy Control", "None",
            {{"None", ""}, {"Springs", "C1"}, {"Average Displacement", "C2"}, {"Stress Points", "seed 001; nearest-neighbour families"}});
  setNumber(mo, "Stress Point Seed", 2018, "seed of the stress-point arrangements (drawn per particle from its global id)", ints(0));
  mo.set("Control Constant", -1.0, "C1 or C2; negative: seed 001 Table 1 value for the particle count (n = 100, 200, 500, 1000)");
}

void damageSchema(ParameterList& dm) {
  dm.set("Enabled", false, "turn the damage effect on");
  damageLawKeys(dm);
  setNumber(dm, "Max Break Rounds", 50, "break-and-re-equilibrate rounds allowed per load step", ints(1));
  setChoice(dm, "On Stall", "Stop",
            {{"Stop", "the paper's Fig. 8; the run stops with a diagnosis"},
             {"Break Most Stretched",
              "break, at the last converged state, the intact bonds whose stretch is within 'Stall Break Tolerance' "
              "of the largest, if that one is in the softening band, re-equilibrate at the same load and go on: the remedy for a "
              "snap-back of softening bonds under displacement control; reported per step as stall_broken_bonds"}},
            "what a load step that fails after all its cut-backs does: ");
  setNumber(dm, "Stall Break Tolerance", 1e-6, "On Stall = Break Most Stretched: bonds within this fraction of (s_cr - s_min) of the largest stretch break together (mirror-image bonds differ by round-off only)",
            reals(End::Closed, 0, 1, End::Open));
  setNumber(dm, "Max Stall Breaks", 200, "On Stall = Break Most Stretched: stall breaks allowed in a run", ints(1));
  setNumber(dm, "Reload Tolerance", 0.01,
            "when a damaged body cannot carry the load it broke at (a snap-back), the highest load it carries is found by reloading "
            "it, to this fraction of that load; the load stepping resumes from there",
            reals(End::Open, 0, 0.5, End::Open));
  setChoice(dm, "After Snap-Back", "Step Load",
            {{"Step Load", "the load stepping resumes from the limit load the reload found"},
             {"Break Most Stretched",
              "the reload found the damaged body's limit load, to 'Reload Tolerance': break there at once as a stall "
              "would, without first failing the next step's cut-backs down to Min Increment"}},
            "what follows a snap-back (with On Stall = Break Most Stretched; ignored with Stop): ");
}

void rotationSchema(ParameterList& rot) {
  const std::string rp = "Superposed Rotation";
  rot.set("Angle", 0.0, "degrees at load factor 1 (0: no rotation)");
  setVector(rot, rp, "Center", arr<double>({0, 0, 0}), "a point on the axis", Length::Dim);
  setVector(rot, rp, "Axis", arr<double>({0, 0, 1}), "3D: the axis (normalised); 2D: must be z", Length::Three);
}

void referenceSchema(ParameterList& r) {
  const std::string refp = "Reference";
  setChoice(r, "Type", "None",
            {{"None", ""}, {"Hydrostatic Hencky", ""}, {"Uniform Stretch", ""}, {"Affine", ""},
             {"Seed001 Bar", "eq. 19 with the Material's field parameters"}});
  setVector(r, refp, "Gradient", arr<double>({}), "Affine: displacement gradient H, row-major (u = H (X - Center))", Length::DimSquaredOrEmpty);
  r.set("Traction", 0.0, "Hydrostatic Hencky: nominal traction P11 on every side");
  setNumber(r, "Stretch", 1.0, "Uniform Stretch: l / l0", reals(End::Closed, 0.01, 100, End::Closed, "of a solid"));
  setVector(r, refp, "Center", arr<double>({0, 0, 0}), "fixed point of the stretch", Length::Dim);
}

void arcLengthSchema(ParameterList& al) {
  al.set("Initial Arc Length", 0.05, "arc length of the first step (Min Arc Length <= it <= Max Arc Length)");
  al.set("Min Arc Length", 1e-4, "the run stops when a failing step would need a shorter arc (> 0)");
  al.set("Max Arc Length", 0.5, "the arc grows by 1.5 after steps needing at most 'Solver/Easy Iterations' corrector iterations, up to this");
  setNumber(al, "Max Steps", 100, "converged continuation steps allowed", ints(1, kMaxArcSteps));
  setNumber(al, "Target Load Factor", 1.0, "stop once the load factor reaches this", positive());
  setNumber(al, "Target Deflection", 0.0, "stop once the magnitude of the deflection reaches this (0: no deflection target)", nonNegative());
  al.set("Deflection Probe", "", "name of a Displacement probe whose component 'Deflection Component' is the deflection (for the target and the path)");
  setChoice<int>(al, "Deflection Component", "y", {{"x", 0, ""}, {"y", 1, ""}, {"z", 2, ""}});
}

void solverSchema(ParameterList& so) {
  setChoice(so, "Method", "Newton", {{"Newton", "implicit, NOX"}, {"ADR", "explicit adaptive dynamic relaxation"}});
  setNumber(so, "ADR Tolerance", 1e-6, "ADR: stop when both e1 and e2 (seed 001) are below this", reals(End::Open, 0, 1, End::Open));
  setNumber(so, "ADR Max Iterations", 2000000, "ADR: iterations allowed per load step", ints(1));
  setNumber(so, "ADR Mass Safety", 4.0, "ADR: fictitious mass = safety * 1/4 sum_j |K_ij|", reals(End::Closed, 1, 0, End::None, "the stability bound"));
  setNumber(so, "Load Steps", 10, "equal load increments to load factor 1 (with a Load Path: per segment)", ints(1, kMaxLoadSteps));
  so.set("Load Path", Array<double>(), "the load factors the load passes through after 0, piecewise linear in pseudo-time, e.g. {1, 0, 1.2}: load, unload, reload past the first peak (empty: 0 to 1); steps land on every corner, the step after a corner starts from the converged state; probes and fields report the load factor, summary.json's steps also the pseudo-time");
  setNumber(so, "Tolerance", 1e-10, "|R| / |f_ext| (or / |reaction| when f_ext = 0)", reals(End::Open, 0, 1, End::Open));
  setNumber(so, "Max Newton Iterations", 25, "per load step", ints(1, kMaxNewtonIterations));
  setChoice(so, "Line Search", "Full Step",
            {{"Full Step", ""}, {"Backtrack", ""}, {"Polynomial", "NOX line searches"},
             {"Trust Region", ""}, {"Inexact Trust Region", "NOX's dogleg trust-region solvers; need the assembled Jacobian"}},
            "globalisation: ");
  so.set("Adaptive Steps", false, "grow the load increment by 1.5 after steps needing at most 'Easy Iterations' Newton iterations (up to 'Max Increment'); cut-backs still halve it");
  setNumber(so, "Easy Iterations", 4, "adaptive stepping: an easy step needs at most this many iterations", ints(0));
  setNumber(so, "Max Increment", 0.25, "adaptive stepping: largest load increment", reals(End::Open, 0, 1, End::Closed));
  setNumber(so, "Max Cutbacks", 4, "halvings of a load step that fails before the run stops", ints(0, kMaxCutbacks));
  setNumber(so, "Limit Load Ratio", 100.0,
            "load stepping without damage: a converged step whose displacement per unit load exceeds this multiple of the first "
            "step's has jumped past a limit load (to an equilibrium far away, e.g. one only the stabilisation holds); it is cut "
            "back, and the run stops at the limit load, naming it (exit 3; summary.json limit_load_factor); 0: no check",
            reals(End::Closed, 0, 1e12, End::Closed, "0 or more than 1"));
  so.set("Max Total Steps", 0, "steps allowed in all, counting reduced ones (0: 20 x Load Steps; else Load Steps to " + std::to_string(kMaxTotalSteps) + ")");
  setNumber(so, "Min Increment", 1e-6, "smallest load increment, as a fraction of the nominal one", reals(End::Open, 0, 1, End::Closed));
  setNumber(so, "Round-off Floor Factor", 2.0, "a step also converges when |R| <= factor * eps * E * |unit-strain forces| (the residual's round-off level); 0 disables", nonNegative());
  so.set("Stability Check", false, "after each converged step, count negative pivots of the tangent (serial LDL^T on rank 0) and stop with a diagnosis when the equilibrium is unstable");
  so.set("Predictor", true, "start each load step from the previous increment extrapolated");
  setNumber(so, "Verbosity", 0, "NOX output level (0 quiet, 1 iterations)", ints(0));
  setChoice(so, "Forcing Term", "Preset",
            {{"Constant", "every Newton system solved to 'Linear Tolerance'"},
             {"Eisenstat-Walker", "the tolerance follows the residual's decrease (NOX Type 2: 1e-4 at first, then 0.9 (|R_k| / "
                                  "|R_k-1|)^2, between 'Linear Tolerance' and 1e-4; the tangent predictor's system to 1e-3): fewer Krylov "
                                  "iterations, Newton still quadratic"},
             {"Preset", "as the linear solver preset says ('Forcing Term' in its list) or auto chooses; Constant if it says nothing"}},
            "iterative linear solvers: how tightly each Newton system is solved: ");
  setNumber(so, "Linear Tolerance", 1e-12, "iterative linear solvers: relative residual of each Newton system (Forcing Term = Constant), "
            "or the tightest one asked (Eisenstat-Walker)", reals(End::Open, 0, 1e-2, End::Closed));
  setNumber(so, "Stagnation Stop", 0, "stop a Newton solve early (and cut back) when its normalised residual has not halved over this many iterations; 0: off (a failed solve is still diagnosed as stagnation over its last 5 iterations)", ints(0));
  setChoice(so, "Continuation", "Load Stepping",
            {{"Load Stepping", "load factor 0 to 1 in increments"},
             {"Arc Length", "pseudo-arc-length continuation through limit points; see the Arc Length sublist"}});
  arcLengthSchema(so.sublist("Arc Length", false, "pseudo-arc-length continuation (Solver/Continuation = Arc Length): Riks normal-plane corrector with a bordering solve; arc length measured as sqrt(w |dx|^2 + dlambda^2) with w = 1 / |dx/dlambda|^2 at the start, so an arc length s first advances the load factor by about s / sqrt 2"));
  so.set("Linear Solver Preset", "auto", "'auto' (perinox chooses the preset, Jacobian and forcing term from the problem and says why: "
         "docs/choosing-a-solver.md), the name of a preset in xml/solvers (the file name without .xml; no path), or 'custom'");
  so.sublist("Linear Solver", false, "Stratimikos parameters (used when the preset is 'custom')");
  setChoice(so, "Jacobian", "Preset",
            {{"Assembled", "sparse matrix"}, {"Matrix-Free", "analytic J v from the linearised kernels; nothing assembled"},
             {"Jacobian-Free", "J v by finite differences of the residual"},
             {"Preset", "as the linear solver preset says (or auto chooses); Assembled if it says nothing"}});
  setChoice(so, "Preconditioner Matrix", "Preset",
            {{"Assembled", "the full Jacobian"}, {"Neighbours", "only couplings within one horizon; memory proportional to the family size"},
             {"None", "no matrix: the Two-Stage preconditioner (scalable) smooths with the matrix-free Jacobian itself"},
             {"Preset", "as the preset says (a preset's None is Neighbours for a Jacobian-free run); Neighbours if it says nothing"}},
            "matrix-free and Jacobian-free solves: the matrix the preconditioner is built from: ");
  setNumber(so, "Jacobian-Free Perturbation", 1e-6, "Jacobian-free: J v = (f(x + h v) - f(x)) / h with h |v|_inf = lambda max(|x|_inf, particle spacing)",
            reals(End::Open, 0, 1e-2, End::Open));
}

void outputSchema(ParameterList& o) {
  o.set("VTK", true, "write .vtu/.pvtu fields (when Format is VTU or Both)");
  setChoice(o, "Format", "VTU", {{"VTU", "fields.pvtu and fields_<rank>.vtu of the last state"},
            {"Exodus", "fields.e: every converged load step as an Exodus II time step (Construction = Distributed on p > 1 "
                        "ranks: one file per rank, fields.e.<p>.<r>; docs/exodus.md)"}, {"Both", "VTU and Exodus"}});
  o.set("Plots", true, "write PNG plots (needs python3-matplotlib)");
}

Teuchos::RCP<ParameterList> buildSchema() {
  templateFor("Regions");  // the templates record their keys' lengths first
  auto s = Teuchos::rcp(new ParameterList("perinox"));
  s->set("Title", "", "one line naming the scene");
  s->set("Description", "", "free text");
  s->set("Expected Outcome", "", "for test scenes: 'converged', or 'failure: TEXT' where TEXT must appear in the failure reason");
  discretizationSchema(s->sublist("Discretization", false, "particles and families"));
  materialSchema(s->sublist("Material", false, "elastic material"));
  modelSchema(s->sublist("Model", false, "effects"));
  damageSchema(s->sublist("Damage", false, "implicit damage: tanh bond softening, bonds broken after converged steps"));
  s->sublist("Blocks", false, "blocks with their own materials (docs/exodus.md): one entry per block; none: every particle has the top-level Material");
  s->sublist("Regions", false, "named particle sets");
  s->sublist("Boundary Conditions", false, "named Dirichlet conditions");
  s->sublist("Loads", false, "named loads");
  rotationSchema(s->sublist("Superposed Rotation", false,
                            "a rigid rotation superposed on the loading: at load factor lambda the body turns by lambda * Angle; "
                            "prescribed particles follow the arc, dead loads turn with the body (objectivity tests)"));
  s->sublist("Probes", false, "named probes written per load step");
  referenceSchema(s->sublist("Reference", false, "analytic reference for errors"));
  solverSchema(s->sublist("Solver", false, "nonlinear and linear solvers"));
  outputSchema(s->sublist("Output", false, "what is written"));
  // For 'perinox schema': the keys of one entry of each named sublist (nothing reads them).
  for (const auto& [sub, what] : namedSublists()) {
    ParameterList& parent = sub == "Holes" ? s->sublist("Discretization").sublist("Holes") : s->sublist(sub);
    if (sub == "Blocks") {  // its entries' sublists are documented as sublists, with their keys
      ParameterList& e = parent.sublist("<name>", false, "one " + what + ", under a name of the scene's choosing");
      e.setParameters(templateFor(sub));
      continue;
    }
    parent.sublist("<name>", false, "one " + what + ", under a name of the scene's choosing").setParameters(templateFor(sub));
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Strict validation
// ---------------------------------------------------------------------------------------------

std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1,
                         prev[j - 1] + (std::tolower(a[i - 1]) == std::tolower(b[j - 1]) ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

/// " (did you mean 'X'?)" for the candidate nearest to `name` (ignoring case), if near enough.
std::string suggestion(const std::string& name, const std::vector<std::string>& candidates) {
  if (name.size() > 64) return "";
  std::string best;
  std::size_t bestD = 4;
  for (const auto& c : candidates) {
    const std::size_t dist = editDistance(name, c);
    if (dist < bestD) bestD = dist, best = c;
  }
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

std::vector<std::string> keysOf(const ParameterList& l) {
  std::vector<std::string> k;
  for (auto v = l.begin(); v != l.end(); ++v) k.push_back(l.name(v));
  return k;
}

std::string typeName(const Teuchos::ParameterEntry& e) {
  if (e.isList()) return "sublist";
  return e.getAny().typeName();
}

std::string friendlyType(const std::string& t) {
  if (t == "double") return "double";
  if (t == "int") return "int";
  if (t == "bool") return "bool";
  if (t.find("basic_string") != std::string::npos || t == "string") return "string";
  if (t.find("Array<double>") != std::string::npos) return "Array(double)";
  if (t.find("Array<int>") != std::string::npos) return "Array(int)";
  if (t.find("Array<std::") != std::string::npos || t.find("Array<std::__cxx11::basic_string") != std::string::npos) return "Array(string)";
  return t;
}

void checkAgainst(const ParameterList& user, const ParameterList& valid, const std::string& path,
                  const std::string& file) {
  for (auto it = user.begin(); it != user.end(); ++it) {
    const std::string& name = user.name(it);
    const auto& entry = user.entry(it);
    const std::string key = joinKey(path, name);
    if (!valid.isParameter(name)) {
      const std::vector<std::string> allowed = keysOf(valid);
      const std::string hint = suggestion(name, allowed);
      std::string list = orList(allowed);
      if (list.size() > 160) list = "see 'perinox schema'";
      fail(file, "unknown key " + quote(key, 80) + hint + (hint.empty() ? "; allowed here: " + list : ""));
    }
    const auto& ventry = valid.getEntry(name);
    if (entry.isList() != ventry.isList())
      fail(file, quote(key, 80) + " must be " + (ventry.isList() ? "a sublist" : "a parameter") + ", not " +
                     (entry.isList() ? "a sublist" : "a parameter"));
    if (entry.isList()) {
      const auto& sub = user.sublist(name);
      if (path.empty() && name == "Solver") {
        // "Linear Solver" is Stratimikos' own list, validated by Stratimikos.
        ParameterList copy(sub);
        if (copy.isSublist("Linear Solver")) copy.remove("Linear Solver");
        checkAgainst(copy, valid.sublist(name), key, file);
        continue;
      }
      auto named = namedSublists().find(name);
      if (named != namedSublists().end()) {
        for (auto c = sub.begin(); c != sub.end(); ++c) {
          const std::string ckey = key + "/" + sub.name(c);
          if (!sub.entry(c).isList())
            fail(file, quote(ckey, 80) + " must be a sublist describing one " + named->second);
          checkAgainst(sub.sublist(sub.name(c)), templateFor(name), ckey, file);
        }
        continue;
      }
      checkAgainst(sub, valid.sublist(name), key, file);
      continue;
    }
    const std::string ut = friendlyType(typeName(entry)), vt = friendlyType(typeName(ventry));
    if (ut != vt) fail(file, "'" + key + "' must be of type " + vt + ", not " + ut);
  }
}

/// Calls f(key, pattern, entry) for every parameter of l and its sublists, where pattern is the
/// key with the names of named sublists' entries replaced by '*'.
template <class F>
void forEachParameter(const ParameterList& l, const std::string& key, const std::string& pattern, const F& f) {
  for (auto it = l.begin(); it != l.end(); ++it) {
    const std::string& name = l.name(it);
    const std::string k = joinKey(key, name), p = joinKey(pattern, name);
    if (!l.entry(it).isList()) {
      f(k, p, l.entry(it));
      continue;
    }
    const ParameterList& sub = l.sublist(name);
    if (!namedSublists().count(name)) {
      forEachParameter(sub, k, p, f);
      continue;
    }
    for (auto c = sub.begin(); c != sub.end(); ++c)
      if (sub.entry(c).isList()) forEachParameter(sub.sublist(sub.name(c)), k + "/" + sub.name(c), p + "/*", f);
  }
}

/// The schema's entry for a key pattern ("Regions/*/Side") or key ("Regions/left/Side": an entry
/// of a named sublist is its template's), or null.
const Teuchos::ParameterEntry* patternEntry(const std::string& pattern) {
  std::vector<std::string> parts;
  std::stringstream ss(pattern);
  for (std::string part; std::getline(ss, part, '/');) parts.push_back(part);
  const ParameterList* l = sceneSchema().get();
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    if (namedSublists().count(parts[i]) && i + 2 < parts.size()) {
      l = &templateFor(parts[i]);
      ++i;
    } else if (l->isSublist(parts[i])) {
      l = &l->sublist(parts[i]);
    } else {
      return nullptr;
    }
  }
  return l->getEntryPtr(parts.back());
}

/// The values the user gave (before defaults): enumerated strings matched exactly, array
/// lengths against the dimension.
void checkGivenValues(const ParameterList& user, int dim, const std::string& file) {
  forEachParameter(user, "", "", [&](const std::string& key, const std::string& pattern, const Teuchos::ParameterEntry& e) {
    const Teuchos::ParameterEntry* schemaEntry = patternEntry(pattern);
    const auto validator = schemaEntry ? schemaEntry->validator() : Teuchos::null;
    if (!validator.is_null() && !validator->validStringValues().is_null()) {
      const std::vector<std::string> allowed = validator->validStringValues()->toVector();
      const auto ok = [&](const std::string& v) { return std::find(allowed.begin(), allowed.end(), v) != allowed.end(); };
      if (e.isType<std::string>()) {
        const std::string v = Teuchos::getValue<std::string>(e);
        if (!ok(v)) fail(file, "'" + key + "' must be " + orList(allowed) + ", not " + quote(v) + suggestion(v, allowed));
      } else if (e.isType<Array<std::string>>()) {
        for (const auto& v : Teuchos::getValue<Array<std::string>>(e))
          if (!ok(v)) fail(file, "'" + key + "' has " + quote(v) + ", but each entry must be " + orList(allowed) + suggestion(v, allowed));
      }
    }
    const auto rule = lengthTable().find(pattern);
    if (rule == lengthTable().end()) return;
    // The schema's own default, as a resolved scene (every default filled in) writes it, is not a
    // value given for this dimension.
    if (schemaEntry && schemaEntry->getAny(false) == e.getAny(false)) return;
    const int n = e.isType<Array<double>>() ? Teuchos::getValue<Array<double>>(e).size() : Teuchos::getValue<Array<int>>(e).size();
    const int want = rule->second == Length::Three ? 3 : rule->second == Length::DimSquaredOrEmpty ? dim * dim : dim;
    const bool emptyOk = rule->second == Length::DimOrEmpty || rule->second == Length::DimSquaredOrEmpty;
    if (n == want || (n == 0 && emptyOk)) return;
    const std::string why = rule->second == Length::Three ? "x, y and z"
                            : rule->second == Length::Dim || rule->second == Length::DimOrEmpty
                                ? "one per axis: Dimension = " + std::to_string(dim)
                                : "Dimension x Dimension, row-major";
    fail(file, "'" + key + "' has " + std::to_string(n) + (n == 1 ? " entry" : " entries") + " but needs " +
                   (emptyOk ? "0 or " : "") + std::to_string(want) + " (" + why + ")");
  });
}

/// No number of the scene is infinite or NaN (none of its keys gives a meaning to them).
void checkFinite(const ParameterList& pl, const std::string& file) {
  forEachParameter(pl, "", "", [&](const std::string& key, const std::string&, const Teuchos::ParameterEntry& e) {
    if (e.isType<double>() && !std::isfinite(Teuchos::getValue<double>(e)))
      fail(file, "'" + key + "' must be a finite number, not " + number(Teuchos::getValue<double>(e)));
    if (!e.isType<Array<double>>()) return;
    const auto& a = Teuchos::getValue<Array<double>>(e);
    for (int i = 0; i < a.size(); ++i)
      if (!std::isfinite(a[i]))
        fail(file, "'" + key + "' entry " + std::to_string(i + 1) + " must be a finite number, not " + number(a[i]));
  });
}

/// A block's keys it does not give take the top-level lists' values (filled before Blocks, which
/// follows them in the schema): Material/..., Model/G as Stabilization/G, Damage/....
void inheritBlockDefaults(ParameterList& block, const ParameterList& top) {
  const std::pair<const char*, const char*> from[] = {{"Material", "Material"}, {"Stabilization", "Model"}, {"Damage", "Damage"}};
  for (const auto& [mine, theirs] : from) {
    ParameterList& l = block.sublist(mine);
    const ParameterList& t = top.sublist(theirs);
    for (auto k = templateFor("Blocks").sublist(mine).begin(); k != templateFor("Blocks").sublist(mine).end(); ++k) {
      const std::string& key = templateFor("Blocks").sublist(mine).name(k);
      if (!l.isParameter(key) && t.isParameter(key)) l.setEntry(key, t.getEntry(key));
    }
  }
}

/// Fills defaults (recursively, including named sublists' children).
void fillDefaults(ParameterList& user, const ParameterList& valid) {
  for (auto v = valid.begin(); v != valid.end(); ++v) {
    const std::string& name = valid.name(v);
    if (valid.entry(v).isList()) {
      if (name == "Linear Solver") continue;
      ParameterList& sub = user.sublist(name);
      auto named = namedSublists().find(name);
      if (named != namedSublists().end()) {
        for (auto c = sub.begin(); c != sub.end(); ++c) {
          if (name == "Blocks") inheritBlockDefaults(sub.sublist(sub.name(c)), user);
          fillDefaults(sub.sublist(sub.name(c)), templateFor(name));
        }
      } else {
        fillDefaults(sub, valid.sublist(name));
      }
    } else if (!user.isParameter(name)) {
      user.setEntry(name, valid.entry(v));
      user.getEntryRCP(name)->setValidator(Teuchos::null);  // the scene's list carries values only
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Values as text (the XML's value="..." and --set's value), checked the same way in both
// ---------------------------------------------------------------------------------------------

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

/// Why `text` is not a number (an int if `integer`), or "" when it is. The whole text must be
/// one decimal number: no trailing characters, no hexadecimal, no nan or inf, no overflow;
/// an int must fit in 32 bits (never wrapped or truncated).
std::string numberProblem(const std::string& text, bool integer) {
  const std::string t = trim(text);
  char* end = nullptr;
  errno = 0;
  if (integer) {
    const long long v = t.empty() ? 0 : std::strtoll(t.c_str(), &end, 10);
    if (t.empty() || *end || t.find_first_not_of("+-0123456789") != std::string::npos) return "an integer";
    if (errno == ERANGE || v < INT_MIN || v > INT_MAX)
      return "an integer from " + std::to_string(INT_MIN) + " to " + std::to_string(INT_MAX);
    return "";
  }
  const double v = t.empty() ? 0 : std::strtod(t.c_str(), &end);
  if (!t.empty() && !*end && !std::isfinite(v)) return "a finite number";
  if (t.empty() || *end || !decimalCharacters(t)) return "a number";
  return "";
}

bool parseBool(const std::string& text, bool& out) {
  std::string v = trim(text);
  std::transform(v.begin(), v.end(), v.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (v == "true" || v == "1") return out = true, true;
  if (v == "false" || v == "0") return out = false, true;
  return false;
}

/// The entries of an array written "{a, b, c}" (trimmed); false if it is not of that form.
bool splitArray(const std::string& text, std::vector<std::string>& out) {
  const std::string t = trim(text);
  out.clear();
  if (t.size() < 2 || t.front() != '{' || t.back() != '}') return false;
  const std::string inner = t.substr(1, t.size() - 2);
  if (trim(inner).empty()) return true;
  std::stringstream ss(inner + ",");
  std::string entry;
  while (std::getline(ss, entry, ',')) out.push_back(trim(entry));
  return std::none_of(out.begin(), out.end(), [](const std::string& e) { return e.empty() || e.find_first_of("{}") != std::string::npos; });
}

/// Why `text` is not a value of the scene type `type` (phrased to follow "is not"), or "".
std::string valueProblem(const std::string& type, const std::string& text) {
  if (type == "double" || type == "int") return numberProblem(text, type == "int");
  bool b;
  if (type == "bool") return parseBool(text, b) ? "" : "true or false";
  if (type == "string") return "";
  const bool ints = type == "Array(int)";
  std::vector<std::string> entries;
  if (!splitArray(text, entries)) return std::string("an array like ") + (type == "Array(string)" ? "{xmin, xmax}" : ints ? "{20, 10}" : "{0.5, 1}");
  if (type == "Array(string)") return "";
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const std::string p = numberProblem(entries[i], ints);
    if (!p.empty()) return std::string("an array of ") + (ints ? "integers" : "numbers") + ": entry " + std::to_string(i + 1) + ", " + quote(entries[i]) + ", is not " + p;
  }
  return "";
}

const std::set<std::string>& sceneTypes() {
  static const std::set<std::string> t{"int", "double", "bool", "string", "Array(int)", "Array(double)", "Array(string)"};
  return t;
}

/// Strict checks on the parsed XML that Teuchos' own conversion lets through or reports badly:
/// every value must be exactly of its type (see valueProblem), keys must be unique and named.
void strictXml(const Teuchos::XMLObject& obj, const std::string& path, const std::string& file) {
  std::set<std::string> seen;
  for (int i = 0; i < obj.numChildren(); ++i) {
    const Teuchos::XMLObject& c = obj.getChild(i);
    const std::string where = path.empty() ? "at the top level" : "in '" + path + "'";
    if (!c.hasAttribute("name")) fail(file, "a <" + c.getTag() + "> " + where + " has no name=\"...\"");
    const std::string name = c.getAttribute("name");
    const std::string key = joinKey(path, name);
    if (!seen.insert(name).second) fail(file, "key '" + key + "' is given twice");
    if (c.getTag() == "ParameterList") {
      strictXml(c, key, file);
      continue;
    }
    if (!c.hasAttribute("type") || !c.hasAttribute("value"))
      fail(file, "the <Parameter> '" + key + "' needs both type=\"...\" and value=\"...\"");
    const std::string type = c.getAttribute("type"), value = c.getAttribute("value");
    if (!sceneTypes().count(type))
      fail(file, "'" + key + "' has type " + quote(type) + "; a scene's types are int, double, bool, string, Array(int), Array(double) and Array(string)");
    const std::string problem = valueProblem(type, value);
    if (!problem.empty()) fail(file, "'" + key + "' = " + quote(value) + " is not " + problem);
  }
}

// ---------------------------------------------------------------------------------------------
// --set overrides
// ---------------------------------------------------------------------------------------------

void applyOverride(ParameterList& pl, const std::string& spec, const ParameterList& schema) {
  const std::string arg = "--set " + quote(spec, 80);
  int line = 0;
  const std::string text = textProblem(spec, line);
  if (!text.empty()) throw SceneError(arg + ": contains " + text);
  const auto eq = spec.find('=');
  if (eq == std::string::npos) throw SceneError(arg + ": expected Sublist/Key=value");
  const std::string path = spec.substr(0, eq), value = spec.substr(eq + 1);
  std::vector<std::string> parts;
  std::stringstream ss(path);
  std::string part;
  while (std::getline(ss, part, '/')) parts.push_back(part);
  if (parts.empty()) throw SceneError(arg + ": empty key");
  ParameterList* cur = &pl;
  const ParameterList* val = &schema;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    if (val) {
      auto named = namedSublists().find(parts[i]);
      if (named != namedSublists().end() && i + 2 < parts.size()) {
        cur = &cur->sublist(parts[i]).sublist(parts[i + 1]);
        val = &templateFor(parts[i]);
        ++i;
        continue;
      }
      if (parts[i] == "Linear Solver") {
        val = nullptr;  // Stratimikos' own list: validated by Stratimikos
      } else if (val->isSublist(parts[i])) {
        val = &val->sublist(parts[i]);
      } else {
        throw SceneError(arg + ": unknown sublist " + quote(parts[i]) + suggestion(parts[i], keysOf(*val)));
      }
    }
    cur = &cur->sublist(parts[i]);
  }
  const std::string& key = parts.back();
  const Teuchos::ParameterEntry* proto = cur->isParameter(key) ? cur->getEntryPtr(key)
                                         : (val && val->isParameter(key) ? val->getEntryPtr(key) : nullptr);
  if (!proto) throw SceneError(arg + ": unknown key " + quote(path, 80) + (val ? suggestion(key, keysOf(*val)) : ""));
  if (proto->isList()) throw SceneError(arg + ": " + quote(path, 80) + " is a sublist; set one of its keys (Sublist/Key=value)");
  const std::string t = friendlyType(typeName(*proto));
  if (!sceneTypes().count(t)) throw SceneError(arg + ": cannot set a value of type " + t);
  const std::string problem = valueProblem(t, value);
  if (!problem.empty()) throw SceneError(arg + ": " + quote(value) + " is not " + problem);
  std::vector<std::string> entries;
  splitArray(value, entries);
  bool b = false;
  if (t == "double") {
    cur->set(key, std::strtod(trim(value).c_str(), nullptr));
  } else if (t == "int") {
    cur->set(key, static_cast<int>(std::strtol(trim(value).c_str(), nullptr, 10)));
  } else if (t == "bool") {
    parseBool(value, b);
    cur->set(key, b);
  } else if (t == "string") {
    cur->set(key, value);
  } else if (t == "Array(double)") {
    Array<double> a;
    for (const auto& e : entries) a.push_back(std::strtod(e.c_str(), nullptr));
    cur->set(key, a);
  } else if (t == "Array(int)") {
    Array<int> a;
    for (const auto& e : entries) a.push_back(static_cast<int>(std::strtol(e.c_str(), nullptr, 10)));
    cur->set(key, a);
  } else {
    cur->set(key, Array<std::string>(entries));
  }
}

// ---------------------------------------------------------------------------------------------
// Building: one function per sublist, in the order of sceneSteps()
// ---------------------------------------------------------------------------------------------

Vec3 vec3(const Array<double>& a) {
  Vec3 v = Vec3::Zero();
  for (int i = 0; i < std::min<int>(3, a.size()); ++i) v[i] = a[i];
  return v;
}

std::string position(const Discretization& d, int p) {
  std::string s = "(";
  for (int a = 0; a < d.dim; ++a) s += (a ? ", " : "") + number(d.X[p][a]);
  return s + ")";
}

template <class T>
std::string shownValue(T v) {
  if constexpr (std::is_integral<T>::value)
    return std::to_string(v);
  else
    return number(v);
}

/// One sublist of the scene (defaults filled) with its schema, named in messages by its path.
struct Section {
  const ParameterList& list;
  const ParameterList& schema;
  std::string path;
  const std::string& file;

  template <class T>
  T get(const std::string& k) const {
    return list.get<T>(k);
  }
  /// "'Path/Key'" for messages.
  std::string key(const std::string& k) const { return "'" + path + "/" + k + "'"; }
  /// An enumerated key's value, through the schema's validator.
  template <class E>
  E choice(const std::string& k) const {
    return perinox::choice<E>(list, schema, k);
  }
  /// A number key's value, refused outside the schema's range for it.
  template <class T>
  T ranged(const std::string& k) const {
    const T v = list.get<T>(k);
    const auto r = Teuchos::rcp_dynamic_cast<const Range<T>>(schema.getEntry(k).validator(), true);
    if (!r->holds(v))
      fail(file, key(k) + " must be " + r->phrase() + ", not " + shownValue(v) + (r->note().empty() ? "" : " (" + r->note() + ")"));
    return v;
  }
  Section sub(const std::string& name) const { return {list.sublist(name), schema.sublist(name), path + "/" + name, file}; }
  /// The entry `name` of a named sublist (Regions, Loads, ...), against its template.
  Section entry(const std::string& name, const std::string& named) const {
    return {list.sublist(name), templateFor(named), path + "/" + name, file};
  }
};

/// What the sublist functions read and fill.
struct SceneBuild {
  Scene& sc;
  ProblemSpec& problem;
  const ParameterList& pl;  // the scene, defaults filled
  const ParameterList& schema;
  const std::string& file;
  const std::string& presetDir;
  int dim;
  ExodusMesh mesh;  // Type = Exodus: the mesh's blocks and sets, for the regions
  Teuchos::RCP<const Teuchos::Comm<int>> comm;  // the ranks building the scene together
  std::string localError;  // distributed: the first failure seen in this rank's share (localFail)

  bool distributed() const { return problem.distributed; }
  /// A failure found in this rank's data. Replicated: every rank finds it; fail now. Distributed:
  /// other ranks may not, so record it and go on to the step's end, where the ranks agree
  /// (runStep) and all fail with the lowest failing rank's sentence.
  void localFail(const std::string& msg) {
    if (!distributed()) fail(file, msg);
    if (localError.empty()) localError = msg;
  }
  /// Sum over the ranks (distributed), else v.
  long long sumOverRanks(long long v) const {
    if (!distributed()) return v;
    long long all = 0;
    Teuchos::reduceAll(*comm, Teuchos::REDUCE_SUM, v, Teuchos::outArg(all));
    return all;
  }
  /// Global id of disc's particle i.
  long long gid(int i) const { return distributed() ? problem.globalId[i] : i; }
  /// Whether a particle (a global id) is owned by this rank; every particle when replicated.
  bool owns(long long g) const { return problem.owns(g); }

  Section section(const std::string& name) const { return {pl.sublist(name), schema.sublist(name), name, file}; }
  const std::vector<int>& region(const std::string& key, const std::string& name) const {
    auto it = sc.regions.find(name);
    if (it == sc.regions.end()) fail(file, "'" + key + "' names region '" + name + "', which is not defined under Regions");
    return it->second;
  }
  /// A path given in the scene, relative to the scene file's folder.
  std::string relativeToScene(std::string path) const {
    if (!path.empty() && path[0] != '/') {
      const auto slash = file.rfind('/');
      if (slash != std::string::npos) path = file.substr(0, slash + 1) + path;
    }
    return path;
  }
};

/// The particles of a region of Type Node Set, Side Set (Exodus meshes) or Block (any
/// discretisation), chosen by the set's or block's Name or Id.
std::vector<int> meshSetRegion(const SceneBuild& b, const Section& r, const std::string& region, const std::string& type) {
  const ExodusMesh& mesh = b.mesh;
  const Discretization& d = b.problem.disc;
  const std::string& file = b.file;
  const bool exodus = b.pl.sublist("Discretization").get<std::string>("Type") == "Exodus";
  const std::string key = "'Regions/" + region + "/";
  const std::string name = r.get<std::string>("Name");
  const int id = r.get<int>("Id");
  if (id < -1) fail(file, key + "Id' must be >= 0 (or -1: none)");
  if (name.empty() == (id == -1))
    fail(file, "region '" + region + "' (Type = " + type + ") needs exactly one of Name and Id");
  const std::string what = name.empty() ? "id " + std::to_string(id) : "name '" + name + "'";
  if (type == "Block") {
    int blockId = id;
    if (!name.empty()) {
      if (!exodus) fail(file, key + "Name' names a block, but only Exodus blocks have names; give its Id");
      auto it = std::find_if(mesh.blocks.begin(), mesh.blocks.end(), [&](const MeshBlock& blk) { return blk.name == name; });
      if (it == mesh.blocks.end()) fail(file, "region '" + region + "': the mesh has no element block named '" + name + "'");
      blockId = it->id;
    }
    std::vector<int> ids;
    for (int i = 0; i < d.size(); ++i)
      if (d.block[i] == blockId && !d.fictitious[i]) ids.push_back(i);
    if (b.sumOverRanks(static_cast<long long>(ids.size())) == 0)
      fail(file, "region '" + region + "': no particle is in block " + std::to_string(blockId));
    return ids;
  }
  if (!exodus) fail(file, "region '" + region + "' is a " + type + ", which needs 'Discretization/Type' = Exodus");
  const auto& sets = type == "Node Set" ? mesh.nodeSets : mesh.sideSets;
  for (const auto& s : sets)
    if (name.empty() ? s.id == id : s.name == name) {
      if (b.sumOverRanks(static_cast<long long>(s.particles.size())) == 0)
        fail(file, "region '" + region + "': the mesh's " + type + " with " + what + " is empty");
      if (!b.distributed()) return s.particles;
      // Each rank holds the set's members in its id slab; its share's members come from there.
      std::vector<int> ids;
      for (long long g : heldMembers(*b.comm, b.problem.globalId, b.problem.globalCount, s.particles))
        ids.push_back(b.problem.index(g));
      std::sort(ids.begin(), ids.end());
      return ids;
    }
  fail(file, "region '" + region + "': the mesh has no " + type + " with " + what);
}

/// The numbers of an Ids File: integers separated by spaces or lines; a line whose first
/// character (after spaces) is '#', '/' or '*' is a comment. One sentence naming the file and line
/// for anything else.
std::vector<long long> readIdsFile(const std::string& path) {
  const std::string text = readInputText(path);
  std::vector<long long> ids;
  std::istringstream in(text);
  std::string line;
  long lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#' || line[first] == '/' || line[first] == '*') continue;
    std::istringstream ls(line);
    std::string tok;
    while (ls >> tok) {
      errno = 0;
      char* end = nullptr;
      const long long v = std::strtoll(tok.c_str(), &end, 10);
      if (end == tok.c_str() || *end != '\0' || errno == ERANGE)
        fail(path + ":" + std::to_string(lineNo), "'" + printable(tok) + "' is not a whole number (an Ids File holds particle numbers)");
      if (static_cast<long long>(ids.size()) >= kMaxParticles)
        fail(path + ":" + std::to_string(lineNo), "more than " + std::to_string(kMaxParticles) + " numbers");
      ids.push_back(v);
    }
  }
  if (ids.empty()) fail(path, "holds no numbers (an Ids File lists particle numbers)");
  return ids;
}

/// The particles of a region of Type Ids: 1-based numbers, a particle file's line order or an
/// Exodus mesh's element number map (Peridigm's node numbers); every number must name a particle.
std::vector<int> numberedRegion(const SceneBuild& b, const Section& r, const std::string& region) {
  const std::string& file = b.file;
  const std::string dtype = b.pl.sublist("Discretization").get<std::string>("Type");
  if (dtype != "Particle File" && dtype != "Exodus")
    fail(file, "region '" + region + "' (Type = Ids) numbers particles of a particle file or an Exodus mesh; this scene's "
               "'Discretization/Type' is " + dtype);
  const auto given = r.get<Array<int>>("Ids");
  const std::string idsFile = r.get<std::string>("Ids File");
  if (given.empty() == idsFile.empty()) fail(file, "region '" + region + "' (Type = Ids) needs exactly one of 'Ids' and 'Ids File'");
  std::vector<long long> numbers(given.begin(), given.end());
  const std::string source = idsFile.empty() ? "'Regions/" + region + "/Ids'" : quote(idsFile);
  if (!idsFile.empty()) numbers = readIdsFile(b.relativeToScene(idsFile));
  for (long long n : numbers)
    if (n < 1) fail(file, "region '" + region + "': " + source + " holds " + std::to_string(n) + "; particle numbers start at 1");
  std::vector<long long> global;
  if (dtype == "Particle File") {
    const long long count = b.problem.particleCount();
    for (long long n : numbers) {
      if (n > count)
        fail(file, "region '" + region + "': " + source + " holds " + std::to_string(n) + ", but the particle file has " +
                       std::to_string(count) + " particles");
      global.push_back(n - 1);
    }
  } else {
    const std::vector<long long> at = exodusElementPositions(b.sc.inputFile, b.dim, numbers);
    for (std::size_t k = 0; k < numbers.size(); ++k) {
      if (at[k] < 0)
        fail(file, "region '" + region + "': " + source + " holds " + std::to_string(numbers[k]) +
                       ", which is no element's id in the mesh's element number map");
      global.push_back(at[k]);
    }
  }
  std::sort(global.begin(), global.end());
  global.erase(std::unique(global.begin(), global.end()), global.end());
  std::vector<int> ids;
  for (long long g : global)
    if (!b.distributed()) ids.push_back(static_cast<int>(g));
    else if (b.problem.holds(g)) ids.push_back(b.problem.index(g));
  std::sort(ids.begin(), ids.end());
  return ids;
}

void checkHorizonFactor(double f, const std::string& file) {
  if (!(f >= 1.0))
    fail(file, "'Discretization/Horizon Factor' must be at least 1: a horizon below the particle spacing leaves particles without neighbours");
  if (f > kMaxHorizonFactor)
    fail(file, "'Discretization/Horizon Factor' must be at most " + number(kMaxHorizonFactor) + " (" + number(f) +
                   " spacings would give every particle a family of thousands or millions)");
}

/// The lattice's sites, fictitious layers included, are bounded before any is allocated.
void checkLatticeSize(const LatticeSpec& ls, const std::string& file) {
  const int layers = static_cast<int>(std::floor(ls.horizonFactor + 1e-9));
  double sites = 1;
  for (int a = 0; a < ls.dim; ++a) {
    double n = ls.counts[a];
    for (Side s : ls.fictitiousSides)
      if (static_cast<int>(s) / 2 == a) n += layers;
    sites *= n;
  }
  if (sites > kMaxParticles)
    fail(file, "'Discretization' asks for " + number(sites) + " particles (fictitious layers included); at most " +
                   std::to_string(kMaxParticles) + " are allowed");
}

/// The linear-solver presets in presetDir: its *.xml files' names without the extension.
std::vector<std::string> presetNames(const std::string& presetDir) {
  std::vector<std::string> names;
  if (DIR* dir = ::opendir(presetDir.c_str())) {
    while (const dirent* e = ::readdir(dir)) {
      const std::string f = e->d_name;
      if (f.size() > 4 && f[0] != '.' && f.compare(f.size() - 4, 4, ".xml") == 0) names.push_back(f.substr(0, f.size() - 4));
    }
    ::closedir(dir);
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// The reason in a Teuchos exception's text, which spans lines (source location, the failed
/// test, then the reason): the line that says "error", else the last non-empty line.
std::string teuchosReason(const std::string& msg) {
  std::string first, last, line;
  std::stringstream ss(msg);
  while (std::getline(ss, line)) {
    if (line.find_first_not_of(" \t") == std::string::npos || line.rfind("Throw number", 0) == 0) continue;
    last = line;
    if (first.empty() && line.find("rror") != std::string::npos) first = line;
  }
  return first.empty() ? last : first;
}

double hydrostaticStretch(double lambda, double mu, double traction, const std::string& file) {
  // Solve 2 (lambda + mu) ln(x) / x = P on the stable branch x < e (plane strain).
  const double k = 2 * (lambda + mu);
  if (traction >= k / std::exp(1.0))
    fail(file, "'Reference/Traction' exceeds the limit load 2(lambda+mu)/e of the Hencky plate");
  double x = 1.0;
  for (int it = 0; it < 100; ++it) {
    const double f = k * std::log(x) / x - traction;
    const double df = k * (1 - std::log(x)) / (x * x);
    const double dx = f / df;
    x -= dx;
    if (std::abs(dx) < 1e-15 * x) break;
  }
  return x;
}

/// A material from a list of materialKeys (the scene's Material, or a block's, whose keys not given
/// hold the top-level values): the one reader of those keys, so a new material key is read
/// everywhere a material is.
MaterialSpec materialFrom(const Section& m, int dim) {
  MaterialSpec mat;
  mat.dim = dim;
  mat.kind = m.choice<MaterialKind>("Model");
  mat.planar = dim == 2 ? m.choice<PlanarMode>("Plane") : PlanarMode::None;
  mat.E = m.ranged<double>("Young's Modulus");
  mat.nu = m.ranged<double>("Poisson's Ratio");
  if (m.choice<PlasticityChoice>("Plasticity") == PlasticityChoice::J2) {
    PlasticitySpec& p = mat.plastic;
    p.enabled = true;
    p.yieldStress = m.ranged<double>("Yield Stress");
    if (!(p.yieldStress > 0.0)) fail(m.file, m.key("Yield Stress") + " must be positive with Plasticity = J2 (it is the initial yield stress)");
    p.hardeningModulus = m.ranged<double>("Hardening Modulus");
    p.voce = m.choice<HardeningChoice>("Hardening") == HardeningChoice::Voce;
    if (p.voce) {
      p.saturationStress = m.ranged<double>("Saturation Stress");
      p.saturationRate = m.ranged<double>("Saturation Rate");
      if (!(p.saturationStress >= p.yieldStress))
        fail(m.file, m.key("Saturation Stress") + " must be at least " + m.key("Yield Stress") + " with Hardening = Voce (got " +
                         shownValue(p.saturationStress) + " against " + shownValue(p.yieldStress) + ")");
      if (!(p.saturationRate > 0.0)) fail(m.file, m.key("Saturation Rate") + " must be positive with Hardening = Voce");
    }
  }
  return mat;
}

/// A damage law from a list of damageLawKeys (Damage, or a block's Damage); `key` names the list in
/// the message ("'Damage/", "'Blocks/steel/Damage/").
DamageSpec damageLawFrom(const Section& dm, const std::string& file, const std::string& key) {
  DamageSpec ds;
  ds.sCr = dm.get<double>("Critical Stretch");
  ds.sMin = dm.get<double>("Softening Start");
  if (!(ds.sMin > 0 && ds.sCr > ds.sMin))
    fail(file, key + "Softening Start' and " + key + "Critical Stretch' must satisfy 0 < s_min < s_cr");
  ds.beta = dm.ranged<double>("Beta");
  ds.softening = dm.choice<DamageSpec::Softening>("Softening");
  const BreakCriterion c = dm.choice<BreakCriterion>("Criterion");
  const double crit = dm.ranged<double>("Critical Plastic Strain");
  ds.stretchCriterion = c != BreakCriterion::PlasticStrain;
  if (c == BreakCriterion::Stretch) {
    if (crit > 0) fail(file, key + "Critical Plastic Strain' is set but " + key + "Criterion' is Stretch; set it to Plastic Strain or Either");
  } else {
    if (!(crit > 0)) fail(file, key + "Criterion' breaks bonds by plastic strain: give " + key + "Critical Plastic Strain' > 0");
    ds.criticalPlasticStrain = crit;
  }
  return ds;
}

void readMaterial(SceneBuild& b) { b.problem.material = materialFrom(b.section("Material"), b.dim); }

/// Discretization/Holes of a lattice.
std::vector<Hole> readHoles(const Section& dl, int dim) {
  std::vector<Hole> holes;
  const Section hs = dl.sub("Holes");
  for (auto h = hs.list.begin(); h != hs.list.end(); ++h) {
    const Section hl = hs.entry(hs.list.name(h), "Holes");
    Hole hole;
    hole.center = vec3(hl.get<Array<double>>("Center"));
    hole.kind = hl.choice<Hole::Kind>("Shape");
    if (hole.kind == Hole::Kind::Circle) {
      hole.radius = hl.ranged<double>("Radius");
    } else {
      hole.halfWidths = vec3(hl.get<Array<double>>("Half Widths"));
      if (!(hole.halfWidths.head(dim).minCoeff() > 0)) fail(dl.file, hl.key("Half Widths") + " must be positive on every axis");
    }
    holes.push_back(hole);
  }
  return holes;
}

/// The lattice's particle counts: Particles, or a Spacing that divides the box.
void latticeCounts(const Section& dl, LatticeSpec& ls) {
  const std::string& file = dl.file;
  const auto counts = dl.get<Array<int>>("Particles");
  const double spacing = dl.get<double>("Spacing");
  if (!counts.empty() && spacing != 0) fail(file, "'Discretization' gives both Particles and Spacing; give one of them");
  if (!counts.empty()) {
    for (int a = 0; a < ls.dim; ++a) {
      if (counts[a] < 1) fail(file, "'Discretization/Particles' counts must be at least 1");
      ls.counts[a] = counts[a];
    }
    return;
  }
  if (!(spacing > 0)) fail(file, "'Discretization' needs Particles (counts per axis) or a positive Spacing");
  for (int a = 0; a < ls.dim; ++a) {
    const double cells = (ls.upper[a] - ls.lower[a]) / spacing;
    const std::string along = std::string(" along ") + "xyz"[a];
    if (!(cells <= kMaxParticles))
      fail(file, "'Discretization/Spacing' = " + number(spacing) + " gives more than " + std::to_string(kMaxParticles) + " particles" + along);
    ls.counts[a] = static_cast<int>(std::lround(cells));
    if (ls.counts[a] < 1 || std::abs(cells - ls.counts[a]) > 1e-6 * cells)
      fail(file, "'Discretization/Spacing' = " + number(spacing) + " does not divide the box" + along + " (" + number(cells) +
                     " spacings); adjust it or give Particles");
  }
}

LatticeSpec readLatticeSpec(const Section& dl, int dim, double thickness) {
  const std::string& file = dl.file;
  LatticeSpec ls;
  ls.dim = dim;
  ls.lower = vec3(dl.get<Array<double>>("Lower Corner"));
  ls.upper = vec3(dl.get<Array<double>>("Upper Corner"));
  for (int a = 0; a < dim; ++a)
    if (!(ls.upper[a] > ls.lower[a])) fail(file, "'Discretization/Upper Corner' must exceed 'Lower Corner' on every axis");
  latticeCounts(dl, ls);
  ls.thickness = thickness;
  ls.horizonFactor = dl.get<double>("Horizon Factor");
  if (dl.get<double>("Horizon") != 0) fail(file, "'Discretization/Horizon' is for particle files; lattices use 'Horizon Factor'");
  checkHorizonFactor(ls.horizonFactor, file);
  for (const auto& s : dl.get<Array<std::string>>("Fictitious Sides")) {
    Side side = Side::XMin;
    parseSide(s, side);
    if (static_cast<int>(side) / 2 >= dim)
      fail(file, "'Discretization/Fictitious Sides' has '" + s + "', which is not a side of this " + std::to_string(dim) + "D body");
    ls.fictitiousSides.push_back(side);
  }
  checkLatticeSize(ls, file);
  ls.jitter = dl.ranged<double>("Jitter");
  ls.jitterSeed = static_cast<unsigned>(dl.ranged<int>("Jitter Seed"));
  ls.holes = readHoles(dl, dim);
  return ls;
}

/// The horizon of a particle file or mesh: Horizon, or Horizon Factor x the spacing, within [1, 50] spacings.
double particleHorizon(const Section& dl, double spacing, const std::string& spacingNote) {
  double horizon = dl.get<double>("Horizon");
  if (horizon < 0) fail(dl.file, "'Discretization/Horizon' must be positive (or 0: Horizon Factor x Spacing)");
  if (horizon == 0) {
    checkHorizonFactor(dl.get<double>("Horizon Factor"), dl.file);
    horizon = dl.get<double>("Horizon Factor") * spacing;
  }
  if (!(horizon >= spacing && horizon <= kMaxHorizonFactor * spacing))
    fail(dl.file, "'Discretization/Horizon' must be from the spacing to " + number(kMaxHorizonFactor) + " x the spacing (" +
                      number(spacing) + " to " + number(kMaxHorizonFactor * spacing) + spacingNote + ")");
  return horizon;
}

/// The particle file of the scene, its keys checked.
ParticleFileSpec particleFile(const SceneBuild& b, const Section& dl, double thickness) {
  std::string path = dl.get<std::string>("Particle File");
  if (path.empty()) fail(b.file, "'Discretization/Particle File' is required when Type = Particle File");
  const double given = dl.get<double>("Spacing");
  if (given < 0) fail(b.file, "'Discretization/Spacing' must be positive (or 0: from the particles' volumes)");
  if (dl.get<double>("Horizon") < 0) fail(b.file, "'Discretization/Horizon' must be positive (or 0: Horizon Factor x Spacing)");
  path = b.relativeToScene(path);
  // Not given: the spacing the volumes imply (every rank reads the file's volumes once).
  const ParticleColumns columns = dl.get<std::string>("Particle File Columns") == "x y z block volume" ? ParticleColumns::BlockThenVolume
                                                                                                      : ParticleColumns::VolumeThenBlock;
  const double spacing = given > 0 ? given : particleFileSpacing(path, b.dim, thickness, columns);
  return {path, b.dim, particleHorizon(dl, spacing, given > 0 ? "" : ", the spacing taken from the particles' volumes"), spacing, thickness,
          columns};
}

Discretization readMesh(SceneBuild& b, const Section& dl, double thickness) {
  const std::string& file = b.file;
  const std::string path = b.relativeToScene(dl.get<std::string>("Mesh File"));
  if (path.empty()) fail(file, "'Discretization/Mesh File' is required when Type = Exodus");
  if (!exodusAvailable())
    fail(file, "'Discretization/Type' = Exodus, but this perinox was built without Exodus II (install libexodusii-dev, e.g. with scripts/setup.sh, and rebuild)");
  if (!dl.get<Array<std::string>>("Fictitious Sides").empty())
    fail(file, "'Discretization/Fictitious Sides' is for lattices; an Exodus mesh's boundary conditions act on its node sets");
  const double given = dl.get<double>("Spacing");
  if (given < 0) fail(file, "'Discretization/Spacing' must be positive (or 0: from the mesh)");
  if (dl.get<double>("Horizon") < 0) fail(file, "'Discretization/Horizon' must be positive (or 0: Horizon Factor x Spacing)");
  // Distributed: this rank's id slab of the elements, the sets' members in it (heldMembers finds
  // a share's), the body's box and median spacing.
  b.mesh = b.distributed() ? readLocalExodusMesh(*b.comm, path, b.dim, thickness) : readExodusMesh(path, b.dim, thickness);
  Discretization md = std::move(b.mesh.disc);
  if (given > 0) md.dx = given;
  md.horizon = particleHorizon(dl, md.dx, given > 0 ? "" : ", the spacing taken from the mesh");
  return md;  // families: each rank finds its own (localParticles)
}

void readDiscretization(SceneBuild& b) {
  const Section dl = b.section("Discretization");
  const std::string dtype = dl.get<std::string>("Type");
  const double thickness = dl.ranged<double>("Thickness");
  if (dtype != "Exodus" && !dl.get<std::string>("Mesh File").empty())
    fail(b.file, "'Discretization/Mesh File' is for Type = Exodus (this scene's Type is " + dtype + ")");
  const bool distributed = dl.get<std::string>("Construction") == "Distributed";
  b.problem.partition = dl.choice<PartitionMethod>("Partition");
  if (dtype == "Particle File") b.sc.inputFile = b.relativeToScene(dl.get<std::string>("Particle File"));
  if (dtype == "Exodus") b.sc.inputFile = b.relativeToScene(dl.get<std::string>("Mesh File"));
  try {
    if (distributed) {
      // This rank's share only (problemOnLocalLattice, problemOnLocalParticleFile, an Exodus
      // mesh's slab through problemOnLocalParticles): its owned particles and those within two
      // horizons of them, with their global ids.
      std::shared_ptr<ProblemSpec> share;
      if (dtype == "Lattice")
        share = problemOnLocalLattice(b.comm, readLatticeSpec(dl, b.dim, thickness), b.problem.material, b.problem.partition);
      else if (dtype == "Particle File")
        share = problemOnLocalParticleFile(b.comm, particleFile(b, dl, thickness), b.problem.material, b.problem.partition);
      else {
        b.problem.distributed = true;  // readMesh reads this rank's slab
        const Discretization slab = readMesh(b, dl, thickness);
        const long long first = partitionBegin(b.sumOverRanks(slab.size()), b.comm->getSize(), b.comm->getRank());
        share = problemOnLocalParticles(b.comm, slab, first, b.problem.material, b.problem.partition);
      }
      ProblemSpec& P = b.problem;
      P.distributed = true;
      P.disc = std::move(share->disc);
      P.globalId = std::move(share->globalId);
      P.owned = std::move(share->owned);
      P.globalCount = share->globalCount;
    } else if (dtype == "Lattice")
      b.problem.disc = buildLattice(readLatticeSpec(dl, b.dim, thickness), false);  // families: each rank finds its own
    else if (dtype == "Particle File") {
      const ParticleFileSpec f = particleFile(b, dl, thickness);
      b.problem.disc = readParticleFile(f.path, f.dim, f.horizon, f.dx, f.thickness, false, f.columns);
    }
    else
      b.problem.disc = readMesh(b, dl, thickness);
  } catch (const std::invalid_argument& e) {
    fail(b.file, std::string("Discretization: ") + e.what());
  } catch (const SceneError&) {
    throw;
  } catch (const std::runtime_error& e) {
    fail(b.file, std::string("Discretization: ") + e.what());
  }
}

/// Model/Stabilization and G. The micromodulus is the library's (ProblemSpec::stabilizationSpec).
void readStabilization(SceneBuild& b) {
  const Section mo = b.section("Model");
  const double G = mo.ranged<double>("G");
  if (mo.get<std::string>("Stabilization") == "Silling") {
    b.problem.stabilization = G > 0;
    b.problem.stab.G = G;
    if (mo.get<std::string>("G Form") == "Peridigm Hourglass") b.problem.stab.form = StabilizationSpec::Form::PeridigmHourglass;
  } else if (G > 0) {
    fail(b.file, "'Model/G' is set but 'Model/Stabilization' is None; set Stabilization to Silling");
  }
}

/// Material/Modulus Field: a per-particle modulus scale.
void readModulusField(SceneBuild& b) {
  const Section ml = b.section("Material");
  if (ml.get<std::string>("Modulus Field") != "Seed001 Bar") return;
  const double fa = ml.ranged<double>("Field Alpha"), fb = ml.ranged<double>("Field Beta"), fl = ml.ranged<double>("Field Length");
  const Discretization& d = b.problem.disc;
  b.problem.modulusScale.resize(d.size());
  for (int p = 0; p < d.size(); ++p) {
    const double xr = d.X[p][0] / fl;
    b.problem.modulusScale[p] = xr <= 0.5 ? 1.0 : 1.0 / (1.0 + fb / (2 * fa) / std::sqrt(xr - 0.5));
  }
}

/// Model/Zero-Energy Control (seed 001): springs, average displacement states or stress points.
void readControls(SceneBuild& b) {
  const Section mo = b.section("Model");
  const Discretization& d = b.problem.disc;
  const std::string ctrl = mo.get<std::string>("Zero-Energy Control");
  double cc = mo.get<double>("Control Constant");
  if (ctrl == "Springs" || ctrl == "Average Displacement") {
    if (cc < 0) {
      // Seed 001 Table 1 (optimum C1, C2 for the 1D bar) by particle count.
      long long mine = 0;  // real particles (owned ones, summed over the ranks when distributed)
      for (int i = 0; i < d.size(); ++i) mine += d.fictitious[i] == 0 && b.owns(b.gid(i));
      const long long nreal = b.sumOverRanks(mine);
      const std::map<int, std::pair<double, double>> table{{100, {0.8, 60}}, {200, {1.28, 150}}, {500, {2, 500}}, {1000, {3, 1750}}};
      auto it = table.find(nreal);
      if (it == table.end())
        fail(b.file, "'Model/Control Constant' is not set and seed 001's Table 1 has no value for " + std::to_string(nreal) + " particles (only 100, 200, 500, 1000)");
      cc = ctrl == "Springs" ? it->second.first : it->second.second;
    }
    b.problem.control = true;
    b.problem.controlSpec.kind = ctrl == "Springs" ? ControlSpec::Kind::Springs : ControlSpec::Kind::AverageDisplacement;
    b.problem.controlSpec.C = cc;
  } else if (ctrl == "Stress Points") {
    if (d.horizon > 1.5 * d.dx) fail(b.file, "stress points use nearest-neighbour families (seed 001): set 'Discretization/Horizon Factor' below 1.5");
    b.problem.stressPoints = true;
    b.problem.stressPointSeed = static_cast<unsigned>(mo.ranged<int>("Stress Point Seed"));
  }
}

void readDamage(SceneBuild& b) {
  const Section dm = b.section("Damage");
  Scene& sc = b.sc;
  sc.maxBreakRounds = dm.ranged<int>("Max Break Rounds");
  if (!dm.get<bool>("Enabled")) return;
  b.problem.damage = true;
  b.problem.damageSpec = damageLawFrom(dm, b.file, "'Damage/");
  sc.stallBreak = dm.get<std::string>("On Stall") == "Break Most Stretched";
  sc.stallBreakTolerance = dm.ranged<double>("Stall Break Tolerance");
  sc.maxStallBreaks = dm.ranged<int>("Max Stall Breaks");
  sc.reloadTolerance = dm.ranged<double>("Reload Tolerance");
  // A break at the limit is a stall break: with On Stall = Stop there is none.
  sc.breakAtSnapBackLimit = sc.stallBreak && dm.get<std::string>("After Snap-Back") == "Break Most Stretched";
}

/// Blocks: each block's material, G and damage law (ProblemSpec::blocks); on a lattice, the
/// blocks' boxes set the particles' block ids first. Every particle's block needs an entry.
void readBlocks(SceneBuild& b) {
  const Section bl = b.section("Blocks");
  if (bl.list.numParams() == 0) return;
  ProblemSpec& P = b.problem;
  Discretization& d = P.disc;
  const std::string& file = b.file;
  const std::string type = b.pl.sublist("Discretization").get<std::string>("Type");
  std::vector<std::string> boxOf(d.size());  // lattice: the entry whose box gave the particle its block
  std::map<int, std::string> entryOf;        // block id -> entry
  for (auto it = bl.list.begin(); it != bl.list.end(); ++it) {
    const std::string name = bl.list.name(it);
    const Section e = bl.entry(name, "Blocks");
    const std::string key = "'Blocks/" + name + "/";
    const std::string bname = e.get<std::string>("Name");
    int id = e.get<int>("Id");
    if (id < -1) fail(file, key + "Id' must be >= 0 (or -1: none, give Name)");
    if (bname.empty() == (id == -1)) fail(file, "block '" + name + "' needs exactly one of Name and Id");
    if (!bname.empty()) {
      if (type != "Exodus") fail(file, key + "Name' names a block, but only Exodus blocks have names; give its Id");
      auto m = std::find_if(b.mesh.blocks.begin(), b.mesh.blocks.end(), [&](const MeshBlock& blk) { return blk.name == bname; });
      if (m == b.mesh.blocks.end()) fail(file, "block '" + name + "': the mesh has no element block named '" + bname + "'");
      id = m->id;
    }
    const auto lo = e.get<Array<double>>("Box Min"), hi = e.get<Array<double>>("Box Max");
    if (lo.empty() != hi.empty()) fail(file, "block '" + name + "' needs both Box Min and Box Max, or neither");
    if (!lo.empty()) {
      if (type != "Lattice") fail(file, key + "Box Min' is for lattices; a particle file's or mesh's blocks come from the file");
      for (int p : selectBox(d, vec3(lo), vec3(hi), Population::All)) {
        if (!boxOf[p].empty())
          b.localFail("the particle at " + position(d, p) + " is in the boxes of blocks '" + boxOf[p] + "' and '" + name + "'; block boxes must not overlap");
        boxOf[p] = name;
        d.block[p] = id;
      }
    }
    if (!entryOf.emplace(id, name).second)
      fail(file, "blocks '" + entryOf[id] + "' and '" + name + "' both name block " + std::to_string(id) + "; give each block one entry");
    BlockSpec spec;
    spec.id = id;
    spec.material = materialFrom(e.sub("Material"), b.dim);
    const double G = e.sub("Stabilization").ranged<double>("G");
    if (G > 0 && b.pl.sublist("Model").get<std::string>("Stabilization") != "Silling")
      fail(file, key + "Stabilization/G' is set but 'Model/Stabilization' is None; set Stabilization to Silling");
    spec.G = G;
    if (G > 0) P.stabilization = true;
    if (P.damage) {
      const DamageSpec ds = damageLawFrom(e.sub("Damage"), file, key + "Damage/");
      spec.damage = ds;
      const DamageSpec& top = P.damageSpec;
      if (b.sc.stallBreak && (ds.sCr != top.sCr || ds.sMin != top.sMin || ds.beta != top.beta || ds.softening != top.softening))
        fail(file, "block '" + name + "' has its own damage law, but 'Damage/On Stall' = Break Most Stretched compares raw stretches "
                   "across blocks; use On Stall = Stop, or the top-level law for every block");
    }
    P.blocks.push_back(spec);
  }
  // Particles per block id, over the owned particles (all of them when replicated); the lowest
  // block id without an entry over the ranks, with its whole count, so that every rank gives
  // the same sentence.
  std::map<int, long long> count;
  for (int p = 0; p < d.size(); ++p)
    if (b.owns(b.gid(p))) ++count[d.block[p]];
  int missing = std::numeric_limits<int>::max();
  for (const auto& [id, n] : count)
    if (!entryOf.count(id) && n > 0) missing = std::min(missing, id);
  if (b.distributed()) {
    int lowest = missing;
    Teuchos::reduceAll(*b.comm, Teuchos::REDUCE_MIN, missing, Teuchos::outArg(lowest));
    missing = lowest;
  }
  if (missing != std::numeric_limits<int>::max())
    fail(file, "block " + std::to_string(missing) + " (" + std::to_string(b.sumOverRanks(count.count(missing) ? count.at(missing) : 0)) +
                   " particles) has no entry under 'Blocks'; give every block its material");
  for (const auto& [id, name] : entryOf)  // every rank has the same entries: the sums agree
    if (b.sumOverRanks(count.count(id) ? count.at(id) : 0) == 0)
      fail(file, "block '" + name + "' names block " + std::to_string(id) + ", which has no particle");
}

/// One region's particles.
std::vector<int> selectRegion(const SceneBuild& b, const Section& r, const std::string& name) {
  const Discretization& d = b.problem.disc;
  const std::string type = r.get<std::string>("Type");
  const std::string popName = r.get<std::string>("Population");
  const Population pop = r.choice<Population>("Population");
  const bool anyFictitious =
      b.sumOverRanks(std::any_of(d.fictitious.begin(), d.fictitious.end(), [](std::uint8_t f) { return f != 0; }) ? 1 : 0) > 0;
  if (!anyFictitious && (type == "All Fictitious" || type == "Fictitious Side" || ((type == "Box" || type == "Nearest") && popName == "Fictitious")))
    fail(b.file, "region '" + name + "' selects fictitious particles, but the body has none (see 'Discretization/Fictitious Sides')");
  auto side = [&]() {
    const Side s = r.choice<Side>("Side");
    if (static_cast<int>(s) / 2 >= b.dim) fail(b.file, r.key("Side") + " is not a side of this " + std::to_string(b.dim) + "D body");
    return s;
  };
  std::vector<int> ids;
  if (type == "Box") {
    ids = selectBox(d, vec3(r.get<Array<double>>("Lower")), vec3(r.get<Array<double>>("Upper")), pop);
  } else if (type == "Side Layer") {
    const double given = r.ranged<double>("Thickness");
    const double t = given > 0 ? given : d.dx;
    ids = selectSideLayer(d, side(), t * (1 - 1e-9));
  } else if (type == "Fictitious Side") {
    ids = selectFictitiousSide(d, side());
  } else if (type == "Nearest") {
    const Vec3 point = vec3(r.get<Array<double>>("Point"));
    if (!b.distributed()) {
      const int p = selectNearest(d, point, pop);
      if (p >= 0) ids.push_back(p);
    } else {
      // The nearest over the ranks' shares, with the tie rule of the whole body: the nearest
      // distance over the ranks, each rank's first candidate in position order, and the first
      // of those over the ranks (coordinate by coordinate); then its global id.
      const double mine = nearestDistance(d, point, pop);
      double nearest = mine;
      Teuchos::reduceAll(*b.comm, Teuchos::REDUCE_MIN, mine, Teuchos::outArg(nearest));
      const int p = selectNearest(d, point, pop, nearest);
      constexpr double none = std::numeric_limits<double>::infinity();
      bool candidate = p >= 0;
      for (int c = 0; c < d.dim; ++c) {
        const double x = candidate ? d.X[p][c] : none;
        double least = x;
        Teuchos::reduceAll(*b.comm, Teuchos::REDUCE_MIN, x, Teuchos::outArg(least));
        candidate = candidate && x == least;
      }
      long long id = candidate ? b.gid(p) : std::numeric_limits<long long>::max(), first = id;
      Teuchos::reduceAll(*b.comm, Teuchos::REDUCE_MIN, id, Teuchos::outArg(first));
      if (first != std::numeric_limits<long long>::max() && b.problem.holds(first)) ids.push_back(b.problem.index(first));
    }
  } else if (type == "Node Set" || type == "Side Set" || type == "Block") {
    ids = meshSetRegion(b, r, name, type);
  } else if (type == "Ids") {
    ids = numberedRegion(b, r, name);
  } else {  // All Fictitious or All Real
    for (int i = 0; i < d.size(); ++i)
      if ((d.fictitious[i] != 0) == (type == "All Fictitious")) ids.push_back(i);
  }
  if (b.sumOverRanks(static_cast<long long>(ids.size())) == 0) fail(b.file, "region '" + name + "' selects no particle");
  return ids;
}

void readRegions(SceneBuild& b) {
  const Section rl = b.section("Regions");
  for (auto it = rl.list.begin(); it != rl.list.end(); ++it) {
    const std::string name = rl.list.name(it);
    b.sc.regions[name] = b.problem.globalIds(selectRegion(b, rl.entry(name, "Regions"), name));  // global ids
  }
}

/// Boundary Conditions: prescribed components. A component prescribed twice must get the same
/// value from both conditions (overlapping regions at a corner, say); the conditions must remove
/// every rigid-body mode.
void readBoundaryConditions(SceneBuild& b) {
  ProblemSpec& P = b.problem;
  const Discretization& d = P.disc;
  const int n = d.size(), dim = b.dim;
  P.fixedMask.assign(n, 0);
  P.prescribed.assign(static_cast<std::size_t>(n) * dim, 0.0);
  P.bodyForce.assign(static_cast<std::size_t>(n) * dim, 0.0);
  const Section bl = b.section("Boundary Conditions");
  // The condition that prescribed each DOF first.
  std::vector<std::string> conditionNames;
  std::vector<int> prescribedBy(static_cast<std::size_t>(n) * dim, -1);
  for (auto it = bl.list.begin(); it != bl.list.end(); ++it) {
    const std::string name = bl.list.name(it);
    const Section c = bl.entry(name, "Boundary Conditions");
    const auto& ids = b.region("Boundary Conditions/" + name + "/Region", c.get<std::string>("Region"));
    const int comp = c.choice<int>("Component");
    if (comp >= dim)
      fail(b.file, c.key("Component") + " must be one of x" + std::string(dim > 1 ? ", y" : "") + (dim > 2 ? ", z" : "") + " or all");
    const double value = c.get<double>("Value");
    const auto grad = c.get<Array<double>>("Gradient");
    conditionNames.push_back(name);
    for (int g : ids)
      for (int k = 0; k < dim; ++k) {
        if (comp >= 0 && k != comp) continue;
        const int p = P.index(g);
        double v = value;
        for (int a = 0; a < static_cast<int>(grad.size()); ++a) v += grad[a] * d.X[p][a];
        const std::size_t dof = static_cast<std::size_t>(p) * dim + k;
        if (prescribedBy[dof] >= 0) {
          const double old = P.prescribed[dof];
          if (std::abs(v - old) > 1e-12 * std::max({std::abs(v), std::abs(old), d.dx}))
            b.localFail("boundary conditions '" + conditionNames[prescribedBy[dof]] + "' and '" + name + "' prescribe different values (" +
                             number(old) + " and " + number(v) + ") for component " + "xyz"[k] + " of the particle at " + position(d, p) +
                             "; a component may be prescribed twice only with the same value");
          continue;
        }
        prescribedBy[dof] = static_cast<int>(conditionNames.size()) - 1;
        P.fixedMask[p] |= static_cast<std::uint8_t>(1u << k);
        P.prescribed[dof] = v;
      }
  }
}

/// Rank of the rigid modes restricted to prescribed DOFs (the evaluator checks it too, for
/// problems built in C++; here the message names the scene's keys). Its own step: distributed,
/// the Gram matrix is summed over the ranks after they agreed on the conditions.
void checkRigidMotion(SceneBuild& b) {
  if (!preventsRigidMotion(*b.comm, b.problem))
    fail(b.file, "the boundary conditions do not prevent rigid-body motion (a translation or rotation of the whole body is free); constrain more components under 'Boundary Conditions'");
}

void readLoads(SceneBuild& b) {
  const Discretization& d = b.problem.disc;
  const Section ll = b.section("Loads");
  for (auto it = ll.list.begin(); it != ll.list.end(); ++it) {
    const std::string name = ll.list.name(it);
    const Section l = ll.entry(name, "Loads");
    const auto& ids = b.region("Loads/" + name + "/Region", l.get<std::string>("Region"));
    const Vec3 value = vec3(l.get<Array<double>>("Value"));
    const std::string type = l.get<std::string>("Type");
    const std::string key = "'Loads/" + name + "/";
    const bool radial = type == "Radial Force";
    const double magnitude = l.get<double>("Magnitude");
    const auto centre = l.get<Array<double>>("Center");
    const auto axisGiven = l.get<Array<double>>("Axis");
    Vec3 axis = Vec3::Zero(), centreAt = Vec3::Zero();
    if (radial) {
      if (value.norm() != 0) fail(b.file, key + "Value' is not used by a Radial Force; give its total as 'Magnitude'");
      if (!std::isfinite(magnitude) || magnitude == 0) fail(b.file, key + "Magnitude' must be finite and non-zero for a Radial Force");
      if (centre.empty()) fail(b.file, key + "Center' is needed by a Radial Force");
      centreAt = vec3(centre);
      if (!axisGiven.empty()) {
        if (b.dim != 3) fail(b.file, key + "Axis' is for 3D scenes (in 2D the forces point away from Center in the plane)");
        axis = vec3(axisGiven);
        if (!(axis.norm() > 0)) fail(b.file, key + "Axis' must not be zero");
        axis.normalize();
      }
    } else if (magnitude != 0 || !centre.empty() || !axisGiven.empty()) {
      fail(b.file, key + "Magnitude', 'Center' and 'Axis' belong to a Radial Force, not a " + type);
    }
    double totalV = 0, mine = 0;  // the region's volume (owned particles, over the ranks, when distributed)
    for (int g : ids)
      if (b.owns(g)) mine += d.volume[b.problem.index(g)];
    totalV = mine;
    if (b.distributed()) Teuchos::reduceAll(*b.comm, Teuchos::REDUCE_SUM, mine, Teuchos::outArg(totalV));
    // Per unit volume: Total Force and Radial Force spread over the region; a Traction's layer is
    // one spacing thick.
    const double scale = type == "Total Force" || radial ? 1.0 / totalV : type == "Traction" ? 1.0 / d.dx : 1.0;
    for (int g : ids) {
      const int p = b.problem.index(g);
      if (d.fictitious[p]) {
        b.localFail("load '" + name + "' acts on fictitious particles; loads go on real particles");
        break;
      }
      Vec3 v = value;
      if (radial) {
        Vec3 r = d.X[p] - centreAt;
        if (b.dim == 2) r[2] = 0;
        if (axis.norm() > 0) r -= r.dot(axis) * axis;
        const double len = r.norm();
        if (!(len > 1e-12 * d.dx)) {
          b.localFail("load '" + name + "' is a Radial Force, but particle " + std::to_string(b.gid(p)) + " at " +
                      position(d, p) + " lies on its centre (or axis): it has no direction");
          break;
        }
        v = magnitude * r / len;
      }
      for (int c = 0; c < b.dim; ++c) b.problem.bodyForce[static_cast<std::size_t>(p) * b.dim + c] += v[c] * scale;
    }
  }
}

void readRotation(SceneBuild& b) {
  const Section rl = b.section("Superposed Rotation");
  const double deg = rl.get<double>("Angle");
  if (deg == 0.0) return;
  const int dim = b.dim;
  if (dim == 1) fail(b.file, "'Superposed Rotation' needs a 2D or 3D scene");
  const Vec3 axis = vec3(rl.get<Array<double>>("Axis"));
  if (dim == 2 && (axis[0] != 0 || axis[1] != 0 || !(axis[2] > 0))) fail(b.file, "'Superposed Rotation/Axis' must be z ({0, 0, 1}) in 2D");
  if (!(axis.norm() > 0)) fail(b.file, "'Superposed Rotation/Axis' must not be zero");
  auto& rot = b.problem.rotation;
  rot.angle = deg * M_PI / 180.0;
  rot.axis = axis.normalized();
  rot.center = vec3(rl.get<Array<double>>("Center"));
  if (dim == 2) rot.center[2] = 0;
  // A partly constrained particle (a roller) would need its constraint direction turned with the
  // body: not supported, so say which particle.
  const std::uint8_t all = static_cast<std::uint8_t>((1u << dim) - 1);
  for (int p = 0; p < b.problem.disc.size(); ++p)
    if (b.problem.fixedMask[p] != 0 && b.problem.fixedMask[p] != all) {
      b.localFail("'Superposed Rotation' needs every constrained particle to have all components prescribed; particle " +
                       std::to_string(b.gid(p)) + " at " + position(b.problem.disc, p) + " has only some (a roller's direction would have to turn with the body)");
      break;
    }
}

void readProbes(SceneBuild& b) {
  const Section pr = b.section("Probes");
  for (auto it = pr.list.begin(); it != pr.list.end(); ++it) {
    const std::string name = pr.list.name(it);
    const Section p = pr.entry(name, "Probes");
    b.sc.probes.push_back({name, p.get<std::string>("Quantity"), b.region("Probes/" + name + "/Region", p.get<std::string>("Region"))});
    if (b.sc.probes.back().quantity == "Plastic Strain" && !b.problem.plastic())
      fail(b.file, "probe '" + name + "' measures the plastic strain, but no material of the scene is plastic (Material/Plasticity = J2)");
  }
}

void readReference(SceneBuild& b) {
  const Section ref = b.section("Reference");
  const MaterialSpec& mat = b.problem.material;
  ReferenceDef& r = b.sc.reference;
  r.type = ref.get<std::string>("Type");
  r.center = vec3(ref.get<Array<double>>("Center"));
  if (r.type == "Hydrostatic Hencky") {
    if (b.dim != 2 || mat.planar != PlanarMode::PlaneStrain || mat.kind != MaterialKind::Hencky)
      fail(b.file, "'Reference/Type' Hydrostatic Hencky needs a 2D plane-strain Hencky material");
    r.stretch = hydrostaticStretch(lameLambda(mat), lameMu(mat), ref.get<double>("Traction"), b.file);
  } else if (r.type == "Uniform Stretch") {
    r.stretch = ref.ranged<double>("Stretch");
  } else if (r.type == "Affine") {
    const auto g = ref.get<Array<double>>("Gradient");
    if (static_cast<int>(g.size()) != b.dim * b.dim)
      fail(b.file, "'Reference/Gradient' needs " + std::to_string(b.dim * b.dim) + " entries (row-major)");
    for (int a = 0; a < b.dim; ++a)
      for (int c = 0; c < b.dim; ++c) r.H(a, c) = g[a * b.dim + c];
  } else if (r.type == "Seed001 Bar") {
    if (b.dim != 1) fail(b.file, "'Reference/Type' Seed001 Bar needs a 1D scene");
    const auto& ml = b.pl.sublist("Material");
    r.barAlpha = ml.get<double>("Field Alpha");
    r.barBeta = ml.get<double>("Field Beta");
    r.barLength = ml.get<double>("Field Length");
  }
  if (r.type == "Hydrostatic Hencky" || r.type == "Uniform Stretch") r.H = (r.stretch - 1.0) * Eigen::Matrix3d::Identity();
}

/// Solver/Arc Length: the controls, their order, the deflection probe; what continuation excludes.
void readArcLength(SceneBuild& b, const Section& so) {
  const Section al = so.sub("Arc Length");
  SolverSettings& s = b.sc.solver;
  auto& a = s.arc;
  const std::string& file = b.file;
  a.initial = al.get<double>("Initial Arc Length");
  a.minimum = al.get<double>("Min Arc Length");
  a.maximum = al.get<double>("Max Arc Length");
  a.maxSteps = al.ranged<int>("Max Steps");
  a.targetLoadFactor = al.get<double>("Target Load Factor");
  a.targetDeflection = al.get<double>("Target Deflection");
  a.deflectionProbe = al.get<std::string>("Deflection Probe");
  a.deflectionComponent = al.choice<int>("Deflection Component");
  if ((s.continuation == "Arc Length" || !a.deflectionProbe.empty()) && a.deflectionComponent >= b.dim)
    fail(file, "'Solver/Arc Length/Deflection Component' must be a component of this " + std::to_string(b.dim) + "D scene (x, y or z)");
  const std::string arcs = "; 'Solver/Arc Length' needs 0 < Min Arc Length <= Initial Arc Length <= Max Arc Length";
  if (!(a.minimum > 0)) fail(file, "'Solver/Arc Length/Min Arc Length' = " + number(a.minimum) + " is not positive" + arcs);
  if (!(a.minimum <= a.initial))
    fail(file, "'Solver/Arc Length/Min Arc Length' = " + number(a.minimum) + " exceeds 'Initial Arc Length' = " + number(a.initial) + arcs);
  if (!(a.initial <= a.maximum))
    fail(file, "'Solver/Arc Length/Initial Arc Length' = " + number(a.initial) + " exceeds 'Max Arc Length' = " + number(a.maximum) + arcs);
  al.ranged<double>("Target Load Factor");
  al.ranged<double>("Target Deflection");
  if (!a.deflectionProbe.empty()) {
    bool found = false;
    for (const auto& p : b.sc.probes) found |= p.name == a.deflectionProbe && p.quantity == "Displacement";
    if (!found) fail(file, "'Solver/Arc Length/Deflection Probe' = '" + a.deflectionProbe + "' is not a Displacement probe under Probes");
  }
  if (a.targetDeflection > 0 && a.deflectionProbe.empty()) fail(file, "'Solver/Arc Length/Target Deflection' needs a 'Deflection Probe'");
  if (s.continuation != "Arc Length") return;
  if (s.method != "Newton") fail(file, "'Solver/Continuation' = Arc Length needs 'Solver/Method' = Newton");
  if (b.problem.damage) fail(file, "'Solver/Continuation' = Arc Length does not support damage (bonds break between load steps); use Load Stepping");
  if (b.problem.rotates()) fail(file, "'Solver/Continuation' = Arc Length does not support a 'Superposed Rotation' (the load is not linear in the load factor); use Load Stepping");
}

/// Solver: the nonlinear method, load stepping and continuation.
void readSolver(SceneBuild& b) {
  const Section so = b.section("Solver");
  SolverSettings& s = b.sc.solver;
  s.method = so.get<std::string>("Method");
  s.adrTolerance = so.ranged<double>("ADR Tolerance");
  s.adrMassSafety = so.ranged<double>("ADR Mass Safety");
  s.adrMaxIterations = so.ranged<int>("ADR Max Iterations");
  s.loadSteps = so.ranged<int>("Load Steps");
  {
    const auto path = so.get<Array<double>>("Load Path");
    if (path.size() > 1000) fail(b.file, "'Solver/Load Path' has " + std::to_string(path.size()) + " entries; at most 1000");
    for (int k = 0; k < path.size(); ++k)
      if (path[k] == (k == 0 ? 0.0 : path[k - 1]))
        fail(b.file, "'Solver/Load Path' entry " + std::to_string(k + 1) + " (" + shownValue(path[k]) +
                         ") equals the load factor before it; every segment must change the load");
    s.loadPath.assign(path.begin(), path.end());
  }
  s.tolerance = so.ranged<double>("Tolerance");
  s.maxIterations = so.ranged<int>("Max Newton Iterations");
  s.lineSearch = so.get<std::string>("Line Search");
  s.adaptive = so.get<bool>("Adaptive Steps");
  s.easyIterations = so.ranged<int>("Easy Iterations");
  s.maxIncrement = so.ranged<double>("Max Increment");
  s.maxCutbacks = so.ranged<int>("Max Cutbacks");
  s.limitLoadRatio = so.ranged<double>("Limit Load Ratio");
  if (s.limitLoadRatio > 0 && s.limitLoadRatio <= 1)
    fail(b.file, "'Solver/Limit Load Ratio' must be 0 (no check) or more than 1, not " + number(s.limitLoadRatio));
  s.maxTotalSteps = so.get<int>("Max Total Steps");
  const long long segments = std::max<long long>(1, static_cast<long long>(s.loadPath.size()));
  if (s.loadSteps * segments > kMaxLoadSteps)
    fail(b.file, "'Solver/Load Steps' x the segments of 'Solver/Load Path' must be at most " + std::to_string(kMaxLoadSteps) +
                     ", not " + std::to_string(s.loadSteps * segments));
  if (s.maxTotalSteps == 0) s.maxTotalSteps = static_cast<int>(20 * s.loadSteps * segments);  // <= 20 x kMaxLoadSteps
  else if (s.maxTotalSteps < s.loadSteps || s.maxTotalSteps > kMaxTotalSteps)
    fail(b.file, "'Solver/Max Total Steps' must be 0 (20 x Load Steps) or from 'Solver/Load Steps' (" + std::to_string(s.loadSteps) +
                     ") to " + std::to_string(kMaxTotalSteps) + ", not " + std::to_string(s.maxTotalSteps));
  s.minIncrement = so.ranged<double>("Min Increment");
  s.verbosity = so.ranged<int>("Verbosity");
  s.predictor = so.get<bool>("Predictor");
  s.stabilityCheck = so.get<bool>("Stability Check");
  s.stagnationStop = so.ranged<int>("Stagnation Stop");
  s.forcingTerm = so.get<std::string>("Forcing Term");  // Preset: resolved by readLinearSolver
  s.linearTolerance = so.ranged<double>("Linear Tolerance");
  s.continuation = so.get<std::string>("Continuation");
  if (s.continuation == "Arc Length" && !s.loadPath.empty())
    fail(b.file, "'Solver/Load Path' needs 'Solver/Continuation' = Load Stepping (arc length chooses the load itself)");
  readArcLength(b, so);
  s.floorFactor = so.ranged<double>("Round-off Floor Factor");
}

/// The Stratimikos list: a preset of presetDir (names only, no paths) or the scene's own (custom).
Teuchos::RCP<ParameterList> linearSolverList(const SceneBuild& b, const Section& so, const std::string& name) {
  const std::string& file = b.file;
  const bool given = so.list.isSublist("Linear Solver") && so.list.sublist("Linear Solver").numParams() > 0;
  if (name == "custom") {
    if (!given) fail(file, "'Solver/Linear Solver Preset' is custom but 'Solver/Linear Solver' is empty");
    return Teuchos::rcp(new ParameterList(so.list.sublist("Linear Solver")));
  }
  if (given)
    fail(file, "'Solver/Linear Solver' is given but 'Solver/Linear Solver Preset' is '" + so.get<std::string>("Linear Solver Preset") +
                   "'; set the preset to custom");
  const auto presets = presetNames(b.presetDir);
  if (std::find(presets.begin(), presets.end(), name) == presets.end()) {
    auto names = presets;
    names.insert(names.begin(), "auto");
    names.push_back("custom");
    // The list of names while it is short; past that the sentence would pass 300 characters.
    const std::string listed = "it must be " + orList(names);
    fail(file, "'Solver/Linear Solver Preset' = " + quote(name) + " is not a preset name (" +
                   (presets.empty() ? "there are no presets in " + b.presetDir + ", so only custom is possible"
                    : listed.size() <= 120 ? listed : "the files of xml/solvers, or custom: perinox schema --json lists them") + ")");
  }
  const std::string presetFile = b.presetDir + "/" + name + ".xml";
  try {
    return Teuchos::getParametersFromXmlFile(presetFile);
  } catch (const std::exception& e) {
    fail(presetFile, "cannot read the solver preset: " + teuchosReason(e.what()));
  }
}

/// Solver/Linear Solver Preset and the Jacobian: a preset may name the Jacobian and the
/// preconditioner matrix it is meant for; the scene's own keys win unless they say Preset.
void readLinearSolver(SceneBuild& b) {
  const Section so = b.section("Solver");
  SolverSettings& s = b.sc.solver;
  const std::string& file = b.file;
  s.linearSolverName = so.get<std::string>("Linear Solver Preset");
  // auto: the rule of AutoLinearSolver.hpp picks a preset, and the Jacobian and forcing term
  // wherever the scene leaves them at Preset; a Jacobian the scene gives is a condition of the rule.
  s.automatic = s.linearSolverName == "auto";
  if (s.automatic) {
    const std::string givenJacobian = so.get<std::string>("Jacobian");
    const bool trustRegion = s.lineSearch.find("Trust Region") != std::string::npos;
    SolverFeatures f = solverFeatures(*b.comm, b.problem, b.pl.sublist("Discretization").get<std::string>("Type") == "Lattice",
                                      s.continuation == "Arc Length" || trustRegion,
                                      s.method == "ADR");
    f.jacobianGiven = givenJacobian == "Preset" ? "" : givenJacobian;
    const LinearSolverChoice c = chooseLinearSolver(f);
    s.linearSolverName = c.preset;
    s.autoReason = c.reason;
    s.autoJacobian = c.jacobian;
    s.autoForcingTerm = c.forcingTerm;
  }
  s.linearSolver = linearSolverList(b, so, s.linearSolverName);
  std::string presetJacobian = "Assembled", presetPrecMatrix = "Neighbours", presetForcing = "Constant";
  for (auto [key, target] : {std::make_pair("Jacobian", &presetJacobian), std::make_pair("Preconditioner Matrix", &presetPrecMatrix),
                             std::make_pair("Forcing Term", &presetForcing)}) {
    if (!s.linearSolver->isParameter(key)) continue;
    if (!s.linearSolver->isType<std::string>(key)) fail(file, std::string("the linear solver's '") + key + "' must be a string");
    *target = s.linearSolver->get<std::string>(key);
    s.linearSolver->remove(key);
  }
  if (s.automatic) presetJacobian = s.autoJacobian, presetForcing = s.autoForcingTerm;
  s.jacobian = so.get<std::string>("Jacobian");
  if (s.jacobian == "Preset") s.jacobian = presetJacobian;
  if (s.jacobian != "Assembled" && s.jacobian != "Matrix-Free" && s.jacobian != "Jacobian-Free")
    fail(file, "'Solver/Jacobian' must be Assembled, Matrix-Free, Jacobian-Free or Preset (got '" + s.jacobian + "')");
  s.preconditionerMatrix = so.get<std::string>("Preconditioner Matrix");
  if (s.preconditionerMatrix == "Preset") {
    // A preset's None (scalable: the matrix-free Jacobian itself) means nothing to a
    // Jacobian-free run, which has no analytic operator to hand over: its neighbour matrix then.
    s.preconditionerMatrix = presetPrecMatrix == "None" && s.jacobian == "Jacobian-Free" ? "Neighbours" : presetPrecMatrix;
  }
  if (s.preconditionerMatrix != "Assembled" && s.preconditionerMatrix != "Neighbours" && s.preconditionerMatrix != "None")
    fail(file, "'Solver/Preconditioner Matrix' must be Assembled, Neighbours, None or Preset (got '" + s.preconditionerMatrix + "')");
  if (s.preconditionerMatrix == "None" && s.jacobian != "Assembled") {
    if (s.jacobian != "Matrix-Free")
      fail(file, "'Solver/Preconditioner Matrix' = None hands the preconditioner the analytic matrix-free Jacobian: it needs "
                 "'Solver/Jacobian' = Matrix-Free (got '" + s.jacobian + "')");
    const std::string precType = s.linearSolver->get<std::string>("Preconditioner Type", "None");
    if (precType != "Two-Stage" && precType != "MUMPS")
      fail(file, "'Solver/Preconditioner Matrix' = None needs a preconditioner that works without a matrix: the preset '" +
                     s.linearSolverName + "' uses '" + precType +
                     "'; use the scalable preset (Two-Stage) or gmres-mumps (MUMPS, which assembles when it refactorises)");
  }
  if (s.forcingTerm == "Preset") s.forcingTerm = presetForcing;
  if (s.forcingTerm != "Constant" && s.forcingTerm != "Eisenstat-Walker")
    fail(file, "the linear solver preset's 'Forcing Term' must be Constant or Eisenstat-Walker (got '" + s.forcingTerm + "')");
  s.jfnkLambda = so.ranged<double>("Jacobian-Free Perturbation");
  if (s.jacobian != "Assembled" && s.lineSearch.find("Trust Region") != std::string::npos)
    fail(file, "'Solver/Line Search' = " + s.lineSearch + " needs the transpose of the Jacobian; set 'Solver/Jacobian' = Assembled");
  if (s.jacobian != "Assembled" && s.continuation == "Arc Length")
    fail(file, "'Solver/Continuation' = Arc Length solves its bordered systems with the assembled tangent; set 'Solver/Jacobian' = Assembled");
  if (s.jacobian != "Assembled" && s.linearSolver->get<std::string>("Linear Solver Type", "Belos") != "Belos")
    fail(file, "'Solver/Jacobian' = " + s.jacobian + " needs a Krylov solver (Linear Solver Type = Belos); the preset '" +
                   s.linearSolverName + "' is a direct solver, which needs the assembled matrix");
  // Damage makes the tangent unsymmetric: conjugate gradients would silently misbehave.
  if (b.problem.damage && s.linearSolver->get<std::string>("Linear Solver Type", "") == "Belos") {
    const auto& belos = s.linearSolver->sublist("Linear Solver Types").sublist("Belos");
    const std::string st = belos.isParameter("Solver Type") ? belos.get<std::string>("Solver Type") : "";
    if (st.find("CG") != std::string::npos)
      fail(file, "damage makes the tangent unsymmetric, but the linear solver is Belos '" + st +
                     "' (conjugate gradients need a symmetric matrix); use a GMRES preset such as gmres-ilu");
  }
}

void readOutput(SceneBuild& b) {
  const Section o = b.section("Output");
  OutputSettings& out = b.sc.output;
  out.vtk = o.get<bool>("VTK");
  out.format = o.get<std::string>("Format");
  if (out.format != "VTU" && !exodusAvailable())
    fail(b.file, "'Output/Format' = " + out.format + ", but this perinox was built without Exodus II (install libexodusii-dev, e.g. with scripts/setup.sh, and rebuild)");
  out.plots = o.get<bool>("Plots");
}

/// The sublist functions, in the order a scene is read (later ones use what earlier ones built:
/// the material and particles, then the regions the conditions, loads and probes name). A new
/// sublist is one more line here.
using SceneStep = void (*)(SceneBuild&);
const std::vector<SceneStep>& sceneSteps() {
  static const std::vector<SceneStep> steps{
      readMaterial, readDiscretization, readStabilization, readModulusField, readControls,
      readDamage,   readBlocks,         readRegions,        readBoundaryConditions, checkRigidMotion, readLoads, readRotation,
      readProbes,   readReference,      readSolver,        readLinearSolver, readOutput};
  return steps;
}

/// The checks on the whole list before any sublist is read: keys and types against the schema,
/// the dimension, the given enumerated values and vector lengths; then the defaults, all finite.
int checkScene(ParameterList& pl, const ParameterList& schema, const std::string& file) {
  checkAgainst(pl, schema, "", file);
  const auto& given = pl.sublist("Discretization");
  const int dim = given.isParameter("Dimension") ? given.get<int>("Dimension") : schema.sublist("Discretization").get<int>("Dimension");
  if (dim < 1 || dim > 3) fail(file, "'Discretization/Dimension' must be 1, 2 or 3");
  checkGivenValues(pl, dim, file);
  // A block's damage law or G only means something with the top-level switch on (checked on the
  // keys given, before the defaults fill them in).
  if (pl.isSublist("Blocks")) {
    const ParameterList& blocks = pl.sublist("Blocks");
    const bool damage = pl.isSublist("Damage") && pl.sublist("Damage").isParameter("Enabled") && pl.sublist("Damage").get<bool>("Enabled");
    for (auto c = blocks.begin(); c != blocks.end(); ++c) {
      const ParameterList& blk = blocks.sublist(blocks.name(c));
      if (!damage && blk.isSublist("Damage") && blk.sublist("Damage").numParams() > 0)
        fail(file, "'Blocks/" + blocks.name(c) + "/Damage' is given but 'Damage/Enabled' is false; enable damage or remove it");
    }
  }
  fillDefaults(pl, schema);
  checkFinite(pl, file);
  return dim;
}

/// Runs a scene step. Once the discretisation is distributed, the ranks agree on its outcome: a
/// failure on any rank (thrown, or recorded by localFail) becomes the same SceneError on every
/// rank, the lowest failing rank's sentence, so none is left waiting in a later collective.
void runStep(SceneStep step, SceneBuild& b) {
  if (!b.distributed()) {  // every rank sees the same (the distributed construction fails on all alike)
    step(b);
    return;
  }
  std::string msg;
  try {
    step(b);
  } catch (const SceneError& e) {
    msg = e.what();
  } catch (const std::exception& e) {
    msg = failMessage(b.file, e.what());
  }
  if (msg.empty() && !b.localError.empty()) msg = failMessage(b.file, b.localError);
  b.localError.clear();
  if (msg = lowestRankMessage(*b.comm, msg); !msg.empty()) throw SceneError(msg);
}

}  // namespace

std::string linearSolverPhrase(const SolverSettings& s) {
  const std::string what = s.linearSolverName + ", " + s.jacobian + " Jacobian, " + s.forcingTerm + " forcing";
  return s.automatic ? "auto: " + what + " (" + s.autoReason + ")" : what;
}

Teuchos::RCP<const ParameterList> sceneSchema() {
  static auto s = buildSchema();
  return s;
}

Scene buildScene(ParameterList pl, const std::string& file, const std::string& presetDir,
                 const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  const auto schema = sceneSchema();
  const int dim = checkScene(pl, *schema, file);
  Scene sc;
  sc.file = file;
  sc.title = pl.get<std::string>("Title");
  auto problem = std::make_shared<ProblemSpec>();
  SceneBuild build{sc, *problem, pl, *schema, file, presetDir, dim, ExodusMesh(),
                   comm.is_null() ? Teuchos::DefaultComm<int>::getComm() : comm, ""};
  for (const SceneStep step : sceneSteps()) runStep(step, build);
  sc.problem = problem;
  const SolverSettings& s = sc.solver;
  sc.resolved = Teuchos::rcp(new ParameterList(pl));
  // The file read, by its absolute path, and the preset's list written out as a custom one: the
  // resolved scene runs as it is, from any folder.
  if (!sc.inputFile.empty()) {
    ParameterList& d = sc.resolved->sublist("Discretization");
    std::error_code ec;
    const std::string at = std::filesystem::absolute(sc.inputFile, ec).lexically_normal().string();
    if (!ec) d.set(d.get<std::string>("Type") == "Exodus" ? "Mesh File" : "Particle File", at);
  }
  if (s.linearSolverName != "custom") {
    sc.resolved->sublist("Solver").sublist("Linear Solver").setParameters(*s.linearSolver);
    sc.resolved->sublist("Solver").set("Linear Solver Preset", std::string("custom"));
  }
  sc.resolved->sublist("Solver").set("Jacobian", s.jacobian);
  sc.resolved->sublist("Solver").set("Preconditioner Matrix", s.preconditionerMatrix);
  sc.resolved->sublist("Solver").set("Forcing Term", s.forcingTerm);
  return sc;
}

namespace {

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// A YAML file: a Peridigm deck (Teuchos' own YAML reader; the top-level "Peridigm" map is the
/// list). Before Teuchos parses it, the text must be a deck's size and shape: at most 1 MiB,
/// flow brackets nested at most 32 deep and lines indented at most 256 columns (Teuchos' reader
/// takes seconds on a few thousand nested maps), no backslash escapes in double-quoted texts
/// (Teuchos drops the backslash: "\t" would read as "t"), and its first line of content "Peridigm:".
ParameterList readYamlDeck(const std::string& path) {
  constexpr std::size_t kMaxYaml = std::size_t(1) << 20;
  const std::string text = readInputText(path);
  if (text.size() > kMaxYaml)
    fail(path, "a YAML deck of " + std::to_string(text.size()) + " bytes; Peridigm decks are a few kilobytes, and perinox reads at most 1 MiB");
  std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '<')
    fail(path, "holds XML: a Teuchos XML deck or scene is read from a file named .xml");
  int depth = 0, deepest = 0, line = 1;
  std::size_t indent = 0, widest = 0;
  bool atStart = true, comment = false;
  char quoted = 0;
  std::string firstContent;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line, atStart = true, comment = false, indent = 0;
      continue;
    }
    if (comment) continue;
    if (atStart && c == ' ') {
      widest = std::max(widest, ++indent);
      continue;
    }
    if (atStart && c != '\r' && c != '\t' && c != '#' && firstContent.empty())
      firstContent = text.substr(i, text.find('\n', i) - i);
    atStart = atStart && (c == '\r' || c == '\t');
    if (quoted) {
      if (c == '\\' && quoted == '"')
        fail(path, "has a backslash escape in a double-quoted text at line " + std::to_string(line) +
                   ", which Teuchos' YAML reader does not interpret (it would change the text)");
      if (c == quoted) quoted = 0;
    } else if (c == '#') {
      comment = true;
    } else if (c == '"' || c == '\'') {
      quoted = c;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
    if (deepest > 32) fail(path, "nests brackets more than 32 deep (line " + std::to_string(line) + "); a Peridigm deck nests a few levels");
  }
  if (widest > 256) fail(path, "indents a line by more than 256 columns; a Peridigm deck nests a few levels");
  if (firstContent.empty()) fail(path, "holds no YAML content (the file is empty or only comments)");
  if (firstContent.rfind("Peridigm:", 0) != 0)
    fail(path, "its top level is " + quote(firstContent, 40) + ", not the map 'Peridigm:' a Peridigm deck holds (perinox scenes are XML)");
  ParameterList pl;
  try {
    pl = *Teuchos::getParametersFromYamlString(text);
  } catch (const std::exception& e) {
    std::string why = teuchosReason(e.what());
    if (why.find_first_not_of(" Error!") == std::string::npos) why = "Teuchos' YAML reader cannot read it as a map of lists and values";
    fail(path, "malformed YAML: " + why);
  }
  if (pl.name() != "Peridigm" || !isPeridigmDeck(pl))
    fail(path, "a YAML file is read as a Peridigm deck (a top-level 'Peridigm' map with its Discretization, Materials and Blocks); "
               "perinox scenes are XML");
  return pl;
}

}  // namespace

ParameterList readSceneList(const std::string& path) {
  if (endsWith(path, ".yaml") || endsWith(path, ".yml")) return readYamlDeck(path);
  const std::string text = readSceneText(path);
  try {
    Teuchos::StringInputSource src(text);
    const Teuchos::XMLObject root = src.getObject();
    strictXml(root, "", path);
    return Teuchos::XMLParameterListReader().toParameterList(root);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    fail(path, "malformed scene XML: " + teuchosReason(e.what()));
  }
}

Scene loadScene(const std::string& path, const std::vector<std::string>& overrides, const std::string& presetDir,
                const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  ParameterList pl = readSceneList(path);
  bool kinematicOnly = false;
  if (isPeridigmDeck(pl)) {
    PeridigmScene made = sceneFromPeridigmDeck(pl, path);
    pl = made.scene;
    kinematicOnly = made.kinematicOnly;
  }
  const auto schema = sceneSchema();
  for (const auto& o : overrides) applyOverride(pl, o, *schema);
  try {
    Scene sc = buildScene(pl, path, presetDir, comm);
    if (kinematicOnly) {
      const ProblemSpec& P = *sc.problem;
      const long long free = P.particleCount() * P.dim() -
                             prescribedDofCount(comm.is_null() ? *Teuchos::DefaultComm<int>::getComm() : *comm, P);
      if (free > 0)
        fail(path, "'Solver/Verlet' is explicit dynamics, which perinox does not solve; a Verlet deck runs only when every "
                   "displacement is prescribed (the motion is then kinematic), and this one leaves " + std::to_string(free) +
                   " free (give a QuasiStatic solver list)");
    }
    return sc;
  } catch (const SceneError& e) {
    // A key that a --set gave: name that argument too (the latest one wins, as in applyOverride).
    const std::string msg = e.what();
    for (auto o = overrides.rbegin(); o != overrides.rend(); ++o)
      if (msg.find("'" + o->substr(0, o->find('=')) + "'") != std::string::npos)
        throw SceneError(msg + " (from --set " + quote(*o, 60) + ")");
    throw;
  } catch (const std::exception& e) {
    fail(path, teuchosReason(e.what()));
  }
}

const Teuchos::ParameterEntry* sceneSchemaEntry(const std::string& key) { return patternEntry(key); }

namespace {

/// obj with only what a scene file holds: <ParameterList> and <Parameter> elements, and their
/// name, type and value (Teuchos' writer adds ids, documentation and <Validators>).
Teuchos::XMLObject sceneElements(const Teuchos::XMLObject& obj) {
  Teuchos::XMLObject out(obj.getTag());
  for (const char* a : {"name", "type", "value"})
    if (obj.hasAttribute(a)) out.addAttribute(a, obj.getAttribute(a));
  for (int i = 0; i < obj.numChildren(); ++i) {
    const Teuchos::XMLObject& c = obj.getChild(i);
    if (c.getTag() == "ParameterList" || c.getTag() == "Parameter") out.addChild(sceneElements(c));
  }
  return out;
}

}  // namespace

std::string sceneXml(const ParameterList& scene) {
  ParameterList named(scene);
  named.setName("perinox");
  return sceneElements(Teuchos::XMLParameterListWriter().toXML(named)).toString();
}

}  // namespace perinox

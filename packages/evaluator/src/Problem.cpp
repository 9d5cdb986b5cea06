// ProblemSpec's own checks (Problem.hpp), free of Trilinos headers.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <map>
#include <set>
#include <stdexcept>

#include "perinox/core/InputFile.hpp"
#include "perinox/evaluator/Problem.hpp"

namespace perinox {

namespace {

[[noreturn]] void refuse(const std::string& what) { throw std::invalid_argument("ProblemSpec: " + what); }

/// Every entry of v finite, and v of the expected size (any size when expected < 0).
void finiteArray(const std::vector<double>& v, long long expected, const char* name, bool mayBeEmpty = false) {
  if (!(mayBeEmpty && v.empty()) && expected >= 0 && static_cast<long long>(v.size()) != expected)
    refuse(std::string(name) + " has " + std::to_string(v.size()) + " entries, not " + std::to_string(expected));
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i])) refuse(std::string(name) + "[" + std::to_string(i) + "] = " + messageNumber(v[i]) + " is not finite");
}

void positive(double v, const char* name) {
  if (!(v > 0) || !std::isfinite(v)) refuse(std::string(name) + " = " + messageNumber(v) + " must be a positive finite number");
}

void damageLaw(const DamageSpec& s, const std::string& name) {
  if (!(s.sMin > 0 && s.sMin < s.sCr) || !std::isfinite(s.sCr))
    refuse(name + " needs 0 < sMin < sCr (sMin = " + messageNumber(s.sMin) + ", sCr = " + messageNumber(s.sCr) + ")");
  if (!(s.beta > 0) || !std::isfinite(s.beta)) refuse(name + ".beta = " + messageNumber(s.beta) + " must be a positive finite number");
}

/// blocks: ids unique, every particle's block given, each block's constants valid.
void validateBlocks(const ProblemSpec& P) {
  std::set<int> ids;
  for (std::size_t k = 0; k < P.blocks.size(); ++k) {
    const BlockSpec& b = P.blocks[k];
    const std::string name = "blocks[" + std::to_string(k) + "] (block " + std::to_string(b.id) + ")";
    if (!ids.insert(b.id).second) refuse(name + " repeats block id " + std::to_string(b.id) + "; each block needs one entry");
    if (b.material.dim != P.disc.dim)
      refuse(name + ".material.dim = " + std::to_string(b.material.dim) + " differs from disc.dim = " + std::to_string(P.disc.dim));
    if (!(b.material.E > 0) || !std::isfinite(b.material.E))
      refuse(name + ".material.E = " + messageNumber(b.material.E) + " must be a positive finite number");
    if (!(b.material.nu > -1.0 && b.material.nu < 0.5))
      refuse(name + ".material.nu = " + messageNumber(b.material.nu) + " must satisfy -1 < nu < 0.5");
    if (P.disc.dim == 2 && b.material.planar == PlanarMode::None)
      refuse(name + ".material.planar must be PlaneStrain or PlaneStress in 2D");
    if (b.G && (!std::isfinite(*b.G) || *b.G < 0)) refuse(name + ".G = " + messageNumber(*b.G) + " must be finite and >= 0");
    if (b.G && *b.G > 0 && !P.stabilization)
      refuse(name + ".G = " + messageNumber(*b.G) + " is given but stabilization is off; set stabilization = true");
    if (b.C != StabilizationSpec::kFromMaterial && (!std::isfinite(b.C) || b.C < 0))
      refuse(name + ".C = " + messageNumber(b.C) + " must be finite and >= 0, or left at its default");
    if (b.damage) {
      if (!P.damage) refuse(name + ".damage is given but damage is off; set damage = true");
      damageLaw(*b.damage, name + ".damage");
    }
  }
  if (P.stabilization && P.stab.C != StabilizationSpec::kFromMaterial)
    refuse("stab.C is set, but with blocks each block's C applies (BlockSpec::C); leave stab.C at its default");
  std::vector<long long> count(P.blocks.size(), 0);
  for (int k : P.blockIndex()) ++count[k];  // throws for a particle whose block has no entry
  for (std::size_t k = 0; k < P.blocks.size() && !P.distributed; ++k)  // a share may miss a block
    if (count[k] == 0) refuse("blocks[" + std::to_string(k) + "] names block " + std::to_string(P.blocks[k].id) + ", which has no particle");
}

/// A distributed problem's share: one global id per particle, ascending, the owned ones among
/// them, a global count that holds them all.
void validateShare(const ProblemSpec& P) {
  const std::size_t n = P.disc.X.size();
  if (P.globalId.size() != n)
    refuse("globalId has " + std::to_string(P.globalId.size()) + " entries, not one per particle of the share (" + std::to_string(n) + ")");
  for (std::size_t i = 0; i < n; ++i)
    if (P.globalId[i] < 0 || P.globalId[i] >= P.globalCount || (i > 0 && P.globalId[i] <= P.globalId[i - 1]))
      refuse("globalId must be ascending ids in [0, globalCount = " + std::to_string(P.globalCount) + "); entry " +
             std::to_string(i) + " is " + std::to_string(P.globalId[i]));
  if (P.owned.empty()) refuse("owned is empty: every rank must own particles");
  for (std::size_t k = 0; k < P.owned.size(); ++k) {
    if (k > 0 && P.owned[k] <= P.owned[k - 1]) refuse("owned must be sorted global ids without repeats");
    if (!std::binary_search(P.globalId.begin(), P.globalId.end(), P.owned[k]))
      refuse("owned particle " + std::to_string(P.owned[k]) + " is not in the share (globalId)");
  }
}

}  // namespace

StabilizationSpec ProblemSpec::stabilizationSpec() const {
  StabilizationSpec s = stab;
  if (s.C == StabilizationSpec::kFromMaterial) s.C = micromodulusC(material, disc.horizon, disc.thickness);
  s.horizon = disc.horizon;
  return s;
}

StabilizationSpec ProblemSpec::stabilizationSpec(const BlockSpec& b) const {
  StabilizationSpec s;
  s.G = b.G ? *b.G : stab.G;
  s.C = b.C == StabilizationSpec::kFromMaterial ? micromodulusC(b.material, disc.horizon, disc.thickness) : b.C;
  s.form = stab.form;
  s.horizon = disc.horizon;
  return s;
}

std::vector<int> ProblemSpec::blockIndex() const {
  std::vector<int> index;
  if (blocks.empty()) return index;
  std::map<int, int> of;
  for (std::size_t k = 0; k < blocks.size(); ++k) of[blocks[k].id] = static_cast<int>(k);
  index.resize(disc.block.size());
  for (std::size_t p = 0; p < disc.block.size(); ++p) {
    const auto it = of.find(disc.block[p]);
    if (it == of.end())
      throw std::invalid_argument("ProblemSpec: particle " + std::to_string(p) + " is in block " + std::to_string(disc.block[p]) +
                                  ", which has no entry in blocks; give every block its material");
    index[p] = it->second;
  }
  return index;
}

std::vector<MaterialSpec> ProblemSpec::materials() const {
  if (blocks.empty()) return {material};
  std::vector<MaterialSpec> m;
  for (const auto& b : blocks) m.push_back(b.material);
  return m;
}

bool ProblemSpec::plastic() const {
  for (const MaterialSpec& m : materials())
    if (m.plastic.enabled) return true;
  return false;
}

double ProblemSpec::stiffestModulus() const {
  double E = blocks.empty() ? material.E : 0.0;
  for (const auto& b : blocks) E = std::max(E, b.material.E);
  return E;
}

std::shared_ptr<ProblemSpec> problemOnLattice(const LatticeSpec& lattice, const MaterialSpec& material) {
  auto P = std::make_shared<ProblemSpec>();
  P->disc = buildLattice(lattice);
  P->material = material;
  const std::size_t n = static_cast<std::size_t>(P->disc.size()), D = static_cast<std::size_t>(P->disc.dim);
  P->fixedMask.assign(n, 0);
  P->prescribed.assign(n * D, 0.0);
  P->bodyForce.assign(n * D, 0.0);
  return P;
}

void prescribe(ProblemSpec& P, const std::vector<int>& particles, int c, const std::function<double(const Vec3&)>& value) {
  if (c < 0 || c >= P.dim()) throw std::invalid_argument("ProblemSpec: prescribe: component " + std::to_string(c) + " is not one of this " + std::to_string(P.dim()) + "D problem's");
  for (int p : particles) {
    if (p < 0 || p >= P.disc.size()) throw std::invalid_argument("ProblemSpec: prescribe: particle " + std::to_string(p) + " does not exist");
    P.fixedMask[p] |= static_cast<std::uint8_t>(1u << c);
    P.prescribed[static_cast<std::size_t>(p) * P.dim() + c] = value(P.disc.X[p]);
  }
}

void prescribe(ProblemSpec& P, const std::vector<int>& particles, int c, double value) {
  prescribe(P, particles, c, [value](const Vec3&) { return value; });
}

Eigen::MatrixXd rigidModeGram(const ProblemSpec& P) {
  const Discretization& d = P.disc;
  const int dim = d.dim;
  const int nm = rigidModeCount(dim);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(nm, nm);
  const Vec3 c = 0.5 * (d.boxLower + d.boxUpper);
  auto add = [&](int p) {
    for (int a = 0; a < dim; ++a) {
      if (!((P.fixedMask[p] >> a) & 1u)) continue;
      Eigen::VectorXd row(nm);
      const Vec3 x = (d.X[p] - c) / std::max(d.dx, 1e-300);
      for (int m = 0; m < nm; ++m) row[m] = rigidModeValue(m, a, dim, x);
      M += row * row.transpose();
    }
  };
  if (P.distributed) {
    for (long long g : P.owned) add(P.index(g));
  } else {
    for (int p = 0; p < d.size(); ++p) add(p);
  }
  return M;
}

bool gramHasFullRank(const Eigen::MatrixXd& M) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M);
  return es.eigenvalues().minCoeff() > 1e-9 * std::max(1.0, es.eigenvalues().maxCoeff());
}

bool preventsRigidMotion(const ProblemSpec& P) { return gramHasFullRank(rigidModeGram(P)); }

std::vector<int> ProblemSpec::globalIds(const std::vector<int>& indices) const {
  if (!distributed) return indices;
  std::vector<int> out;
  out.reserve(indices.size());
  for (int i : indices) {
    if (i < 0 || i >= static_cast<int>(globalId.size()))
      throw std::out_of_range("ProblemSpec: particle index " + std::to_string(i) + " is not in this rank's share");
    if (globalId[i] > std::numeric_limits<int>::max())
      throw std::out_of_range("ProblemSpec: global id " + std::to_string(globalId[i]) + " does not fit an int");
    out.push_back(static_cast<int>(globalId[i]));
  }
  return out;
}

bool ProblemSpec::holds(long long g) const {
  return distributed ? std::binary_search(globalId.begin(), globalId.end(), g) : g >= 0 && g < disc.size();
}

bool ProblemSpec::owns(long long g) const {
  return !distributed || std::binary_search(owned.begin(), owned.end(), g);
}

int ProblemSpec::index(long long g) const {
  if (!distributed) return static_cast<int>(g);
  if (!holds(g)) throw std::out_of_range("ProblemSpec: particle " + std::to_string(g) + " is not in this rank's share");
  return static_cast<int>(std::lower_bound(globalId.begin(), globalId.end(), g) - globalId.begin());
}

void validateProblem(const ProblemSpec& P) {
  const Discretization& d = P.disc;
  const int D = d.dim;
  if (D < 1 || D > 3) refuse("disc.dim = " + std::to_string(D) + " must be 1, 2 or 3");
  if (P.material.dim != D) refuse("material.dim = " + std::to_string(P.material.dim) + " differs from disc.dim = " + std::to_string(D));
  const long long n = d.size();
  if (n == 0) refuse("the discretisation has no particles");
  positive(d.dx, "disc.dx");
  positive(d.thickness, "disc.thickness");
  if (!std::isfinite(d.horizon) || d.horizon < d.dx * (1 - 1e-12))
    refuse("disc.horizon = " + messageNumber(d.horizon) + " must be finite and at least the spacing disc.dx = " + messageNumber(d.dx));
  if (static_cast<long long>(d.volume.size()) != n || static_cast<long long>(d.fictitious.size()) != n)
    refuse("disc.volume and disc.fictitious need one entry per particle (" + std::to_string(n) + ")");
  // Families are optional (the evaluator then finds those of each rank's particles itself); given,
  // they must be whole.
  if (!d.familyOffset.empty() && static_cast<long long>(d.familyOffset.size()) != n + 1)
    refuse("disc.familyOffset has " + std::to_string(d.familyOffset.size()) + " entries, not one per particle plus one (" +
           std::to_string(n + 1) + "): call buildFamilies, or leave the families empty");
  for (long long i = 0; i < n; ++i) {
    if (!d.X[i].allFinite()) refuse("disc.X[" + std::to_string(i) + "] is not finite");
    if (!(d.volume[i] > 0) || !std::isfinite(d.volume[i]))
      refuse("disc.volume[" + std::to_string(i) + "] = " + messageNumber(d.volume[i]) + " must be a positive finite number");
  }
  positive(P.material.E, "material.E");
  if (!(P.material.nu > -1.0 && P.material.nu < 0.5))
    refuse("material.nu = " + messageNumber(P.material.nu) + " must satisfy -1 < nu < 0.5");
  if (P.fixedMask.size() != static_cast<std::size_t>(n)) refuse("fixedMask needs one entry per particle (" + std::to_string(n) + ")");
  for (long long i = 0; i < n; ++i)
    if (P.fixedMask[i] >> D) refuse("fixedMask[" + std::to_string(i) + "] names a component beyond the dimension");
  finiteArray(P.prescribed, n * D, "prescribed");
  finiteArray(P.bodyForce, n * D, "bodyForce");
  finiteArray(P.modulusScale, n, "modulusScale", true);
  for (double s : P.modulusScale)
    if (!(s > 0)) refuse("modulusScale holds " + messageNumber(s) + "; every E_i / E must be positive");
  if (P.stabilization) {
    if (!(P.stab.G >= 0) || !std::isfinite(P.stab.G)) refuse("stab.G = " + messageNumber(P.stab.G) + " must be finite and >= 0");
    if (P.stab.C != StabilizationSpec::kFromMaterial && (!std::isfinite(P.stab.C) || P.stab.C < 0))
      refuse("stab.C = " + messageNumber(P.stab.C) + " must be finite and >= 0, or left at its default (then micromodulusC of the material, horizon and thickness gives it)");
  }
  if (P.control && (!std::isfinite(P.controlSpec.C) || P.controlSpec.C < 0))
    refuse("controlSpec.C = " + messageNumber(P.controlSpec.C) + " must be finite and >= 0");
  if (P.damage) {
    const auto& s = P.damageSpec;
    if (!(s.sMin > 0 && s.sMin < s.sCr) || !std::isfinite(s.sCr))
      refuse("damageSpec needs 0 < sMin < sCr (sMin = " + messageNumber(s.sMin) + ", sCr = " + messageNumber(s.sCr) + ")");
    positive(s.beta, "damageSpec.beta");
  }
  if (!P.blocks.empty()) validateBlocks(P);
  if (P.stabilization) {  // the micromodulus derived from E, the horizon and the thickness must be a number
    auto finiteC = [&](const StabilizationSpec& st, const MaterialSpec& m, const std::string& whose) {
      if (!std::isfinite(st.C))
        refuse("the stabilisation's micromodulus C of " + whose + " is not finite (Young's modulus " + messageNumber(m.E) +
               " with the horizon " + messageNumber(P.disc.horizon) + "): the modulus is too large for these units");
    };
    if (P.blocks.empty()) finiteC(P.stabilizationSpec(), P.material, "the material");
    for (const BlockSpec& b : P.blocks) finiteC(P.stabilizationSpec(b), b.material, "block " + std::to_string(b.id));
  }
  if (!std::isfinite(P.rotation.angle) || !P.rotation.center.allFinite() || !P.rotation.axis.allFinite())
    refuse("rotation has a non-finite angle, centre or axis");
  if (P.rotates() && std::abs(P.rotation.axis.norm() - 1.0) > 1e-9) refuse("rotation.axis must be a unit vector");
  if (P.distributed) validateShare(P);
  else if (!preventsRigidMotion(P))
    refuse("the prescribed DOFs (fixedMask) do not prevent rigid-body motion: a translation or rotation of the whole "
           "body is free; prescribe more components");
}

}  // namespace perinox

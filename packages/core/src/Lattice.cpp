// Regular particle lattices: real particles at the cell centres of a box, optional holes,
// fictitious (Dirichlet) layers outside chosen sides, optional deterministic jitter.
#include "perinox/core/Discretization.hpp"

#include <climits>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <stdexcept>

namespace perinox {

namespace {

constexpr char kAxisName[3] = {'x', 'y', 'z'};

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

std::string num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

/// Checks the scalar parameters of the spec and returns the common spacing dx.
double validateAndSpacing(const LatticeSpec& spec) {
  if (spec.dim < 1 || spec.dim > 3)
    fail("lattice dimension must be 1, 2 or 3 (got " + std::to_string(spec.dim) + ")");
  const int dim = spec.dim;
  for (int a = 0; a < dim; ++a) {
    if (spec.counts[a] < 1)
      fail(std::string("lattice counts must be at least 1 per axis (counts along ") + kAxisName[a] +
           " = " + std::to_string(spec.counts[a]) + ")");
    if (!std::isfinite(spec.lower[a]) || !std::isfinite(spec.upper[a]) ||
        !(spec.upper[a] > spec.lower[a]))
      fail(std::string("lattice box is empty or not finite along ") + kAxisName[a] + ": lower = " +
           num(spec.lower[a]) + ", upper = " + num(spec.upper[a]) + " (upper must exceed lower)");
  }
  if (!(spec.thickness > 0.0) || !std::isfinite(spec.thickness))
    fail("lattice thickness (2D) / cross-section area (1D) must be positive and finite (got " +
         num(spec.thickness) + ")");
  if (!(spec.horizonFactor >= 1.0) || !std::isfinite(spec.horizonFactor))
    fail("horizonFactor = " + num(spec.horizonFactor) +
         " is below 1: a horizon smaller than the lattice spacing leaves particles without "
         "neighbours");
  if (!(spec.jitter >= 0.0 && spec.jitter <= 1.0))
    fail("lattice jitter must lie in [0, 1] (a fraction of the spacing; got " + num(spec.jitter) +
         ")");

  double d[3];
  for (int a = 0; a < dim; ++a) d[a] = (spec.upper[a] - spec.lower[a]) / spec.counts[a];
  for (int a = 1; a < dim; ++a) {
    if (std::abs(d[a] - d[0]) > 1e-9 * d[0]) {
      std::string msg = "lattice spacing differs between axes: ";
      for (int b = 0; b < dim; ++b)
        msg += (b ? ", d" : "d") + std::string(1, kAxisName[b]) + " = " + num(d[b]);
      msg += "; adjust counts or box";
      fail(msg);
    }
  }

  for (Side s : spec.fictitiousSides) {
    const int si = static_cast<int>(s);
    if (si < 0 || si >= 2 * dim)
      fail(std::string("fictitious side ") + sideName(s) + " does not exist in " +
           std::to_string(dim) + "D");
  }
  for (const Hole& h : spec.holes) {
    if (h.kind == Hole::Kind::Circle && !(h.radius >= 0.0 && std::isfinite(h.radius)))
      fail("hole radius must be non-negative and finite (got " + num(h.radius) + ")");
    if (h.kind == Hole::Kind::Rectangle &&
        !(h.halfWidths.minCoeff() >= 0.0 && h.halfWidths.allFinite()))
      fail("hole halfWidths must be non-negative and finite");
  }
  return d[0];
}

/// True when lattice site x (unjittered centre) lies strictly inside hole h.
bool insideHole(const Hole& h, const Vec3& x, int dim) {
  if (h.kind == Hole::Kind::Circle) {
    // Disc in 2D, interval in 1D, cylinder along z in 3D: only the first min(dim, 2) axes count.
    const int n = dim < 2 ? dim : 2;
    double r2 = 0.0;
    for (int a = 0; a < n; ++a) r2 += (x[a] - h.center[a]) * (x[a] - h.center[a]);
    return r2 < h.radius * h.radius;
  }
  for (int a = 0; a < dim; ++a)
    if (!(std::abs(x[a] - h.center[a]) < h.halfWidths[a])) return false;
  return true;
}

}  // namespace

Discretization buildLattice(const LatticeSpec& spec) {
  const double dx = validateAndSpacing(spec);
  const int dim = spec.dim;

  // Number of fictitious rows: enough to cover the horizon of the outermost real particle.
  // The 1e-9 guards horizon factors that are integers up to rounding (e.g. 3.0).
  const int nL = static_cast<int>(std::floor(spec.horizonFactor + 1e-9));
  unsigned sideBits = 0;
  for (Side s : spec.fictitiousSides) sideBits |= 1u << static_cast<int>(s);

  // Extended index range per axis: [begin, end) with real sites in [0, counts).
  int begin[3] = {0, 0, 0}, end[3] = {1, 1, 1};
  std::int64_t total = 1;
  for (int a = 0; a < dim; ++a) {
    begin[a] = (sideBits >> (2 * a)) & 1u ? -nL : 0;
    end[a] = spec.counts[a] + ((sideBits >> (2 * a + 1)) & 1u ? nL : 0);
    total *= end[a] - begin[a];
  }
  if (total > INT_MAX) fail("lattice has too many sites (" + std::to_string(total) + ")");

  Discretization d;
  d.dim = dim;
  d.dx = dx;
  d.horizon = spec.horizonFactor * dx;
  d.thickness = spec.thickness;
  d.boxLower = Vec3::Zero();
  d.boxUpper = Vec3::Zero();
  for (int a = 0; a < dim; ++a) {
    d.boxLower[a] = spec.lower[a];
    d.boxUpper[a] = spec.upper[a];
  }
  d.X.reserve(total);
  d.fictitious.reserve(total);
  d.sideMask.reserve(total);

  // Lexicographic order with x fastest: contiguous id blocks are compact in space.
  std::int64_t nReal = 0;
  int idx[3];
  for (idx[2] = begin[2]; idx[2] < end[2]; ++idx[2]) {
    for (idx[1] = begin[1]; idx[1] < end[1]; ++idx[1]) {
      for (idx[0] = begin[0]; idx[0] < end[0]; ++idx[0]) {
        Vec3 x = Vec3::Zero();
        std::uint8_t mask = 0;
        for (int a = 0; a < dim; ++a) {
          x[a] = spec.lower[a] + (idx[a] + 0.5) * dx;
          if (idx[a] < 0) mask |= 1u << (2 * a);
          if (idx[a] >= spec.counts[a]) mask |= 1u << (2 * a + 1);
        }
        const bool fict = mask != 0;
        if (!fict) {
          bool cut = false;
          for (const Hole& h : spec.holes) cut = cut || insideHole(h, x, dim);
          if (cut) continue;
          ++nReal;
        }
        d.X.push_back(x);
        d.fictitious.push_back(fict ? 1 : 0);
        d.sideMask.push_back(mask);
      }
    }
  }
  if (nReal == 0) fail("no real particle left in the lattice after cutting the holes");

  // Jitter of real particles, in id order. The uniform variate is mapped by hand from the raw
  // 32-bit mt19937 output (u = k / 2^32 in [0, 1)) because std::uniform_real_distribution is
  // not guaranteed to produce the same sequence across standard libraries.
  if (spec.jitter > 0.0) {
    std::mt19937 gen(spec.jitterSeed);
    const double amp = spec.jitter * dx;  // full width of the shift interval
    for (std::size_t i = 0; i < d.X.size(); ++i) {
      if (d.fictitious[i]) continue;
      for (int a = 0; a < dim; ++a) {
        const double u = static_cast<double>(gen()) * (1.0 / 4294967296.0);
        d.X[i][a] += (u - 0.5) * amp;
      }
    }
  }

  const double cellVolume = dim == 1 ? dx * spec.thickness
                            : dim == 2 ? dx * dx * spec.thickness
                                       : dx * dx * dx;
  d.volume.assign(d.X.size(), cellVolume);
  d.block.assign(d.X.size(), 1);

  buildFamilies(d);
  return d;
}

}  // namespace perinox

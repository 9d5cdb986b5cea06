// Regular particle lattices: real particles at the cell centres of a box, optional holes,
// fictitious (Dirichlet) layers outside chosen sides, optional deterministic jitter.
#include "perinox/core/Discretization.hpp"
#include "perinox/core/InputFile.hpp"

#include <algorithm>
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
           messageNumber(spec.lower[a]) + ", upper = " + messageNumber(spec.upper[a]) + " (upper must exceed lower)");
  }
  if (!(spec.thickness > 0.0) || !std::isfinite(spec.thickness))
    fail("lattice thickness (2D) / cross-section area (1D) must be positive and finite (got " +
         messageNumber(spec.thickness) + ")");
  if (!(spec.horizonFactor >= 1.0) || !std::isfinite(spec.horizonFactor))
    fail("horizonFactor = " + messageNumber(spec.horizonFactor) +
         " is below 1: a horizon smaller than the lattice spacing leaves particles without "
         "neighbours");
  if (!(spec.jitter >= 0.0 && spec.jitter <= 1.0))
    fail("lattice jitter must lie in [0, 1] (a fraction of the spacing; got " + messageNumber(spec.jitter) +
         ")");

  double d[3];
  for (int a = 0; a < dim; ++a) d[a] = (spec.upper[a] - spec.lower[a]) / spec.counts[a];
  for (int a = 1; a < dim; ++a) {
    if (std::abs(d[a] - d[0]) > 1e-9 * d[0]) {
      std::string msg = "lattice spacing differs between axes: ";
      for (int b = 0; b < dim; ++b)
        msg += (b ? ", d" : "d") + std::string(1, kAxisName[b]) + " = " + messageNumber(d[b]);
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
      fail("hole radius must be non-negative and finite (got " + messageNumber(h.radius) + ")");
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

/// The lattice's index ranges and layer bits: what every site-range pass shares.
struct SiteRange {
  int dim = 1;
  double dx = 0.0;
  int begin[3] = {0, 0, 0}, end[3] = {1, 1, 1};
  std::int64_t total = 1;  // sites, fictitious layers included, before holes
};

SiteRange siteRange(const LatticeSpec& spec) {
  SiteRange r;
  r.dx = validateAndSpacing(spec);
  r.dim = spec.dim;
  // Number of fictitious rows: enough to cover the horizon of the outermost real particle.
  // The 1e-9 guards horizon factors that are integers up to rounding (e.g. 3.0).
  const int nL = static_cast<int>(std::floor(spec.horizonFactor + 1e-9));
  unsigned sideBits = 0;
  for (Side s : spec.fictitiousSides) sideBits |= 1u << static_cast<int>(s);
  // Extended index range per axis: [begin, end) with real sites in [0, counts).
  for (int a = 0; a < r.dim; ++a) {
    r.begin[a] = (sideBits >> (2 * a)) & 1u ? -nL : 0;
    r.end[a] = spec.counts[a] + ((sideBits >> (2 * a + 1)) & 1u ? nL : 0);
    r.total *= r.end[a] - r.begin[a];
  }
  if (r.total > INT_MAX) fail("lattice has too many sites (" + std::to_string(r.total) + ")");
  return r;
}

/// Visits the kept sites with index in [first, last) in id order (lexicographic, x fastest:
/// contiguous id blocks are compact in space): f(x, sideMask), holes cut from real sites.
template <class F>
void forEachSite(const LatticeSpec& spec, const SiteRange& r, std::int64_t first, std::int64_t last, F&& f) {
  const std::int64_t nx = r.end[0] - r.begin[0], ny = r.end[1] - r.begin[1];
  for (std::int64_t k = first; k < last; ++k) {
    const int idx[3] = {static_cast<int>(k % nx) + r.begin[0], static_cast<int>((k / nx) % ny) + r.begin[1],
                        static_cast<int>(k / (nx * ny)) + r.begin[2]};
    Vec3 x = Vec3::Zero();
    std::uint8_t mask = 0;
    for (int a = 0; a < r.dim; ++a) {
      x[a] = spec.lower[a] + (idx[a] + 0.5) * r.dx;
      if (idx[a] < 0) mask |= 1u << (2 * a);
      if (idx[a] >= spec.counts[a]) mask |= 1u << (2 * a + 1);
    }
    if (mask == 0) {
      bool cut = false;
      for (const Hole& h : spec.holes) cut = cut || insideHole(h, x, r.dim);
      if (cut) continue;
    }
    f(x, mask);
  }
}

}  // namespace

std::int64_t latticeSiteCount(const LatticeSpec& spec) { return siteRange(spec).total; }

LatticeSiteCounts countLatticeSites(const LatticeSpec& spec, std::int64_t first, std::int64_t last) {
  const SiteRange r = siteRange(spec);
  LatticeSiteCounts c;
  forEachSite(spec, r, first, last, [&](const Vec3&, std::uint8_t mask) {
    ++c.particles;
    if (mask == 0) ++c.real;
  });
  return c;
}

Discretization latticeSites(const LatticeSpec& spec, std::int64_t first, std::int64_t last, std::int64_t realBefore) {
  const SiteRange r = siteRange(spec);
  const int dim = spec.dim;
  const double dx = r.dx;
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
  d.X.reserve(static_cast<std::size_t>(last - first));
  d.fictitious.reserve(static_cast<std::size_t>(last - first));
  d.sideMask.reserve(static_cast<std::size_t>(last - first));
  forEachSite(spec, r, first, last, [&](const Vec3& x, std::uint8_t mask) {
    d.X.push_back(x);
    d.fictitious.push_back(mask != 0 ? 1 : 0);
    d.sideMask.push_back(mask);
  });

  // Jitter of real particles, in id order: the real particles before this range drew dim
  // variates each from the same stream. The uniform variate is mapped by hand from the raw
  // 32-bit mt19937 output (u = k / 2^32 in [0, 1)) because std::uniform_real_distribution is
  // not guaranteed to produce the same sequence across standard libraries.
  if (spec.jitter > 0.0) {
    std::mt19937 gen(spec.jitterSeed);
    gen.discard(static_cast<unsigned long long>(realBefore) * dim);
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
  return d;
}

Discretization buildLattice(const LatticeSpec& spec, bool families) {
  const std::int64_t sites = latticeSiteCount(spec);
  Discretization d = latticeSites(spec, 0, sites, 0);
  if (std::count(d.fictitious.begin(), d.fictitious.end(), 0) == 0)
    fail("no real particle left in the lattice after cutting the holes");
  if (families) buildFamilies(d);
  return d;
}

}  // namespace perinox

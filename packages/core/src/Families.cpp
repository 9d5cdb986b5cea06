// Neighbour families by a cell list: a uniform grid whose cells are at least one horizon wide,
// so the neighbours of a particle lie in its own cell or the 3^dim - 1 adjacent ones.
// Cost O(n * m) for near-uniform clouds (m = particles per 3^dim cells), memory O(n + cells).
#include "perinox/core/Discretization.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>

namespace perinox {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Grid {
  double lo[3] = {0, 0, 0};
  double cell = 1.0;               // cell edge length (same on all used axes)
  int nc[3] = {1, 1, 1};           // cells per axis (1 on unused axes)
  int coord(double x, int a) const {
    const int c = static_cast<int>((x - lo[a]) / cell);
    return std::min(std::max(c, 0), nc[a] - 1);
  }
};

/// Grid covering the particles with cells >= horizon. If the cloud is sparse (bounding box much
/// larger than n horizons), cells are enlarged so that the grid has O(n) cells: still correct,
/// only with more candidates per cell.
Grid makeGrid(const Discretization& d) {
  Grid g;
  const int dim = d.dim;
  double hi[3] = {0, 0, 0};
  for (int a = 0; a < dim; ++a) {
    g.lo[a] = hi[a] = d.X[0][a];
    for (const Vec3& x : d.X) {
      g.lo[a] = std::min(g.lo[a], x[a]);
      hi[a] = std::max(hi[a], x[a]);
    }
    if (!std::isfinite(hi[a] - g.lo[a]))
      throw std::invalid_argument("the particle coordinates span too large a range for the neighbour search (a coordinate near the largest double)");
  }
  // Slightly above the search radius horizon * (1 + 1e-12), so that a neighbour can never be
  // two cells away because of rounding.
  g.cell = d.horizon * (1.0 + 1e-9);
  const double maxCells = std::max(64.0, 2.0 * static_cast<double>(d.X.size()));
  for (;;) {
    double total = 1.0;
    for (int a = 0; a < dim; ++a) total *= std::floor((hi[a] - g.lo[a]) / g.cell) + 1.0;
    if (total <= maxCells) break;
    g.cell *= 1.01 * std::pow(total / maxCells, 1.0 / dim);
  }
  for (int a = 0; a < dim; ++a)
    g.nc[a] = static_cast<int>(std::floor((hi[a] - g.lo[a]) / g.cell)) + 1;
  return g;
}

template <int DIM>
void search(Discretization& d, const Grid& g) {
  const int n = d.size();
  const std::int64_t ncells = static_cast<std::int64_t>(g.nc[0]) * g.nc[1] * g.nc[2];

  // Counting sort of particles by cell (stable: ids ascend inside a cell).
  std::vector<int> cellOf(n);
  std::vector<int> cellStart(ncells + 1, 0);
  for (int i = 0; i < n; ++i) {
    std::int64_t c = 0;
    for (int a = DIM - 1; a >= 0; --a) c = c * g.nc[a] + g.coord(d.X[i][a], a);
    cellOf[i] = static_cast<int>(c);
    ++cellStart[c + 1];
  }
  for (std::int64_t c = 0; c < ncells; ++c) cellStart[c + 1] += cellStart[c];
  std::vector<int> sortedId(n);
  // Coordinates copied in cell order, so the inner loop reads memory sequentially.
  std::vector<double> sortedX(static_cast<std::size_t>(n) * DIM);
  {
    std::vector<int> fill(cellStart.begin(), cellStart.end() - 1);
    for (int i = 0; i < n; ++i) {
      const int k = fill[cellOf[i]]++;
      sortedId[k] = i;
      for (int a = 0; a < DIM; ++a) sortedX[static_cast<std::size_t>(k) * DIM + a] = d.X[i][a];
    }
  }

  // Reserve for the expected family size: ball measure over the mean volume per particle.
  double boxMeasure = 1.0, ball = 1.0;
  for (int a = 0; a < DIM; ++a) boxMeasure *= g.nc[a] * g.cell;
  const double r = d.horizon;
  ball = DIM == 1 ? 2 * r : DIM == 2 ? kPi * r * r : 4.0 / 3.0 * kPi * r * r * r;
  const double expected = std::min(static_cast<double>(n), 1.5 * ball * n / boxMeasure + 1.0);
  d.familyIndex.clear();
  d.familyIndex.reserve(static_cast<std::size_t>(expected * n));
  d.familyOffset.assign(static_cast<std::size_t>(n) + 1, 0);

  const double r2 = [&] { const double rr = d.horizon * (1.0 + 1e-12); return rr * rr; }();
  for (int i = 0; i < n; ++i) {
    double xi[3] = {0, 0, 0};
    int ci[3] = {0, 0, 0};
    for (int a = 0; a < DIM; ++a) {
      xi[a] = d.X[i][a];
      ci[a] = g.coord(xi[a], a);
    }
    int cLo[3] = {0, 0, 0}, cHi[3] = {0, 0, 0};
    for (int a = 0; a < DIM; ++a) {
      cLo[a] = std::max(ci[a] - 1, 0);
      cHi[a] = std::min(ci[a] + 1, g.nc[a] - 1);
    }
    const std::size_t first = d.familyIndex.size();
    for (int cz = cLo[2]; cz <= cHi[2]; ++cz)
      for (int cy = cLo[1]; cy <= cHi[1]; ++cy) {
        // Cells along x at fixed (y, z) are contiguous in the sorted order: scan them at once.
        const std::int64_t row = (static_cast<std::int64_t>(cz) * g.nc[1] + cy) * g.nc[0];
        const int kBegin = cellStart[row + cLo[0]];
        const int kEnd = cellStart[row + cHi[0] + 1];
        for (int k = kBegin; k < kEnd; ++k) {
          const double* xj = &sortedX[static_cast<std::size_t>(k) * DIM];
          double dist2 = 0.0;
          for (int a = 0; a < DIM; ++a) dist2 += (xj[a] - xi[a]) * (xj[a] - xi[a]);
          if (dist2 <= r2 && sortedId[k] != i) d.familyIndex.push_back(sortedId[k]);
        }
      }
    std::sort(d.familyIndex.begin() + first, d.familyIndex.end());
    d.familyOffset[i + 1] = static_cast<std::int64_t>(d.familyIndex.size());
  }
  d.familyIndex.shrink_to_fit();
}

}  // namespace

void buildFamilies(Discretization& d) {
  if (d.dim < 1 || d.dim > 3)
    throw std::invalid_argument("the neighbour search: dimension must be 1, 2 or 3 (got " +
                                std::to_string(d.dim) + ")");
  if (!(d.horizon > 0.0) || !std::isfinite(d.horizon))
    throw std::invalid_argument("the horizon must be positive and finite (got " +
                                std::to_string(d.horizon) + ")");
  if (d.X.size() > static_cast<std::size_t>(INT_MAX))
    throw std::invalid_argument("too many particles (more than 2^31 - 1)");
  for (const Vec3& x : d.X)
    if (!x.allFinite())
      throw std::invalid_argument("a particle position is not finite");
  if (d.X.empty()) {
    d.familyOffset.assign(1, 0);
    d.familyIndex.clear();
    return;
  }
  const Grid g = makeGrid(d);
  switch (d.dim) {
    case 1: search<1>(d, g); break;
    case 2: search<2>(d, g); break;
    default: search<3>(d, g); break;
  }
}

}  // namespace perinox

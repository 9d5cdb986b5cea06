// Kernel benchmark: cost per particle of the residual, the matrix-free Jacobian-vector product
// (J v) and the dense element tangent as the particle count grows; the achieved memory bandwidth
// of the residual and J v passes against a streaming kernel measured in the same run; the memory
// an assembled Jacobian would need against the matrix-free solve's; and the cost of effects left
// off. Prints medians of repeated runs; asserts nothing (timings on shared machines are noisy, so
// they belong in reports, not tests).
//
//   build/drivers/bench_kernels [max_particles_2d] [max_particles_3d]   (default 1000000 216000)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <vector>

#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"

using namespace perinox;

namespace {

using Clock = std::chrono::steady_clock;

struct NullSink final : ElementSink {
  double checksum = 0;
  void add(const int*, int n, const double* r, const double* K) override {
    checksum += r[0] + (K ? K[0] : 0.0) + n;
  }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class F>
double medianSeconds(int reps, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto a = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - a).count());
  }
  return median(t);
}

/// Streaming bandwidth (bytes/s) of the triad a = b + s c over arrays far larger than the cache,
/// counting 24 bytes per element as STREAM does.
double streamBandwidth() {
  const std::size_t n = 20'000'000;
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  const double s = 0.5;
  const double t = medianSeconds(7, [&] {
    for (std::size_t k = 0; k < n; ++k) a[k] = b[k] + s * c[k];
  });
  if (a[n / 2] == 12345.0) std::puts("");
  return 24.0 * n / t;
}

Discretization lattice(int dim, int perAxis, double factor) {
  LatticeSpec s;
  s.dim = dim;
  s.counts = {perAxis, dim > 1 ? perAxis : 1, dim > 2 ? perAxis : 1};
  s.upper = Vec3(perAxis * 1e-3, dim > 1 ? perAxis * 1e-3 : 1.0, dim > 2 ? perAxis * 1e-3 : 1.0);
  s.horizonFactor = factor;
  return buildLattice(s);
}

/// Particles within two horizons of an interior particle (the row length, in particles, of the
/// assembled Jacobian: every element {i} u H_i containing the particle couples it to all of them).
long long interiorCoupled(const Discretization& d) {
  long long best = 0;
  // The particle nearest the centre of the box.
  Eigen::Vector3d c = 0.5 * (d.boxLower + d.boxUpper);
  int p = 0;
  for (int k = 0; k < d.size(); ++k)
    if ((d.X[k] - c).squaredNorm() < (d.X[p] - c).squaredNorm()) p = k;
  std::set<int> s{p};
  for (auto q = d.familyOffset[p]; q < d.familyOffset[p + 1]; ++q) {
    const int i = d.familyIndex[q];
    s.insert(i);
    for (auto r = d.familyOffset[i]; r < d.familyOffset[i + 1]; ++r) s.insert(d.familyIndex[r]);
  }
  best = static_cast<long long>(s.size());
  return best;
}

struct Row {
  double residual = NAN, jv = NAN, tangent = NAN;  // seconds per particle
};

Row timeModel(const Model& model, const std::vector<double>& u, bool tangent, int reps) {
  Row r;
  NullSink sink;
  const double n = model.particles().numOwned;
  r.residual = medianSeconds(reps, [&] { model.evaluate(u, sink, false); }) / n;
  std::vector<double> v(u.size()), jv(u.size());
  for (std::size_t k = 0; k < v.size(); ++k) v[k] = std::cos(0.11 * k);
  r.jv = medianSeconds(reps, [&] {
           std::fill(jv.begin(), jv.end(), 0.0);
           model.applyTangent(u, v, jv.data());
         }) / n;
  if (tangent) r.tangent = medianSeconds(std::max(1, reps / 2), [&] { model.evaluate(u, sink, true); }) / n;
  if (sink.checksum == 12345.678 || jv[0] == 12345.678) std::puts("");  // keep the work observable
  return r;
}

std::vector<double> smallField(std::size_t n) {
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = 1e-6 * std::sin(0.37 * k);
  return u;
}

}  // namespace

int main(int argc, char** argv) {
  const long long max2 = argc > 1 ? std::atoll(argv[1]) : 1000000;
  const long long max3 = argc > 2 ? std::atoll(argv[2]) : 216000;
  std::printf("# perinox kernel benchmark: one core, medians of 3-5 runs\n");
  const double bw = streamBandwidth();
  std::printf("# streaming triad bandwidth in this run: %.2f GB/s\n\n", bw / 1e9);
  std::printf("# bytes = the bond data a pass must read: per bond the neighbour index (4), position (24),\n"
              "# volume (8) and displacement (8 dim; J v adds the direction and the scattered result, 24 dim);\n"
              "# bound = bytes / streaming bandwidth; ratio = measured time / bound.\n");
  std::printf("%-3s %-6s %9s %7s | %9s %6s | %9s %6s | %10s | %9s %9s %6s\n", "dim", "delta", "particles", "bonds/p",
              "resid us/p", "ratio", "J v us/p", "ratio", "tangent us/p", "J MiB", "MF MiB", "J/MF");
  MaterialSpec m;
  m.E = 1e9;
  m.nu = 0.3;
  for (int dim : {2, 3}) {
    m.dim = dim;
    m.planar = dim == 2 ? PlanarMode::PlaneStrain : PlanarMode::None;
    for (double factor : {1.015, 3.015}) {
      const std::vector<int> sizes = dim == 2 ? std::vector<int>{100, 316, 500, 1000} : std::vector<int>{20, 40, 60};
      for (int perAxis : sizes) {
        long long n = 1;
        for (int a = 0; a < dim; ++a) n *= perAxis;
        const long long cap = dim == 2 ? (factor < 2 ? max2 : max2 / 4) : max3;
        if (n > cap) continue;
        const Discretization d = lattice(dim, perAxis, factor);
        Model model(m, localParticles(d, 0, d.size()));
        model.enableCorrespondence();
        const auto u = smallField(static_cast<std::size_t>(d.size()) * dim);
        const double bonds = static_cast<double>(d.familyIndex.size()) / d.size();
        const bool tangent = n * bonds * bonds <= 5e8;  // the dense element tangent grows like m^2
        const Row r = timeModel(model, u, tangent, n > 200000 ? 3 : 5);
        const double bytesR = bonds * (4 + 24 + 8 + 8 * dim) + (8 + 24 + 8 + 8 * dim);
        const double bytesJ = bonds * (4 + 24 + 8 + 8 * dim + 24 * dim) + (8 + 24 + 8 + 8 * dim * 3);
        // Memory on one rank: the assembled Jacobian as the evaluator stores it
        // (one owned CRS copy, summed in place; ghost rows, absent on one rank, come on top on
        // several: 8-byte value + 4-byte column index per entry), from the interior row length
        // (an upper bound: boundary rows are shorter); the matrix-free solve keeps the model
        // (positions, volumes, families), the neighbour preconditioner matrix (one copy too) and
        // 40 Krylov vectors.
        const double rowJ = static_cast<double>(interiorCoupled(d)) * dim;
        const double bytesAssembled = n * dim * (rowJ * 12.0 + 8.0);
        const double bytesModel = n * (24 + 8 + 8 + (bonds * 4)) + n * dim * 8.0 * 4;
        const double bytesMF = bytesModel + n * dim * ((bonds + 1) * dim * 12.0 + 8.0) + 40.0 * n * dim * 8.0;
        std::printf("%-3d %-6.3f %9lld %7.1f | %9.3f %6.1f | %9.3f %6.1f | %10.3f | %9.1f %9.1f %6.1f\n", dim, factor, n,
                    bonds, 1e6 * r.residual, r.residual / (bytesR / bw), 1e6 * r.jv, r.jv / (bytesJ / bw),
                    1e6 * r.tangent, (bytesAssembled + bytesModel) / 1048576.0, bytesMF / 1048576.0,
                    (bytesAssembled + bytesModel) / bytesMF);
        std::fflush(stdout);
      }
    }
  }

  // Effects left off cost nothing: they are never constructed, and the model's data do not
  // depend on them. The plain model is timed twice (the difference is the noise level), then
  // with each effect on, to show what turning it on costs.
  m.dim = 2;
  m.planar = PlanarMode::PlaneStrain;
  std::printf("\n# effects (2D, 90000 particles): us/particle, median of 7; ratios to the first plain run\n");
  std::printf("%-34s %10s %7s %10s %7s\n", "model", "residual", "ratio", "J v", "ratio");
  for (double factor : {2.015, 1.015}) {
    const Discretization d = lattice(2, 300, factor);
    const auto u = smallField(static_cast<std::size_t>(d.size()) * 2);
    auto make = [&](int which) {
      auto model = std::make_unique<Model>(m, localParticles(d, 0, d.size()));
      if (which == 3) model->enableStressPoints();
      else model->enableCorrespondence();
      if (which == 1) model->enableStabilization({0.1, micromodulusC(m, d.horizon, d.thickness)});
      if (which == 2) model->enableDamage(DamageSpec{});
      return model;
    };
    const char* names[] = {"plain", "+ stabilisation", "+ damage softening", "stress points"};
    Row base;
    for (int run = 0; run < 2; ++run) {
      auto model = make(0);
      const Row r = timeModel(*model, u, false, 7);
      if (run == 0) base = r;
      std::printf("plain, delta %.3f dx (run %d)%*s %10.3f %7.3f %10.3f %7.3f\n", factor, run + 1, 3, "", 1e6 * r.residual,
                  r.residual / base.residual, 1e6 * r.jv, r.jv / base.jv);
    }
    for (int which : factor > 2 ? std::vector<int>{1, 2} : std::vector<int>{3}) {
      auto model = make(which);
      const Row r = timeModel(*model, u, false, 7);
      std::printf("%-34s %10.3f %7.3f %10.3f %7.3f\n", names[which], 1e6 * r.residual, r.residual / base.residual,
                  1e6 * r.jv, r.jv / base.jv);
    }
  }
  return 0;
}

// Kernel benchmark: residual and tangent evaluation cost per particle as the particle count
// grows, and the cost of effects left off. Prints medians of repeated runs; asserts nothing
// (timings on shared machines are noisy, so they belong in reports, not tests).
//
//   build/drivers/bench_kernels [max_particles_2d]     (default 250000)
#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "perinox/model/Model.hpp"
#include "perinox/model/Partition.hpp"

using namespace perinox;

namespace {

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

Discretization lattice(int dim, int perAxis, double factor) {
  LatticeSpec s;
  s.dim = dim;
  s.counts = {perAxis, dim > 1 ? perAxis : 1, dim > 2 ? perAxis : 1};
  s.upper = Vec3(perAxis * 1e-3, dim > 1 ? perAxis * 1e-3 : 1.0, dim > 2 ? perAxis * 1e-3 : 1.0);
  s.horizonFactor = factor;
  return buildLattice(s);
}

/// Seconds per particle (median of `reps`) for one evaluation.
double timePerParticle(const Model& model, const std::vector<double>& u, bool tangent, int reps) {
  std::vector<double> t;
  NullSink sink;
  for (int r = 0; r < reps; ++r) {
    const auto a = std::chrono::steady_clock::now();
    model.evaluate(u, sink, tangent);
    t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
  }
  if (sink.checksum == 12345.678) std::puts("");  // keep the work observable
  return median(t) / model.particles().numOwned;
}

}  // namespace

int main(int argc, char** argv) {
  const long long maxParticles = argc > 1 ? std::atoll(argv[1]) : 250000;
  MaterialSpec m;
  m.dim = 2;
  m.E = 1e9;
  m.nu = 0.3;
  std::printf("# perinox kernel benchmark (one core; medians of 3-5 runs)\n");
  std::printf("%-4s %-8s %10s %10s %14s %14s\n", "dim", "horizon", "particles", "bonds/p", "residual us/p", "tangent us/p");
  for (int dim : {2, 3}) {
    m.dim = dim;
    m.planar = dim == 2 ? PlanarMode::PlaneStrain : PlanarMode::None;
    for (double factor : {1.015, 3.015}) {
      for (int perAxis : dim == 2 ? std::vector<int>{50, 100, 200, 500, 1000} : std::vector<int>{10, 20, 40, 60}) {
        long long n = 1;
        for (int a = 0; a < dim; ++a) n *= perAxis;
        if (n > maxParticles || (factor > 2 && n > maxParticles / (dim == 2 ? 4 : 8))) continue;
        const Discretization d = lattice(dim, perAxis, factor);
        Model model(m, localParticles(d, 0, d.size()));
        model.enableCorrespondence();
        std::vector<double> u(static_cast<size_t>(d.size()) * dim);
        for (size_t k = 0; k < u.size(); ++k) u[k] = 1e-6 * std::sin(0.37 * k);
        const double bonds = static_cast<double>(d.familyIndex.size()) / d.size();
        const double tr = timePerParticle(model, u, false, 5);
        const double tt = n <= 40000 || factor < 2 ? timePerParticle(model, u, true, 3) : NAN;
        std::printf("%-4d %-8.3f %10lld %10.1f %14.3f %14.3f\n", dim, factor, n, bonds, 1e6 * tr, 1e6 * tt);
        std::fflush(stdout);
      }
    }
  }
  // Effects left off cost nothing: they are never constructed. Compare the plain model with the
  // same model after enabling and then not using anything (identical code path), and with the
  // effects on, to show what turning them on costs.
  m.dim = 2;
  m.planar = PlanarMode::PlaneStrain;
  const Discretization d = lattice(2, 300, 2.015);
  std::vector<double> u(static_cast<size_t>(d.size()) * 2);
  for (size_t k = 0; k < u.size(); ++k) u[k] = 1e-6 * std::sin(0.37 * k);
  Model plain(m, localParticles(d, 0, d.size()));
  plain.enableCorrespondence();
  Model stab(m, localParticles(d, 0, d.size()));
  stab.enableCorrespondence();
  stab.enableStabilization({0.1, micromodulusC(m, d.horizon, d.thickness)});
  Model dmg(m, localParticles(d, 0, d.size()));
  dmg.enableCorrespondence();
  dmg.enableDamage(DamageSpec{});
  std::printf("\n# effects (2D, 90000 particles, delta = 2.015 dx): residual us/particle, median of 7\n");
  const double a = timePerParticle(plain, u, false, 7), b = timePerParticle(stab, u, false, 7),
               c = timePerParticle(dmg, u, false, 7), a2 = timePerParticle(plain, u, false, 7);
  std::printf("plain (run 1)        %8.3f\nplain (run 2)        %8.3f   (ratio to run 1: %.3f, the noise level)\n", 1e6 * a, 1e6 * a2, a2 / a);
  std::printf("+ stabilisation      %8.3f   (ratio %.3f)\n+ damage softening   %8.3f   (ratio %.3f)\n", 1e6 * b, b / a, 1e6 * c, c / a);
  return 0;
}

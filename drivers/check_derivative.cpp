// A derivative check of a scene's evaluator, as the driver builds it (its particles, regions,
// boundary conditions and effects): central differences of the residual along random
// directions against the assembled Jacobian and the matrix-free product, at load factor
// --load and at a random state of --amplitude spacings. A diagnostic: it prints the relative
// differences and exits 1 when one is above --tolerance.
//
//   check_derivative SCENE.xml [--set Sublist/Key=value]... [--load 0.25] [--amplitude 0.005]
//                    [--step 1e-6] [--tolerance 1e-6] [--directions 3]
#include <Teuchos_DefaultComm.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Tpetra_Core.hpp>

#include <cstdio>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "perinox/evaluator/PeridynamicEvaluator.hpp"
#include "perinox/io/Scene.hpp"

using namespace perinox;

namespace {
const char* kUsage =
    "usage: check_derivative SCENE.xml [--set Sublist/Key=value]... [--load L] [--amplitude A] [--step H] "
    "[--tolerance T] [--directions N]\n";

// Random owned free DOF values of amplitude amp, seeded by the global DOF (the same on any rank count).
void randomFill(const PeridynamicEvaluator& ev, Thyra::VectorBase<double>& z, unsigned seed, double amp) {
  auto values = ev.ownedDofValues(z);
  for (auto& [dof, v] : values) {
    std::mt19937 g(seed * 1000003u + static_cast<unsigned>(dof));
    v = amp * std::uniform_real_distribution<double>(-1, 1)(g);
  }
  ev.setOwnedDofValues(z, values);
}

void residual(const PeridynamicEvaluator& ev, const Teuchos::RCP<const Thyra::VectorBase<double>>& x,
              const Teuchos::RCP<Thyra::VectorBase<double>>& f) {
  auto in = ev.createInArgs();
  in.set_x(x);
  auto out = ev.createOutArgs();
  out.set_f(f);
  ev.evalModel(in, out);
}

// The evaluator's Jacobian operator at x (assembled, or the matrix-free product's linearisation).
Teuchos::RCP<Thyra::LinearOpBase<double>> jacobian(const PeridynamicEvaluator& ev,
                                                   const Teuchos::RCP<const Thyra::VectorBase<double>>& x) {
  auto W = ev.create_W_op();
  auto in = ev.createInArgs();
  in.set_x(x);
  auto out = ev.createOutArgs();
  out.set_W_op(W);
  ev.evalModel(in, out);
  return W;
}
}  // namespace

int main(int argc, char** argv) {
  Tpetra::ScopeGuard tpetra(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  std::string scenePath;
  std::vector<std::string> overrides;
  double load = 0.25, amplitude = 0.005, step = 1e-6, tolerance = 1e-6;
  int directions = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    try {
      if (a == "--set") overrides.push_back(next());
      else if (a == "--load") load = std::stod(next());
      else if (a == "--amplitude") amplitude = std::stod(next());
      else if (a == "--step") step = std::stod(next());
      else if (a == "--tolerance") tolerance = std::stod(next());
      else if (a == "--directions") directions = std::stoi(next());
      else if (!a.empty() && a[0] != '-' && scenePath.empty()) scenePath = a;
      else throw std::invalid_argument("unknown argument '" + a + "'");
    } catch (const std::exception& e) {
      std::cerr << "check_derivative: " << e.what() << "\n" << kUsage;
      return 2;
    }
  }
  if (scenePath.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    const Scene scene = loadScene(scenePath, overrides, std::string(PERINOX_SOURCE_DIR) + "/xml/solvers");
    const double dx = scene.problem->disc.dx;
    bool failed = false;
    for (int form = 0; form < 2; ++form) {
      auto ev = Teuchos::rcp(new PeridynamicEvaluator(comm, scene.problem));
      if (form == 1) ev->setJacobian(JacobianMode::MatrixFree, PreconditionerMatrix::Neighbours, Teuchos::null);
      ev->setLoadFactor(load);
      auto x = Thyra::createMember(ev->get_x_space());
      randomFill(*ev, *x, 1, amplitude * dx);
      const auto W = jacobian(*ev, x);
      for (int k = 0; k < directions; ++k) {
        auto v = Thyra::createMember(ev->get_x_space());
        randomFill(*ev, *v, 2 + k, dx);
        auto Wv = Thyra::createMember(ev->get_f_space());
        Thyra::apply(*W, Thyra::NOTRANS, *v, Wv.ptr());
        auto xp = x->clone_v(), xm = x->clone_v();
        Thyra::Vp_StV(xp.ptr(), step, *v);
        Thyra::Vp_StV(xm.ptr(), -step, *v);
        auto fp = Thyra::createMember(ev->get_f_space()), fm = Thyra::createMember(ev->get_f_space());
        residual(*ev, xp, fp);
        residual(*ev, xm, fm);
        auto d = Thyra::createMember(ev->get_f_space());
        Thyra::V_StVpStV(d.ptr(), 0.5 / step, *fp, -0.5 / step, *fm);
        Thyra::Vp_StV(d.ptr(), -1.0, *Wv);
        const double rel = Thyra::norm_2(*d) / Thyra::norm_2(*Wv);
        const double relInf = Thyra::norm_inf(*d) / Thyra::norm_inf(*Wv);
        if (comm->getRank() == 0)
          std::printf("%-12s direction %d: |FD - W v| / |W v| = %.3e (2-norm), %.3e (max norm)\n",
                      form == 0 ? "assembled" : "matrix-free", k, rel, relInf);
        failed = failed || !(rel <= tolerance);
      }
    }
    return failed ? 1 : 0;
  } catch (const std::exception& e) {
    if (comm->getRank() == 0) std::cerr << "check_derivative: " << e.what() << "\n";
    return 2;
  }
}

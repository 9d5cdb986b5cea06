// Reduced case: LOCA arc-length continuation in the load factor p(0) through Piro::LOCASolver
// (Trilinos 13.2), (a) on a 2-DOF snap-through with a closed-form path (lambda = x0 exp(-x0) / b,
// a limit point at x0 = 1), (b) on perinox's evaluator (the tension block, lambda 0 -> 1).
#include <LOCA_Thyra_SaveDataStrategy.H>
#include <NOX_Thyra_Vector.H>
#include <Piro_LOCASolver.hpp>
#include <Teuchos_DefaultComm.hpp>
#include <Teuchos_XMLParameterListHelpers.hpp>
#include <Thyra_DefaultSerialDenseLinearOpWithSolveFactory.hpp>
#include <Thyra_DefaultSpmdVectorSpace.hpp>
#include <Thyra_DetachedMultiVectorView.hpp>
#include <Thyra_DetachedVectorView.hpp>
#include <Thyra_StateFuncModelEvaluatorBase.hpp>
#include <Thyra_VectorStdOps.hpp>
#include <Tpetra_Core.hpp>
#include <cmath>
#include <iostream>

#include <perinox/io/HostOutput.hpp>
#include <perinox/solver/LinearSolver.hpp>

using MEB = Thyra::ModelEvaluatorBase;

class SnapThrough : public Thyra::StateFuncModelEvaluatorBase<double> {
 public:
  explicit SnapThrough(double b) : b(b) {
    space_ = Thyra::defaultSpmdVectorSpace<double>(2);
    pSpace_ = Thyra::defaultSpmdVectorSpace<double>(1);
    nominal_ = createInArgs();
    auto x0 = Thyra::createMember(space_);
    Thyra::assign(x0.ptr(), 0.0);
    nominal_.set_x(x0);
    auto p = Thyra::createMember(pSpace_);
    Thyra::assign(p.ptr(), 0.0);
    nominal_.set_p(0, p);
  }
  double b;
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_x_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_f_space() const override { return space_; }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> get_p_space(int) const override { return pSpace_; }
  Teuchos::RCP<const Teuchos::Array<std::string>> get_p_names(int) const override {
    return Teuchos::rcp(new Teuchos::Array<std::string>(1, "Load Factor"));
  }
  MEB::InArgs<double> getNominalValues() const override { return nominal_; }
  MEB::InArgs<double> createInArgs() const override {
    MEB::InArgsSetup<double> in;
    in.setModelEvalDescription("snap-through");
    in.set_Np(1);
    in.setSupports(MEB::IN_ARG_x);
    return in;
  }
  Teuchos::RCP<Thyra::LinearOpBase<double>> create_W_op() const override { return Thyra::createMembers(space_, 2); }
  Teuchos::RCP<const Thyra::LinearOpWithSolveFactoryBase<double>> get_W_factory() const override {
    return Thyra::defaultSerialDenseLinearOpWithSolveFactory<double>();
  }

 private:
  MEB::OutArgs<double> createOutArgsImpl() const override {
    MEB::OutArgsSetup<double> out;
    out.setModelEvalDescription("snap-through");
    out.set_Np_Ng(1, 0);
    out.setSupports(MEB::OUT_ARG_f);
    out.setSupports(MEB::OUT_ARG_W_op);
    out.setSupports(MEB::OUT_ARG_DfDp, 0, MEB::DerivativeSupport(MEB::DERIV_MV_BY_COL));
    return out;
  }
  void evalModelImpl(const MEB::InArgs<double>& in, const MEB::OutArgs<double>& out) const override {
    Thyra::ConstDetachedVectorView<double> x(*in.get_x());
    const double lambda = in.get_p(0).is_null() ? 0.0 : Thyra::get_ele(*in.get_p(0), 0);
    const double e = std::exp(-x[0]);
    if (auto f = out.get_f(); !f.is_null()) {
      Thyra::DetachedVectorView<double> fv(*f);
      fv[0] = x[0] * e - lambda * b;
      fv[1] = 2 * x[1] - x[0];
    }
    if (auto W = out.get_W_op(); !W.is_null()) {
      auto mv = Teuchos::rcp_dynamic_cast<Thyra::MultiVectorBase<double>>(W, true);
      Thyra::DetachedMultiVectorView<double> Wv(*mv);
      Wv(0, 0) = (1 - x[0]) * e, Wv(0, 1) = 0.0, Wv(1, 0) = -1.0, Wv(1, 1) = 2.0;
    }
    auto dfdp = out.get_DfDp(0).getMultiVector();
    if (!dfdp.is_null()) {
      const auto column = dfdp->col(0);
      Thyra::DetachedVectorView<double> d(*column);
      d[0] = -b, d[1] = 0.0;
    }
  }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> space_, pSpace_;
  MEB::InArgs<double> nominal_;
};

/// Records every converged point LOCA saves: (lambda, x as a Thyra vector clone).
class PathSaver : public LOCA::Thyra::SaveDataStrategy {
 public:
  void saveSolution(const NOX::Abstract::Vector& x, double p) override {
    lambdas.push_back(p);
    states.push_back(dynamic_cast<const NOX::Thyra::Vector&>(x).getThyraVector().clone_v());
  }
  std::vector<double> lambdas;
  std::vector<Teuchos::RCP<Thyra::VectorBase<double>>> states;
};

Teuchos::RCP<Teuchos::ParameterList> locaParams(double maxValue, int maxSteps, double step, double maxStep, double normF) {
  auto p = Teuchos::getParametersFromXmlString(R"(<ParameterList name="Piro">
    <ParameterList name="LOCA">
      <ParameterList name="Predictor"><Parameter name="Method" type="string" value="Tangent"/></ParameterList>
      <ParameterList name="Stepper">
        <Parameter name="Continuation Method" type="string" value="Arc Length"/>
        <Parameter name="Continuation Parameter" type="string" value="Load Factor"/>
        <Parameter name="Initial Value" type="double" value="0.0"/>
        <Parameter name="Min Value" type="double" value="-10.0"/>
        <Parameter name="Max Nonlinear Iterations" type="int" value="15"/>
        <Parameter name="Compute Eigenvalues" type="bool" value="false"/>
      </ParameterList>
      <ParameterList name="Step Size"><Parameter name="Method" type="string" value="Adaptive"/>
        <Parameter name="Min Step Size" type="double" value="1e-6"/>
        <Parameter name="Aggressiveness" type="double" value="0.5"/></ParameterList>
    </ParameterList>
    <ParameterList name="NOX"><Parameter name="Nonlinear Solver" type="string" value="Line Search Based"/>
      <ParameterList name="Printing"><Parameter name="Output Information" type="int" value="0"/></ParameterList>
      <ParameterList name="Status Tests"><Parameter name="Test Type" type="string" value="Combo"/>
        <Parameter name="Combo Type" type="string" value="OR"/><Parameter name="Number of Tests" type="int" value="2"/>
        <ParameterList name="Test 0"><Parameter name="Test Type" type="string" value="NormF"/></ParameterList>
        <ParameterList name="Test 1"><Parameter name="Test Type" type="string" value="MaxIters"/>
          <Parameter name="Maximum Iterations" type="int" value="15"/></ParameterList>
      </ParameterList></ParameterList></ParameterList>)");
  auto& st = p->sublist("LOCA").sublist("Stepper");
  st.set("Max Value", maxValue);
  st.set("Max Steps", maxSteps);
  p->sublist("LOCA").sublist("Step Size").set("Initial Step Size", step);
  p->sublist("LOCA").sublist("Step Size").set("Max Step Size", maxStep);
  p->sublist("NOX").sublist("Status Tests").sublist("Test 0").set("Tolerance", normF);
  return p;
}

int main(int argc, char** argv) {
  Tpetra::ScopeGuard mpi(&argc, &argv);
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const bool speak = comm->getRank() == 0;
  if (speak) {  // (a) the snap-through
    auto model = Teuchos::rcp(new SnapThrough(0.5));
    auto saver = Teuchos::rcp(new PathSaver);
    Piro::LOCASolver<double> solver(locaParams(10.0, 40, 0.05, 0.3, 1e-12), model, saver);
    auto in = solver.getNominalValues();
    auto out = solver.createOutArgs();
    auto x = Thyra::createMember(solver.get_g_space(solver.Ng() - 1));
    out.set_g(solver.Ng() - 1, x);
    try {
      solver.evalModel(in, out);
    } catch (const std::exception& e) {
      std::cout << "(a) threw: " << e.what() << "\n";
    }
    double worst = 0, peak = 0;
    int turned = 0;
    for (std::size_t k = 0; k < saver->lambdas.size(); ++k) {
      const double x0 = Thyra::get_ele(*saver->states[k], 0), l = saver->lambdas[k];
      worst = std::max(worst, std::abs(l - x0 * std::exp(-x0) / 0.5));
      peak = std::max(peak, l);
      if (k > 0 && l < saver->lambdas[k - 1]) ++turned;
      std::cout << "  (a) point " << k << " lambda " << l << " x0 " << x0 << "\n";
    }
    std::cout << "(a) snap-through: " << saver->lambdas.size() << " points, max |lambda - path(x0)| " << worst << ", peak "
              << peak << " (closed form " << 2 / std::exp(1.0) << "), decreasing steps " << turned << "\n";
  }
  {  // (b) perinox's evaluator: the tension block, lambda from 0 to 1
    using namespace perinox;
    LatticeSpec lattice;
    lattice.upper = Vec3(1.0, 0.5, 0.0);
    lattice.counts = {20, 10, 1};
    lattice.horizonFactor = 1.015;
    lattice.fictitiousSides = {Side::XMin, Side::XMax};
    auto problem = problemOnLattice(lattice, {MaterialKind::Hencky, 2, PlanarMode::PlaneStrain, 1.0e9, 0.3});
    const Discretization& d = problem->disc;
    const auto right = selectFictitiousSide(d, Side::XMax), end = selectSideLayer(d, Side::XMax, d.dx * (1 - 1e-9));
    prescribe(*problem, selectFictitiousSide(d, Side::XMin), 0);
    prescribe(*problem, selectBox(d, Vec3(-1.0, 0.0, 0.0), Vec3(0.0, 0.03, 0.0), Population::Fictitious), 1);
    prescribe(*problem, right, 0, [](const Vec3& X) { return 0.1 * X[0]; });
    auto evaluator = Teuchos::rcp(new PeridynamicEvaluator(comm, problem));
    auto linear = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));
    linear->set("Linear Solver Type", "MUMPS");
    linear->set("Preconditioner Type", "None");
    evaluator->set_W_factory(buildLinearSolverFactory(linear, comm->getSize()));
    auto saver = Teuchos::rcp(new PathSaver);
    Piro::LOCASolver<double> solver(locaParams(1.0, 60, 0.05, 0.25, 2 * evaluator->roundoffScale() + 1e-3), evaluator, saver);
    auto in = solver.getNominalValues();
    auto out = solver.createOutArgs();
    auto x = Thyra::createMember(solver.get_g_space(solver.Ng() - 1));
    out.set_g(solver.Ng() - 1, x);
    try {
      solver.evalModel(in, out);
      const auto mean = evaluator->meanDisplacement(*x, end);
      if (speak)
        std::cout << std::setprecision(12) << "(b) tension block: " << saver->lambdas.size() << " points, last lambda "
                  << (saver->lambdas.empty() ? -1 : saver->lambdas.back()) << ", mean u_x of the pulled end " << mean[0]
                  << " (driver at lambda 1: 0.0999205681585)\n";
    } catch (const std::exception& e) {
      if (speak) std::cout << "(b) threw: " << e.what() << "\n";
    }
  }
  return 0;
}

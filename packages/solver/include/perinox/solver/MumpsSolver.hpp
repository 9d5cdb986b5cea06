#pragma once
// MUMPS (a multifrontal sparse direct solver, MPI-parallel) as a Thyra linear-solve strategy,
// registered with Stratimikos as "Linear Solver Type" = "MUMPS". This Trilinos build's Amesos2
// offers only KLU2 (wrong answers on more than one rank) and Tacho (crashes beyond small sizes);
// MUMPS comes from Debian's libmumps and factorises the distributed Tpetra matrix on every rank.
//
// Each rank hands MUMPS its own rows (distributed assembled input, 1-based global indices); the
// ordering and symbolic analysis are kept while the sparsity pattern stays the same (every Newton
// iteration of a load step, and every step until bonds break), so a new Jacobian costs a numeric
// factorisation only. Right-hand sides are gathered to rank 0 and the solution scattered back.
// A numerically singular matrix throws std::runtime_error with "factorization failed" in the
// message, which the Newton wrapper reports as a singular tangent and the load stepping cuts back.
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>
#include <Thyra_LinearOpWithSolveFactoryBase.hpp>

namespace perinox {

class MumpsLinearOpWithSolveFactory : public Thyra::LinearOpWithSolveFactoryBase<double> {
 public:
  MumpsLinearOpWithSolveFactory();

  bool isCompatible(const Thyra::LinearOpSourceBase<double>& fwdOpSrc) const override;
  Teuchos::RCP<Thyra::LinearOpWithSolveBase<double>> createOp() const override;
  void initializeOp(const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& fwdOpSrc,
                    Thyra::LinearOpWithSolveBase<double>* op,
                    const Thyra::ESupportSolveUse supportSolveUse) const override;
  void uninitializeOp(Thyra::LinearOpWithSolveBase<double>* op,
                      Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* fwdOpSrc,
                      Teuchos::RCP<const Thyra::PreconditionerBase<double>>* prec,
                      Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* approxFwdOpSrc,
                      Thyra::ESupportSolveUse* supportSolveUse) const override;

  void setParameterList(const Teuchos::RCP<Teuchos::ParameterList>& params) override;
  Teuchos::RCP<Teuchos::ParameterList> getNonconstParameterList() override;
  Teuchos::RCP<Teuchos::ParameterList> unsetParameterList() override;
  Teuchos::RCP<const Teuchos::ParameterList> getParameterList() const override;
  Teuchos::RCP<const Teuchos::ParameterList> getValidParameters() const override;
  std::string description() const override;

 private:
  Teuchos::RCP<Teuchos::ParameterList> params_;
  int ordering_ = 7;        // MUMPS ICNTL(7): 7 = chosen by MUMPS
  int memoryRelaxation_ = 30;  // ICNTL(14), percent of the estimated working space
};

}  // namespace perinox

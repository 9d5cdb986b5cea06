// MUMPS as a Thyra linear-solve strategy (see MumpsSolver.hpp).
#include "perinox/solver/MumpsSolver.hpp"

#include "perinox/evaluator/OperatorAssembly.hpp"

#include <Teuchos_DefaultMpiComm.hpp>
#include <Teuchos_StandardParameterEntryValidators.hpp>
#include <Thyra_DefaultPreconditioner.hpp>
#include <Thyra_LinearOpWithSolveBase.hpp>
#include <Thyra_TpetraLinearOp.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_MultiVector.hpp>
#include <dmumps_c.h>
#include <smumps_c.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace perinox {

namespace {
using Node = Tpetra::Map<int, long long>::node_type;
using Map = Tpetra::Map<int, long long, Node>;
using Matrix = Tpetra::CrsMatrix<double, int, long long, Node>;
using MV = Tpetra::MultiVector<double, int, long long, Node>;
using Importer = Tpetra::Import<int, long long, Node>;
using Extract = Thyra::TpetraOperatorVectorExtraction<double, int, long long, Node>;

// MUMPS's codes that a user can act on, in words (the MUMPS users' guide, section "Error
// diagnostics"); anything else is reported with its numbers.
std::string mumpsMessage(int infog1, int infog2) {
  std::ostringstream s;
  switch (infog1) {
    case -10: s << "the matrix is numerically singular"; break;
    case -6: s << "the matrix is structurally singular (rank " << infog2 << ")"; break;
    case -5:
    case -7:
    case -13: s << "MUMPS could not allocate " << infog2 << " entries of memory"; break;
    case -8:
    case -9:
    case -14:
    case -15: s << "MUMPS's working space was too small even after enlarging it (INFOG(1) = " << infog1 << ")"; break;
    default: s << "MUMPS error INFOG(1) = " << infog1 << ", INFOG(2) = " << infog2;
  }
  return s.str();
}

MPI_Comm rawComm(const Teuchos::RCP<const Teuchos::Comm<int>>& comm) {
  auto mpi = Teuchos::rcp_dynamic_cast<const Teuchos::MpiComm<int>>(comm);
  return mpi.is_null() ? MPI_COMM_SELF : (*mpi->getRawMpiComm())();
}

// One MUMPS instance: the analysis of one sparsity pattern and the factors of the last matrix.
class MumpsContext {
 public:
  virtual ~MumpsContext() = default;
  virtual void factor(const Matrix& A) = 0;
  virtual bool factored() const = 0;
  virtual const Teuchos::RCP<const Map>& rowMap() const = 0;
  /// X = A^-1 B (A^-T B when transposed), in the factors' precision.
  virtual void solve(bool transpose, const MV& B, MV& X) = 0;
  /// The last factorisation's entries on all ranks (MUMPS's INFOG(29)) and the bytes of each.
  virtual long long factorEntries() const = 0;
  virtual int bytesPerEntry() const = 0;
};

// MUMPS's double- and single-precision real interfaces (libdmumps, libsmumps): the same
// structure with other scalar types. Single precision halves the factors' bytes, and a solve with
// them reads half as much memory (a preconditioner's solves are memory-bound).
struct DoublePrecision {
  using Struct = DMUMPS_STRUC_C;
  using Real = double;
  static void call(Struct& id) { dmumps_c(&id); }
};
struct SinglePrecision {
  using Struct = SMUMPS_STRUC_C;
  using Real = float;
  static void call(Struct& id) { smumps_c(&id); }
};

template <class P>
class MumpsContextT final : public MumpsContext {
 public:
  MumpsContextT(const Teuchos::RCP<const Teuchos::Comm<int>>& comm, int ordering, int memoryRelaxation)
      : comm_(rawComm(comm)) {
    MPI_Comm_rank(comm_, &rank_);
    id_.par = 1;  // rank 0 works too
    id_.sym = 0;  // general (the tangent is not symmetric)
    id_.comm_fortran = static_cast<MUMPS_INT>(MPI_Comm_c2f(comm_));
    id_.job = -1;
    P::call(id_);
    if (id_.infog[0] < 0) throw std::runtime_error("MUMPS: initialisation failed: " + mumpsMessage(id_.infog[0], id_.infog[1]));
    id_.icntl[0] = -1;  // no MUMPS printing: failures are reported by perinox
    id_.icntl[1] = -1;
    id_.icntl[2] = -1;
    id_.icntl[3] = 0;
    id_.icntl[6] = ordering;           // ICNTL(7)
    id_.icntl[13] = memoryRelaxation;  // ICNTL(14)
    id_.icntl[17] = 3;                 // ICNTL(18): distributed assembled input
  }

  ~MumpsContextT() override {
    id_.job = -2;
    P::call(id_);
  }
  MumpsContextT(const MumpsContextT&) = delete;
  MumpsContextT& operator=(const MumpsContextT&) = delete;

  void factor(const Matrix& A) override {
    const auto rowMap = A.getRowMap();
    if (!A.getDomainMap()->isSameAs(*rowMap) || !A.getRangeMap()->isSameAs(*rowMap))
      throw std::invalid_argument("MUMPS: the matrix's domain and range must be its row layout (perinox's Jacobians are)");
    const long long n = static_cast<long long>(rowMap->getGlobalNumElements());
    if (n > 2147483647LL) throw std::invalid_argument("MUMPS: more than 2^31 - 1 unknowns");
    if (rowMap_.is_null() || !rowMap->isSameAs(*rowMap_)) numberRows(rowMap);
    // Numbering the columns is collective: renumber on every rank when any rank's column layout
    // is a new object (the kept RCP stops a new layout from reusing the old one's address).
    int newColumns = colMap_.get() != A.getColMap().get();
    MPI_Allreduce(MPI_IN_PLACE, &newColumns, 1, MPI_INT, MPI_LOR, comm_);
    if (newColumns) numberColumns(A.getColMap());
    auto lcl = A.getLocalMatrixHost();
    const std::size_t nnz = lcl.values.extent(0);
    std::vector<MUMPS_INT> irn(nnz), jcn(nnz);
    a_.resize(nnz);
    auto colNumber = colNumber_->getData(0);
    for (int r = 0; r < lcl.numRows(); ++r) {
      const auto row = static_cast<MUMPS_INT>(rowOffset_ + r + 1);
      for (auto k = lcl.graph.row_map(r); k < lcl.graph.row_map(r + 1); ++k) {
        irn[k] = row;
        jcn[k] = static_cast<MUMPS_INT>(colNumber[lcl.graph.entries(k)]);
        a_[k] = static_cast<typename P::Real>(lcl.values(k));
      }
    }
    // The analysis (ordering, symbolic factorisation) is kept while no rank's pattern changes.
    int changed = !analysed_ || n != id_.n || irn != irn_ || jcn != jcn_;
    MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_LOR, comm_);
    if (changed) {
      irn_.swap(irn);
      jcn_.swap(jcn);
      id_.n = static_cast<MUMPS_INT>(n);
      analysed_ = false;
    }
    id_.nnz_loc = static_cast<MUMPS_INT8>(nnz);
    id_.irn_loc = irn_.data();
    id_.jcn_loc = jcn_.data();
    id_.a_loc = a_.data();
    if (!analysed_) {
      call(1, "analysis");
      analysed_ = true;
    }
    // Factorise; when MUMPS finds its working-space estimate too small (pivoting can need more
    // than the analysis predicted), enlarge it and try again.
    factored_ = false;
    for (int attempt = 0;; ++attempt) {
      id_.job = 2;
      P::call(id_);
      const int e = id_.infog[0];
      if (!((e == -8 || e == -9 || e == -14 || e == -15) && attempt < 4)) break;
      id_.icntl[13] *= 2;
    }
    check("numeric factorization");
    factored_ = true;
  }

  bool factored() const override { return factored_; }
  long long factorEntries() const override {
    const long long e = id_.infog[28];  // negative: millions of entries
    return e >= 0 ? e : -e * 1000000LL;
  }
  int bytesPerEntry() const override { return static_cast<int>(sizeof(typename P::Real)); }
  const Teuchos::RCP<const Map>& rowMap() const override { return rowMap_; }

  void solve(bool transpose, const MV& B, MV& X) override {
    if (!factored_) throw std::logic_error("MUMPS: solve without a factorisation");
    if (!B.getMap()->isSameAs(*rowMap_) || !X.getMap()->isSameAs(*rowMap_))
      throw std::invalid_argument("MUMPS: the vectors' layout differs from the matrix's rows");
    const std::size_t nrhs = B.getNumVectors();
    MV root(rootMap_, nrhs);
    root.doImport(B, *toRoot_, Tpetra::INSERT);
    const std::size_t n = static_cast<std::size_t>(id_.n);
    if (rank_ == 0) {
      rhs_.assign(n * nrhs, 0);
      for (std::size_t j = 0; j < nrhs; ++j) {
        auto col = root.getData(j);
        for (std::size_t i = 0; i < n; ++i) rhs_[j * n + i] = static_cast<typename P::Real>(col[i]);
      }
      id_.rhs = rhs_.data();
      id_.nrhs = static_cast<MUMPS_INT>(nrhs);
      id_.lrhs = static_cast<MUMPS_INT>(n);
    }
    id_.icntl[8] = transpose ? 2 : 1;  // ICNTL(9): 1 solves A x = b, otherwise A^T x = b
    call(3, "solve");
    if (rank_ == 0) {
      for (std::size_t j = 0; j < nrhs; ++j) {
        auto col = root.getDataNonConst(j);
        for (std::size_t i = 0; i < n; ++i) col[i] = static_cast<double>(rhs_[j * n + i]);
      }
    }
    X.doExport(root, *toRoot_, Tpetra::INSERT);
  }

 private:
  // MUMPS numbers the unknowns 1..n; here rank r's rows come after those of ranks 0..r-1, in
  // local order (Tpetra's global indices need not be contiguous). The right-hand side is
  // gathered to rank 0 in that order: the root layout lists every row's global index by number.
  void numberRows(const Teuchos::RCP<const Map>& rowMap) {
    const long long nLocal = static_cast<long long>(rowMap->getNodeNumElements());
    long long offset = 0;
    MPI_Exscan(&nLocal, &offset, 1, MPI_LONG_LONG, MPI_SUM, comm_);
    rowOffset_ = rank_ == 0 ? 0 : offset;
    rowNumber_ = Teuchos::rcp(new MV(rowMap, 1));
    for (long long i = 0; i < nLocal; ++i)
      rowNumber_->replaceLocalValue(static_cast<int>(i), 0, static_cast<double>(rowOffset_ + i + 1));

    int size = 1;
    MPI_Comm_size(comm_, &size);
    const int count = static_cast<int>(nLocal);
    std::vector<int> counts(size), displs(size);
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_);
    for (int r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
    auto mine = rowMap->getNodeElementList();
    std::vector<long long> all(rank_ == 0 ? static_cast<std::size_t>(displs[size - 1] + counts[size - 1]) : 0);
    MPI_Gatherv(mine.getRawPtr(), count, MPI_LONG_LONG, all.data(), counts.data(), displs.data(), MPI_LONG_LONG, 0,
                comm_);
    const auto invalid = Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid();
    rootMap_ = Teuchos::rcp(new Map(invalid, Teuchos::ArrayView<const long long>(all), rowMap->getIndexBase(),
                                    rowMap->getComm()));
    toRoot_ = Teuchos::rcp(new Importer(rowMap, rootMap_));
    rowMap_ = rowMap;
    colMap_ = Teuchos::null;
  }

  // The numbers of the local matrix's columns, brought from the rows' owners (a Jacobian's column
  // layout changes when bonds break).
  void numberColumns(const Teuchos::RCP<const Map>& colMap) {
    colNumber_ = Teuchos::rcp(new MV(colMap, 1));
    colNumber_->doImport(*rowNumber_, Importer(rowMap_, colMap), Tpetra::INSERT);
    colMap_ = colMap;
  }

  void call(int job, const char* what) {
    id_.job = job;
    P::call(id_);
    check(what);
  }
  void check(const char* what) const {
    if (id_.infog[0] < 0)  // INFOG is the same on every rank: all throw together
      throw std::runtime_error(std::string("MUMPS: ") + what + " failed: " + mumpsMessage(id_.infog[0], id_.infog[1]));
  }

  MPI_Comm comm_;
  int rank_ = 0;
  typename P::Struct id_{};
  std::vector<MUMPS_INT> irn_, jcn_;
  std::vector<typename P::Real> a_, rhs_;
  long long rowOffset_ = 0;
  Teuchos::RCP<MV> rowNumber_, colNumber_;  // MUMPS's 1-based numbers of the rows and local columns
  bool analysed_ = false, factored_ = false;
  Teuchos::RCP<const Map> rowMap_, colMap_, rootMap_;
  Teuchos::RCP<Importer> toRoot_;
};

class MumpsLinearOpWithSolve : public Thyra::LinearOpWithSolveBase<double> {
 public:
  void initialize(const Teuchos::RCP<const Thyra::LinearOpBase<double>>& op,
                  const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& src,
                  const std::shared_ptr<MumpsContext>& context) {
    op_ = op;
    src_ = src;
    context_ = context;
  }
  const std::shared_ptr<MumpsContext>& context() const { return context_; }
  Teuchos::RCP<const Thyra::LinearOpSourceBase<double>> extractSource() {
    auto s = src_;
    src_ = Teuchos::null;
    return s;
  }

  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> range() const override {
    return op_.is_null() ? Teuchos::null : op_->range();
  }
  Teuchos::RCP<const Thyra::VectorSpaceBase<double>> domain() const override {
    return op_.is_null() ? Teuchos::null : op_->domain();
  }

 protected:
  bool opSupportedImpl(Thyra::EOpTransp t) const override { return Thyra::opSupported(*op_, t); }
  void applyImpl(const Thyra::EOpTransp t, const Thyra::MultiVectorBase<double>& X,
                 const Teuchos::Ptr<Thyra::MultiVectorBase<double>>& Y, const double alpha,
                 const double beta) const override {
    Thyra::apply(*op_, t, X, Y, alpha, beta);
  }
  bool solveSupportsImpl(Thyra::EOpTransp) const override { return true; }
  bool solveSupportsSolveMeasureTypeImpl(Thyra::EOpTransp, const Thyra::SolveMeasureType&) const override {
    return true;  // a direct solve meets any tolerance a Newton step asks for
  }
  Thyra::SolveStatus<double> solveImpl(const Thyra::EOpTransp t, const Thyra::MultiVectorBase<double>& B,
                                       const Teuchos::Ptr<Thyra::MultiVectorBase<double>>& X,
                                       const Teuchos::Ptr<const Thyra::SolveCriteria<double>>) const override {
    auto b = Extract::getConstTpetraMultiVector(Teuchos::rcpFromRef(B));
    auto x = Extract::getTpetraMultiVector(Teuchos::rcpFromPtr(X));
    context_->solve(Thyra::real_trans(t) != Thyra::NOTRANS, *b, *x);
    Thyra::SolveStatus<double> status;
    status.solveStatus = Thyra::SOLVE_STATUS_CONVERGED;
    return status;
  }

 private:
  Teuchos::RCP<const Thyra::LinearOpBase<double>> op_;
  Teuchos::RCP<const Thyra::LinearOpSourceBase<double>> src_;
  std::shared_ptr<MumpsContext> context_;
};

double seconds() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// Applications of fresh single- or double-precision factors a Newton system needs (one, two
/// at the tightest Eisenstat-Walker tolerances): what a solve needs beyond it is the stale factors' cost.
constexpr long long kFreshApplications = 2;

/// The kept factors of a MUMPS preconditioner, what it is configured to do with them, how they
/// were used, and the matrix of the current set-up (assembled when asked) for a factorisation
/// during a solve. Shared by the factory and the operators its set-ups hand out.
struct KeptFactors {
  // The factors in use: those of the configured precision (primary), or of the double-precision
  // fallback when the primary's factorisation failed.
  std::shared_ptr<MumpsContext> context, primary, fallback;
  // The configuration ('Ordering', 'Memory Relaxation Percent', 'Refactor Above Krylov
  // Iterations', 'Refactor Within A Solve Above', 'Refactor Above Excess Applications', 'Factor
  // Precision' = Single).
  int ordering = 7, memoryRelaxation = 30, refactorAbove = 20, withinSolveAbove = 0, excessAbove = 0;
  bool singlePrecision = false;
  // Applications since the last factorisation within this set-up.
  long long sinceFactor = 0;
  // Applications the solves since the last factorisation needed beyond what fresh factors need
  // (kFreshApplications a solve): the price paid so far for keeping them.
  long long excess = 0;
  // Whether this set-up factorised (at the set-up or during its solve): fresh factors are not
  // renewed again before the next set-up.
  bool factoredThisSetup = false;
  std::function<Teuchos::RCP<const Matrix>()> matrix;
  MumpsPreconditionerStatistics stats;

  // Factorises A, in the configured precision or, when that fails in single precision, in double.
  void factor(const Matrix& A) {
    auto make = [&](bool single) -> std::shared_ptr<MumpsContext> {
      if (single) return std::make_shared<MumpsContextT<SinglePrecision>>(A.getComm(), ordering, memoryRelaxation);
      return std::make_shared<MumpsContextT<DoublePrecision>>(A.getComm(), ordering, memoryRelaxation);
    };
    const double t0 = seconds();
    if (!primary) primary = make(singlePrecision);
    try {
      primary->factor(A);
      context = primary;
    } catch (const std::runtime_error&) {
      // A matrix that is singular in single precision only (a pivot lost to its rounding, near a
      // limit point) is factorised in double precision this time; an error there is the caller's.
      // Every rank throws together (MUMPS's INFOG is global), so every rank falls back.
      if (!singlePrecision) throw;
      if (!fallback) fallback = make(false);
      fallback->factor(A);
      context = fallback;
      ++stats.doublePrecisionFallbacks;
    }
    stats.factorSeconds += seconds() - t0;
    ++stats.factorizations;
    stats.factorBytes = std::max(stats.factorBytes, context->factorEntries() * context->bytesPerEntry());
    stats.bytesPerEntry = context->bytesPerEntry();
    sinceFactor = 0;
    excess = 0;
    factoredThisSetup = true;
  }

  // y = (LU)^-1 x. Stale factors that have already been applied 'Refactor Within A Solve Above'
  // times in this solve are first renewed from the set-up's matrix (collective: every rank counts
  // the same applications of a global Krylov solver).
  void solve(bool transpose, const MV& X, MV& Y) {
    if (withinSolveAbove > 0 && !factoredThisSetup && sinceFactor >= withinSolveAbove && matrix) {
      const auto A = matrix();
      if (A.is_null())
        throw std::logic_error("the MUMPS preconditioner's operator could not assemble itself during a solve");
      factor(*A);
      ++stats.factorizationsDuringSolves;
    }
    ++sinceFactor;
    ++stats.solves;
    const double t0 = seconds();
    context->solve(transpose, X, Y);
    stats.solveSeconds += seconds() - t0;
  }
};

/// The kept factors as a Tpetra operator, y = alpha (LU)^-1 x + beta y.
class MumpsFactorsOperator final : public Tpetra::Operator<double, int, long long, Node> {
 public:
  MumpsFactorsOperator(std::shared_ptr<KeptFactors> kept, Teuchos::RCP<const Map> map)
      : kept_(std::move(kept)), map_(std::move(map)) {}
  Teuchos::RCP<const Map> getDomainMap() const override { return map_; }
  Teuchos::RCP<const Map> getRangeMap() const override { return map_; }
  bool hasTransposeApply() const override { return true; }
  void apply(const MV& X, MV& Y, Teuchos::ETransp mode, double alpha, double beta) const override {
    const bool transpose = mode != Teuchos::NO_TRANS;
    if (alpha == 1.0 && beta == 0.0) {
      kept_->solve(transpose, X, Y);
    } else {
      MV z(map_, X.getNumVectors());
      kept_->solve(transpose, X, z);
      Y.update(alpha, z, beta);
    }
  }

 private:
  std::shared_ptr<KeptFactors> kept_;
  Teuchos::RCP<const Map> map_;
};

Teuchos::RCP<const Matrix> crsMatrix(const Thyra::LinearOpSourceBase<double>& src) {
  auto op = src.getOp();
  if (op.is_null()) return Teuchos::null;
  auto tpetraOp = Extract::getConstTpetraOperator(op);
  return Teuchos::rcp_dynamic_cast<const Matrix>(tpetraOp);
}

const char* const kOrdering = "Ordering";
const char* const kRelaxation = "Memory Relaxation Percent";
const char* const kRefactor = "Refactor Above Krylov Iterations";
const char* const kPrecision = "Factor Precision";
const char* const kWithinSolve = "Refactor Within A Solve Above";
const char* const kExcess = "Refactor Above Excess Applications";
}  // namespace

MumpsLinearOpWithSolveFactory::MumpsLinearOpWithSolveFactory() = default;

bool MumpsLinearOpWithSolveFactory::isCompatible(const Thyra::LinearOpSourceBase<double>& src) const {
  try {
    return !crsMatrix(src).is_null();
  } catch (const std::exception&) {
    return false;  // not a Tpetra operator
  }
}

Teuchos::RCP<Thyra::LinearOpWithSolveBase<double>> MumpsLinearOpWithSolveFactory::createOp() const {
  return Teuchos::rcp(new MumpsLinearOpWithSolve());
}

void MumpsLinearOpWithSolveFactory::initializeOp(const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& src,
                                                 Thyra::LinearOpWithSolveBase<double>* op,
                                                 const Thyra::ESupportSolveUse) const {
  TEUCHOS_TEST_FOR_EXCEPT(op == nullptr || src.is_null());
  auto A = crsMatrix(*src);
  if (A.is_null())
    throw std::invalid_argument("MUMPS needs an assembled Tpetra::CrsMatrix (set 'Solver/Jacobian' to Assembled)");
  auto& lows = Teuchos::dyn_cast<MumpsLinearOpWithSolve>(*op);
  auto context = lows.context();
  if (!context) context = std::make_shared<MumpsContextT<DoublePrecision>>(A->getComm(), ordering_, memoryRelaxation_);
  context->factor(*A);
  lows.initialize(src->getOp(), src, context);
}

void MumpsLinearOpWithSolveFactory::uninitializeOp(Thyra::LinearOpWithSolveBase<double>* op,
                                                   Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* fwdOpSrc,
                                                   Teuchos::RCP<const Thyra::PreconditionerBase<double>>* prec,
                                                   Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* approx,
                                                   Thyra::ESupportSolveUse*) const {
  TEUCHOS_TEST_FOR_EXCEPT(op == nullptr);
  auto src = Teuchos::dyn_cast<MumpsLinearOpWithSolve>(*op).extractSource();
  if (fwdOpSrc) *fwdOpSrc = src;
  if (prec) *prec = Teuchos::null;
  if (approx) *approx = Teuchos::null;
}

void MumpsLinearOpWithSolveFactory::setParameterList(const Teuchos::RCP<Teuchos::ParameterList>& params) {
  TEUCHOS_TEST_FOR_EXCEPT(params.is_null());
  params->validateParametersAndSetDefaults(*getValidParameters());
  params_ = params;
  ordering_ = Teuchos::getIntegralValue<int>(*params_, kOrdering);
  memoryRelaxation_ = params_->get<int>(kRelaxation);
  if (memoryRelaxation_ < 0)
    throw std::invalid_argument("MUMPS: 'Memory Relaxation Percent' must be at least 0");
}

Teuchos::RCP<Teuchos::ParameterList> MumpsLinearOpWithSolveFactory::getNonconstParameterList() { return params_; }

Teuchos::RCP<Teuchos::ParameterList> MumpsLinearOpWithSolveFactory::unsetParameterList() {
  auto p = params_;
  params_ = Teuchos::null;
  return p;
}

Teuchos::RCP<const Teuchos::ParameterList> MumpsLinearOpWithSolveFactory::getParameterList() const { return params_; }

Teuchos::RCP<const Teuchos::ParameterList> MumpsLinearOpWithSolveFactory::getValidParameters() const {
  static Teuchos::RCP<Teuchos::ParameterList> valid;
  if (valid.is_null()) {
    valid = Teuchos::rcp(new Teuchos::ParameterList("MUMPS"));
    Teuchos::setStringToIntegralParameter<int>(
        kOrdering, "Auto", "fill-reducing ordering (MUMPS ICNTL(7)); Auto lets MUMPS choose",
        Teuchos::tuple<std::string>("Auto", "AMD", "AMF", "Scotch", "PORD", "METIS", "QAMD"),
        Teuchos::tuple<int>(7, 0, 2, 3, 4, 5, 6), valid.get());
    valid->set(kRelaxation, 30,
               "extra working space over MUMPS's estimate, percent (ICNTL(14)); doubled and retried when short");
  }
  return valid;
}

std::string MumpsLinearOpWithSolveFactory::description() const { return "perinox::MumpsLinearOpWithSolveFactory"; }

// --- the kept factorisation as a preconditioner ---

struct MumpsPreconditionerFactory::State : KeptFactors {};

MumpsPreconditionerFactory::MumpsPreconditionerFactory() : state_(std::make_shared<State>()) {}
MumpsPreconditionerFactory::~MumpsPreconditionerFactory() = default;

namespace {
/// The Tpetra operator of a source (null when it is not one).
Teuchos::RCP<const Tpetra::Operator<double, int, long long, Node>> tpetraOperator(const Thyra::LinearOpSourceBase<double>& src) {
  try {
    auto op = src.getOp();
    return op.is_null() ? Teuchos::null : Extract::getConstTpetraOperator(op);
  } catch (const std::exception&) {
    return Teuchos::null;
  }
}
}  // namespace

bool MumpsPreconditionerFactory::isCompatible(const Thyra::LinearOpSourceBase<double>& src) const {
  auto op = tpetraOperator(src);
  return !Teuchos::rcp_dynamic_cast<const Matrix>(op).is_null() ||
         dynamic_cast<const OperatorAssembly*>(op.get()) != nullptr;
}

Teuchos::RCP<Thyra::PreconditionerBase<double>> MumpsPreconditionerFactory::createPrec() const {
  return Teuchos::rcp(new Thyra::DefaultPreconditioner<double>);
}

void MumpsPreconditionerFactory::initializePrec(const Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>& src,
                                                Thyra::PreconditionerBase<double>* prec,
                                                const Thyra::ESupportSolveUse) const {
  TEUCHOS_TEST_FOR_EXCEPT(prec == nullptr || src.is_null());
  // An assembled matrix, or an operator that assembles itself when asked (the matrix-free
  // Jacobian with Preconditioner Matrix = None: assembled only when the factors are renewed).
  auto op = tpetraOperator(*src);
  auto A = Teuchos::rcp_dynamic_cast<const Matrix>(op);
  const auto* lazy = A.is_null() ? dynamic_cast<const OperatorAssembly*>(op.get()) : nullptr;
  if (A.is_null() && lazy == nullptr)
    throw std::invalid_argument(
        "the MUMPS preconditioner needs an assembled matrix: the assembled Jacobian, or with Solver/Jacobian = "
        "Matrix-Free a 'Preconditioner Matrix' of Assembled, Neighbours or None (the Jacobian assembled when refactorised)");
  State& st = *state_;
  ++st.stats.setups;
  const Teuchos::RCP<const Map> rows = op->getRangeMap();
  // The matrix of this set-up, for a factorisation now or during the solve that follows.
  if (!A.is_null()) {
    st.matrix = [A] { return A; };
  } else {
    st.matrix = [op, lazy, &st]() -> Teuchos::RCP<const Matrix> {
      auto assembled = lazy->assembled();
      if (!assembled.is_null()) ++st.stats.selfAssembled;
      return assembled;
    };
  }
  st.factoredThisSetup = false;
  if (st.context) st.excess += std::max(0LL, st.sinceFactor - kFreshApplications);
  // Refactorise when there are no factors, the rows moved, the last solve needed more than the
  // allowed Krylov iterations with the kept ones, or the solves since the last factorisation
  // have together paid more than the allowed excess applications for keeping them (the rule of
  // renting until the rent adds up to the price of buying; every rank has the same counts: the
  // Krylov solver's iterations are global).
  const bool refactor = !st.context || !st.context->factored() || st.context->rowMap().is_null() ||
                        !st.context->rowMap()->isSameAs(*rows) || st.sinceFactor > st.refactorAbove ||
                        (st.excessAbove > 0 && st.excess > st.excessAbove);
  if (refactor) {
    const auto matrix = st.matrix();
    if (matrix.is_null())
      throw std::logic_error("the MUMPS preconditioner's operator could not assemble itself at its set-up");
    st.factor(*matrix);
  }
  st.sinceFactor = 0;
  Teuchos::RCP<const Tpetra::Operator<double, int, long long, Node>> M = Teuchos::rcp(new MumpsFactorsOperator(state_, rows));
  auto space = Thyra::tpetraVectorSpace<double, int, long long, Node>(rows);
  Teuchos::RCP<const Thyra::LinearOpBase<double>> thyraM = Thyra::constTpetraLinearOp<double, int, long long, Node>(
      space, space, M);
  auto* def = dynamic_cast<Thyra::DefaultPreconditioner<double>*>(prec);
  if (def == nullptr) throw std::logic_error("the MUMPS preconditioner needs a Thyra::DefaultPreconditioner");
  def->initializeUnspecified(thyraM);
  src_ = src.create_weak();  // the factory must not keep the matrix alive
}

void MumpsPreconditionerFactory::uninitializePrec(Thyra::PreconditionerBase<double>* prec,
                                                  Teuchos::RCP<const Thyra::LinearOpSourceBase<double>>* src,
                                                  Thyra::ESupportSolveUse* use) const {
  if (src) *src = src_.is_valid_ptr() ? src_.create_strong() : Teuchos::null;
  if (use) *use = Thyra::SUPPORT_SOLVE_UNSPECIFIED;
  if (auto* def = dynamic_cast<Thyra::DefaultPreconditioner<double>*>(prec)) def->uninitialize();
}

void MumpsPreconditionerFactory::setParameterList(const Teuchos::RCP<Teuchos::ParameterList>& params) {
  TEUCHOS_TEST_FOR_EXCEPT(params.is_null());
  params->validateParametersAndSetDefaults(*getValidParameters());
  params_ = params;
  State& st = *state_;
  st.ordering = Teuchos::getIntegralValue<int>(*params_, kOrdering);
  st.memoryRelaxation = params_->get<int>(kRelaxation);
  st.refactorAbove = params_->get<int>(kRefactor);
  st.singlePrecision = params_->get<std::string>(kPrecision) == "Single";
  st.withinSolveAbove = params_->get<int>(kWithinSolve);
  st.excessAbove = params_->get<int>(kExcess);
  if (st.memoryRelaxation < 0) throw std::invalid_argument("MUMPS: 'Memory Relaxation Percent' must be at least 0");
  if (st.refactorAbove < 0) throw std::invalid_argument("MUMPS: 'Refactor Above Krylov Iterations' must be at least 0");
  if (st.excessAbove < 0) throw std::invalid_argument("MUMPS: 'Refactor Above Excess Applications' must be at least 0");
  if (st.withinSolveAbove < 0) throw std::invalid_argument("MUMPS: 'Refactor Within A Solve Above' must be at least 0");
}

Teuchos::RCP<Teuchos::ParameterList> MumpsPreconditionerFactory::getNonconstParameterList() { return params_; }

Teuchos::RCP<Teuchos::ParameterList> MumpsPreconditionerFactory::unsetParameterList() {
  auto p = params_;
  params_ = Teuchos::null;
  return p;
}

Teuchos::RCP<const Teuchos::ParameterList> MumpsPreconditionerFactory::getParameterList() const { return params_; }

Teuchos::RCP<const Teuchos::ParameterList> MumpsPreconditionerFactory::getValidParameters() const {
  static Teuchos::RCP<Teuchos::ParameterList> valid;
  if (valid.is_null()) {
    valid = Teuchos::rcp(new Teuchos::ParameterList(*MumpsLinearOpWithSolveFactory().getValidParameters()));
    valid->setName("MUMPS");
    valid->set(kRefactor, 20,
               "keep the factors while a solve needs at most this many Krylov iterations with them; refactorise at the "
               "next set-up after one that needed more (0: every set-up)");
    valid->set(kExcess, 0,
               "also refactorise at the next set-up once the solves since the last factorisation have together applied the "
               "factors this many times more than fresh factors would have (two a solve); about the cost of a factorisation "
               "in applications pays the least in total (0: never)");
    valid->set(kPrecision, "Double",
               "precision of the kept factors: Double, or Single (MUMPS's single-precision interface: half the bytes, "
               "and solves that read half as much; the Krylov solver still converges in double precision)",
               Teuchos::rcp(new Teuchos::StringValidator(Teuchos::tuple<std::string>("Double", "Single"))));
    valid->set(kWithinSolve, 0,
               "renew stale factors within a solve once they have been applied this many times in it (once a set-up; 0: "
               "never); only for a flexible Krylov solver (Belos Block GMRES with 'Flexible Gmres' = true), which allows "
               "the preconditioner to change between iterations");
  }
  return valid;
}

std::string MumpsPreconditionerFactory::description() const { return "perinox::MumpsPreconditionerFactory"; }

MumpsPreconditionerStatistics MumpsPreconditionerFactory::statistics() const {
  return state_->stats;
}

MumpsPreconditionerStatistics mumpsPreconditionerStatistics(const Thyra::PreconditionerFactoryBase<double>& factory) {
  if (auto* f = dynamic_cast<const MumpsPreconditionerFactory*>(&factory)) return f->statistics();
  return {};
}

void MumpsPreconditionerFactory::renewFactors() const {
  State& st = *state_;
  st.context.reset();
  st.primary.reset();
  st.fallback.reset();
  st.sinceFactor = 0;
  st.excess = 0;
  st.factoredThisSetup = false;
}

void renewKeptFactors(const Thyra::PreconditionerFactoryBase<double>& factory) {
  if (auto* f = dynamic_cast<const MumpsPreconditionerFactory*>(&factory)) f->renewFactors();
}

}  // namespace perinox

// The MUMPS linear-solve strategy on a hand-made nonsymmetric matrix whose solution is known:
// b = A x_true is formed by Tpetra's own product, MUMPS must return x_true. Run on 1, 2 and 3
// ranks with global indices that are neither contiguous nor starting at 0, two right-hand sides,
// the transposed system, a refactorisation with new values on the kept pattern, a new pattern,
// and a numerically singular matrix (which must throw, on every rank, naming the singularity).
#include <gtest/gtest.h>

#include <Teuchos_DefaultComm.hpp>
#include <Thyra_DefaultLinearOpSource.hpp>
#include <Thyra_LinearOpWithSolveFactoryHelpers.hpp>
#include <Thyra_LinearOpWithSolveHelpers.hpp>
#include <Thyra_TpetraThyraWrappers.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <cmath>
#include <functional>

#include "perinox/solver/LinearSolver.hpp"
#include "perinox/solver/LinearSolverValidation.hpp"
#include "perinox/solver/MumpsSolver.hpp"

namespace {
using Node = Tpetra::Map<int, long long>::node_type;
using Map = Tpetra::Map<int, long long, Node>;
using Matrix = Tpetra::CrsMatrix<double, int, long long, Node>;
using MV = Tpetra::MultiVector<double, int, long long, Node>;

constexpr int N = 60;
long long gid(int i) { return 3LL * i + 7; }  // not contiguous, not starting at 0

Teuchos::RCP<const Map> makeMap() {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const int p = comm->getSize(), r = comm->getRank();
  // Uneven blocks: rank r owns rows [lo, hi).
  const int lo = (N * r * r) / (p * p), hi = (N * (r + 1) * (r + 1)) / (p * p);
  Teuchos::Array<long long> mine;
  for (int i = lo; i < hi; ++i) mine.push_back(gid(i));
  return Teuchos::rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(), mine(), 7, comm));
}

// A diagonally dominant nonsymmetric matrix with banded and far couplings. `variant` changes the
// values (1) or adds one more far coupling per row (2, a new pattern); `singularRow` >= 0 makes
// that row a copy of the next one (numerically, not structurally, singular), plus `nudge` on the
// copied diagonal entry (a nudge below single precision's resolution leaves the matrix singular
// in single precision only).
Teuchos::RCP<Matrix> makeMatrix(const Teuchos::RCP<const Map>& map, int variant, int singularRow = -1,
                                double nudge = 0.0) {
  auto A = Teuchos::rcp(new Matrix(map, 8));
  auto rowEntries = [&](int i, std::vector<std::pair<int, double>>& e) {
    e.clear();
    const double s = variant == 1 ? 2.0 : 1.0;
    e.push_back({i, s * (4.0 + 0.1 * i)});
    if (i + 1 < N) e.push_back({i + 1, -1.3});
    if (i > 0) e.push_back({i - 1, -0.7 * s});
    const int far = (7 * i + 3) % N;
    if (far != i && far != i + 1 && far != i - 1) e.push_back({far, 0.25});
    if (variant == 2) {
      const int far2 = (11 * i + 5) % N;
      bool dup = false;
      for (auto& [c, v] : e) dup = dup || c == far2;
      if (!dup) e.push_back({far2, -0.3});
    }
  };
  std::vector<std::pair<int, double>> e;
  for (std::size_t k = 0; k < map->getNodeNumElements(); ++k) {
    const int i = static_cast<int>((map->getGlobalElement(static_cast<int>(k)) - 7) / 3);
    rowEntries(i == singularRow ? i + 1 : i, e);
    if (i == singularRow) {  // the next row's entries, plus explicit zeros to keep the pattern
      std::vector<std::pair<int, double>> own;
      rowEntries(i, own);
      for (auto& [c, v] : own) {
        bool have = false;
        for (auto& [c2, v2] : e) have = have || c2 == c;
        if (!have) e.push_back({c, 0.0});
      }
    }
    Teuchos::Array<long long> cols;
    Teuchos::Array<double> vals;
    for (auto& [c, v] : e) {
      cols.push_back(gid(c));
      vals.push_back(i == singularRow && c == i + 1 ? v + nudge : v);
    }
    A->insertGlobalValues(gid(i), cols(), vals());
  }
  A->fillComplete();
  return A;
}

Teuchos::RCP<MV> exact(const Teuchos::RCP<const Map>& map) {
  auto x = Teuchos::rcp(new MV(map, 2));
  for (std::size_t k = 0; k < map->getNodeNumElements(); ++k) {
    const double i = static_cast<double>((map->getGlobalElement(static_cast<int>(k)) - 7) / 3);
    x->replaceLocalValue(static_cast<int>(k), 0, std::sin(i + 1.0));
    x->replaceLocalValue(static_cast<int>(k), 1, 1.0 + 0.01 * i * i);
  }
  return x;
}

// Largest |x - x_true| relative to max |x_true|, over both columns.
double relativeError(const MV& x, const MV& xTrue) {
  MV d(xTrue, Teuchos::Copy);
  d.update(1.0, x, -1.0);
  Teuchos::Array<double> nd(2), nt(2);
  d.normInf(nd());
  xTrue.normInf(nt());
  return std::max(nd[0] / nt[0], nd[1] / nt[1]);
}

Teuchos::RCP<Thyra::LinearOpWithSolveFactoryBase<double>> factory() {
  auto f = Teuchos::rcp(new perinox::MumpsLinearOpWithSolveFactory());
  f->setParameterList(Teuchos::rcp(new Teuchos::ParameterList("MUMPS")));
  return f;
}

// Solves op(A) x = op(A) x_true through Thyra with the given (re)initialised operator.
double solveError(Thyra::LinearOpWithSolveBase<double>& lows, const Matrix& A, Thyra::EOpTransp t) {
  auto map = A.getRowMap();
  auto xTrue = exact(map);
  auto b = Teuchos::rcp(new MV(map, 2));
  A.apply(*xTrue, *b, t == Thyra::NOTRANS ? Teuchos::NO_TRANS : Teuchos::TRANS);
  auto x = Teuchos::rcp(new MV(map, 2));
  auto tb = Thyra::createMultiVector<double>(b);
  auto tx = Thyra::createMultiVector<double>(x);
  Thyra::solve<double>(lows, t, *tb, tx.ptr());
  return relativeError(*x, *xTrue);
}

Teuchos::RCP<const Thyra::LinearOpSourceBase<double>> source(const Teuchos::RCP<Matrix>& A) {
  return Thyra::defaultLinearOpSource<double>(Thyra::createConstLinearOp<double>(Teuchos::RCP<const Tpetra::Operator<double, int, long long, Node>>(A)));
}
}  // namespace

// Condition numbers here are below 10, so a backward-stable LU gives 1e-13 or better.
constexpr double kTol = 1e-12;

TEST(Mumps, SolvesForwardAndTransposedWithTwoRightHandSides) {
  auto map = makeMap();
  auto A = makeMatrix(map, 0);
  auto f = factory();
  auto lows = f->createOp();
  f->initializeOp(source(A), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
  EXPECT_LT(solveError(*lows, *A, Thyra::NOTRANS), kTol);
  EXPECT_LT(solveError(*lows, *A, Thyra::TRANS), kTol);
}

TEST(Mumps, RefactorsNewValuesAndNewPatterns) {
  auto map = makeMap();
  auto f = factory();
  auto lows = f->createOp();
  auto A0 = makeMatrix(map, 0);
  f->initializeOp(source(A0), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
  EXPECT_LT(solveError(*lows, *A0, Thyra::NOTRANS), kTol);
  auto A1 = makeMatrix(map, 1);  // same pattern, other values: numeric factorisation only
  f->initializeOp(source(A1), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
  EXPECT_LT(solveError(*lows, *A1, Thyra::NOTRANS), kTol);
  // The old factors would solve A0 instead: the answer must differ from A0's solution.
  auto A2 = makeMatrix(map, 2);  // one more coupling per row: a new analysis
  f->initializeOp(source(A2), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
  EXPECT_LT(solveError(*lows, *A2, Thyra::NOTRANS), kTol);
  EXPECT_LT(solveError(*lows, *A2, Thyra::TRANS), kTol);
}

TEST(Mumps, ReusedFactorsOfAnotherMatrixWouldFail) {
  // Guards the test above: solving A1's system with A0's factors misses by far more than kTol.
  auto map = makeMap();
  auto f = factory();
  auto lows = f->createOp();
  auto A0 = makeMatrix(map, 0), A1 = makeMatrix(map, 1);
  f->initializeOp(source(A0), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
  EXPECT_GT(solveError(*lows, *A1, Thyra::NOTRANS), 1e-2);
}

TEST(Mumps, SingularMatrixThrowsNamingIt) {
  auto map = makeMap();
  auto A = makeMatrix(map, 0, 20);
  auto f = factory();
  auto lows = f->createOp();
  try {
    f->initializeOp(source(A), lows.get(), Thyra::SUPPORT_SOLVE_FORWARD_ONLY);
    FAIL() << "a singular matrix was factorised";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("factorization failed"), std::string::npos) << what;
    EXPECT_NE(what.find("singular"), std::string::npos) << what;
  }
}

TEST(Mumps, UnknownOrderingIsRefused) {
  perinox::MumpsLinearOpWithSolveFactory f;
  auto p = Teuchos::rcp(new Teuchos::ParameterList("MUMPS"));
  p->set("Ordering", "Magic");
  EXPECT_THROW(f.setParameterList(p), std::exception);
}

// A preset may carry perinox's own keys (the Jacobian, preconditioner matrix and forcing term it
// is meant for; xml/solvers/scalable.xml does): a host passes it to buildLinearSolverFactory as
// read, so those keys never reach Stratimikos, which would refuse them as unknown. A misspelt key
// and a bad value are still refused, each naming itself.
TEST(LinearSolverFactory, PerinoxKeysOfAPresetAreAcceptedAndTyposRefused) {
  auto p = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));
  p->set("Jacobian", "Matrix-Free");
  p->set("Preconditioner Matrix", "None");
  p->set("Forcing Term", "Eisenstat-Walker");
  p->set("Linear Solver Type", "Belos");
  p->set("Preconditioner Type", "None");
  EXPECT_NO_THROW(perinox::validateLinearSolverList(*p, "the test list"));
  EXPECT_NO_THROW(perinox::buildLinearSolverFactory(p, 1));
  EXPECT_NO_THROW(perinox::buildSplitLinearSolver(p, 1));
  EXPECT_TRUE(p->isParameter("Preconditioner Matrix"));  // the caller's list is left as it was
  auto refused = [](const std::function<void()>& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "accepted; expected a refusal naming " << part;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  auto typo = Teuchos::rcp(new Teuchos::ParameterList(*p));
  typo->set("Preconditioner Matrx", "None");
  refused([&] { perinox::buildLinearSolverFactory(typo, 1); }, "Preconditioner Matrx");
  auto bad = Teuchos::rcp(new Teuchos::ParameterList(*p));
  bad->set("Forcing Term", "Sometimes");
  refused([&] { perinox::validateLinearSolverList(*bad, "the test list"); }, "Sometimes");
}

namespace {
// The kept factors of A as a preconditioner (MumpsPreconditionerFactory, 'Factor Precision' =
// precision), applied to b = A x_true: the error of M b against x_true, and the statistics.
double preconditionerError(const std::string& precision, perinox::MumpsPreconditionerStatistics& stats,
                           int singularRow = -1, double nudge = 0.0) {
  auto map = makeMap();
  auto A = makeMatrix(map, 0, singularRow, nudge);
  perinox::MumpsPreconditionerFactory f;
  auto p = Teuchos::rcp(new Teuchos::ParameterList("MUMPS"));
  p->set("Factor Precision", precision);
  f.setParameterList(p);
  auto prec = f.createPrec();
  f.initializePrec(source(A), prec.get(), Thyra::SUPPORT_SOLVE_UNSPECIFIED);
  auto xTrue = exact(map);
  auto b = Teuchos::rcp(new MV(map, 2));
  A->apply(*xTrue, *b);
  auto x = Teuchos::rcp(new MV(map, 2));
  auto tb = Thyra::createMultiVector<double>(b);
  auto tx = Thyra::createMultiVector<double>(x);
  Thyra::apply<double>(*prec->getUnspecifiedPrecOp(), Thyra::NOTRANS, *tb, tx.ptr());
  stats = f.statistics();
  return relativeError(*x, *xTrue);
}
}  // namespace

// Single-precision factors solve to single precision (unit round-off 6e-8 times a condition
// number below 10, so between 1e-9 and 1e-5: above 1e-9 only if the factors really are single),
// in half the bytes of the double-precision factors of the same matrix; double to kTol.
TEST(MumpsPreconditioner, SinglePrecisionFactorsHoldHalfTheBytesAndSolveToSinglePrecision) {
  perinox::MumpsPreconditionerStatistics d, s;
  const double errDouble = preconditionerError("Double", d);
  const double errSingle = preconditionerError("Single", s);
  EXPECT_LT(errDouble, kTol);
  EXPECT_GT(errSingle, 1e-9);
  EXPECT_LT(errSingle, 1e-5);
  EXPECT_EQ(d.factorizations, 1);
  EXPECT_EQ(s.factorizations, 1);
  EXPECT_EQ(d.bytesPerEntry, 8);
  EXPECT_EQ(s.bytesPerEntry, 4);
  EXPECT_GT(d.factorBytes, 8 * N);  // at least the diagonal
  EXPECT_EQ(2 * s.factorBytes, d.factorBytes);
  EXPECT_EQ(s.solves, 1);  // one application (two right-hand sides)
}

TEST(MumpsPreconditioner, UnknownPrecisionIsRefused) {
  perinox::MumpsPreconditionerFactory f;
  auto p = Teuchos::rcp(new Teuchos::ParameterList("MUMPS"));
  p->set("Factor Precision", "Half");
  EXPECT_THROW(f.setParameterList(p), std::exception);
}

// A matrix that is singular in single precision only (two rows equal but for 1e-9 on a diagonal
// entry of size 6, below single precision's resolution there) is factorised in double precision
// instead: no failure, one fallback, double-precision factors.
TEST(MumpsPreconditioner, MatrixSingularInSinglePrecisionFallsBackToDouble) {
  perinox::MumpsPreconditionerStatistics s;
  const double err = preconditionerError("Single", s, 20, 1e-9);
  EXPECT_EQ(s.doublePrecisionFallbacks, 1);
  EXPECT_EQ(s.factorizations, 1);
  EXPECT_EQ(s.bytesPerEntry, 8);
  EXPECT_LT(err, 1e-3);  // condition number about 1e10: double precision keeps about 6 digits
  // Without the nudge the matrix is singular in double precision too: refused, naming it.
  try {
    preconditionerError("Single", s, 20, 0.0);
    ADD_FAILURE() << "a singular matrix was factorised";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
}

namespace {
// The preset's form of the kept factors: flexible GMRES to 1e-12 with the MUMPS preconditioner
// (double-precision factors, renewed above `refactorAbove` applications, during the solve or not).
Teuchos::RCP<Teuchos::ParameterList> keptFactorsList(int refactorAbove, int withinSolve, bool flexible = true,
                                                    int excessAbove = 0) {
  auto p = Teuchos::rcp(new Teuchos::ParameterList("Linear Solver"));
  p->set("Linear Solver Type", "Belos");
  auto& belos = p->sublist("Linear Solver Types").sublist("Belos");
  belos.set("Solver Type", "Block GMRES");
  auto& gmres = belos.sublist("Solver Types").sublist("Block GMRES");
  gmres.set("Convergence Tolerance", 1e-12);
  gmres.set("Maximum Iterations", 200);
  gmres.set("Num Blocks", 200);
  gmres.set("Flexible Gmres", flexible);
  p->set("Preconditioner Type", "MUMPS");
  auto& mumps = p->sublist("Preconditioner Types").sublist("MUMPS");
  mumps.set("Refactor Above Krylov Iterations", refactorAbove);
  mumps.set("Refactor Within A Solve Above", withinSolve);
  mumps.set("Refactor Above Excess Applications", excessAbove);
  return p;
}

struct KeptSolve {
  int iterations = 0;
  double error = 1.0;
};

// Solves A x = A x_true (first column) with a preconditioner set up on A, through the split
// solver (Krylov factory and preconditioner factory), as the matrix-free evaluator does.
KeptSolve keptSolve(const perinox::SplitLinearSolver& split, const Teuchos::RCP<Matrix>& A) {
  auto op = Thyra::createConstLinearOp<double>(Teuchos::RCP<const Tpetra::Operator<double, int, long long, Node>>(A));
  auto prec = split.preconditioner->createPrec();
  split.preconditioner->initializePrec(Thyra::defaultLinearOpSource<double>(op), prec.get(), Thyra::SUPPORT_SOLVE_UNSPECIFIED);
  auto lows = split.krylov->createOp();
  Thyra::initializePreconditionedOp<double>(*split.krylov, op, prec.getConst(), lows.ptr());
  auto map = A->getRowMap();
  auto xTrue = exact(map)->subCopy(Teuchos::tuple<std::size_t>(0));
  auto b = Teuchos::rcp(new MV(map, 1));
  A->apply(*xTrue, *b);
  auto x = Teuchos::rcp(new MV(map, 1));
  const auto st = Thyra::solve<double>(*lows, Thyra::NOTRANS, *Thyra::createMultiVector<double>(b),
                                       Thyra::createMultiVector<double>(x).ptr());
  KeptSolve r;
  r.iterations = st.extraParameters.is_null() ? -1 : st.extraParameters->get("Iteration Count", -1);
  x->update(-1.0, *xTrue, 1.0);
  r.error = x->getVector(0)->normInf() / xTrue->getVector(0)->normInf();
  return r;
}
}  // namespace

// The factors of A (variant 0) kept for a system of other values (variant 1: the diagonal and
// lower band doubled, far from A). Flexible GMRES with the stale factors needs many iterations;
// with 'Refactor Within A Solve Above' = 2 the factors are renewed from the new matrix at the third
// application, and the solve ends within a few more (the new factors are exact, so GMRES
// converges in about one more iteration). The next set-up keeps the renewed factors (one
// iteration: 'Refactor Above Krylov Iterations' = 100 does not ask for more). Both reach the
// solution; the counts show where the factorisations happened.
TEST(MumpsPreconditioner, StaleFactorsAreRenewedWithinAFlexibleSolve) {
  auto map = makeMap();
  auto A0 = makeMatrix(map, 0), A1 = makeMatrix(map, 1);
  KeptSolve stale, renewed, after;
  perinox::MumpsPreconditionerStatistics s0, s1;
  {
    auto split = perinox::buildSplitLinearSolver(keptFactorsList(100, 0), map->getComm()->getSize());
    EXPECT_EQ(keptSolve(split, A0).iterations, 1);
    stale = keptSolve(split, A1);
    s0 = perinox::mumpsPreconditionerStatistics(*split.preconditioner);
  }
  {
    auto split = perinox::buildSplitLinearSolver(keptFactorsList(100, 2), map->getComm()->getSize());
    EXPECT_EQ(keptSolve(split, A0).iterations, 1);
    renewed = keptSolve(split, A1);
    after = keptSolve(split, A1);
    s1 = perinox::mumpsPreconditionerStatistics(*split.preconditioner);
  }
  EXPECT_LT(stale.error, 1e-9);
  EXPECT_LT(renewed.error, 1e-9);
  EXPECT_LT(after.error, 1e-9);
  EXPECT_GT(stale.iterations, 8);
  EXPECT_EQ(s0.factorizations, 1);
  EXPECT_EQ(s0.factorizationsDuringSolves, 0);
  EXPECT_GE(renewed.iterations, 3);
  EXPECT_LE(renewed.iterations, 5);
  EXPECT_EQ(after.iterations, 1);
  EXPECT_EQ(s1.factorizations, 2);
  EXPECT_EQ(s1.factorizationsDuringSolves, 1);
}

// Renewing the factors within a solve needs a flexible Krylov solver: refused otherwise, naming
// the key and what it needs.
TEST(MumpsPreconditioner, RefactorDuringASolveNeedsFlexibleGmres) {
  EXPECT_NO_THROW(perinox::validateLinearSolverList(*keptFactorsList(20, 2), "the test list"));
  EXPECT_NO_THROW(perinox::validateLinearSolverList(*keptFactorsList(20, 0, false), "the test list"));
  try {
    perinox::validateLinearSolverList(*keptFactorsList(20, 2, false), "the test list");
    ADD_FAILURE() << "accepted a non-flexible GMRES with 'Refactor Within A Solve Above'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Refactor Within A Solve Above"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Flexible Gmres"), std::string::npos) << e.what();
  }
}

// Stale factors that each solve needs S applications of (S > 8, measured first; fresh ones need
// one) are kept by the per-solve rule ('Refactor Above Krylov Iterations' = 100) for ever. With
// 'Refactor Above Excess Applications' = E between the excess of one stale solve (S - 2) and that
// of two, they are renewed at the set-up after the second stale solve: the third solve needs one
// iteration. E = 0 keeps them. Counts only (iterations, factorisations): no timing.
TEST(MumpsPreconditioner, StaleFactorsAreRenewedOnceTheirExcessApplicationsAddUp) {
  auto map = makeMap();
  auto A0 = makeMatrix(map, 0), A1 = makeMatrix(map, 1);
  // The iterations of the solves of A0, A1, A1, A1 with one kept-factors solver allowing
  // `excessAbove`, and its statistics.
  auto solves = [&](int excessAbove, perinox::MumpsPreconditionerStatistics& stats) {
    auto split = perinox::buildSplitLinearSolver(keptFactorsList(100, 0, true, excessAbove), map->getComm()->getSize());
    std::vector<int> iterations;
    for (const auto& A : {A0, A1, A1, A1}) {
      const KeptSolve r = keptSolve(split, A);
      EXPECT_LT(r.error, 1e-9);
      iterations.push_back(r.iterations);
    }
    stats = perinox::mumpsPreconditionerStatistics(*split.preconditioner);
    return iterations;
  };
  perinox::MumpsPreconditionerStatistics sKept, sRenewed;
  const std::vector<int> kept = solves(0, sKept);
  const int S = kept[1];
  ASSERT_GT(S, 8);
  EXPECT_EQ(kept[0], 1);
  EXPECT_EQ(kept[2], S);
  EXPECT_EQ(kept[3], S);
  EXPECT_EQ(sKept.factorizations, 1);
  const int E = (3 * (S - 2)) / 2;  // more than one stale solve's excess, less than two
  ASSERT_GT(E, S - 2);
  ASSERT_LT(E, 2 * (S - 2));
  const std::vector<int> renewed = solves(E, sRenewed);
  EXPECT_EQ(renewed[0], 1);
  EXPECT_EQ(renewed[1], S);
  EXPECT_EQ(renewed[2], S);
  EXPECT_EQ(renewed[3], 1);
  EXPECT_EQ(sRenewed.factorizations, 2);
  EXPECT_EQ(sRenewed.factorizationsDuringSolves, 0);
}

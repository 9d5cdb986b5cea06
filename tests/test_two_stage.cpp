// The auxiliary V-cycle as the Two-Stage preconditioner applies it (auxiliaryCycle): entered at
// level 1 when MueLu's finest level has no smoother, it must give exactly the numbers of the
// hierarchy's own apply (which forms the finest residual B - A 0 with a product the shortcut
// skips). A 3D vector Laplacian (3 equations a node, a three-level hierarchy), on 1 and 2 ranks,
// also with the coarse levels repartitioned onto one rank (an import between levels 0 and 1, as
// the Two-Stage preconditioner asks on several ranks); with a smoothed finest level, and with the
// hierarchy on one level only, auxiliaryCycle must hand back the hierarchy itself.
#include <gtest/gtest.h>

#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <MueLu_Level.hpp>
#include <Teuchos_DefaultComm.hpp>
#include <Tpetra_Core.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <cmath>

#include "perinox/solver/TwoStagePreconditioner.hpp"

namespace {
using Node = Tpetra::Map<int, long long>::node_type;
using Map = Tpetra::Map<int, long long, Node>;
using Matrix = Tpetra::CrsMatrix<double, int, long long, Node>;
using MV = Tpetra::MultiVector<double, int, long long, Node>;
using OP = Tpetra::Operator<double, int, long long, Node>;

constexpr int M = 14;  // nodes along an edge: 2 744 nodes, 8 232 rows

// -Laplacian (7-point, Dirichlet outside) on each of 3 components, with a weak coupling between
// the components of one node so the blocks are not identical.
Teuchos::RCP<Matrix> makeMatrix() {
  auto comm = Teuchos::DefaultComm<int>::getComm();
  const long long n = 3LL * M * M * M;
  auto map = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(n), 0, comm));
  auto A = Teuchos::rcp(new Matrix(map, 9));
  for (std::size_t l = 0; l < map->getNodeNumElements(); ++l) {
    const long long row = map->getGlobalElement(static_cast<int>(l));
    const long long node = row / 3;
    const int c = static_cast<int>(row % 3);
    const int i = static_cast<int>(node % M), j = static_cast<int>((node / M) % M), k = static_cast<int>(node / (M * M));
    std::vector<long long> cols;
    std::vector<double> vals;
    cols.push_back(row);
    vals.push_back(6.0 + 0.5);
    for (int d = 1; d < 3; ++d) {
      cols.push_back(3 * node + (c + d) % 3);
      vals.push_back(-0.25);
    }
    const int off[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& o : off) {
      const int a = i + o[0], b = j + o[1], e = k + o[2];
      if (a < 0 || b < 0 || e < 0 || a >= M || b >= M || e >= M) continue;
      cols.push_back(3 * ((static_cast<long long>(e) * M + b) * M + a) + c);
      vals.push_back(-1.0);
    }
    A->insertGlobalValues(row, Teuchos::ArrayView<const long long>(cols), Teuchos::ArrayView<const double>(vals));
  }
  A->fillComplete();
  return A;
}

Teuchos::ParameterList parameters(bool smoothFinest, int maxLevels, bool repartition) {
  Teuchos::ParameterList p;
  p.set("verbosity", "none");
  p.set("number of equations", 3);
  p.set("max levels", maxLevels);
  p.set("coarse: max size", 100);
  p.set("smoother: type", "CHEBYSHEV");
  if (!smoothFinest) p.sublist("level 0").set("smoother: pre or post", "none");
  if (repartition) {  // the Two-Stage preconditioner's settings on several ranks, all moved to one
    p.set("repartition: enable", true);
    p.set("repartition: min rows per proc", 100000);
    p.set("repartition: start level", 1);
    p.set("repartition: partitioner", "zoltan2");
    p.sublist("repartition: params").set("algorithm", "multijagged");
  }
  return p;
}

// The nodes' coordinates on the node map (rows / 3; each rank's rows hold whole nodes), which
// the repartitioner needs.
Teuchos::RCP<MV> coordinates(const Teuchos::RCP<Matrix>& A) {
  const auto rows = A->getRowMap();
  const std::size_t local = rows->getNodeNumElements() / 3;
  auto nodes = Teuchos::rcp(new Map(static_cast<Tpetra::global_size_t>(M) * M * M, local, 0, rows->getComm()));
  auto c = Teuchos::rcp(new MV(nodes, 3));
  for (std::size_t l = 0; l < local; ++l) {
    const long long node = nodes->getGlobalElement(static_cast<int>(l));
    c->replaceLocalValue(static_cast<int>(l), 0, static_cast<double>(node % M));
    c->replaceLocalValue(static_cast<int>(l), 1, static_cast<double>((node / M) % M));
    c->replaceLocalValue(static_cast<int>(l), 2, static_cast<double>(node / (M * M)));
  }
  return c;
}

Teuchos::RCP<OP> hierarchy(const Teuchos::RCP<Matrix>& A, Teuchos::ParameterList p) {
  p.sublist("user data").set("Coordinates", coordinates(A));
  Teuchos::RCP<OP> op = A;
  return MueLu::CreateTpetraPreconditioner<double, int, long long, Node>(op, p);
}

double maxDifference(const MV& a, const MV& b, double& scale) {
  auto x = a.getData(0), y = b.getData(0);
  double local[2] = {0.0, 0.0};
  for (decltype(x.size()) i = 0; i < x.size(); ++i) {
    local[0] = std::max(local[0], std::abs(x[i] - y[i]));
    local[1] = std::max(local[1], std::abs(x[i]));
  }
  double global[2];
  Teuchos::reduceAll(*a.getMap()->getComm(), Teuchos::REDUCE_MAX, 2, local, global);
  scale = global[1];
  return global[0];
}
}  // namespace

void expectTheHierarchysOwnNumbers(bool repartition) {
  auto A = makeMatrix();
  const auto p = parameters(false, 3, repartition);
  auto H = hierarchy(A, p);
  if (repartition && A->getComm()->getSize() > 1) {
    // The case this test is for: level 1 reached through an import (MueLu's default keeps P and R
    // unrebalanced).
    auto muelu = Teuchos::rcp_dynamic_cast<MueLu::TpetraOperator<double, int, long long, Node>>(H);
    ASSERT_FALSE(muelu.is_null());
    ASSERT_TRUE(muelu->GetHierarchy()->GetLevel(1)->IsAvailable("Importer"));
  }
  auto cycle = perinox::auxiliaryCycle(H, p);
  ASSERT_NE(cycle.get(), H.get()) << "an unsmoothed finest level must be skipped";
  MV b(A->getRangeMap(), 1), own(A->getDomainMap(), 1), shortcut(A->getDomainMap(), 1);
  b.randomize();
  H->apply(b, own);
  shortcut.putScalar(7.0);  // overwritten, not accumulated
  cycle->apply(b, shortcut);
  double scale = 0.0;
  const double diff = maxDifference(own, shortcut, scale);
  EXPECT_GT(scale, 0.0);
  // The same operations in the same order: equal to the last bit (1e-15 allows for nothing else).
  EXPECT_LE(diff, 1e-15 * scale) << "difference " << diff << " against entries up to " << scale;
  // Applied again (buffers kept), with alpha and beta.
  MV y(A->getDomainMap(), 1);
  y.putScalar(1.0);
  cycle->apply(b, y, Teuchos::NO_TRANS, 2.0, 0.5);
  MV want(A->getDomainMap(), 1);
  want.putScalar(0.5);
  want.update(2.0, own, 1.0);
  EXPECT_LE(maxDifference(want, y, scale), 1e-14 * scale);
}

TEST(AuxiliaryCycle, EnteredAtLevelOneGivesTheHierarchysOwnNumbers) { expectTheHierarchysOwnNumbers(false); }

TEST(AuxiliaryCycle, EnteredAtLevelOneWithRepartitionedCoarseLevels) { expectTheHierarchysOwnNumbers(true); }

TEST(AuxiliaryCycle, SmoothedFinestLevelOrSingleLevelIsLeftToMueLu) {
  auto A = makeMatrix();
  const auto ps = parameters(true, 3, false), p1 = parameters(false, 1, false);
  auto smoothed = hierarchy(A, ps);
  EXPECT_EQ(perinox::auxiliaryCycle(smoothed, ps).get(), smoothed.get());
  auto single = hierarchy(A, p1);
  EXPECT_EQ(perinox::auxiliaryCycle(single, p1).get(), single.get());
  EXPECT_EQ(perinox::auxiliaryCycle(A, p1).get(), A.get());  // not a MueLu hierarchy
}

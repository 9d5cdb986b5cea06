// main() of the GoogleTest executables that run under MPI: Tpetra (and MPI) set up around the
// tests, and only rank 0 prints GoogleTest's report.
#include <gtest/gtest.h>

#include <Teuchos_DefaultComm.hpp>
#include <Tpetra_Core.hpp>

int main(int argc, char** argv) {
  Tpetra::ScopeGuard guard(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (Teuchos::DefaultComm<int>::getComm()->getRank() != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  return RUN_ALL_TESTS();
}

// Particle files: parsing, optional block column, and error messages naming file and line.
#include "perinox/core/Discretization.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

using namespace perinox;

namespace {

/// Writes `text` to a per-test, per-process temporary file and returns its path.
std::string writeTemp(const std::string& text) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string path = ::testing::TempDir() + "perinox_core_" + info->name() + "_" +
                           std::to_string(::getpid()) + ".txt";
  std::ofstream(path) << text;
  return path;
}

/// Expects readParticleFile to throw std::runtime_error containing "path:line:" and `word`.
void expectFileError(const std::string& text, int line, const std::string& word) {
  const std::string path = writeTemp(text);
  try {
    readParticleFile(path, 2, 1.0, 1.0, 1.0);
    ADD_FAILURE() << "expected std::runtime_error for:\n" << text;
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path + ":" + std::to_string(line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(word), std::string::npos) << msg;
  }
  std::remove(path.c_str());
}

}  // namespace

TEST(ParticleFile, ParsesGoodFile) {
  const std::string path = writeTemp(
      "# x y z volume [block]\n"
      "\n"
      "0 0 5 0.25\n"
      "  1.0 0 5 0.5 2   # trailing comment\n"
      "\t0 1e0 -5 2.5e-1 3.0\n"
      "1 1 0 0.125\n");
  const Discretization d = readParticleFile(path, 2, 1.5, 1.0, 0.1);
  std::remove(path.c_str());
  ASSERT_EQ(d.size(), 4);
  EXPECT_EQ(d.dim, 2);
  EXPECT_EQ(d.horizon, 1.5);
  EXPECT_EQ(d.dx, 1.0);
  EXPECT_EQ(d.thickness, 0.1);
  EXPECT_EQ(d.volume, (std::vector<double>{0.25, 0.5, 0.25, 0.125}));
  EXPECT_EQ(d.block, (std::vector<int>{1, 2, 3, 1}));
  EXPECT_EQ(d.X[1], Vec3(1, 0, 0));  // z ignored (set to 0) in 2D
  EXPECT_EQ(d.X[2], Vec3(0, 1, 0));
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(d.fictitious[i], 0);
    EXPECT_EQ(d.sideMask[i], 0);
    EXPECT_EQ(d.familySize(i), 3);  // diagonal sqrt(2) < 1.5
  }
  EXPECT_EQ(d.boxLower, Vec3(0, 0, 0));
  EXPECT_EQ(d.boxUpper, Vec3(1, 1, 0));
}

TEST(ParticleFile, ThreeDimensionalKeepsZ) {
  const std::string path = writeTemp("0 0 0 1\n0 0 2 1\n");
  const Discretization d = readParticleFile(path, 3, 1.0, 1.0, 1.0);
  std::remove(path.c_str());
  EXPECT_EQ(d.X[1], Vec3(0, 0, 2));
  EXPECT_EQ(d.familySize(0), 0);  // 2 > horizon 1
  EXPECT_EQ(d.boxUpper, Vec3(0, 0, 2));
}

TEST(ParticleFile, MalformedToken) { expectFileError("0 0 0 1\n\n1 2 x 4\n", 3, "'x'"); }
TEST(ParticleFile, TrailingGarbage) { expectFileError("# c\n1.0x 0 0 1\n", 2, "1.0x"); }
TEST(ParticleFile, TooFewNumbers) { expectFileError("1 2 3\n", 1, "at least 4"); }
TEST(ParticleFile, TooManyNumbers) { expectFileError("1 2 3 4 5 6\n", 1, "too many"); }
TEST(ParticleFile, NegativeVolume) { expectFileError("0 0 0 1\n1 0 0 -1\n", 2, "volume"); }
TEST(ParticleFile, ZeroVolume) { expectFileError("0 0 0 0\n", 1, "volume"); }
TEST(ParticleFile, NonFinite) { expectFileError("0 nan 0 1\n", 1, "finite"); }
TEST(ParticleFile, Overflow) { expectFileError("0 1e999 0 1\n", 1, "finite"); }
TEST(ParticleFile, NonIntegerBlock) { expectFileError("0 0 0 1 1.5\n", 1, "block"); }
TEST(ParticleFile, EmptyFile) { expectFileError("", 0, "no particles"); }
TEST(ParticleFile, CommentsOnly) { expectFileError("# nothing\n\n   \n", 3, "no particles"); }

TEST(ParticleFile, MissingFileAndBadParameters) {
  const std::string missing = ::testing::TempDir() + "perinox_core_does_not_exist.txt";
  try {
    readParticleFile(missing, 2, 1.0, 1.0, 1.0);
    ADD_FAILURE() << "expected an error for a missing file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing + ":"), std::string::npos) << e.what();
  }
  const std::string path = writeTemp("0 0 0 1\n");
  EXPECT_THROW(readParticleFile(path, 2, 0.0, 1.0, 1.0), std::runtime_error);
  EXPECT_THROW(readParticleFile(path, 2, -1.0, 1.0, 1.0), std::runtime_error);
  EXPECT_THROW(readParticleFile(path, 4, 1.0, 1.0, 1.0), std::runtime_error);
  std::remove(path.c_str());
}

TEST(ParticleFile, SpacingFromTheMedianVolume) {
  // Five particles: the median volume is the third smallest, whatever the order and the outliers.
  const std::string path = writeTemp("# five\n0 0 0 0.08\n1 0 0 0.0001\n2 0 0 0.02 3\n3 0 0 0.02\n4 0 0 5.0\n");
  EXPECT_DOUBLE_EQ(particleFileSpacing(path, 1, 0.5), 0.04);                 // 1D: volume / area
  EXPECT_DOUBLE_EQ(particleFileSpacing(path, 2, 0.5), std::sqrt(0.04));      // 2D: (volume / thickness)^(1/2)
  EXPECT_DOUBLE_EQ(particleFileSpacing(path, 3, 0.5), std::cbrt(0.02));      // 3D: volume^(1/3)
  // The whole file is checked: a bad line further down is reported with its number.
  const std::string bad = writeTemp("0 0 0 1\n1 0 0 -1\n");
  try {
    particleFileSpacing(bad, 2, 1.0);
    ADD_FAILURE() << "accepted a negative volume";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":2: volume must be positive"), std::string::npos) << e.what();
  }
}

// Interlacing matrices of the preset weaves (pkg/weave/Pattern.hpp) against their definitions, and
// the ParameterError raised for each kind of invalid input. Integer matrices: all checks are exact.
#include "core/Errors.hpp"
#include "weave/Pattern.hpp"
#include "chain_util.hpp"
#include <gtest/gtest.h>
#include <functional>
#include <numeric>
#include <string>

using woven::ParameterError;
using woven::Pattern;
using Matrix = std::vector<std::vector<int>>;

using woven_test::parameterOf;

namespace {

int rowSum(const Pattern& p, int i) {
  int s = 0;
  for (int j = 0; j < p.cols(); ++j) s += p.warpOver(i, j) ? 1 : 0;
  return s;
}
int colSum(const Pattern& p, int j) {
  int s = 0;
  for (int i = 0; i < p.rows(); ++i) s += p.warpOver(i, j) ? 1 : 0;
  return s;
}

}  // namespace

TEST(Pattern, PlainIsTheTwoByTwoCheckerboard) {
  const Pattern p = Pattern::plain();
  EXPECT_EQ(p.matrix(), (Matrix{{1, 0}, {0, 1}}));
  EXPECT_EQ(p.rows(), 2);
  EXPECT_EQ(p.cols(), 2);
  EXPECT_EQ(Pattern::byName("plain").matrix(), p.matrix());
}

TEST(Pattern, TwillRowsFloatOverThenUnderShiftedByOne) {
  for (int over = 1; over <= 4; ++over)
    for (int under = 1; under <= 4; ++under) {
      SCOPED_TRACE("twill " + std::to_string(over) + "/" + std::to_string(under));
      const Pattern p = Pattern::twill(over, under);
      const int n = over + under;
      ASSERT_EQ(p.rows(), n);
      ASSERT_EQ(p.cols(), n);
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(rowSum(p, i), over);
        EXPECT_EQ(colSum(p, i), over);  // a cyclic shift per row puts `over` ones in each column too
        // Definition: warp i is over wefts i, i+1, ..., i+over-1 (mod n), under the rest.
        for (int j = 0; j < n; ++j) EXPECT_EQ(p.warpOver(i, j), ((j - i + n) % n) < over) << i << "," << j;
        // Row i+1 is row i shifted by one weft.
        for (int j = 0; j < n; ++j) EXPECT_EQ(p.warpOver((i + 1) % n, (j + 1) % n), p.warpOver(i, j));
      }
      EXPECT_EQ(Pattern::byName("twill", over, under).matrix(), p.matrix());
    }
}

TEST(Pattern, SatinHasOneOverPerRowAndColumnAtTheMove) {
  const int cases[][2] = {{5, 2}, {5, 3}, {7, 2}, {7, 3}, {8, 3}, {8, 5}, {11, 4}};
  for (const auto& c : cases) {
    const int n = c[0], step = c[1];
    SCOPED_TRACE("satin " + std::to_string(n) + "/" + std::to_string(step));
    const Pattern p = Pattern::satin(n, step);
    ASSERT_EQ(p.rows(), n);
    ASSERT_EQ(p.cols(), n);
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(rowSum(p, i), 1);
      EXPECT_EQ(colSum(p, i), 1);
      EXPECT_TRUE(p.warpOver(i, (i * step) % n));
    }
    EXPECT_EQ(Pattern::byName("satin", n, step).matrix(), p.matrix());
  }
}

TEST(Pattern, BasketIsPlainWithEveryYarnRepeatedNTimes) {
  for (int n = 1; n <= 4; ++n) {
    SCOPED_TRACE("basket " + std::to_string(n));
    const Pattern p = Pattern::basket(n);
    const Pattern plain = Pattern::plain();
    ASSERT_EQ(p.rows(), 2 * n);
    ASSERT_EQ(p.cols(), 2 * n);
    for (int i = 0; i < 2 * n; ++i)
      for (int j = 0; j < 2 * n; ++j) EXPECT_EQ(p.warpOver(i, j), plain.warpOver(i / n, j / n)) << i << "," << j;
    EXPECT_EQ(Pattern::byName("basket", n).matrix(), p.matrix());
  }
  EXPECT_EQ(Pattern::basket(1).matrix(), Pattern::plain().matrix());
}

TEST(Pattern, UserMatrixIsKeptAsGiven) {
  const Matrix m{{1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};  // 4 warps x 3 wefts, all interlace
  const Pattern p(m);
  EXPECT_EQ(p.matrix(), m);
  EXPECT_EQ(p.rows(), 4);
  EXPECT_EQ(p.cols(), 3);
  EXPECT_TRUE(p.warpOver(0, 1));
  EXPECT_FALSE(p.warpOver(3, 2));
}

TEST(Pattern, BadMatricesThrowPatternError) {
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{}); }), "pattern");                       // empty
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{}, {}}); }), "pattern");                 // empty rows
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 0}, {0, 1, 0}}); }), "pattern");      // ragged
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 0}, {0, 2}}); }), "pattern");         // not 0/1
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, -1}, {0, 1}}); }), "pattern");        // not 0/1
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 1}, {0, 1}}); }), "pattern");         // warp 0 always over
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 0}, {0, 0}}); }), "pattern");         // warp 1 always under
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 0, 0}, {1, 0, 1}}); }), "pattern");   // weft 0 never interlaces
  EXPECT_EQ(parameterOf([] { Pattern p(Matrix{{1, 0, 1}, {0, 0, 1}}); }), "pattern");   // weft 1 never over, weft 2 always over
  EXPECT_EQ(parameterOf([] { Pattern::byName("jacquard"); }), "pattern");               // unknown name
}

TEST(Pattern, BadPresetParametersNameTheParameter) {
  EXPECT_EQ(parameterOf([] { Pattern::twill(0, 1); }), "twill_over");
  EXPECT_EQ(parameterOf([] { Pattern::twill(2, 0); }), "twill_under");
  EXPECT_EQ(parameterOf([] { Pattern::byName("twill", -1, 1); }), "twill_over");
  EXPECT_EQ(parameterOf([] { Pattern::satin(4, 2); }), "satin_n");   // fewer than 5 harnesses
  EXPECT_EQ(parameterOf([] { Pattern::satin(8, 2); }), "satin_step");  // gcd(8, 2) = 2: not coprime
  EXPECT_EQ(parameterOf([] { Pattern::satin(9, 3); }), "satin_step");  // gcd(9, 3) = 3
  EXPECT_EQ(parameterOf([] { Pattern::satin(5, 1); }), "satin_step");  // step 1 is a twill
  EXPECT_EQ(parameterOf([] { Pattern::satin(5, 4); }), "satin_step");  // step n-1 is a twill
  EXPECT_EQ(parameterOf([] { Pattern::byName("satin", 6, 4); }), "satin_step");
  EXPECT_EQ(parameterOf([] { Pattern::basket(0); }), "basket_n");
}

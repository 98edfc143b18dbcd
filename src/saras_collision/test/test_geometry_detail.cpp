// Tests of the bit-pattern predicates of the private header src/geometry_detail.h against the
// floating-point comparisons they stand for (no roscore, no library).
#include "geometry_detail.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace
{
using saras_collision::detail::bitsInOpenRange;
using saras_collision::detail::bitsOf;
using saras_collision::detail::notNearlyParallelBits;

double fromBits(std::uint64_t bits)
{
  double x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

/// Special values, their neighbours and random bit patterns (every class of double).
std::vector<double> testValues(const std::vector<double>& bounds)
{
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> xs = { 0.0,  -0.0, inf, -inf, std::numeric_limits<double>::quiet_NaN(),
                             -std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::min(), std::numeric_limits<double>::max(), 1.0, -1.0 };
  for (double b : bounds)
    for (double x : { b, -b })
    {
      xs.push_back(x);
      xs.push_back(std::nextafter(x, inf));
      xs.push_back(std::nextafter(x, -inf));
    }
  std::mt19937_64 gen(7);
  for (int i = 0; i < 200000; ++i)
    xs.push_back(fromBits(gen()));
  std::uniform_real_distribution<double> exponent(-320.0, 300.0);
  for (int i = 0; i < 200000; ++i)
    xs.push_back(std::pow(10.0, exponent(gen)));
  return xs;
}
}  // namespace

// bitsInOpenRange() is lo < x < hi for every double x (NaN: false), with the capsule-capsule
// fast path's bounds.
TEST(GeometryDetail, BitsInOpenRangeIsTheOpenIntervalForEveryDouble)
{
  const double his[] = { 0x1p238, 1.0 };
  const double los[] = { 0.0, 1e-30, 1e-290, std::numeric_limits<double>::denorm_min() };
  std::vector<double> bounds(std::begin(his), std::end(his));
  bounds.insert(bounds.end(), std::begin(los), std::end(los));
  const std::vector<double> xs = testValues(bounds);
  long checked = 0, inside = 0;
  for (double hi : his)
    for (double lo : los)
      for (double x : xs)
      {
        const bool expected = lo < x && x < hi;
        ASSERT_EQ(bitsInOpenRange(bitsOf(x), bitsOf(lo), bitsOf(hi)), expected)
            << x << " in (" << lo << ", " << hi << ")";
        inside += expected;
        ++checked;
      }
  EXPECT_GT(inside, checked / 10);
}

// notNearlyParallelBits(a, e, d) implies d > 1e-3 a e (never a false "not parallel") and holds
// whenever d > 1.23e-3 a e, over the whole range of normal a, e and of d / (a e) around the
// switch (products in long double, exact for these doubles' 53-bit significands up to rounding
// far below the margins).
TEST(GeometryDetail, NotNearlyParallelBitsBracketsTheAngleBound)
{
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> exponent(-30.0, 30.0), ratio(0.5e-3, 2e-3), unit(0.0, 1.0);
  long passed = 0, failed = 0;
  for (int i = 0; i < 2000000; ++i)
  {
    const double a = std::pow(10.0, exponent(gen)), e = std::pow(10.0, exponent(gen));
    const double d = (i % 100 == 0 ? -unit(gen) : ratio(gen)) * a * e;
    const long double r = static_cast<long double>(d) / (static_cast<long double>(a) * e);
    const bool pass = notNearlyParallelBits(bitsOf(a), bitsOf(e), bitsOf(d));
    if (pass)
    {
      ASSERT_GT(r, 1e-3L) << "a " << a << " e " << e << " d " << d;
      ++passed;
    }
    else
    {
      ASSERT_LE(r, 1.23e-3L) << "a " << a << " e " << e << " d " << d;
      ++failed;
    }
  }
  // Both outcomes occur in the switching band, and the bound is not far from 1e-3 (half of the
  // ratios in [0.5e-3, 2e-3] are above 1.25e-3).
  EXPECT_GT(passed, 2000000 / 3);
  EXPECT_GT(failed, 2000000 / 4);
  // d = 0, -0, NaN, and a d of the exact bound's neighbours.
  EXPECT_FALSE(notNearlyParallelBits(bitsOf(1.0), bitsOf(1.0), bitsOf(0.0)));
  EXPECT_FALSE(notNearlyParallelBits(bitsOf(1.0), bitsOf(1.0), bitsOf(-0.0)));
  EXPECT_FALSE(notNearlyParallelBits(bitsOf(1.0), bitsOf(1.0), bitsOf(-std::numeric_limits<double>::quiet_NaN())));
  EXPECT_FALSE(notNearlyParallelBits(bitsOf(1.0), bitsOf(1.0), bitsOf(1e-3)));
  EXPECT_TRUE(notNearlyParallelBits(bitsOf(1.0), bitsOf(1.0), bitsOf(1.24e-3)));
}

// zeroIfLess() is x < limit ? +0 : value, and unlessIntersecting() (the witness-point switch of
// every distance function) zeroes exactly where classify() says kIntersecting, at and one ulp
// around -kTangentTolerance.
TEST(GeometryDetail, ZeroIfLessAndTheWitnessSwitchAtTheLimit)
{
  const double limit = -saras_collision::kTangentTolerance;
  const double value = 0.75;
  for (double x : { limit, std::nextafter(limit, 0.0), std::nextafter(limit, -1.0), 0.0, -0.0, 1.0, -1.0,
                    std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::quiet_NaN() })
  {
    const double out = saras_collision::detail::zeroIfLess(x, &limit, value);
    const double witness = saras_collision::detail::unlessIntersecting(x, value);
    if (x < limit)
    {
      EXPECT_EQ(bitsOf(out), bitsOf(0.0)) << x;
    }
    else
    {
      EXPECT_EQ(out, value) << x;
    }
    EXPECT_EQ(bitsOf(witness), bitsOf(out)) << x;
    EXPECT_EQ(witness == 0.0, saras_collision::detail::classify(x) == saras_collision::kIntersecting) << x;
  }
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

// Linked into saras_collision_test_geometry_v3 only (compiled for the baseline x86-64, unlike
// the geometry code of that test, which is built with -march=x86-64-v3): skips every test on a
// CPU that cannot run x86-64-v3 code (AVX2, FMA, BMI2, ...) instead of dying on an illegal
// instruction.
#include <gtest/gtest.h>

namespace
{
class RequireX86_64V3 : public ::testing::Environment
{
public:
  void SetUp() override
  {
    if (!__builtin_cpu_supports("x86-64-v3"))
      GTEST_SKIP() << "this CPU cannot run x86-64-v3 code; the library's loader picks another clone here";
  }
};

// gtest owns the environment; registered before main() runs the tests, as TEST() cases are.
::testing::Environment* const kRequireX86_64V3 = ::testing::AddGlobalTestEnvironment(new RequireX86_64V3);
}  // namespace

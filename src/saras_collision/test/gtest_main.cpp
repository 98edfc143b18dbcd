// main() of the geometry gtest executable (test_capsule_capsule.cpp, test_box.cpp).
#include <gtest/gtest.h>

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

// ImagePool: a buffer is handed out again only when nobody else holds it; the most recently
// released one first; no allocation in steady state.
#include <gtest/gtest.h>

#include <vector>

#include "saras_visual_feedback/image_pool.h"

using saras_visual_feedback::ImagePool;

TEST(ImagePool, ReusesTheLastReleasedBufferWithoutAllocating)
{
  ImagePool pool;
  const std::size_t bytes = 1920 * 1080 * 3;
  sensor_msgs::ImagePtr a = pool.acquire(bytes);
  ASSERT_EQ(a->data.size(), bytes);
  const sensor_msgs::Image* first = a.get();
  const std::uint8_t* first_data = a->data.data();
  a.reset();  // the subscriber released it
  for (int i = 0; i < 100; ++i)
  {
    sensor_msgs::ImagePtr b = pool.acquire(bytes);
    EXPECT_EQ(b.get(), first);  // same message, same (warm) data buffer
    EXPECT_EQ(b->data.data(), first_data);
  }
  EXPECT_EQ(pool.allocations(), 1u);
}

TEST(ImagePool, NeverHandsOutABufferStillHeld)
{
  ImagePool pool;
  std::vector<sensor_msgs::ImagePtr> held;
  for (std::size_t i = 0; i < ImagePool::kSize + 3; ++i)
  {
    held.push_back(pool.acquire(16));
    for (std::size_t j = 0; j + 1 < held.size(); ++j)
      EXPECT_NE(held.back().get(), held[j].get()) << "buffer " << j << " handed out twice";
  }
  EXPECT_EQ(pool.allocations(), ImagePool::kSize + 3);
  // Readers keep the replaced buffers alive and unchanged.
  held[0]->data[0] = 42;
  held.resize(1);
  sensor_msgs::ImagePtr c = pool.acquire(16);
  EXPECT_NE(c.get(), held[0].get());
  EXPECT_EQ(held[0]->data[0], 42);
}

TEST(ImagePool, ResizesOnSizeChange)
{
  ImagePool pool;
  pool.acquire(100);
  sensor_msgs::ImagePtr b = pool.acquire(300);
  EXPECT_EQ(b->data.size(), 300u);
  EXPECT_EQ(pool.allocations(), 1u);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

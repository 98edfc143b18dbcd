// gtest of saras_bringup::BoundedQueue (the bag recorder's hand-off queue), no roscore.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "saras_bringup/bounded_queue.h"

using saras_bringup::BoundedQueue;
using std::chrono::milliseconds;

TEST(BoundedQueue, FifoWithinBudget)
{
  BoundedQueue<int> q(100);
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(q.push(i, 10), 0u);
  EXPECT_EQ(q.size(), 10u);
  int v = -1;
  for (int i = 0; i < 10; ++i)
  {
    ASSERT_TRUE(q.pop(v, milliseconds(0)));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(q.pop(v, milliseconds(1)));
  EXPECT_EQ(q.dropped(), 0u);
  EXPECT_EQ(q.pushed(), 10u);
  EXPECT_EQ(q.peakBytes(), 100u);
}

TEST(BoundedQueue, DropsTheOldestBeyondTheBudgetAndCountsThem)
{
  BoundedQueue<int> q(100);
  for (int i = 0; i < 10; ++i)
    q.push(i, 10);
  EXPECT_EQ(q.push(10, 25), 3u);  // 125 bytes: the three oldest go (95 left)
  EXPECT_EQ(q.dropped(), 3u);
  int v = -1;
  ASSERT_TRUE(q.pop(v, milliseconds(0)));
  EXPECT_EQ(v, 3);
  // an item larger than the budget is kept alone
  EXPECT_EQ(q.push(99, 1000), 7u);
  EXPECT_EQ(q.size(), 1u);
  ASSERT_TRUE(q.pop(v, milliseconds(0)));
  EXPECT_EQ(v, 99);
}

TEST(BoundedQueue, ProducersAndOneConsumerLoseNothingWithinBudget)
{
  BoundedQueue<int> q(1 << 20);
  constexpr int kPerProducer = 20000;
  std::vector<std::thread> producers;
  for (int p = 0; p < 3; ++p)
    producers.emplace_back([&q, p] {
      for (int i = 0; i < kPerProducer; ++i)
        q.push(p * kPerProducer + i, 8);
    });
  std::vector<int> last(3, -1);
  int received = 0;
  bool ordered = true;
  int v = 0;
  while (received < 3 * kPerProducer && q.pop(v, milliseconds(2000)))
  {
    const int p = v / kPerProducer;
    ordered = ordered && v > last[p];  // per producer in order
    last[p] = v;
    ++received;
  }
  for (auto& t : producers)
    t.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(received, 3 * kPerProducer);
  EXPECT_EQ(q.dropped(), 0u);
}

TEST(BoundedQueue, CloseWakesAWaitingConsumer)
{
  BoundedQueue<int> q(10);
  std::atomic<bool> returned{ false };
  std::thread consumer([&] {
    int v;
    EXPECT_FALSE(q.pop(v, milliseconds(10000)));
    returned = true;
  });
  std::this_thread::sleep_for(milliseconds(50));
  const auto t0 = std::chrono::steady_clock::now();
  q.close();
  consumer.join();
  EXPECT_TRUE(returned);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, milliseconds(2000));
  q.push(5, 1);  // items pushed after close can still be drained
  int v = 0;
  EXPECT_TRUE(q.pop(v, milliseconds(0)));
  EXPECT_EQ(v, 5);
}

TEST(BoundedQueue, WithAWakeThresholdSmallItemsDoNotWakeTheConsumerButLargeOnesDo)
{
  BoundedQueue<int> q(1000, 100);
  std::atomic<int> got{ 0 };
  std::atomic<bool> go_on{ true };
  std::thread consumer([&] {
    int v;
    while (go_on)
      if (q.pop(v, milliseconds(10000)))
        got = v;
  });
  std::this_thread::sleep_for(milliseconds(50));
  q.push(1, 10);  // below the threshold: the waiting consumer sleeps on (its timeout is 10 s)
  std::this_thread::sleep_for(milliseconds(300));
  EXPECT_EQ(got, 0);
  EXPECT_EQ(q.size(), 1u);
  q.push(2, 95);  // 105 bytes queued: wakes it, it drains both
  for (int i = 0; i < 200 && got != 2; ++i)
    std::this_thread::sleep_for(milliseconds(10));
  EXPECT_EQ(got, 2);
  EXPECT_EQ(q.size(), 0u);
  go_on = false;
  q.close();
  consumer.join();
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

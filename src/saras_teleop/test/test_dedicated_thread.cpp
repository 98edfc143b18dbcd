// DedicatedCallbackThread (src/nodes/node_common.h): the teleop nodelets' callbacks run on one
// thread of their own, never concurrently, in the order they were queued.
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "../src/nodes/node_common.h"

namespace
{
class Probe : public ros::CallbackInterface
{
public:
  Probe(std::atomic<int>& inside, std::atomic<int>& max_inside, std::mutex& m, std::set<std::thread::id>& ids,
        std::vector<int>& order, int tag)
    : inside_(inside), max_inside_(max_inside), m_(m), ids_(ids), order_(order), tag_(tag)
  {
  }
  CallResult call() override
  {
    const int now = ++inside_;
    int seen = max_inside_.load();
    while (now > seen && !max_inside_.compare_exchange_weak(seen, now))
    {
    }
    std::this_thread::sleep_for(std::chrono::microseconds(20));  // widen any overlap
    {
      std::lock_guard<std::mutex> lock(m_);
      ids_.insert(std::this_thread::get_id());
      order_.push_back(tag_);
    }
    --inside_;
    return Success;
  }

private:
  std::atomic<int>& inside_;
  std::atomic<int>& max_inside_;
  std::mutex& m_;
  std::set<std::thread::id>& ids_;
  std::vector<int>& order_;
  int tag_;
};

/// The thread under test and what its callbacks record.
class DedicatedCallbackThreadTest : public ::testing::Test
{
protected:
  boost::shared_ptr<Probe> probe(int tag) { return boost::make_shared<Probe>(inside, max_inside, m, ids, order, tag); }

  std::atomic<int> inside{ 0 }, max_inside{ 0 };
  std::mutex m;
  std::set<std::thread::id> ids;
  std::vector<int> order;
  saras_teleop::node::DedicatedCallbackThread t;  // last: stopped before what its callbacks touch
};
}  // namespace

TEST_F(DedicatedCallbackThreadTest, OneThreadNoOverlapInOrder)
{
  t.start();
  constexpr int kPerProducer = 500;
  auto produce = [&](int base) {
    for (int i = 0; i < kPerProducer; ++i)
      t.queue()->addCallback(probe(base + i));
  };
  std::thread a(produce, 0), b(produce, 100000);
  a.join();
  b.join();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < end)
  {
    std::lock_guard<std::mutex> lock(m);
    if (order.size() == 2u * kPerProducer)
      break;
  }
  t.stop();
  std::lock_guard<std::mutex> lock(m);
  ASSERT_EQ(order.size(), 2u * kPerProducer);
  EXPECT_EQ(max_inside.load(), 1);  // never two callbacks at once
  ASSERT_EQ(ids.size(), 1u);        // one thread ...
  EXPECT_NE(*ids.begin(), std::this_thread::get_id());  // ... of its own
  // each producer's callbacks in the order they were queued
  int last_a = -1, last_b = 99999;
  for (int tag : order)
  {
    int& last = tag >= 100000 ? last_b : last_a;
    EXPECT_EQ(tag, last + 1);
    last = tag;
  }
}

TEST_F(DedicatedCallbackThreadTest, StoppedThreadRunsNothing)
{
  t.start();
  t.stop();
  t.queue()->addCallback(probe(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  std::lock_guard<std::mutex> lock(m);
  EXPECT_TRUE(order.empty());
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_dedicated_thread", ros::init_options::NoRosout | ros::init_options::AnonymousName);
  return RUN_ALL_TESTS();  // no roscore needed: ros::ok() is true after ros::init
}

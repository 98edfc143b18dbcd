// MessagePool: a slot is handed out again only when nobody else holds it; the most recently handed-out
// free slot first; no allocation in steady state (zero-copy intra-process publishing).
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "saras_common/message_pool.h"

namespace
{
struct Msg
{
  std::string frame_id;
  double value = 0.0;
};

struct Image  // the shape of sensor_msgs::Image that nextWithData() relies on
{
  std::uint32_t width = 0;
  std::vector<std::uint8_t> data;
};
}  // namespace

using saras_common::MessagePool;

TEST(MessagePool, PrototypeCopiedIntoEverySlot)
{
  Msg proto;
  proto.frame_id = "mesa_left/sbs_world";
  MessagePool<Msg> pool(3, proto);
  std::vector<boost::shared_ptr<Msg>> held;
  for (int i = 0; i < 3; ++i)
    held.push_back(pool.next());
  held.push_back(pool.next());  // a replacement slot is a copy of the prototype too
  for (const auto& m : held)
    EXPECT_EQ(m->frame_id, "mesa_left/sbs_world");
  EXPECT_EQ(pool.size(), 3u);
  EXPECT_EQ(pool.prototype().frame_id, "mesa_left/sbs_world");
  EXPECT_THROW(MessagePool<Msg>(0), std::invalid_argument);
}

TEST(MessagePool, PromptlyReleasedSlotIsReusedWithoutAllocation)
{
  MessagePool<Msg> pool(4);
  const Msg* first = pool.next().get();
  for (int i = 0; i < 1000; ++i)
  {
    boost::shared_ptr<Msg> m = pool.next();  // dropped at the end of the iteration, like a publish
    EXPECT_EQ(m.get(), first);               // the same (cache-warm) object every time
    m->value = i;
  }
  EXPECT_EQ(pool.allocations(), 0u);
}

TEST(MessagePool, HeldMessagesAreNeverOverwritten)
{
  MessagePool<Msg> pool(4);
  std::vector<boost::shared_ptr<const Msg>> held;  // a subscriber queue that keeps every message
  for (int i = 0; i < 10; ++i)
  {
    boost::shared_ptr<Msg> m = pool.next();
    for (const auto& h : held)
      ASSERT_NE(h.get(), m.get()) << "slot handed out while still referenced, i=" << i;
    m->value = i;
    held.push_back(m);
  }
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(held[i]->value, i);     // contents intact
  EXPECT_EQ(pool.allocations(), 6u);  // 10 held messages, 4 slots

  // the subscriber releases everything: slots are reused again, no more allocations
  held.clear();
  for (int i = 0; i < 100; ++i)
    pool.next()->value = -i;
  EXPECT_EQ(pool.allocations(), 6u);
}

TEST(MessagePool, ReleasedSlotIsFoundAmongHeldOnes)
{
  MessagePool<Msg> pool(3);
  boost::shared_ptr<Msg> a = pool.next(), b = pool.next(), c = pool.next();
  ASSERT_NE(a.get(), b.get());
  ASSERT_NE(b.get(), c.get());
  const Msg* pb = b.get();
  b.reset();  // only b's subscriber finished
  boost::shared_ptr<Msg> d = pool.next();
  EXPECT_EQ(d.get(), pb);
  EXPECT_EQ(pool.allocations(), 0u);
}

TEST(MessagePool, ImageBufferIsSizedOnceAndReused)
{
  MessagePool<Image> pool(6);
  const std::size_t bytes = 1920 * 1080 * 3;
  boost::shared_ptr<Image> a = pool.nextWithData(bytes);
  ASSERT_EQ(a->data.size(), bytes);
  const std::uint8_t* buffer = a->data.data();
  EXPECT_EQ(pool.allocations(), 1u);  // the first frame sizes the buffer
  a.reset();
  for (int i = 0; i < 100; ++i)
  {
    boost::shared_ptr<Image> b = pool.nextWithData(bytes);
    EXPECT_EQ(b->data.data(), buffer);  // same buffer: no allocation, no page faults
  }
  // a smaller frame (another resolution) and back: the buffer keeps its capacity
  EXPECT_EQ(pool.nextWithData(640 * 480 * 3)->data.size(), 640u * 480u * 3u);
  EXPECT_EQ(pool.nextWithData(bytes)->data.data(), buffer);
  EXPECT_EQ(pool.allocations(), 1u);
  // a larger frame grows the buffer: counted
  EXPECT_EQ(pool.nextWithData(bytes + 1)->data.size(), bytes + 1);
  EXPECT_EQ(pool.allocations(), 2u);
}

TEST(MessagePool, HeldImageKeepsItsPixels)
{
  MessagePool<Image> pool(2);
  boost::shared_ptr<Image> a = pool.nextWithData(16);
  a->data[0] = 42;
  boost::shared_ptr<Image> b = pool.nextWithData(16), c = pool.nextWithData(16);
  b->data[0] = 1;
  c->data[0] = 2;
  EXPECT_NE(c.get(), a.get());
  EXPECT_NE(c.get(), b.get());
  EXPECT_EQ(a->data[0], 42);
  EXPECT_EQ(b->data[0], 1);
}

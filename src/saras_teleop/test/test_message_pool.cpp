// MessagePool: a slot is reused only when nobody else holds it (zero-copy intra-process publishing).
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "saras_teleop/message_pool.h"

namespace
{
struct Msg
{
  std::string frame_id;
  double value = 0.0;
};
}  // namespace

using saras_teleop::MessagePool;

TEST(MessagePool, PrototypeCopiedIntoEverySlot)
{
  Msg proto;
  proto.frame_id = "mesa_left/sbs_world";
  MessagePool<Msg> pool(3, proto);
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(pool.next()->frame_id, "mesa_left/sbs_world");
  EXPECT_EQ(pool.allocations(), 0u);
  EXPECT_THROW(MessagePool<Msg>(0), std::invalid_argument);
}

TEST(MessagePool, FreedSlotsAreReusedWithoutAllocation)
{
  MessagePool<Msg> pool(4);
  std::set<const Msg*> seen;
  for (int i = 0; i < 1000; ++i)
  {
    boost::shared_ptr<Msg> m = pool.next();  // dropped at the end of the iteration, like a publish
    m->value = i;
    seen.insert(m.get());
  }
  EXPECT_EQ(seen.size(), 4u);  // only the preallocated objects were ever handed out
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
    EXPECT_EQ(held[i]->value, i);  // contents intact
  EXPECT_EQ(pool.allocations(), 6u);  // 10 held messages, 4 slots

  // subscriber releases everything: the (new) slots are reused again, no more allocations
  held.clear();
  for (int i = 0; i < 100; ++i)
    pool.next()->value = -i;
  EXPECT_EQ(pool.allocations(), 6u);
}

TEST(MessagePool, ReleasedSlotIsFoundAmongHeldOnes)
{
  MessagePool<Msg> pool(3);
  boost::shared_ptr<Msg> a = pool.next(), b = pool.next(), c = pool.next();
  const Msg* pb = b.get();
  b.reset();  // only b's subscriber finished
  boost::shared_ptr<Msg> d = pool.next();
  EXPECT_EQ(d.get(), pb);
  EXPECT_EQ(pool.allocations(), 0u);
}

// gtest of saras_bringup::BagWriter (the recorder's bag side), no roscore: typed messages serialised
// into pooled buffers and ShapeShifter messages end up in the bag with their types and values.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <unistd.h>

#include <boost/make_shared.hpp>
#include <geometry_msgs/PoseStamped.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/Float64.h>

#include "saras_bringup/bag_writer.h"

using saras_bringup::BagWriter;
using saras_bringup::BagWriterOptions;

namespace
{
std::string tmpBag(const char* name)
{
  return "/tmp/test_bag_writer_" + std::to_string(getpid()) + "_" + name + ".bag";
}

/// A ShapeShifter holding @p m, as roscpp hands a message received over TCP to the recorder.
template <class M>
topic_tools::ShapeShifter::ConstPtr shift(const M& m)
{
  std::vector<std::uint8_t> buf(ros::serialization::serializationLength(m));
  ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
  ros::serialization::serialize(out, m);
  auto s = boost::make_shared<topic_tools::ShapeShifter>();
  s->morph(ros::message_traits::md5sum<M>(), ros::message_traits::datatype<M>(),
           ros::message_traits::definition<M>(), "0");
  ros::serialization::IStream in(buf.data(), static_cast<std::uint32_t>(buf.size()));
  s->read(in);
  return s;
}
}  // namespace

TEST(BagWriter, TypedAndShiftedMessagesAreWrittenWithTheirTypes)
{
  ros::Time::init();
  BagWriterOptions o;
  o.output = tmpBag("mixed");
  o.buffer_mb = 16;
  BagWriter w(o, { "/pose", "/energy" });
  w.setType<geometry_msgs::PoseStamped>(0);
  w.start();
  for (int i = 0; i < 500; ++i)
  {
    geometry_msgs::PoseStamped p;
    p.header.seq = 7777;  // the writer numbers the topic's messages itself
    p.header.frame_id = "world";
    p.pose.position.x = 0.001 * i;
    p.pose.orientation.w = 1.0;
    w.pushTyped(0, p, ros::Time(100, 0) + ros::Duration(0.001 * i));
    std_msgs::Float64 e;
    e.data = 10.0 - 0.01 * i;
    w.push(1, shift(e), nullptr, ros::Time(100, 0) + ros::Duration(0.001 * i));
  }
  EXPECT_TRUE(w.stop());
  EXPECT_NE(access((o.output + ".active").c_str(), F_OK), 0);  // renamed when closed

  rosbag::Bag bag(o.output, rosbag::bagmode::Read);
  int poses = 0, energies = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag))
  {
    if (m.getTopic() == "/pose")
    {
      EXPECT_EQ(m.getDataType(), "geometry_msgs/PoseStamped");
      const auto p = m.instantiate<geometry_msgs::PoseStamped>();
      ASSERT_TRUE(p != nullptr);
      EXPECT_EQ(p->header.seq, static_cast<unsigned>(poses));
      EXPECT_EQ(p->header.frame_id, "world");
      EXPECT_DOUBLE_EQ(p->pose.position.x, 0.001 * poses);
      EXPECT_EQ(m.getTime(), ros::Time(100, 0) + ros::Duration(0.001 * poses));
      ++poses;
    }
    else
    {
      const auto e = m.instantiate<std_msgs::Float64>();
      ASSERT_TRUE(e != nullptr);
      EXPECT_DOUBLE_EQ(e->data, 10.0 - 0.01 * energies);
      ++energies;
    }
  }
  EXPECT_EQ(poses, 500);
  EXPECT_EQ(energies, 500);
  bag.close();
  std::remove(o.output.c_str());
}

TEST(BagWriter, NothingIsQueuedAfterStop)
{
  BagWriterOptions o;
  o.output = tmpBag("stop");
  o.buffer_mb = 16;
  BagWriter w(o, { "/x" });
  w.setType<std_msgs::Float64>(0);
  w.start();
  std_msgs::Float64 e;
  w.pushTyped(0, e, ros::Time(1, 0));
  EXPECT_TRUE(w.stop());
  w.pushTyped(0, e, ros::Time(2, 0));  // ignored, no crash
  EXPECT_TRUE(w.stop());               // second stop: no-op
  rosbag::Bag bag(o.output, rosbag::bagmode::Read);
  EXPECT_EQ(rosbag::View(bag).size(), 1u);
  bag.close();
  std::remove(o.output.c_str());
}

TEST(BagWriter, AnUnwritablePathThrowsAtStart)
{
  BagWriterOptions o;
  o.output = "/nonexistent_dir/x.bag";
  BagWriter w(o, { "/x" });
  EXPECT_THROW(w.start(), rosbag::BagException);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

/**
 * channel: delay / jitter / loss model on the master <-> slave link, for experiments and the demo.
 * Nodelet saras_teleop/Channel; executable channel.
 *
 * For every topic T in ~topics (any message type, relayed with topic_tools::ShapeShifter) it
 * subscribes T and republishes on T + ~suffix after ~delay_ms plus U(0, ~jitter_ms), dropping
 * messages with the Gilbert-Elliott model (~loss in [0, 1), ~burst_length mean consecutive drops).
 * Order is preserved. With delay 0 and no jitter the message is forwarded inside the callback.
 * ~seed makes a run reproducible. Timer at ~rate Hz delivers due messages.
 */
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <pluginlib/class_list_macros.hpp>
#include <topic_tools/shape_shifter.h>

#include "node_common.h"
#include "saras_teleop/delay_channel.h"

namespace saras_teleop
{
namespace node
{
class ChannelNode
{
public:
  ChannelNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& /*name*/) : nh_(nh)
  {
    using saras_common::nonNegative;
    const saras_common::Params prm(pnh);
    ChannelParams p;
    p.delay = prm.number("delay_ms", 0.0, "ms", { nonNegative() }) * 1e-3;
    p.jitter = prm.number("jitter_ms", 0.0, "ms", { nonNegative() }) * 1e-3;
    p.loss = prm.number("loss", 0.0, "", { nonNegative() });  // < 1: ChannelParams::validate()
    p.burst_length = prm.number("burst_length", 1.0, "messages", { saras_common::atLeast(1.0) });
    p.seed = static_cast<std::uint32_t>(prm.integer("seed", 1, "", { nonNegative() }));
    p.validate();
    suffix_ = prm.text("suffix", "_delayed", { saras_common::nonEmpty() });
    const double rate = prm.number("rate", 2000.0, "Hz", { saras_common::positive() });
    const std::vector<std::string> topics = prm.texts("topics", {}, { saras_common::nonEmpty() });
    if (topics.empty())
      prm.fail("topics", "[]", "", "a non-empty list of topics");
    passthrough_ = p.delay == 0.0 && p.jitter == 0.0;
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    for (std::size_t i = 0; i < topics.size(); ++i)
    {
      std::unique_ptr<Link> l(new Link(p));
      l->params.seed = p.seed + static_cast<std::uint32_t>(i) * 7919u;
      l->channel.reset(new DelayChannel<topic_tools::ShapeShifter::ConstPtr>(l->params));
      l->out_name = topics[i] + suffix_;
      Link* raw = l.get();
      l->sub = nh.subscribe<topic_tools::ShapeShifter>(
          topics[i], 100, [this, raw](const topic_tools::ShapeShifter::ConstPtr& m) { onMessage(*raw, m); },
          ros::VoidConstPtr(), fast);
      links_.push_back(std::move(l));
    }
    timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / rate), &ChannelNode::onTimer, this);
    ROS_INFO("channel: %zu topic(s), delay %.1f ms, jitter %.1f ms, loss %.3f (burst %.1f)", topics.size(),
             p.delay * 1e3, p.jitter * 1e3, p.loss, p.burst_length);
  }

private:
  struct Link
  {
    explicit Link(const ChannelParams& p) : params(p) {}
    ChannelParams params;
    std::unique_ptr<DelayChannel<topic_tools::ShapeShifter::ConstPtr>> channel;
    std::string out_name;
    ros::Subscriber sub;
    ros::Publisher pub;
    bool advertised = false;
  };

  void onMessage(Link& l, const topic_tools::ShapeShifter::ConstPtr& m)
  {
    if (!l.advertised)
    {
      l.pub = m->advertise(nh_, l.out_name, 100);
      l.advertised = true;
    }
    const double now = ros::Time::now().toSec();
    if (!l.channel->push(m, now))
      return;
    if (passthrough_)
      l.channel->deliver(now, [&l](const topic_tools::ShapeShifter::ConstPtr& x) { l.pub.publish(*x); });
  }

  void onTimer(const ros::SteadyTimerEvent&)
  {
    const double now = ros::Time::now().toSec();
    for (auto& l : links_)
    {
      Link& r = *l;
      r.channel->deliver(now, [&r](const topic_tools::ShapeShifter::ConstPtr& x) { r.pub.publish(*x); });
    }
  }

  ros::NodeHandle nh_;
  std::vector<std::unique_ptr<Link>> links_;
  std::string suffix_;
  bool passthrough_ = false;
  ros::SteadyTimer timer_;
};

/// Nodelet `saras_teleop/Channel` (nodelet_plugins.xml).
class ChannelNodelet : public NodeletAdapter<ChannelNode>
{
};

}  // namespace node
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::node::ChannelNodelet, nodelet::Nodelet)

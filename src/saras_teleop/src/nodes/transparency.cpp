/**
 * transparency: transparency layer for every channel in ~channels (one instance).
 * Nodelet saras_teleop/Transparency; executable transparency.
 *
 * Per channel c (relative names): sub c/master_pose (PoseStamped, slave base frame), c/master_twist
 * (TwistStamped), c/slave_pose (PoseStamped, measured slave pose), c/device_state
 * (saras_msgs/HapticDeviceState: clutch, stale), c/fixture_wrench (WrenchStamped, optional virtual
 * fixture in the slave base frame), c/contact_force (geometry_msgs/Twist, linear = force of the
 * tissue on the tool [N] in the slave base frame, D7.2 Section 8; reflected on the master scaled by
 * contact_force_scale while contact_feedback is true); sub link_status (saras_msgs/ComponentStatus, STALE => hold);
 * pub c/des_wrench (WrenchStamped), c/des_twist (TwistStamped), both in mesa_<c>/sbs_world.
 * Computes a channel when its master twist arrives (event-driven, stamps propagated); a ~rate
 * timer recomputes a channel whose twists stopped and publishes zero set-points once it holds
 * (inputs older than ~input_timeout, clutch, link STALE); while every channel's twists flow the
 * timer runs at ~watchdog_rate instead (PacedTimer, node_common.h).
 * Params: pose_error_gain [N/m], scale_factor, rotation_scale, max_force [N], rate [Hz], watchdog_rate [Hz],
 * input_timeout [s] (master/slave inputs older than this => hold), fixture_timeout [s],
 * contact_feedback (bool), contact_force_scale [-], contact_timeout [s] (older contact force => zero).
 */
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <pluginlib/class_list_macros.hpp>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/HapticDeviceState.h>

#include "node_common.h"
#include "saras_common/message_pool.h"
#include "saras_teleop/transparency.h"

namespace saras_teleop
{
namespace node
{
class TransparencyNode
{
public:
  /// @param name node or nodelet name (the /diagnostics status is "<name>: transparency")
  TransparencyNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name)
  {
    using saras_common::nonNegative;
    using saras_common::positive;
    const saras_common::Params prm(pnh);
    TransparencyParams p;
    p.pose_error_gain = prm.number("pose_error_gain", p.pose_error_gain, "N/m", { nonNegative() });
    p.scale_factor = prm.number("scale_factor", p.scale_factor, "", { positive() });
    p.rotation_scale = prm.number("rotation_scale", p.rotation_scale, "", { nonNegative() });
    p.max_force = prm.number("max_force", p.max_force, "N", { positive() });
    p.contact_feedback = prm.flag("contact_feedback", p.contact_feedback);
    p.contact_force_scale = prm.number("contact_force_scale", p.contact_force_scale, "", { nonNegative() });
    p.validate();
    contact_feedback_ = p.contact_feedback;
    const double rate = prm.number("rate", 1000.0, "Hz", { positive() });
    period_ = 1.0 / rate;
    const double watchdog = prm.number("watchdog_rate", 100.0, "Hz", { positive() });
    input_timeout_ = prm.number("input_timeout", 0.1, "s", { positive() });
    fixture_timeout_ = prm.number("fixture_timeout", 0.2, "s", { positive() });
    contact_timeout_ = prm.number("contact_timeout", 0.2, "s", { positive() });
    const std::vector<std::string> channels = paramChannels(prm);

    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    ch_.resize(channels.size());
    for (std::size_t i = 0; i < channels.size(); ++i)
    {
      Channel& c = ch_[i];
      const std::string& n = channels[i];
      c.name = n;
      c.core.reset(new TransparencyChannel(p));
      geometry_msgs::WrenchStamped wrench;
      geometry_msgs::TwistStamped twist;
      wrench.header.frame_id = twist.header.frame_id = "mesa_" + n + "/sbs_world";
      c.wrench_pool.reset(new MessagePool<geometry_msgs::WrenchStamped>(kPoolSize, wrench));
      c.twist_pool.reset(new MessagePool<geometry_msgs::TwistStamped>(kPoolSize, twist));
      c.pub_wrench = nh.advertise<geometry_msgs::WrenchStamped>(n + "/des_wrench", kStreamQueue);
      c.pub_twist = nh.advertise<geometry_msgs::TwistStamped>(n + "/des_twist", kStreamQueue);
      c.subs.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
          n + "/master_pose", 10, [this, i](const geometry_msgs::PoseStamped::ConstPtr& m) { onMasterPose(i, *m); },
          ros::VoidConstPtr(), fast));
      c.subs.push_back(nh.subscribe<geometry_msgs::TwistStamped>(
          n + "/master_twist", 10,
          [this, i](const geometry_msgs::TwistStamped::ConstPtr& m) { onMasterTwist(i, *m); }, ros::VoidConstPtr(),
          fast));
      c.subs.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
          n + "/slave_pose", 10, [this, i](const geometry_msgs::PoseStamped::ConstPtr& m) { onSlavePose(i, *m); },
          ros::VoidConstPtr(), fast));
      c.subs.push_back(nh.subscribe<saras_msgs::HapticDeviceState>(
          n + "/device_state", 10,
          [this, i](const saras_msgs::HapticDeviceState::ConstPtr& m) {
            ch_[i].clutch = m->clutch;
            ch_[i].device_stale = m->stale;
          },
          ros::VoidConstPtr(), fast));
      c.subs.push_back(nh.subscribe<geometry_msgs::WrenchStamped>(
          n + "/fixture_wrench", 10,
          [this, i](const geometry_msgs::WrenchStamped::ConstPtr& m) { onFixture(i, *m); }, ros::VoidConstPtr(),
          fast));
      if (p.contact_feedback)
        c.subs.push_back(nh.subscribe<geometry_msgs::Twist>(
            n + "/contact_force", 10, [this, i](const geometry_msgs::Twist::ConstPtr& m) { onContactForce(i, *m); },
            ros::VoidConstPtr(), fast));
    }
    link_sub_ = nh.subscribe("link_status", 10, &TransparencyNode::onLinkStatus, this, fast);
    timer_.reset(new PacedTimer(nh, period_, 1.0 / watchdog, [this](const ros::Time& now) { return onTimer(now); }));
    health_.reset(new Health(nh, pnh, name, "transparency",
                             [this](diagnostic_updater::DiagnosticStatusWrapper& s) { report(s); }));
  }

private:
  struct Channel
  {
    std::string name;
    std::unique_ptr<TransparencyChannel> core;
    std::vector<ros::Subscriber> subs;
    ros::Publisher pub_wrench, pub_twist;
    std::unique_ptr<MessagePool<geometry_msgs::WrenchStamped>> wrench_pool;
    std::unique_ptr<MessagePool<geometry_msgs::TwistStamped>> twist_pool;
    ros::Time t_master, t_slave, t_fixture, t_contact, t_last;
    double contact_norm = 0.0;  ///< |contact force| [N] last received
    bool clutch = false, device_stale = false;
    TransparencyChannel::State state = TransparencyChannel::WAITING;
  };

  void bad(const std::string& what)
  {
    ++rejected_;
    ROS_ERROR_THROTTLE(1.0, "transparency: rejected %s (non-finite); %lu rejected so far", what.c_str(),
                       static_cast<unsigned long>(rejected_));
  }

  void onMasterPose(std::size_t i, const geometry_msgs::PoseStamped& m)
  {
    const Eigen::Vector3d p(m.pose.position.x, m.pose.position.y, m.pose.position.z);
    if (!ch_[i].core->setMasterPosition(p))
      return bad(ch_[i].name + "/master_pose");
    ++received_;
    ch_[i].t_master = ros::Time::now();
  }

  void onMasterTwist(std::size_t i, const geometry_msgs::TwistStamped& m)
  {
    if (!ch_[i].core->setMasterTwist(toVec(m.twist)))
      return bad(ch_[i].name + "/master_twist");
    ++received_;
    compute(i, m.header.stamp);
  }

  void onSlavePose(std::size_t i, const geometry_msgs::PoseStamped& m)
  {
    const Eigen::Vector3d p(m.pose.position.x, m.pose.position.y, m.pose.position.z);
    if (!ch_[i].core->setSlavePosition(p))
      return bad(ch_[i].name + "/slave_pose");
    ++received_;
    ch_[i].t_slave = ros::Time::now();
  }

  void onFixture(std::size_t i, const geometry_msgs::WrenchStamped& m)
  {
    if (!ch_[i].core->setFixtureWrench(toVec(m.wrench)))
      return bad(ch_[i].name + "/fixture_wrench");
    ch_[i].t_fixture = ros::Time::now();
  }

  void onContactForce(std::size_t i, const geometry_msgs::Twist& m)
  {
    const Eigen::Vector3d f(m.linear.x, m.linear.y, m.linear.z);
    if (!ch_[i].core->setContactForce(f))
      return bad(ch_[i].name + "/contact_force");
    ch_[i].t_contact = ros::Time::now();
    ch_[i].contact_norm = f.norm();
  }

  void onLinkStatus(const saras_msgs::ComponentStatus::ConstPtr& m)
  {
    link_ok_ = m->level != saras_msgs::ComponentStatus::STALE;
  }

  /// from_timer: the master twist stopped arriving; publish only if that makes the channel hold.
  void compute(std::size_t i, const ros::Time& stamp, bool from_timer = false)
  {
    Channel& c = ch_[i];
    const ros::Time now = ros::Time::now();
    const bool fresh = !c.t_master.isZero() && !c.t_slave.isZero() &&
                       (now - c.t_master).toSec() <= input_timeout_ && (now - c.t_slave).toSec() <= input_timeout_;
    if (!c.t_fixture.isZero() && (now - c.t_fixture).toSec() > fixture_timeout_)
    {
      c.core->setFixtureWrench(Vector6d::Zero());
      c.t_fixture = ros::Time();
    }
    if (!c.t_contact.isZero() && (now - c.t_contact).toSec() > contact_timeout_)
    {
      c.core->setContactForce(Eigen::Vector3d::Zero());
      c.t_contact = ros::Time();
      c.contact_norm = 0.0;
    }
    c.core->setClutch(c.clutch);
    c.core->setLinkOk(link_ok_ && !c.device_stale && (fresh || c.state == TransparencyChannel::WAITING));
    Vector6d w, v;
    c.state = c.core->update(w, v);
    const bool publish = from_timer ? c.state == TransparencyChannel::HOLD : c.state != TransparencyChannel::WAITING;
    if (publish)
    {
      const ros::Time st = stamp.isZero() ? now : stamp;
      // zero-copy to nodelets in the same manager: pooled shared messages
      const boost::shared_ptr<geometry_msgs::TwistStamped> twist = c.twist_pool->next();
      twist->header.stamp = st;
      fromVec(v, twist->twist);
      c.pub_twist.publish(twist);  // the slave path first: it is the latency-critical one
      const boost::shared_ptr<geometry_msgs::WrenchStamped> wrench = c.wrench_pool->next();
      wrench->header.stamp = st;
      fromVec(w, wrench->wrench);
      c.pub_wrench.publish(wrench);
      published_.count();
    }
    c.t_last = now;
  }

  /// PacedTimer tick: true if a channel's master twists stopped (it was computed here)
  bool onTimer(const ros::Time& now)
  {
    bool gap = false;
    for (std::size_t i = 0; i < ch_.size(); ++i)
    {
      Channel& c = ch_[i];
      if (c.t_last.isZero() || (now - c.t_last).toSec() > 1.5 * period_)
      {
        compute(i, ros::Time(), true);  // master twist stopped: hold (fresh == false) or keep waiting
        gap = true;
      }
    }
    return gap;
  }

  /// /diagnostics (Health, 1 Hz): the worst channel state sets the level; each channel's state listed.
  void report(diagnostic_updater::DiagnosticStatusWrapper& s)
  {
    using diagnostic_msgs::DiagnosticStatus;
    const ros::Time now = ros::Time::now();
    std::string msg;
    int level = DiagnosticStatus::OK;
    double age = 0.0;
    for (const Channel& c : ch_)
    {
      if (!c.t_master.isZero())
        age = std::max(age, (now - c.t_master).toSec());
      std::string state = "running";
      if (c.state == TransparencyChannel::WAITING)
      {
        level = std::max<int>(level, DiagnosticStatus::WARN);
        state = "waiting for master and slave poses";
      }
      else if (c.state == TransparencyChannel::HOLD)
      {
        if (!c.clutch)
          level = std::max<int>(level, DiagnosticStatus::STALE);
        state = c.clutch ? "clutch" : "holding (link stale or inputs old)";
      }
      if (state != "running")
        msg += c.name + ": " + state + "; ";
      s.add(c.name + " state", state);
      s.add(c.name + " contact force [N]", c.contact_norm);
    }
    s.summary(static_cast<unsigned char>(level), msg.empty() ? "running" : msg);
    s.add("input age [s]", age);
    s.add("set-point rate [Hz]", published_.rate());
    s.add("link ok", link_ok_);
    s.add("contact force feedback", contact_feedback_);
    s.add("received", received_);
    s.add("rejected", rejected_);
    s.add("timer", timer_->describe());
  }

  static constexpr std::size_t kPoolSize = 16;  // > subscriber queue sizes (10)
  std::vector<Channel> ch_;
  ros::Subscriber link_sub_;
  std::unique_ptr<PacedTimer> timer_;  ///< fill-in (~rate; ~watchdog_rate while every channel's twists flow)
  std::unique_ptr<Health> health_;  // /diagnostics, created at the end of the constructor
  RateMeter published_;             // des_twist + des_wrench pairs, all channels
  double period_ = 0.001, input_timeout_ = 0.1, fixture_timeout_ = 0.2, contact_timeout_ = 0.2;
  bool contact_feedback_ = true;
  bool link_ok_ = true;
  uint64_t received_ = 0, rejected_ = 0;
};

/// Nodelet `saras_teleop/Transparency` (nodelet_plugins.xml).
class TransparencyNodelet : public NodeletAdapter<TransparencyNode>
{
};

}  // namespace node
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::node::TransparencyNodelet, nodelet::Nodelet)

/**
 * tf_transformer: master pose/twist in the slave base frame, force command to the Touch frame
 * (one instance per channel). Nodelet saras_teleop/TfTransformer; executable tf_transformer.
 *
 * Subscribes /tf and /tf_static itself (TCP_NODELAY, own tf2::BufferCore) so that each new master
 * sample is processed the moment it arrives: lookup reference_frame <- tracked_frame at the latest
 * time, publish master_pose (PoseStamped, stamp = TF sample time) and the low-pass filtered twist
 * master_twist (TwistStamped, reference frame, differentiated over TF sample times).
 * tank_wrench (WrenchStamped, reference frame) is rotated into device_base_frame (no lever arm: the
 * force acts at the stylus), saturated to ~max_force and published as wrench_cmd at once.
 * A ~rate timer republishes the command (zero if tank_wrench is older than ~wrench_timeout), waits
 * for the frames at start-up (clear error after ~wait_timeout, keeps waiting) and declares the
 * master STALE if no new sample arrived within ~stale_timeout (twist cleared); while samples and
 * commands flow it runs at ~watchdog_rate instead (PacedTimer, node_common.h).
 * Params: reference_frame, tracked_frame, device_base_frame, rate [Hz], watchdog_rate [Hz], low_pass_cutoff [Hz],
 * wait_timeout [s], stale_timeout [s], wrench_timeout [s], max_force [N], max_torque [N m].
 */
#include <cmath>
#include <set>
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <pluginlib/class_list_macros.hpp>
#include <tf2_msgs/TFMessage.h>

#include "node_common.h"
#include "saras_common/message_pool.h"
#include "saras_teleop/twist_estimator.h"

namespace saras_teleop
{
namespace node
{
class TfTransformerNode
{
public:
  /// @param name node or nodelet name without the leading '/' (the /diagnostics status is "<name>: master tracking")
  TfTransformerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name)
    : buffer_(ros::Duration(5.0))
    , est_(saras_common::Params(pnh).number("low_pass_cutoff", 50.0, "Hz", { saras_common::positive() }),
           saras_common::Params(pnh).number("max_gap", 0.1, "s", { saras_common::positive() }))
  {
    using saras_common::nonEmpty;
    using saras_common::positive;
    const saras_common::Params prm(pnh);
    reference_ = prm.text("reference_frame", "mesa_left/sbs_world", { nonEmpty() });
    tracked_ = prm.text("tracked_frame", "touch_left/stylus", { nonEmpty() });
    device_base_ = prm.text("device_base_frame", "touch_left/base", { nonEmpty() });
    // Dynamic (/tf) transforms kept in the buffer: the tracked frame plus ~extra_dynamic_frames (list
    // of child frame ids, default none: the Touchball receiver publishes the stylus directly under the
    // static device base). Everything else on /tf (the SARAS arms' and the da Vinci's links, several
    // thousand transforms/s) cannot be on the chain and is skipped without touching the buffer.
    dynamic_frames_.insert(tracked_);
    for (const std::string& f : prm.texts("extra_dynamic_frames", {}, { nonEmpty() }))
      dynamic_frames_.insert(f);
    const double rate = prm.number("rate", 1000.0, "Hz", { positive() });
    period_ = 1.0 / rate;
    const double watchdog = prm.number("watchdog_rate", 100.0, "Hz", { positive() });
    wait_timeout_ = prm.number("wait_timeout", 10.0, "s", { positive() });
    stale_timeout_ = prm.number("stale_timeout", 0.05, "s", { positive() });
    wrench_timeout_ = prm.number("wrench_timeout", 0.05, "s", { positive() });
    max_force_ = prm.number("max_force", 3.3, "N", { positive() });
    max_torque_ = prm.number("max_torque", 0.1, "N m", { positive() });

    geometry_msgs::PoseStamped pose;
    geometry_msgs::TwistStamped twist;
    geometry_msgs::WrenchStamped wrench;
    pose.header.frame_id = twist.header.frame_id = reference_;
    wrench.header.frame_id = device_base_;
    pose_pool_.reset(new MessagePool<geometry_msgs::PoseStamped>(kPoolSize, pose));
    twist_pool_.reset(new MessagePool<geometry_msgs::TwistStamped>(kPoolSize, twist));
    wrench_pool_.reset(new MessagePool<geometry_msgs::WrenchStamped>(kPoolSize, wrench));
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("master_pose", kStreamQueue);
    twist_pub_ = nh.advertise<geometry_msgs::TwistStamped>("master_twist", kStreamQueue);
    wrench_pub_ = nh.advertise<geometry_msgs::WrenchStamped>("wrench_cmd", kStreamQueue);
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    tf_sub_ = nh.subscribe("/tf", 100, &TfTransformerNode::onTf, this, fast);
    tf_static_sub_ = nh.subscribe("/tf_static", 100, &TfTransformerNode::onTfStatic, this, fast);
    wrench_sub_ = nh.subscribe("tank_wrench", 10, &TfTransformerNode::onWrench, this, fast);
    start_ = ros::Time::now();
    timer_.reset(new PacedTimer(nh, period_, 1.0 / watchdog, [this](const ros::Time& now) { return onTimer(now); }));
    health_.reset(new Health(nh, pnh, name, "master tracking",
                             [this](diagnostic_updater::DiagnosticStatusWrapper& s) { report(s); }));
  }

private:
  void insert(const tf2_msgs::TFMessage& m, bool is_static, bool& has_tracked)
  {
    for (const auto& t : m.transforms)
    {
      if (!is_static && dynamic_frames_.find(t.child_frame_id) == dynamic_frames_.end())
        continue;  // not on the device_base -> tracked chain (see dynamic_frames_)
      const auto& tr = t.transform.translation;
      const auto& rq = t.transform.rotation;
      // checked here so that a NaN stream gives one throttled error instead of tf2's unthrottled one
      bool ok = std::isfinite(tr.x) && std::isfinite(tr.y) && std::isfinite(tr.z) && std::isfinite(rq.x) &&
                std::isfinite(rq.y) && std::isfinite(rq.z) && std::isfinite(rq.w);
      if (ok)
      {
        try
        {
          ok = buffer_.setTransform(t, "tf_transformer", is_static);  // false for empty/self frames
        }
        catch (const std::exception&)
        {
          ok = false;
        }
      }
      if (!ok)
      {
        ++rejected_;
        ROS_ERROR_THROTTLE(1.0, "tf_transformer: rejected transform %s -> %s (invalid); %lu rejected so far",
                           t.header.frame_id.c_str(), t.child_frame_id.c_str(), static_cast<unsigned long>(rejected_));
        continue;
      }
      if (t.child_frame_id == tracked_)
        has_tracked = true;
    }
  }

  void onTf(const tf2_msgs::TFMessage::ConstPtr& m)
  {
    bool has = false;
    insert(*m, false, has);
    if (has)
      track();
  }

  void onTfStatic(const tf2_msgs::TFMessage::ConstPtr& m)
  {
    bool has = false;
    insert(*m, true, has);
    if (has)
      track();
  }

  bool ready()
  {
    if (have_rotation_)
      return true;
    try
    {
      const geometry_msgs::TransformStamped t = buffer_.lookupTransform(device_base_, reference_, ros::Time(0));
      const auto& q = t.transform.rotation;
      R_dev_ref_ = KDL::Rotation::Quaternion(q.x, q.y, q.z, q.w);
      buffer_.lookupTransform(reference_, tracked_, ros::Time(0));
      have_rotation_ = true;
      ROS_INFO("tf_transformer: tracking %s in %s, commands in %s", tracked_.c_str(), reference_.c_str(),
               device_base_.c_str());
    }
    catch (const tf2::TransformException&)
    {
      return false;
    }
    return true;
  }

  void track()
  {
    if (!ready())
      return;
    geometry_msgs::TransformStamped t;
    try
    {
      t = buffer_.lookupTransform(reference_, tracked_, ros::Time(0));
    }
    catch (const tf2::TransformException& e)
    {
      ROS_ERROR_THROTTLE(1.0, "tf_transformer: %s", e.what());
      return;
    }
    const auto& p = t.transform.translation;
    const auto& q = t.transform.rotation;
    const KDL::Frame f(KDL::Rotation::Quaternion(q.x, q.y, q.z, q.w), KDL::Vector(p.x, p.y, p.z));
    const TwistEstimator::Result r = est_.addSample(t.header.stamp.toSec(), f);
    if (r == TwistEstimator::REJECTED)
    {
      ++rejected_;
      ROS_ERROR_THROTTLE(1.0, "tf_transformer: non-finite master pose rejected (%lu so far)",
                         static_cast<unsigned long>(rejected_));
      return;
    }
    if (r == TwistEstimator::SAME_SAMPLE)
      return;
    ++received_;
    last_sample_wall_ = ros::Time::now();
    // zero-copy to nodelets in the same manager: publish pooled shared messages
    const boost::shared_ptr<geometry_msgs::PoseStamped> pose = pose_pool_->next();
    pose->header.stamp = t.header.stamp;
    pose->pose.position.x = p.x;
    pose->pose.position.y = p.y;
    pose->pose.position.z = p.z;
    pose->pose.orientation = q;
    pose_pub_.publish(pose);
    pose_rate_.count();
    publishTwist(t.header.stamp);
  }

  void onWrench(const geometry_msgs::WrenchStamped::ConstPtr& m)
  {
    const Vector6d w = toVec(m->wrench);
    if (!w.allFinite())
    {
      ++rejected_;
      ROS_ERROR_THROTTLE(1.0, "tf_transformer: non-finite tank_wrench rejected, commanding zero force");
      w_ref_.setZero();
      return;
    }
    w_ref_ = w;
    t_wrench_ = ros::Time::now();
    publishWrench(m->header.stamp);
  }

  void publishTwist(const ros::Time& stamp)
  {
    const boost::shared_ptr<geometry_msgs::TwistStamped> twist = twist_pool_->next();
    twist->header.stamp = stamp;
    fromVec(est_.twist(), twist->twist);
    twist_pub_.publish(twist);
  }

  void publishWrench(const ros::Time& stamp)
  {
    if (!have_rotation_)
      return;
    Vector6d w = rotateWrench(R_dev_ref_, w_ref_);
    const double nf = w.head<3>().norm(), nt = w.tail<3>().norm();
    if (nf > max_force_)
      w.head<3>() *= max_force_ / nf;
    if (nt > max_torque_)
      w.tail<3>() *= max_torque_ / nt;
    const boost::shared_ptr<geometry_msgs::WrenchStamped> wrench = wrench_pool_->next();
    wrench->header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
    fromVec(w, wrench->wrench);
    wrench_pub_.publish(wrench);
    wrench_rate_.count();
    t_wrench_pub_ = ros::Time::now();
  }

  /// PacedTimer tick: true if a stream stopped (no master sample or no command for 1.5 periods)
  bool onTimer(const ros::Time& now)
  {
    if (!ready())
    {
      if ((now - start_).toSec() > wait_timeout_)
      {
        ROS_ERROR_THROTTLE(wait_timeout_, "tf_transformer: frames %s -> %s -> %s not available after %.1f s "
                                          "(is the touchball receiver running and world_frames published?)",
                           device_base_.c_str(), reference_.c_str(), tracked_.c_str(), (now - start_).toSec());
      }
      return true;
    }
    const bool stale = sampleAge(now) > stale_timeout_;
    if (stale && est_.twist().norm() > 0.0)
    {
      est_.clear();
      publishTwist(now);
    }
    if (t_wrench_.isZero() || (now - t_wrench_).toSec() > wrench_timeout_)
      w_ref_.setZero();  // no fresh command: no force
    bool gap = sampleAge(now) > 1.5 * period_;
    if (t_wrench_pub_.isZero() || (now - t_wrench_pub_).toSec() > 1.5 * period_)
    {
      publishWrench(ros::Time());
      gap = true;
    }
    return gap;
  }

  /// [s] since the last new master sample (1e6 if none yet)
  double sampleAge(const ros::Time& now) const
  {
    return last_sample_wall_.isZero() ? 1e6 : std::min((now - last_sample_wall_).toSec(), 1e6);
  }

  /// /diagnostics (Health, 1 Hz)
  void report(diagnostic_updater::DiagnosticStatusWrapper& s)
  {
    using diagnostic_msgs::DiagnosticStatus;
    const ros::Time now = ros::Time::now();
    const double waited = (now - start_).toSec();
    if (!have_rotation_)
      s.summary(waited > wait_timeout_ ? DiagnosticStatus::ERROR : DiagnosticStatus::WARN,
                "waiting for TF " + tracked_ + " in " + reference_);
    else if (sampleAge(now) > stale_timeout_)
      s.summary(DiagnosticStatus::STALE, "no new master sample on TF " + tracked_);
    else
      s.summary(DiagnosticStatus::OK, "tracking");
    s.add("tracked frame", tracked_);
    s.add("input age [s]", have_rotation_ ? sampleAge(now) : waited);
    s.add("master_pose rate [Hz]", pose_rate_.rate());
    s.add("wrench_cmd rate [Hz]", wrench_rate_.rate());
    s.add("received", received_);
    s.add("rejected", rejected_);
    s.add("timer", timer_->describe());
  }

  tf2::BufferCore buffer_;
  TwistEstimator est_;
  std::unique_ptr<Health> health_;  // /diagnostics, created at the end of the constructor
  RateMeter pose_rate_, wrench_rate_;
  std::string reference_, tracked_, device_base_;
  double period_ = 0.001, wait_timeout_ = 10.0, stale_timeout_ = 0.05, wrench_timeout_ = 0.05;
  double max_force_ = 3.3, max_torque_ = 0.1;
  bool have_rotation_ = false;
  KDL::Rotation R_dev_ref_;
  Vector6d w_ref_ = Vector6d::Zero();
  static constexpr std::size_t kPoolSize = 16;  // > subscriber queue sizes (10)
  std::unique_ptr<MessagePool<geometry_msgs::PoseStamped>> pose_pool_;
  std::unique_ptr<MessagePool<geometry_msgs::TwistStamped>> twist_pool_;
  std::unique_ptr<MessagePool<geometry_msgs::WrenchStamped>> wrench_pool_;
  ros::Publisher pose_pub_, twist_pub_, wrench_pub_;
  ros::Subscriber tf_sub_, tf_static_sub_, wrench_sub_;
  std::set<std::string> dynamic_frames_;  ///< child frames taken from /tf (the rest is skipped)
  std::unique_ptr<PacedTimer> timer_;  ///< fill-in and supervision (~rate; ~watchdog_rate while samples flow)
  ros::Time start_, last_sample_wall_, t_wrench_, t_wrench_pub_;
  uint64_t received_ = 0, rejected_ = 0;
};


/// Nodelet `saras_teleop/TfTransformer` (nodelet_plugins.xml).
class TfTransformerNodelet : public NodeletAdapter<TfTransformerNode>
{
};
}  // namespace node
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::node::TfTransformerNodelet, nodelet::Nodelet)

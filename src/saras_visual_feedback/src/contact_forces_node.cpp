// contact_forces: elastic contact force of one SARAS tool (D7.2 Section 8).
// One instance per side, in the tool's namespace (e.g. /mesa_left):
//   subscribes  contact        saras_msgs/Contact
//   publishes   contact_force  geometry_msgs/Twist (linear = force [N], angular = 0) at ~rate
//               /saras/status  saras_msgs/ComponentStatus (1 Hz + on change)
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/Contact.h>

#include "saras_visual_feedback/contact_force.h"

namespace saras_visual_feedback
{

class ContactForcesNode
{
public:
  /// Reads and validates the private parameters; throws std::runtime_error naming a bad one.
  ContactForcesNode(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh)
  {
    ContactForceParams p;
    pnh.param("k_skin", p.k_skin, p.k_skin);
    pnh.param("stale_timeout", p.stale_timeout, p.stale_timeout);
    pnh.param("max_force", p.max_force, p.max_force);
    std::string why;
    if (!validateContactForceParams(p, &why))
      throw std::runtime_error("invalid parameter ~" + why);
    double rate = 60.0;
    pnh.param("rate", rate, rate);
    if (!(std::isfinite(rate) && rate > 0.0 && rate <= 1000.0))
      throw std::runtime_error("invalid parameter ~rate: must be in (0, 1000] Hz, got " + std::to_string(rate));
    pnh.param<std::string>("component", component_, ros::this_node::getName());
    model_ = ContactForceModel(p);

    force_pub_ = nh_.advertise<geometry_msgs::Twist>("contact_force", 10);
    status_pub_ = nh_.advertise<saras_msgs::ComponentStatus>("/saras/status", 10, true);
    contact_sub_ = nh_.subscribe("contact", 10, &ContactForcesNode::contactCb, this,
                                 ros::TransportHints().tcpNoDelay());
    timer_ = nh_.createTimer(ros::Duration(1.0 / rate), &ContactForcesNode::timerCb, this);
    ROS_INFO("contact_forces: %s -> %s at %.1f Hz, K_skin %.1f N/m, stale after %.3f s, max %.1f N",
             contact_sub_.getTopic().c_str(), force_pub_.getTopic().c_str(), rate, p.k_skin, p.stale_timeout,
             p.max_force);
  }

private:
  void contactCb(const saras_msgs::ContactConstPtr& msg)
  {
    const Vec3 d{msg->direction.x, msg->direction.y, msg->direction.z};
    const ContactRejection r = model_.update(msg->depth, d, ros::Time::now().toSec());
    if (r != ContactRejection::kNone)
      ROS_ERROR_THROTTLE(1.0, "%s: contact rejected (%s: depth %g, direction [%g %g %g]); %llu rejected so far; the "
                              "force drops to zero %.3f s after the last valid contact",
                         contact_sub_.getTopic().c_str(), toString(r), msg->depth, d.x, d.y, d.z,
                         static_cast<unsigned long long>(model_.rejected()), model_.params().stale_timeout);
  }

  void timerCb(const ros::TimerEvent& /*event*/)
  {
    const ros::Time now = ros::Time::now();
    const Vec3 f = model_.force(now.toSec());
    msg_.linear.x = f.x;
    msg_.linear.y = f.y;
    msg_.linear.z = f.z;  // angular stays zero
    force_pub_.publish(msg_);
    publishStatus(now);
  }

  void publishStatus(const ros::Time& now)
  {
    const double t = now.toSec();
    std::uint8_t level = saras_msgs::ComponentStatus::OK;
    const char* text = "contact fresh";
    if (!model_.fresh(t))
    {
      level = saras_msgs::ComponentStatus::STALE;
      text = "no valid contact within stale_timeout: publishing zero force";
    }
    else if (model_.rejected() > rejected_reported_)
    {
      level = saras_msgs::ComponentStatus::WARN;
      text = "rejected contact messages (NaN, negative depth or zero-length direction)";
    }
    if (level == last_level_ && !last_status_.isZero() && (now - last_status_).toSec() < 1.0)
      return;
    saras_msgs::ComponentStatus s;
    s.header.stamp = now;
    s.component = component_;
    s.level = level;
    s.message = text;
    const double age = model_.age(t);
    s.input_age = age;  // +inf before the first valid contact
    s.received = model_.accepted();
    s.rejected = model_.rejected();
    status_pub_.publish(s);
    last_level_ = level;
    last_status_ = now;
    rejected_reported_ = model_.rejected();
  }

  ros::NodeHandle nh_;
  ContactForceModel model_;
  std::string component_;
  ros::Subscriber contact_sub_;
  ros::Publisher force_pub_, status_pub_;
  ros::Timer timer_;
  geometry_msgs::Twist msg_;  ///< reused: no allocation in the periodic path
  std::uint8_t last_level_ = 255;
  ros::Time last_status_;
  std::uint64_t rejected_reported_ = 0;
};

}  // namespace saras_visual_feedback

int main(int argc, char** argv)
{
  ros::init(argc, argv, "contact_forces");
  // Handles outlive the node object so that the FATAL message is printed before shutdown.
  ros::NodeHandle nh, pnh("~");
  try
  {
    saras_visual_feedback::ContactForcesNode node(nh, pnh);
    ros::spin();
  }
  catch (const std::exception& e)
  {
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}

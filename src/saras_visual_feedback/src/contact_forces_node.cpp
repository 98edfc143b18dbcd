// contact_forces: elastic contact force of one SARAS tool (D7.2 Section 8).
// One instance per side, in the tool's namespace (e.g. /mesa_left):
//   subscribes  contact        saras_msgs/Contact
//   publishes   contact_force  geometry_msgs/Twist (linear = force [N], angular = 0) at ~rate
//               /diagnostics   diagnostic_msgs/DiagnosticArray ("<node>: contact force", hardware_id visual_feedback)
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <geometry_msgs/Twist.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
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
    model_ = ContactForceModel(p);

    force_pub_ = nh_.advertise<geometry_msgs::Twist>("contact_force", 10);
    updater_.setHardwareID("visual_feedback");
    updater_.add("contact force", this, &ContactForcesNode::diagnose);
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
    updater_.update();  // at ~diagnostic_period (1 s)
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    using diagnostic_msgs::DiagnosticStatus;
    const double t = ros::Time::now().toSec();
    stat.addf("accepted contacts", "%llu", static_cast<unsigned long long>(model_.accepted()));
    stat.addf("rejected contacts", "%llu", static_cast<unsigned long long>(model_.rejected()));
    stat.addf("contact age [s]", "%.3f", model_.age(t));  // inf before the first valid contact
    stat.addf("stale_timeout [s]", "%.3f", model_.params().stale_timeout);
    if (!model_.fresh(t))
      stat.summary(DiagnosticStatus::STALE, "no valid contact within stale_timeout: publishing zero force");
    else if (model_.rejected() > rejected_reported_)
      stat.summary(DiagnosticStatus::WARN, "rejected contact messages (NaN, negative depth or zero-length direction)");
    else
      stat.summary(DiagnosticStatus::OK, "contact fresh");
    rejected_reported_ = model_.rejected();
  }

  ros::NodeHandle nh_;
  ContactForceModel model_;
  ros::Subscriber contact_sub_;
  ros::Publisher force_pub_;
  diagnostic_updater::Updater updater_;
  ros::Timer timer_;
  geometry_msgs::Twist msg_;  ///< reused: no allocation in the periodic path
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

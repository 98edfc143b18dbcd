/**
 * Standalone executable of one saras_teleop nodelet (compiled once per nodelet with
 * SARAS_TELEOP_NODELET = "saras_teleop/<Type>" and SARAS_TELEOP_NODE = default node name).
 *
 * Loads the nodelet into an in-process nodelet::Loader under this node's name, so node name,
 * private parameters (~) and command-line remappings behave exactly as for a plain node, and spins.
 * A nodelet that refuses to start (bad parameter: it logs ROS_FATAL naming the parameter) makes the
 * process exit with status 1.
 */
#include <string>
#include <vector>

#include <nodelet/loader.h>
#include <ros/ros.h>

#ifndef SARAS_TELEOP_NODELET
#error "define SARAS_TELEOP_NODELET (nodelet type) and SARAS_TELEOP_NODE (default node name)"
#endif

int main(int argc, char** argv)
{
  ros::init(argc, argv, SARAS_TELEOP_NODE);
  ros::NodeHandle nh;  // keeps the node alive (and logging working) for the whole main
  std::vector<std::string> args;
  ros::removeROSArgs(argc, argv, args);
  nodelet::V_string my_argv(args.size() > 1 ? args.begin() + 1 : args.end(), args.end());
  bool ok = false;
  {
    nodelet::Loader loader(false);  // no manager services: a private, in-process manager
    try
    {
      ok = loader.load(ros::this_node::getName(), SARAS_TELEOP_NODELET, nodelet::M_string(), my_argv);
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", ros::this_node::getName().c_str(), e.what());
      ok = false;
    }
    if (ok)
      ros::spin();
    else
      ROS_FATAL("%s: nodelet %s failed to start (see the error above)", ros::this_node::getName().c_str(),
                SARAS_TELEOP_NODELET);
  }
  ros::console::shutdown();
  return ok ? 0 : 1;
}

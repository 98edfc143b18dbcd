/**
 * @file touchball_receiver_node.cpp
 * @brief Executable touchball_receiver: loads the nodelet saras_drivers/TouchballReceiver in-process
 *        (image_proc style), so node name, private parameters and remappings behave as for a plain
 *        node. A nodelet that refuses to start (invalid parameter, port in use: logged with ROS_FATAL
 *        naming the parameter) makes the process exit with status 2.
 */
#include <string>
#include <vector>

#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "touchball_receiver");
  ros::NodeHandle nh;  // keeps the node alive (and logging working) for the whole main
  std::vector<std::string> args;
  ros::removeROSArgs(argc, argv, args);
  const nodelet::V_string my_argv(args.size() > 1 ? args.begin() + 1 : args.end(), args.end());
  bool ok = false;
  {
    nodelet::Loader loader(false);  // no manager services: a private, in-process manager
    try
    {
      ok = loader.load(ros::this_node::getName(), "saras_drivers/TouchballReceiver", nodelet::M_string(), my_argv);
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", ros::this_node::getName().c_str(), e.what());
      ok = false;
    }
    if (ok)
      ros::spin();
    else
      ROS_FATAL("%s: the Touchball receiver failed to start (see the error above)", ros::this_node::getName().c_str());
  }
  ros::console::shutdown();
  return ok ? 0 : 2;
}

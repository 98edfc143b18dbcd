/**
 * @file nodelet_node_main.cpp
 * @brief main() of the executables that run one saras_drivers nodelet as a plain node
 *        (touchball_receiver, endoscope_sim_node): the nodelet is loaded in-process (image_proc
 *        style), so node name, private parameters and remappings behave as for a plain node. A
 *        nodelet that refuses to start (invalid parameter, port in use, unreadable file: logged
 *        with ROS_FATAL naming the cause) makes the process exit with status 2.
 *
 * Compiled once per executable with SARAS_NODE_NAME (default node name), SARAS_NODELET_TYPE
 * (pluginlib class) and SARAS_NODE_WHAT (what failed, for the message) defined.
 */
#include <string>
#include <vector>

#include <nodelet/loader.h>
#include <ros/ros.h>

#if !defined(SARAS_NODE_NAME) || !defined(SARAS_NODELET_TYPE) || !defined(SARAS_NODE_WHAT)
#error "define SARAS_NODE_NAME, SARAS_NODELET_TYPE and SARAS_NODE_WHAT"
#endif

int main(int argc, char** argv)
{
  ros::init(argc, argv, SARAS_NODE_NAME);
  ros::NodeHandle nh;  // keeps the node alive (and logging working) for the whole main
  std::vector<std::string> args;
  ros::removeROSArgs(argc, argv, args);
  const nodelet::V_string my_argv(args.size() > 1 ? args.begin() + 1 : args.end(), args.end());
  bool ok = false;
  {
    nodelet::Loader loader(false);  // no manager services: a private, in-process manager
    try
    {
      ok = loader.load(ros::this_node::getName(), SARAS_NODELET_TYPE, nodelet::M_string(), my_argv);
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", ros::this_node::getName().c_str(), e.what());
      ok = false;
    }
    if (ok)
      ros::spin();
    else
      ROS_FATAL("%s: %s failed to start (see the error above)", ros::this_node::getName().c_str(), SARAS_NODE_WHAT);
  }
  ros::console::shutdown();
  return ok ? 0 : 2;
}

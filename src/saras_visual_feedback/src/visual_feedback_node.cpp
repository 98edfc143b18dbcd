// Standalone VisualFeedback: loads the nodelet into its own process (like image_proc's node).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv)
{
  ros::init(argc, argv, "visual_feedback");
  nodelet::Loader loader(false);
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string my_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "saras_visual_feedback/VisualFeedback", remappings, my_argv))
  {
    ROS_FATAL("could not start the VisualFeedback nodelet (see the error above)");
    return 1;
  }
  ros::spin();
  return 0;
}

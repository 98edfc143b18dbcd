// colliding_regions: thin entry point of the CollidingRegions adapter (see colliding_regions.h).
#include <ros/ros.h>

#include "saras_collision/colliding_regions.h"

int main(int argc, char** argv)
{
  ros::init(argc, argv, "colliding_regions");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  saras_collision::CollidingRegionsConfig config;
  std::string error;
  if (!saras_collision::loadConfig(pnh, config, error))
  {
    ROS_FATAL("colliding_regions: %s", error.c_str());
    return 1;
  }
  saras_collision::CollidingRegions node(nh, config);
  if (!node.start(error))
  {
    ROS_FATAL("colliding_regions: %s", error.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}

// Params on a real ros::NodeHandle (rostest params.test): names resolve relative to the private
// namespace, YAML types arrive as expected, an error names the resolved parameter.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "saras_common/params.h"

TEST(ParamsNode, ReadsThePrivateNamespace)
{
  ros::NodeHandle pnh("~");
  const saras_common::Params p(pnh);
  EXPECT_EQ(p.number("timeout", 1.0, "s", { saras_common::positive() }), 0.25);
  EXPECT_EQ(p.integer("port", 1, "", { saras_common::inRange(0, 65535) }), 5005);
  EXPECT_FALSE(p.flag("publish_tf", true));
  EXPECT_EQ(p.text("mode", "shared", { saras_common::oneOf({ "manager", "shared" }) }), "manager");
  EXPECT_EQ(p.numbers("gains", {}, "N/m", {}, 3), (std::vector<double>{ 1.0, 2.0, 3.5 }));
  EXPECT_EQ(p.number("nested/value", 0.0, "m"), 7.0);
  EXPECT_EQ(p.number("absent", 4.0, "m"), 4.0);
  try
  {
    p.number("negative", 1.0, "s", { saras_common::positive() });
    FAIL() << "no exception";
  }
  catch (const saras_common::ParamError& e)
  {
    EXPECT_EQ(e.name(), ros::this_node::getName() + "/negative");
    EXPECT_EQ(std::string(e.what()), "parameter " + e.name() + " = -2 [s] is invalid: must be > 0");
  }
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "params_node_test");
  return RUN_ALL_TESTS();
}

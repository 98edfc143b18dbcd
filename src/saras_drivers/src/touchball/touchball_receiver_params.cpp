/**
 * @file touchball_receiver_params.cpp
 * @brief Type-checked reading of the receiver parameters (ranges and units: ReceiverConfig::validate).
 */
#include "touchball_receiver_params.h"

#include <stdexcept>
#include <string>

namespace saras_drivers
{
namespace touchball
{
namespace
{
[[noreturn]] void wrongType(const ros::NodeHandle& pnh, const std::string& name, XmlRpc::XmlRpcValue& x,
                            const char* expected)
{
  throw std::invalid_argument("parameter " + pnh.resolveName(name) + " = " + x.toXml() + " is invalid: " + expected);
}

void read(const ros::NodeHandle& pnh, const std::string& name, double& v)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return;
  if (x.getType() == XmlRpc::XmlRpcValue::TypeInt)
    v = static_cast<int>(x);
  else if (x.getType() == XmlRpc::XmlRpcValue::TypeDouble)
    v = static_cast<double>(x);
  else
    wrongType(pnh, name, x, "a number");
}

void read(const ros::NodeHandle& pnh, const std::string& name, int& v)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeInt)
    wrongType(pnh, name, x, "an integer");
  v = static_cast<int>(x);
}

void read(const ros::NodeHandle& pnh, const std::string& name, bool& v)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
    wrongType(pnh, name, x, "true or false");
  v = static_cast<bool>(x);
}

void read(const ros::NodeHandle& pnh, const std::string& name, std::string& v)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeString)
    wrongType(pnh, name, x, "a string");
  v = static_cast<std::string>(x);
}
}  // namespace

ReceiverConfig readReceiverConfig(const ros::NodeHandle& pnh)
{
  ReceiverConfig c;
  read(pnh, "bind_address", c.bind_address);
  read(pnh, "port", c.port);
  read(pnh, "allowed_source", c.allowed_source);
  read(pnh, "command_port", c.command_port);
  read(pnh, "timeout", c.link.timeout);
  read(pnh, "resync_after", c.link.resync_after);
  read(pnh, "twist_cutoff_hz", c.link.twist_cutoff_hz);
  read(pnh, "max_force", c.wrench.max_force);
  read(pnh, "max_torque", c.wrench.max_torque);
  read(pnh, "wrench_timeout", c.wrench.wrench_timeout);
  read(pnh, "status_rate", c.status_rate);
  read(pnh, "joint_states_rate", c.joint_states_rate);
  read(pnh, "publish_tf", c.publish_tf);
  read(pnh, "publish_queue_size", c.publish_queue_size);
  read(pnh, "realtime_priority", c.realtime_priority);
  try
  {
    c.validate();
  }
  catch (const std::invalid_argument& e)
  {
    throw std::invalid_argument("parameter " + pnh.getNamespace() + "/" + e.what());
  }
  return c;
}

}  // namespace touchball
}  // namespace saras_drivers

/**
 * @file touchball_receiver_params.cpp
 * @brief Reading and validation of the Touchball receiver parameters.
 */
#include "saras_drivers/touchball_receiver_params.h"

#include "saras_drivers/touchball_udp.h"

namespace saras_drivers
{
namespace touchball
{
namespace
{
std::uint32_t address(const saras_common::Params& p, const char* name, const std::string& text)
{
  std::uint32_t ip = 0;
  if (!parseIpv4(text, ip))
    p.fail(name, "'" + text + "'", "", "an IPv4 address");
  return ip;
}
}  // namespace

ReceiverConfig readReceiverConfig(const saras_common::Params& p)
{
  using saras_common::inRange;
  using saras_common::nonNegative;
  using saras_common::positive;
  ReceiverConfig c;
  c.bind_address = p.text("bind_address", c.bind_address);
  address(p, "bind_address", c.bind_address);
  c.port = p.integer("port", c.port, "", { inRange(0, 65535) });
  c.allowed_source = p.text("allowed_source", c.allowed_source);
  c.link.any_source = c.allowed_source.empty() || c.allowed_source == "*";
  if (!c.link.any_source)
    c.link.source_ip = address(p, "allowed_source", c.allowed_source);
  c.command_port = p.integer("command_port", c.command_port, "", { inRange(0, 65535) });
  c.key_file = p.text("key_file", c.key_file);
  if (c.key_file.empty())
    p.fail("key_file", "''", "", "the path of the console link key file");
  c.link.timeout = p.number("timeout", c.link.timeout, "s", { positive() });
  c.link.resync_after = p.number("resync_after", c.link.resync_after, "s", { positive() });
  if (c.link.resync_after < c.link.timeout)
    p.fail("resync_after", c.link.resync_after, "s", ">= ~timeout");
  c.link.twist_cutoff_hz = p.number("twist_cutoff_hz", c.link.twist_cutoff_hz, "Hz", { nonNegative() });
  c.wrench.max_force = p.number("max_force", c.wrench.max_force, "N", { nonNegative() });
  c.wrench.max_torque = p.number("max_torque", c.wrench.max_torque, "N m", { nonNegative() });
  c.wrench.wrench_timeout = p.number("wrench_timeout", c.wrench.wrench_timeout, "s", { positive() });
  c.status_rate = p.number("status_rate", c.status_rate, "Hz", { positive() });
  c.joint_states_rate = p.number("joint_states_rate", c.joint_states_rate, "Hz", { nonNegative() });
  c.publish_tf = p.flag("publish_tf", c.publish_tf);
  c.tf_rate = p.number("tf_rate", c.tf_rate, "Hz", { nonNegative() });
  c.publish_queue_size = p.integer("publish_queue_size", c.publish_queue_size, "", { inRange(0, 100000) });
  c.realtime_priority = p.integer("realtime_priority", c.realtime_priority, "", { inRange(0, 99) });
  return c;
}

}  // namespace touchball
}  // namespace saras_drivers

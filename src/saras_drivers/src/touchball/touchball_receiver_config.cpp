/**
 * @file touchball_receiver_config.cpp
 * @brief Validation of the Touchball receiver parameters.
 */
#include "saras_drivers/touchball_receiver_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "saras_drivers/touchball_udp.h"

namespace saras_drivers
{
namespace touchball
{
namespace
{
template <class T>
[[noreturn]] void invalid(const char* name, const T& value, const std::string& rule)
{
  std::ostringstream s;
  s << name << " = " << value << " is invalid: " << rule;
  throw std::invalid_argument(s.str());
}

void number(const char* name, double v, bool strictly_positive, const char* unit, const char* doc)
{
  if (!std::isfinite(v) || (strictly_positive ? !(v > 0.0) : !(v >= 0.0)))
    invalid(name, v, std::string(doc) + (strictly_positive ? " (> 0)" : " (>= 0)") + " [" + unit + "]");
}

void integer(const char* name, int v, int lo, int hi, const char* doc)
{
  if (v < lo || v > hi)
    invalid(name, v, std::string(doc) + " (" + std::to_string(lo) + ".." + std::to_string(hi) + ")");
}

void address(const char* name, const std::string& text, std::uint32_t& ip, const char* doc)
{
  if (!parseIpv4(text, ip))
    invalid(name, "'" + text + "'", std::string(doc) + " (an IPv4 address)");
}
}  // namespace

void ReceiverConfig::validate()
{
  std::uint32_t ip = 0;
  address("bind_address", bind_address, ip, "local IP address to listen on (0.0.0.0 = all)");
  integer("port", port, 0, 65535, "UDP port of the state stream");
  link.any_source = allowed_source.empty() || allowed_source == "*";
  if (!link.any_source)
    address("allowed_source", allowed_source, link.source_ip, "console IP address, '' or '*' = any");
  integer("command_port", command_port, 0, 65535, "console UDP port for force commands (0 = source port)");
  number("timeout", link.timeout, true, "s", "watchdog timeout");
  number("resync_after", link.resync_after, true, "s", "silence after which the sequence restarts");
  if (link.resync_after < link.timeout)
    invalid("resync_after", link.resync_after, "must be >= ~timeout [s]");
  number("twist_cutoff_hz", link.twist_cutoff_hz, false, "Hz", "twist low-pass cut-off (0 = none)");
  number("max_force", wrench.max_force, false, "N", "force command clamp");
  number("max_torque", wrench.max_torque, false, "N m", "torque command clamp");
  number("wrench_timeout", wrench.wrench_timeout, true, "s", "age after which a force command is dropped");
  number("status_rate", status_rate, true, "Hz", "touchball/status rate");
  number("joint_states_rate", joint_states_rate, false, "Hz", "touch_<side>/joint_states rate (0 = off)");
  integer("publish_queue_size", publish_queue_size, 0, 100000, "outgoing queue of the per-packet topics (0 = 100)");
  integer("realtime_priority", realtime_priority, 0, 99,
          "SCHED_FIFO priority 1-99 of the receive thread (0 = normal scheduling)");
}

}  // namespace touchball
}  // namespace saras_drivers

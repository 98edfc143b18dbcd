/**
 * @file touchball_receiver_core.cpp
 * @brief Receive-thread / callback-queue hand-off of the Touchball receiver and its health report.
 */
#include "saras_drivers/touchball_receiver_core.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace saras_drivers
{
namespace touchball
{
std::uint64_t LinkHealth::rejectedDatagrams() const
{
  std::uint64_t n = 0;
  for (const auto c : rejected)
    n += c;
  return n;
}

// ------------------------------------------------------------------ ReceiverCore
ReceiverCore::ReceiverCore(const LinkParams& link, const WrenchLimits& wrench, const std::vector<std::uint8_t>& key,
                           double stall_factor, NonceSource nonce)
  : params_(link)
  , stall_factor_(stall_factor)
  , link_(link, key, nonce)
  , latches_{ { WrenchLatch(wrench.max_force, wrench.max_torque, wrench.wrench_timeout),
                WrenchLatch(wrench.max_force, wrench.max_torque, wrench.wrench_timeout) } }
{
}

double ReceiverCore::waitTime(double now, double idle_wake) const
{
  std::lock_guard<std::mutex> lock(mutex_);
  return link_.waitTime(now, stale_, idle_wake);
}

Reject ReceiverCore::accept(const std::uint8_t* data, std::size_t n, std::uint32_t source_ip, double now,
                            std::int64_t stamp_ns, AcceptedPacket& out, bool& resumed)
{
  std::lock_guard<std::mutex> lock(mutex_);
  resumed = false;
  const Reject r = link_.accept(data, n, source_ip, now);
  if (r != Reject::NONE)
    return r;
  out.kind = link_.kind();
  out.session = link_.session();
  out.console_nonce = link_.consoleNonce();
  if (out.kind != Accepted::STATE)
    return r;
  out.packet = link_.packet();
  for (int i = 0; i < kDevices; ++i)
  {
    std::copy(link_.twist(i).linear(), link_.twist(i).linear() + 3, out.linear[i]);
    std::copy(link_.twist(i).angular(), link_.twist(i).angular() + 3, out.angular[i]);
    out.commands[i] = latches_[i].get(now);
  }
  stamp_ns_ = stamp_ns;
  resumed = stale_;
  stale_ = false;
  return r;
}

bool ReceiverCore::watchdog(double now)
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (stale_ || !link_.isStale(now))
    return false;
  stale_ = true;
  return true;
}

void ReceiverCore::countSendError()
{
  std::lock_guard<std::mutex> lock(mutex_);
  ++send_errors_;
}

bool ReceiverCore::stale() const
{
  std::lock_guard<std::mutex> lock(mutex_);
  return stale_;
}

bool ReceiverCore::setWrench(int device, const double force[3], const double torque[3], double now)
{
  std::lock_guard<std::mutex> lock(mutex_);
  const bool ok = latches_[device].set(force, torque, now);
  if (!ok)
    ++wrench_rejected_;
  return ok;
}

void ReceiverCore::rejectWrench(int device)
{
  std::lock_guard<std::mutex> lock(mutex_);
  latches_[device].clear();
  ++wrench_rejected_;
}

bool ReceiverCore::packetSince(std::uint64_t& seen, StatePacket& out, std::int64_t& stamp_ns) const
{
  std::lock_guard<std::mutex> lock(mutex_);
  if (!link_.hasValid() || link_.received() == seen)
    return false;
  seen = link_.received();
  out = link_.packet();
  stamp_ns = stamp_ns_;
  return true;
}

LinkHealth ReceiverCore::health(double now) const
{
  std::lock_guard<std::mutex> lock(mutex_);
  LinkHealth h;
  h.has_valid = link_.hasValid();
  h.input_age = link_.inputAge(now);
  h.timeout = params_.timeout;
  h.stalled = !stale_ && h.input_age > stall_factor_ * params_.timeout;
  h.level = stale_ || h.stalled ? LinkLevel::STALE : LinkLevel::OK;
  h.received = link_.received();
  h.gaps = link_.gaps();
  for (int i = 0; i < kRejectReasons; ++i)
    h.rejected[i] = link_.rejected(static_cast<Reject>(i));
  h.wrench_rejected = wrench_rejected_;
  h.send_errors = send_errors_;
  h.sessions = link_.sessions();
  return h;
}

// ------------------------------------------------------------------ RateMeter
double RateMeter::update(std::uint64_t count, double now)
{
  double rate = 0.0;
  if (has_prev_ && now > t_ && count >= count_)
    rate = static_cast<double>(count - count_) / (now - t_);
  has_prev_ = true;
  count_ = count;
  t_ = now;
  return rate;
}

// ------------------------------------------------------------------ RejectLogLimiter
bool RejectLogLimiter::allow(Reject r, double now, std::uint64_t& suppressed)
{
  const int i = static_cast<int>(r);
  suppressed = 0;
  if (i < 0 || i >= kRejectReasons)
    return false;
  if (has_[i] && now - last_[i] < period_)
  {
    ++skipped_[i];
    return false;
  }
  suppressed = skipped_[i];
  skipped_[i] = 0;
  has_[i] = true;
  last_[i] = now;
  return true;
}

// ------------------------------------------------------------------ reports
const char* formatStatusText(const LinkHealth& h, const char* source, char* out, std::size_t size)
{
  if (h.stalled)
    std::snprintf(out, size, "receive thread stalled: no packet handled for %.1f ms", 1e3 * h.input_age);
  else if (h.level == LinkLevel::STALE && !h.has_valid)
    std::snprintf(out, size, "no valid packet from %s yet", source);
  else if (h.level == LinkLevel::STALE)
    std::snprintf(out, size, "no valid packet from %s for %.1f ms (timeout %.0f ms)", source, 1e3 * h.input_age,
                  1e3 * h.timeout);
  else
    std::snprintf(out, size, "streaming");
  return out;
}

namespace
{
std::string number(double v, const char* format)
{
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}
}  // namespace

HealthReport describeHealth(const LinkHealth& h, double packet_rate, const char* source)
{
  HealthReport r;
  r.level = h.level;
  char text[256];
  r.message = formatStatusText(h, source, text, sizeof text);
  auto add = [&r](const std::string& key, const std::string& value) { r.values.emplace_back(key, value); };
  add("packet rate [Hz]", number(packet_rate, "%.1f"));
  add("packets received", std::to_string(h.received));
  add("input age [ms]", h.has_valid ? number(1e3 * h.input_age, "%.1f") : "none received");
  add("timeout [ms]", number(1e3 * h.timeout, "%.1f"));
  add("sequence gaps", std::to_string(h.gaps));
  add("rejected datagrams", std::to_string(h.rejectedDatagrams()));
  for (int i = 0; i < kRejectReasons; ++i)
    add(std::string("rejected ") + rejectName(static_cast<Reject>(i)), std::to_string(h.rejected[i]));
  add("rejected wrench_cmd", std::to_string(h.wrench_rejected));
  add("command send errors", std::to_string(h.send_errors));
  add("sessions opened", std::to_string(h.sessions));
  add("source", source);
  return r;
}

}  // namespace touchball
}  // namespace saras_drivers

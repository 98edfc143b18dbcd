/**
 * @file touchball_link.cpp
 * @brief Touchball receiver core: authentication, session, validation, sequence, twist, watchdog,
 *        force latch.
 */
#include "saras_drivers/touchball_link.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace saras_drivers
{
namespace touchball
{
// ------------------------------------------------------------------ SequenceTracker
Reject SequenceTracker::accept(std::uint32_t seq, std::uint32_t& gap)
{
  gap = 0;
  if (has_last_)
  {
    const std::uint32_t diff = seq - last_;  // modulo 2^32
    if (diff == 0)
      return Reject::DUPLICATE;
    if (diff >= (1u << 31))
      return Reject::OUT_OF_ORDER;
    gap = diff - 1;
  }
  has_last_ = true;
  last_ = seq;
  gaps_ += gap;
  return Reject::NONE;
}

// ------------------------------------------------------------------ TwistEstimator
TwistEstimator::TwistEstimator(double cutoff_hz, double max_dt)
  : tau_(cutoff_hz > 0.0 ? 1.0 / (2.0 * M_PI * cutoff_hz) : 0.0), max_dt_(max_dt)
{
}

void TwistEstimator::reset()
{
  has_prev_ = false;
  std::fill(linear_, linear_ + 3, 0.0);
  std::fill(angular_, angular_ + 3, 0.0);
}

void TwistEstimator::update(double t, const double p[3], const double q[4])
{
  if (has_prev_)
  {
    const double dt = t - t_;
    if (!(dt > 0.0) || dt > max_dt_)
    {
      reset();
    }
    else
    {
      const double qx = q[0], qy = q[1], qz = q[2], qw = q[3];
      const double ax = q_[0], ay = q_[1], az = q_[2], aw = q_[3];
      // r = q * conj(q_prev): rotation from the previous to this orientation (base frame)
      double rx = -qw * ax + qx * aw - qy * az + qz * ay;
      double ry = -qw * ay + qx * az + qy * aw - qz * ax;
      double rz = -qw * az - qx * ay + qy * ax + qz * aw;
      const double rw = qw * aw + qx * ax + qy * ay + qz * az;
      if (rw < 0.0)
      {
        rx = -rx;
        ry = -ry;
        rz = -rz;
      }
      const double s = std::sqrt(rx * rx + ry * ry + rz * rz);
      double k = s < 1e-12 ? 2.0 : 2.0 * std::atan2(s, std::fabs(rw)) / s;  // log: axis * angle
      const double a = dt / (dt + tau_), b = a / dt;
      for (int i = 0; i < 3; ++i)
        linear_[i] += b * (p[i] - p_[i]) - a * linear_[i];
      k *= b;
      angular_[0] += k * rx - a * angular_[0];
      angular_[1] += k * ry - a * angular_[1];
      angular_[2] += k * rz - a * angular_[2];
    }
  }
  std::copy(p, p + 3, p_);
  std::copy(q, q + 4, q_);
  t_ = t;
  has_prev_ = true;
}

// ------------------------------------------------------------------ TouchballLink
TouchballLink::TouchballLink(const LinkParams& p, const std::vector<std::uint8_t>& key, NonceSource nonce)
  : p_(p), mac_(new Hmac(key)), nonce_(nonce)
{
  if (!(p.timeout > 0.0) || !std::isfinite(p.timeout))
    throw std::invalid_argument("timeout must be > 0 s");
  if (!(p.resync_after >= p.timeout) || !std::isfinite(p.resync_after))
    throw std::invalid_argument("resync_after must be >= timeout [s]");
  if (!(p.twist_cutoff_hz >= 0.0) || !std::isfinite(p.twist_cutoff_hz))
    throw std::invalid_argument("twist_cutoff_hz must be >= 0 Hz");
  if (nonce_ == nullptr)
    throw std::invalid_argument("no nonce source");
  for (auto& t : twist_)
    t = TwistEstimator(p.twist_cutoff_hz);
}

Reject TouchballLink::accept(const std::uint8_t* data, std::size_t n, std::uint32_t source_ip, double now)
{
  kind_ = Accepted::NONE;
  std::uint8_t type = 0;
  Reject r = Reject::NONE;
  if (!p_.any_source && source_ip != p_.source_ip)
    r = Reject::FOREIGN_SOURCE;
  else
    r = checkFrame(data, n, *mac_, type);
  if (r == Reject::NONE)
    r = type == kTypeHello ? onHello(data, now) : onState(data, now);
  if (r != Reject::NONE)
  {
    ++rejected_[static_cast<int>(r)];
    last_error_ = r;
  }
  return r;
}

Reject TouchballLink::onHello(const std::uint8_t* data, double now)
{
  Hello h;
  const Reject r = decodeHello(data, h);
  if (r != Reject::NONE)
    return r;
  if (session_states_ > 0 && now - last_valid_ <= p_.resync_after)
    return Reject::SESSION;  // a session is streaming: a second console or a replayed hello
  // the same console asking again before its first state packet (challenge lost): same session
  if (session_ == 0 || session_states_ > 0 || h.console_nonce != console_nonce_)
  {
    session_ = nonce_();
    console_nonce_ = h.console_nonce;
    session_states_ = 0;
    ++sessions_;
    sequence_.reset();
    for (auto& t : twist_)
      t.reset();
  }
  kind_ = Accepted::HELLO;
  return Reject::NONE;
}

Reject TouchballLink::onState(const std::uint8_t* data, double now)
{
  Reject r = decodeState(data, session_, scratch_);
  std::uint32_t gap = 0;
  if (r == Reject::NONE)
    r = sequence_.accept(scratch_.seq, gap);
  if (r != Reject::NONE)
    return r;
  packet_ = scratch_;
  gap_ = gap;
  for (int d = 0; d < kDevices; ++d)
    twist_[d].update(packet_.sender_time, packet_.devices[d].position, packet_.devices[d].orientation);
  ++received_;
  ++session_states_;
  has_valid_ = true;
  last_valid_ = now;
  kind_ = Accepted::STATE;
  return Reject::NONE;
}

std::uint64_t TouchballLink::rejectedTotal() const
{
  std::uint64_t n = 0;
  for (const auto c : rejected_)
    n += c;
  return n;
}

std::string TouchballLink::rejectedSummary() const
{
  std::string s;
  for (int i = 0; i < kRejectReasons; ++i)
  {
    if (rejected_[i] == 0)
      continue;
    if (!s.empty())
      s += ", ";
    s += rejectName(static_cast<Reject>(i));
    s += ' ' + std::to_string(rejected_[i]);
  }
  return s;
}

double TouchballLink::inputAge(double now) const
{
  return has_valid_ ? now - last_valid_ : std::numeric_limits<double>::infinity();
}

double TouchballLink::waitTime(double now, bool stale, double idle_wake) const
{
  if (stale || !has_valid_)
    return idle_wake;
  return std::max(0.0, last_valid_ + p_.timeout - now);
}

// ------------------------------------------------------------------ WrenchLatch
WrenchLatch::WrenchLatch(double max_force, double max_torque, double max_age)
  : max_force_(max_force), max_torque_(max_torque), max_age_(max_age)
{
  if (!(max_force >= 0.0) || !(max_torque >= 0.0) || !(max_age > 0.0) || !std::isfinite(max_force) ||
      !std::isfinite(max_torque) || !std::isfinite(max_age))
    throw std::invalid_argument("max_force, max_torque must be >= 0 and max_age > 0");
}

namespace
{
void clamp(const double in[3], double limit, double out[3])
{
  const double n = std::sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
  const double s = n > limit ? (n > 0.0 ? limit / n : 0.0) : 1.0;
  for (int i = 0; i < 3; ++i)
    out[i] = in[i] * s;
}
}  // namespace

bool WrenchLatch::set(const double force[3], const double torque[3], double now)
{
  for (int i = 0; i < 3; ++i)
  {
    if (!std::isfinite(force[i]) || !std::isfinite(torque[i]))
    {
      has_ = false;
      return false;
    }
  }
  clamp(force, max_force_, cmd_.force);
  clamp(torque, max_torque_, cmd_.torque);
  cmd_.enabled = true;
  has_ = true;
  stamp_ = now;
  return true;
}

DeviceCommand WrenchLatch::get(double now) const
{
  if (!has_ || now - stamp_ > max_age_)
    return DeviceCommand();
  return cmd_;
}

}  // namespace touchball
}  // namespace saras_drivers

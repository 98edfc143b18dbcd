/**
 * @file delay_channel.h
 * @brief Communication-channel model: constant delay, uniform jitter, random or bursty loss
 *        (Gilbert-Elliott), ROS-agnostic. Used by the closed-loop simulation and the channel node.
 *
 * Each pushed message is dropped with the loss model or scheduled for delivery at
 * t + delay + U(0, jitter). With preserve_order (default) a message is never delivered before an
 * earlier one (like a TCP stream), so jitter delays but does not reorder.
 */
#ifndef SARAS_TELEOP_DELAY_CHANNEL_H
#define SARAS_TELEOP_DELAY_CHANNEL_H

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <random>
#include <utility>

namespace saras_teleop
{
struct ChannelParams
{
  double delay = 0.0;         ///< constant one-way delay [s]
  double jitter = 0.0;        ///< extra delay, uniform in [0, jitter] [s]
  double loss = 0.0;          ///< long-run fraction of dropped messages [0, 1)
  double burst_length = 1.0;  ///< mean number of consecutive drops (1: independent losses) [messages]
  bool preserve_order = true;
  std::uint32_t seed = 1;
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/// Gilbert-Elliott two-state loss process (good: deliver, bad: drop).
class LossModel
{
public:
  explicit LossModel(const ChannelParams& p);
  /// True if the next message is dropped.
  bool drop();
  std::size_t dropped() const { return dropped_; }

private:
  double loss_, p_gb_, p_bg_;
  bool bad_ = false;
  std::mt19937 rng_;
  std::uniform_real_distribution<double> u_{ 0.0, 1.0 };
  std::size_t dropped_ = 0;
};

template <class T>
class DelayChannel
{
public:
  explicit DelayChannel(const ChannelParams& p)
    : p_(p), loss_(p), rng_(p.seed ^ 0x9e3779b9u), u_(0.0, 1.0)
  {
    p_.validate();
  }

  /// Offer a message sent at time now [s]. Returns false if the channel dropped it.
  bool push(const T& msg, double now)
  {
    if (loss_.drop())
      return false;
    double t = now + p_.delay + (p_.jitter > 0.0 ? p_.jitter * u_(rng_) : 0.0);
    if (p_.preserve_order && !queue_.empty())
      t = std::max(t, queue_.back().first);
    if (p_.preserve_order || queue_.empty() || t >= queue_.back().first)
    {
      queue_.emplace_back(t, msg);
    }
    else
    {
      auto it = std::upper_bound(queue_.begin(), queue_.end(), t,
                                 [](double a, const std::pair<double, T>& b) { return a < b.first; });
      queue_.emplace(it, t, msg);
    }
    return true;
  }

  /// Deliver every message due at time now [s] (1 ns tolerance for rounding of sampled clocks),
  /// in order, to f(const T&). Returns how many.
  template <class F>
  std::size_t deliver(double now, F&& f)
  {
    std::size_t n = 0;
    while (!queue_.empty() && queue_.front().first <= now + 1e-9)
    {
      f(queue_.front().second);
      queue_.pop_front();
      ++n;
    }
    return n;
  }

  std::size_t pending() const { return queue_.size(); }
  std::size_t dropped() const { return loss_.dropped(); }
  const ChannelParams& params() const { return p_; }

private:
  ChannelParams p_;
  LossModel loss_;
  std::mt19937 rng_;
  std::uniform_real_distribution<double> u_;
  std::deque<std::pair<double, T>> queue_;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_DELAY_CHANNEL_H

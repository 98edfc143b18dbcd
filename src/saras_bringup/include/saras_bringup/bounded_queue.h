/**
 * @file bounded_queue.h
 * @brief ROS-agnostic hand-off queue of the bag recorder: many producers (subscription callbacks),
 *        one consumer (the bag writer), bounded by a byte budget; when full the oldest items are
 *        dropped and counted (a recorder must never grow without bound, and must say what it lost).
 */
#ifndef SARAS_BRINGUP_BOUNDED_QUEUE_H
#define SARAS_BRINGUP_BOUNDED_QUEUE_H

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>

namespace saras_bringup
{
/**
 * FIFO of items of known size [bytes]. push() never blocks: when the queued bytes would exceed
 * the budget, the oldest items are dropped (dropped() counts them). pop() waits up to a timeout.
 * Thread-safe. An item larger than the whole budget is still accepted alone (everything older
 * is dropped), so a single large message never stalls the stream.
 * With a wake threshold, push() wakes a waiting pop() only once that many bytes are queued: a consumer
 * polling with a short timeout then takes the items in batches, instead of one thread wake-up per item
 * (the recorder takes ~15000 small messages per second at 1 kHz).
 */
template <class T>
class BoundedQueue
{
public:
  /// @param budget_bytes largest sum of item sizes kept [bytes] (> 0)
  /// @param wake_bytes push() wakes a waiting pop() when at least this many bytes are queued (0: always)
  explicit BoundedQueue(std::size_t budget_bytes, std::size_t wake_bytes = 0)
    : budget_(budget_bytes > 0 ? budget_bytes : 1), wake_bytes_(wake_bytes)
  {
  }

  /// Appends @p item of @p bytes; drops the oldest items beyond the budget. Returns how many were dropped.
  std::size_t push(T item, std::size_t bytes)
  {
    std::size_t dropped = 0;
    bool wake = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      items_.emplace_back(std::move(item), bytes);
      bytes_ += bytes;
      while (bytes_ > budget_ && items_.size() > 1)
      {
        bytes_ -= items_.front().second;
        items_.pop_front();
        ++dropped;
      }
      dropped_ += dropped;
      ++pushed_;
      if (bytes_ > peak_bytes_)
        peak_bytes_ = bytes_;
      wake = bytes_ >= wake_bytes_;
    }
    if (wake)
      cv_.notify_one();
    return dropped;
  }

  /// Takes the oldest item into @p out; waits up to @p timeout. False on timeout (or close() and empty).
  bool pop(T& out, std::chrono::milliseconds timeout)
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!cv_.wait_for(lock, timeout, [this] { return !items_.empty() || closed_; }) || items_.empty())
      return false;
    out = std::move(items_.front().first);
    bytes_ -= items_.front().second;
    items_.pop_front();
    return true;
  }

  /// Wakes a waiting pop(); items already queued can still be popped.
  void close()
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

  std::size_t size() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  /// Items dropped because the budget was exceeded.
  std::uint64_t dropped() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  std::uint64_t pushed() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }
  /// Bytes queued now [bytes].
  std::size_t bytes() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return bytes_;
  }
  /// Largest number of queued bytes seen [bytes].
  std::size_t peakBytes() const
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return peak_bytes_;
  }

private:
  const std::size_t budget_;
  const std::size_t wake_bytes_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<T, std::size_t>> items_;
  std::size_t bytes_ = 0;
  std::size_t peak_bytes_ = 0;
  std::uint64_t dropped_ = 0;
  std::uint64_t pushed_ = 0;
  bool closed_ = false;
};

}  // namespace saras_bringup

#endif  // SARAS_BRINGUP_BOUNDED_QUEUE_H

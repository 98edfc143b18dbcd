/**
 * @file message_pool.h
 * @brief Reusable outgoing messages for zero-copy intra-process publishing without allocating on the
 *        real-time path (header only, ROS-agnostic: any copyable type held by boost::shared_ptr).
 *
 * roscpp hands a published boost::shared_ptr<const M> to intra-process subscribers (nodelets in the
 * same manager) without serialising it; the message must then never be modified again while anybody
 * still holds it. next() returns a slot whose only owner is the pool (use_count() == 1: no publisher
 * queue or subscriber references it any more), so it may be overwritten and published.
 *
 * Why the check cannot race: roscpp serialises a message for its TCP/UDP subscribers inside
 * publish(), and intra-process subscribers keep their shared pointer while they read the message.
 * Once the count is 1, only the pool can create a new reference. The pool itself is not thread-safe:
 * one pool per publishing thread.
 *
 * Reuse order: the most recently handed-out free slot first. When subscribers release messages
 * promptly the same slot is reused every time, so a large buffer (a 6 MB image) stays warm in the
 * CPU caches instead of cycling through cold ones. If every slot is still referenced (slow
 * subscribers with long queues), one slot is given up to its readers and replaced by a fresh copy of
 * the prototype; allocations() counts those, and also the growth of a slot's byte buffer in
 * nextWithData(). In steady state, with at least as many slots as messages in flight, it stays 0.
 */
#ifndef SARAS_COMMON_MESSAGE_POOL_H
#define SARAS_COMMON_MESSAGE_POOL_H

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <boost/make_shared.hpp>
#include <boost/shared_ptr.hpp>

namespace saras_common
{
/**
 * @tparam M message type (copyable; e.g. geometry_msgs::PoseStamped, sensor_msgs::Image)
 */
template <class M>
class MessagePool
{
public:
  /**
   * @param size number of preallocated messages (>= 1): publisher queue depth plus the messages a
   *        slow intra-process subscriber may hold
   * @param prototype copied into every slot (constant fields such as header.frame_id are set once)
   * @throws std::invalid_argument if size is 0
   */
  explicit MessagePool(std::size_t size, const M& prototype = M()) : prototype_(prototype)
  {
    if (size == 0)
      throw std::invalid_argument("MessagePool size must be >= 1");
    slots_.reserve(size);
    for (std::size_t i = 0; i < size; ++i)
      slots_.push_back(boost::make_shared<M>(prototype));
  }

  /// A message nobody else references. Its previous content is left in place: the caller
  /// overwrites every variable field. Never returns a message that a subscriber may still read.
  boost::shared_ptr<M> next()
  {
    const std::size_t n = slots_.size();
    for (std::size_t k = 0; k < n; ++k)
    {
      const std::size_t i = (last_ + n - k) % n;
      if (slots_[i].use_count() == 1)
      {
        last_ = i;
        return slots_[i];
      }
    }
    // every slot is in use: replace the one after the last handed out (its holders keep it alive)
    last_ = (last_ + 1) % n;
    slots_[last_] = boost::make_shared<M>(prototype_);
    ++allocations_;
    return slots_[last_];
  }

  /**
   * next(), with its byte buffer `data` (sensor_msgs::Image, CompressedImage ...) resized to
   * @p bytes (contents unspecified). Resizing a slot to a size it has held before does not allocate;
   * a buffer that must grow is counted in allocations(). Only for types with a std::vector `data`.
   */
  boost::shared_ptr<M> nextWithData(std::size_t bytes)
  {
    boost::shared_ptr<M> m = next();
    if (m->data.capacity() < bytes)
      ++allocations_;
    m->data.resize(bytes);
    return m;
  }

  /// The prototype every slot was (and every replacement is) copied from.
  const M& prototype() const { return prototype_; }
  /// Number of slots.
  std::size_t size() const { return slots_.size(); }
  /// Allocations since construction: slots replaced because every slot was held, and byte
  /// buffers grown by nextWithData(). Constant in steady state.
  std::uint64_t allocations() const { return allocations_; }

private:
  M prototype_;
  std::vector<boost::shared_ptr<M>> slots_;
  std::size_t last_ = 0;  ///< slot handed out last
  std::uint64_t allocations_ = 0;
};

}  // namespace saras_common

#endif  // SARAS_COMMON_MESSAGE_POOL_H

/**
 * @file message_pool.h
 * @brief A fixed ring of shared messages for zero-copy intra-process publishing without allocating
 *        on the control path (ROS-agnostic: any copyable type held by boost::shared_ptr).
 *
 * roscpp hands a published boost::shared_ptr<const M> to intra-process subscribers (nodelets in the
 * same manager) without serialising it; the message must then never be modified again while anybody
 * still holds it. next() returns a slot whose only owner is the pool (use_count() == 1: no queue,
 * subscriber or publisher references it any more), so it may be overwritten and published. If every
 * slot is still referenced (slow subscribers with long queues), a fresh copy of the prototype is
 * allocated and replaces the oldest slot; allocations() counts those (0 in steady state when the
 * pool is at least as large as the subscriber queues).
 */
#ifndef SARAS_TELEOP_MESSAGE_POOL_H
#define SARAS_TELEOP_MESSAGE_POOL_H

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <boost/make_shared.hpp>
#include <boost/shared_ptr.hpp>

namespace saras_teleop
{
template <class M>
class MessagePool
{
public:
  /**
   * @param size number of preallocated messages (>= 1)
   * @param prototype copied into every slot (constant fields such as header.frame_id are set once)
   */
  explicit MessagePool(std::size_t size, const M& prototype = M()) : prototype_(prototype)
  {
    if (size == 0)
      throw std::invalid_argument("MessagePool size must be >= 1");
    slots_.reserve(size);
    for (std::size_t i = 0; i < size; ++i)
      slots_.push_back(boost::make_shared<M>(prototype));
  }

  /// A message nobody else references (its previous content is left in place: overwrite every
  /// variable field). Never returns a message that a subscriber may still read.
  boost::shared_ptr<M> next()
  {
    for (std::size_t k = 0; k < slots_.size(); ++k)
    {
      const std::size_t i = (cursor_ + k) % slots_.size();
      if (slots_[i].use_count() == 1)
      {
        cursor_ = (i + 1) % slots_.size();
        return slots_[i];
      }
    }
    // every slot is in use: replace the slot at the cursor (its holders keep their copy alive)
    ++allocations_;
    slots_[cursor_] = boost::make_shared<M>(prototype_);
    const std::size_t i = cursor_;
    cursor_ = (cursor_ + 1) % slots_.size();
    return slots_[i];
  }

  /// The prototype (change constant fields here before the first next(); slots keep their copies).
  const M& prototype() const { return prototype_; }
  std::size_t size() const { return slots_.size(); }
  /// Number of messages allocated after construction because every slot was still referenced.
  std::uint64_t allocations() const { return allocations_; }

private:
  M prototype_;
  std::vector<boost::shared_ptr<M>> slots_;
  std::size_t cursor_ = 0;
  std::uint64_t allocations_ = 0;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_MESSAGE_POOL_H

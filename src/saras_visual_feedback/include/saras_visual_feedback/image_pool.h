/**
 * @file image_pool.h
 * @brief A small pool of sensor_msgs::Image output buffers reused once every subscriber has
 *        released them, so that publishing a 1080p frame costs one memcpy and no allocation (a
 *        fresh 6 MB vector costs page faults and zero-filling on every frame).
 *
 * Safety: a buffer is handed out again only when the pool holds the last reference
 * (use_count() == 1). roscpp serialises for remote subscribers inside publish(), and
 * intra-process subscribers (nodelets in the same manager) keep their shared pointer while they
 * use the message, so no reader can see a reused buffer change. No new reference to a released
 * buffer can appear except through the pool, so the check cannot race.
 */
#ifndef SARAS_VISUAL_FEEDBACK_IMAGE_POOL_H
#define SARAS_VISUAL_FEEDBACK_IMAGE_POOL_H

#include <array>
#include <cstddef>

#include <boost/make_shared.hpp>
#include <sensor_msgs/Image.h>

namespace saras_visual_feedback
{

class ImagePool
{
public:
  /// Pool size: enough for the publisher queue plus a few slow subscribers.
  static constexpr std::size_t kSize = 6;

  /**
   * @brief A message whose data has @p bytes bytes (contents unspecified), not referenced by
   *        anyone else. Allocates only when every pooled buffer is still in use (the oldest
   *        slot is then replaced, its buffer stays alive with its readers) or when the size changes.
   */
  sensor_msgs::ImagePtr acquire(std::size_t bytes)
  {
    // The most recently handed-out free buffer first: when subscribers release frames promptly
    // (intra-process), the same buffer is reused frame after frame and is still in the CPU
    // caches, instead of cycling through kSize cold 6 MB buffers.
    for (std::size_t k = 0; k < kSize; ++k)
    {
      const std::size_t i = (last_ + kSize - k) % kSize;
      sensor_msgs::ImagePtr& slot = slots_[i];
      if (slot && slot.use_count() == 1)
        return handOut(i, bytes);
    }
    for (std::size_t i = 0; i < kSize; ++i)
      if (!slots_[i])
        return handOut(i, bytes);
    // All in use: replace one slot (its old buffer lives on with its readers).
    const std::size_t i = (last_ + 1) % kSize;
    slots_[i].reset();
    return handOut(i, bytes);
  }

  /// Buffers allocated since construction (steady state: stays at the number in flight).
  std::size_t allocations() const { return allocations_; }

private:
  sensor_msgs::ImagePtr handOut(std::size_t i, std::size_t bytes)
  {
    sensor_msgs::ImagePtr& slot = slots_[i];
    if (!slot)
    {
      slot = boost::make_shared<sensor_msgs::Image>();
      ++allocations_;
    }
    if (slot->data.size() != bytes)
      slot->data.resize(bytes);
    last_ = i;
    return slot;
  }

  std::array<sensor_msgs::ImagePtr, kSize> slots_;
  std::size_t last_ = 0;
  std::size_t allocations_ = 0;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_IMAGE_POOL_H

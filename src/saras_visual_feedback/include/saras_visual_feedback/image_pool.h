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
    for (std::size_t k = 0; k < kSize; ++k)
    {
      const std::size_t i = (next_ + k) % kSize;
      sensor_msgs::ImagePtr& slot = slots_[i];
      if (slot && slot.use_count() == 1)
      {
        next_ = (i + 1) % kSize;
        if (slot->data.size() != bytes)
          slot->data.resize(bytes);
        return slot;
      }
      if (!slot)
      {
        slot = boost::make_shared<sensor_msgs::Image>();
        slot->data.resize(bytes);
        ++allocations_;
        next_ = (i + 1) % kSize;
        return slot;
      }
    }
    // All in use: replace the next slot (its old buffer lives on with its readers).
    sensor_msgs::ImagePtr& slot = slots_[next_];
    slot = boost::make_shared<sensor_msgs::Image>();
    slot->data.resize(bytes);
    ++allocations_;
    next_ = (next_ + 1) % kSize;
    return slot;
  }

  /// Buffers allocated since construction (steady state: stays at the number in flight).
  std::size_t allocations() const { return allocations_; }

private:
  std::array<sensor_msgs::ImagePtr, kSize> slots_;
  std::size_t next_ = 0;
  std::size_t allocations_ = 0;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_IMAGE_POOL_H

/**
 * @file endoscope_message_pool.h
 * @brief Reusable outgoing messages for the endoscope simulator (header only, no ROS needed:
 *        works for any default-constructible message type held by boost::shared_ptr).
 *
 * Publishing a fresh 1280x720 bgr8 sensor_msgs::Image per frame costs a 2.7 MB allocation with
 * page faults and zero-filling (6.2 MB at 1080p); the pool hands out a message that nobody else
 * references any more, so the renderer writes straight into an already-mapped buffer.
 *
 * Why reuse is safe: a message is handed out again only when the pool's reference is the only
 * one (use_count() == 1). roscpp serialises a message for its TCP/UDP subscribers inside
 * publish(); intra-process subscribers (nodelets in the same manager) hold the shared pointer
 * for as long as they use the message. Once the count is 1, only the pool can create a new
 * reference, so the check does not race with readers. Not thread-safe itself: one pool per
 * publishing thread (the simulator keeps one per eye).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_MESSAGE_POOL_H
#define SARAS_SIMULATION_ENDOSCOPE_MESSAGE_POOL_H

#include <array>
#include <cstddef>

#include <boost/make_shared.hpp>
#include <boost/shared_ptr.hpp>

namespace saras_simulation
{
namespace endoscope
{
/**
 * @tparam M message type (e.g. sensor_msgs::Image, sensor_msgs::CompressedImage)
 * @tparam N slots: publisher queue depth + messages a slow intra-process subscriber may hold
 */
template <class M, std::size_t N = 4>
class MessagePool
{
public:
  /**
   * A message referenced by nobody else (its previous contents are left as they were: the caller
   * overwrites every field). Prefers the most recently used free slot (its buffer is still warm
   * in the caches); allocates only while every slot is held by a subscriber (the oldest slot is
   * then given up to its readers and replaced).
   */
  boost::shared_ptr<M> acquire()
  {
    for (std::size_t k = 0; k < N; ++k)
    {
      const std::size_t i = (last_ + N - k) % N;
      if (slots_[i] && slots_[i].use_count() == 1)
        return take(i);
    }
    for (std::size_t i = 0; i < N; ++i)
      if (!slots_[i])
        return take(i);
    const std::size_t i = (last_ + 1) % N;  // all held: the least recently handed out goes
    slots_[i].reset();
    return take(i);
  }

  /// Messages constructed since the pool was created (steady state: constant).
  std::size_t allocations() const { return allocations_; }

private:
  boost::shared_ptr<M> take(std::size_t i)
  {
    if (!slots_[i])
    {
      slots_[i] = boost::make_shared<M>();
      ++allocations_;
    }
    last_ = i;
    return slots_[i];
  }

  std::array<boost::shared_ptr<M>, N> slots_;
  std::size_t last_ = 0;
  std::size_t allocations_ = 0;
};

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_MESSAGE_POOL_H

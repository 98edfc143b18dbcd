/**
 * @file inline_callback_queue.h
 * @brief A roscpp callback queue that runs each callback at once, in the thread that adds it.
 *
 * roscpp delivers a message from another process in its network (poll) thread, which adds the
 * subscription's callback to a callback queue; a spinner thread then wakes up and runs it: two thread
 * hand-offs per message. For a subscription whose callback is short, thread-safe and never blocks
 * (e.g. the recorder's: it appends the serialised message to its writer's queue), giving it an
 * InlineCallbackQueue (ros::SubscribeOptions::callback_queue) runs the callback in the poll thread and
 * saves the wake-up of a spinner per message. No spinner serves this queue.
 *
 * Rules for callbacks on this queue: they run in roscpp's poll thread (or, for an intra-process
 * publisher, in the publisher's thread) while roscpp holds the subscription's callback lock, so they
 * must return quickly, must not block, and must not subscribe or unsubscribe. Timers and services do
 * not belong on it. A callback that asks to be tried again (another thread runs the same
 * non-reentrant subscription) is retried a bounded number of times, then dropped and counted.
 */
#ifndef SARAS_COMMON_INLINE_CALLBACK_QUEUE_H
#define SARAS_COMMON_INLINE_CALLBACK_QUEUE_H

#include <atomic>
#include <cstdint>
#include <thread>

#include <ros/callback_queue_interface.h>

namespace saras_common
{
class InlineCallbackQueue : public ros::CallbackQueueInterface
{
public:
  void addCallback(const ros::CallbackInterfacePtr& callback, uint64_t /*owner_id*/ = 0) override
  {
    for (int attempt = 0; attempt < kAttempts; ++attempt)
    {
      if (callback->ready() && callback->call() != ros::CallbackInterface::TryAgain)
        return;
      std::this_thread::yield();
    }
    ++dropped_;
  }

  void removeByID(uint64_t /*owner_id*/) override {}  // nothing is ever pending

  /// Callbacks given up after kAttempts TryAgain answers.
  std::uint64_t dropped() const { return dropped_.load(); }

private:
  static constexpr int kAttempts = 100;
  std::atomic<std::uint64_t> dropped_{ 0 };
};

}  // namespace saras_common

#endif  // SARAS_COMMON_INLINE_CALLBACK_QUEUE_H

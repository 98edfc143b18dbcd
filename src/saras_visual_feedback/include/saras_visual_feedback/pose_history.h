/**
 * @file pose_history.h
 * @brief ROS-agnostic, allocation-free time-indexed ring buffer of tool poses, interpolated at an
 *        arbitrary stamp (linear position, slerp orientation). Lets the overlay draw each tool
 *        where it was when the endoscope image was taken (image header.stamp) instead of where it
 *        is when the image happens to be processed.
 */
#ifndef SARAS_VISUAL_FEEDBACK_POSE_HISTORY_H
#define SARAS_VISUAL_FEEDBACK_POSE_HISTORY_H

#include <cstddef>
#include <cstdint>
#include <vector>

namespace saras_visual_feedback
{

/// A pose sample: stamp [ns] (any monotonic clock shared with the images, e.g. ROS time),
/// position [m] and unit quaternion (x, y, z, w), both in the pose's frame.
struct TimedPose
{
  std::int64_t stamp_ns = 0;                    ///< [ns]
  double position[3] = {0.0, 0.0, 0.0};         ///< [m]
  double orientation[4] = {0.0, 0.0, 0.0, 1.0}; ///< x, y, z, w (unit)
};

/// Spherical linear interpolation of unit quaternions (x, y, z, w) along the shortest arc:
/// @p f = 0 gives @p q0, 1 gives @p q1 (or -q1). The result is normalised.
void slerp(const double q0[4], const double q1[4], double f, double out[4]);

/// Interpolates @p a and @p b at stamp @p stamp_ns (a.stamp <= stamp <= b.stamp; a when equal).
TimedPose interpolate(const TimedPose& a, const TimedPose& b, std::int64_t stamp_ns);

/// How PoseHistory::lookup() answered.
enum class PoseLookup
{
  kEmpty,         ///< no sample: nothing returned
  kInterpolated,  ///< stamp inside [oldest, newest]: pose interpolated at the stamp
  kAfterNewest,   ///< stamp newer than the newest sample: the newest is returned (no extrapolation)
  kBeforeOldest   ///< stamp older than the buffered window: the newest is returned (fallback)
};

/// Result of PoseHistory::lookup().
struct PoseLookupResult
{
  PoseLookup status = PoseLookup::kEmpty;
  TimedPose pose;              ///< the pose used (stamp_ns = the stamp it is valid at)
  std::int64_t offset_ns = 0;  ///< |requested stamp - stamp of the pose used| [ns]; 0 when interpolated
};

/// What PoseHistory::push() did with a sample.
enum class PosePush
{
  kAppended,  ///< newer than the newest: appended (the oldest dropped when full)
  kReplaced,  ///< same stamp as the newest: replaced it
  kRestarted  ///< older than the newest (clock jumped back, e.g. a looped bag): history restarted with it
};

/**
 * @brief Fixed-capacity ring buffer of TimedPose in increasing stamp order.
 *
 * Memory is reserved by the constructor / setCapacity(); push() and lookup() never allocate and
 * run in O(1) and O(log n). Not thread-safe (the caller holds a lock).
 */
class PoseHistory
{
public:
  /// @param capacity number of samples kept (>= 2), e.g. 512 ≈ 2 s at 250 Hz
  explicit PoseHistory(std::size_t capacity = 512);

  /// Changes the capacity (allocates) and clears the history.
  void setCapacity(std::size_t capacity);
  std::size_t capacity() const { return buffer_.size(); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  void clear() { size_ = 0; }

  /// Adds a sample (see PosePush).
  PosePush push(const TimedPose& sample);

  /// Oldest / newest sample (undefined when empty).
  const TimedPose& oldest() const { return at(0); }
  const TimedPose& newest() const { return at(size_ - 1); }

  /// The pose at @p stamp_ns (see PoseLookup).
  PoseLookupResult lookup(std::int64_t stamp_ns) const;

private:
  /// i-th sample in stamp order, 0 = oldest.
  const TimedPose& at(std::size_t i) const { return buffer_[(head_ + i) % buffer_.size()]; }

  std::vector<TimedPose> buffer_;
  std::size_t head_ = 0;  ///< index of the oldest sample in buffer_
  std::size_t size_ = 0;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_POSE_HISTORY_H

#include "saras_visual_feedback/pose_history.h"

#include <algorithm>
#include <cmath>

namespace saras_visual_feedback
{

void slerp(const double q0[4], const double q1[4], double f, double out[4])
{
  double b[4] = {q1[0], q1[1], q1[2], q1[3]};
  double dot = q0[0] * b[0] + q0[1] * b[1] + q0[2] * b[2] + q0[3] * b[3];
  if (dot < 0.0)  // q and -q are the same rotation: take the shortest arc
  {
    for (double& c : b)
      c = -c;
    dot = -dot;
  }
  double w0, w1;
  if (dot > 0.9995)
  {
    // Nearly parallel: sin(theta) -> 0, linear interpolation (normalised below) is exact enough.
    w0 = 1.0 - f;
    w1 = f;
  }
  else
  {
    const double theta = std::acos(std::min(dot, 1.0));
    const double s = std::sin(theta);
    w0 = std::sin((1.0 - f) * theta) / s;
    w1 = std::sin(f * theta) / s;
  }
  double n = 0.0;
  for (int i = 0; i < 4; ++i)
  {
    out[i] = w0 * q0[i] + w1 * b[i];
    n += out[i] * out[i];
  }
  n = std::sqrt(n);
  if (n > 0.0)
    for (int i = 0; i < 4; ++i)
      out[i] /= n;
}

TimedPose interpolate(const TimedPose& a, const TimedPose& b, std::int64_t stamp_ns)
{
  const std::int64_t span = b.stamp_ns - a.stamp_ns;
  if (span <= 0 || stamp_ns <= a.stamp_ns)
  {
    TimedPose r = a;
    r.stamp_ns = stamp_ns;
    return r;
  }
  const double f = std::min(1.0, static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(span));
  TimedPose r;
  r.stamp_ns = stamp_ns;
  for (int i = 0; i < 3; ++i)
    r.position[i] = a.position[i] + f * (b.position[i] - a.position[i]);
  slerp(a.orientation, b.orientation, f, r.orientation);
  return r;
}

PoseHistory::PoseHistory(std::size_t capacity)
{
  setCapacity(capacity);
}

void PoseHistory::setCapacity(std::size_t capacity)
{
  buffer_.assign(std::max<std::size_t>(capacity, 2), TimedPose());
  head_ = 0;
  size_ = 0;
}

PosePush PoseHistory::push(const TimedPose& sample)
{
  if (size_ > 0)
  {
    const std::int64_t newest_ns = newest().stamp_ns;
    if (sample.stamp_ns == newest_ns)
    {
      buffer_[(head_ + size_ - 1) % buffer_.size()] = sample;
      return PosePush::kReplaced;
    }
    if (sample.stamp_ns < newest_ns)
    {
      head_ = 0;
      size_ = 1;
      buffer_[0] = sample;
      return PosePush::kRestarted;
    }
  }
  if (size_ < buffer_.size())
  {
    buffer_[(head_ + size_) % buffer_.size()] = sample;
    ++size_;
  }
  else
  {
    buffer_[head_] = sample;  // overwrite the oldest
    head_ = (head_ + 1) % buffer_.size();
  }
  return PosePush::kAppended;
}

PoseLookupResult PoseHistory::lookup(std::int64_t stamp_ns) const
{
  PoseLookupResult r;
  if (size_ == 0)
    return r;
  const TimedPose& last = newest();
  if (stamp_ns >= last.stamp_ns)
  {
    r.status = stamp_ns == last.stamp_ns ? PoseLookup::kInterpolated : PoseLookup::kAfterNewest;
    r.pose = last;
    r.offset_ns = stamp_ns - last.stamp_ns;
    return r;
  }
  if (stamp_ns < oldest().stamp_ns)
  {
    r.status = PoseLookup::kBeforeOldest;
    r.pose = last;
    r.offset_ns = last.stamp_ns - stamp_ns;
    return r;
  }
  // Binary search of the last sample with stamp <= stamp_ns (exists: oldest <= stamp < newest).
  std::size_t lo = 0, hi = size_ - 1;  // invariant: at(lo) <= stamp < at(hi)
  while (hi - lo > 1)
  {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (at(mid).stamp_ns <= stamp_ns)
      lo = mid;
    else
      hi = mid;
  }
  r.status = PoseLookup::kInterpolated;
  r.pose = interpolate(at(lo), at(hi), stamp_ns);
  r.offset_ns = 0;
  return r;
}

}  // namespace saras_visual_feedback

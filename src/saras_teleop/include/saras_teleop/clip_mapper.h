/**
 * @file clip_mapper.h
 * @brief Simball clip angle -> instrument jaw command (D7.2 Sections 2.3.1-2.3.2), ROS-agnostic.
 *
 * The assistant opens and closes the SARAS instrument's jaw with the Simball clip. The clip angle
 * (after the console's clip-range calibration, [rad]) is mapped to a jaw target
 * `clamp(offset + scale * clip, jaw_min, jaw_max)`; the command moves toward that target at no more
 * than max_velocity [rad/s] (rate limit over the time between steps, at most max_step per step).
 *
 * The command starts at the MEASURED jaw (setMeasured): before a measured jaw there is no command.
 * It holds (does not change) while the caller says so (console link stale, clutch, safe hold of the
 * arm), while no clip sample is younger than input_timeout, and after a rejected (non-finite)
 * sample until the next valid one: bad or missing input never moves the jaw.
 */
#ifndef SARAS_TELEOP_CLIP_MAPPER_H
#define SARAS_TELEOP_CLIP_MAPPER_H

#include <cstddef>

namespace saras_teleop
{
struct ClipParams
{
  double scale = 1.0;          ///< jaw [rad] per clip [rad] (> 0)
  double offset = 0.0;         ///< [rad] jaw target at clip angle 0
  double jaw_min = 0.0;        ///< [rad] lower end of the jaw range (closed)
  double jaw_max = 1.0472;     ///< [rad] upper end of the jaw range (open; SARAS adapter: 60 deg)
  double max_velocity = 1.0;   ///< [rad/s] largest jaw command speed
  double input_timeout = 0.1;  ///< [s] clip sample older than this => hold
  double max_step = 0.05;      ///< [s] longest interval integrated in one step (a longer pause moves less)
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class ClipMapper
{
public:
  explicit ClipMapper(const ClipParams& p);

  /// Measured jaw [rad]; the first finite one starts the command there (clamped to the range).
  /// Returns false (ignored) if not finite.
  bool setMeasured(double jaw);
  /// Clip angle [rad] sampled at @p t [s] (monotonic). Returns false (rejected, counted; the jaw
  /// holds until the next valid sample) if not finite.
  bool setClip(double clip, double t);
  /// Advance the command to time @p t [s]; with @p hold (or stale/absent input) it does not move.
  /// Returns the command [rad] (valid only if started()).
  double step(double t, bool hold);

  /// Jaw target of a clip angle [rad]: scaled, offset, clamped to [jaw_min, jaw_max].
  double map(double clip) const;
  bool started() const { return started_; }
  double command() const { return cmd_; }
  /// true if the last step did not follow the clip (hold, stale, absent or rejected input)
  bool holding() const { return holding_; }
  /// true if the input is stale or absent at @p t
  bool stale(double t) const { return !have_clip_ || t - t_clip_ > p_.input_timeout; }
  std::size_t rejected() const { return rejected_; }
  const ClipParams& params() const { return p_; }

private:
  ClipParams p_;
  double cmd_ = 0.0, target_ = 0.0, t_clip_ = 0.0, t_step_ = 0.0;
  bool started_ = false, have_clip_ = false, stepped_ = false, holding_ = true;
  std::size_t rejected_ = 0;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_CLIP_MAPPER_H

#include "saras_teleop/delay_channel.h"

#include <cmath>
#include <stdexcept>

namespace saras_teleop
{
void ChannelParams::validate() const
{
  if (!(std::isfinite(delay) && delay >= 0.0))
    throw std::invalid_argument("parameter 'delay' must be finite and >= 0 s");
  if (!(std::isfinite(jitter) && jitter >= 0.0))
    throw std::invalid_argument("parameter 'jitter' must be finite and >= 0 s");
  if (!(std::isfinite(loss) && loss >= 0.0 && loss < 1.0))
    throw std::invalid_argument("parameter 'loss' must be in [0, 1)");
  if (!(std::isfinite(burst_length) && burst_length >= 1.0))
    throw std::invalid_argument("parameter 'burst_length' must be >= 1 message");
}

LossModel::LossModel(const ChannelParams& p) : loss_(p.loss), rng_(p.seed)
{
  // Stationary probability of the bad state = p_gb / (p_gb + p_bg) = loss; mean bad run = 1 / p_bg.
  p_bg_ = 1.0 / p.burst_length;
  p_gb_ = p.loss < 1.0 ? p.loss * p_bg_ / (1.0 - p.loss) : 1.0;
}

bool LossModel::drop()
{
  if (loss_ <= 0.0)
    return false;
  bool d;
  if (p_bg_ >= 1.0)
  {
    d = u_(rng_) < loss_;  // independent (Bernoulli) losses
  }
  else
  {
    bad_ = bad_ ? (u_(rng_) >= p_bg_) : (u_(rng_) < p_gb_);
    d = bad_;
  }
  if (d)
    ++dropped_;
  return d;
}

}  // namespace saras_teleop

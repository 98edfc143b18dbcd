#include "saras_teleop/energy_tank.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace saras_teleop
{
namespace
{
void require(bool ok, const std::string& name, const std::string& why)
{
  if (!ok)
    throw std::invalid_argument("parameter '" + name + "' " + why);
}
}  // namespace

void TankParams::validate() const
{
  const double vals[] = { T_init, T_max, T_min, T_req, T_ava, P_const };
  const char* names[] = { "T_init", "T_max", "T_min", "T_req", "T_ava", "P_const" };
  for (int i = 0; i < 6; ++i)
    require(std::isfinite(vals[i]) && vals[i] >= 0.0, names[i], "must be finite and >= 0");
  require(T_min > 0.0, "T_min", "must be > 0 J (xt = sqrt(2 T) must stay positive)");
  require(T_min < T_req, "T_req", "must be > T_min");
  require(T_req <= T_ava, "T_ava", "must be >= T_req");
  require(T_ava < T_max, "T_max", "must be > T_ava");
  require(T_init > T_min && T_init <= T_max, "T_init", "must be in (T_min, T_max]");
  for (int i = 0; i < 6; ++i)
  {
    require(std::isfinite(damping_std[i]) && damping_std[i] >= 0.0, "damping_std",
            "entries must be finite and >= 0");
    require(std::isfinite(damping_max[i]) && damping_max[i] >= damping_std[i], "damping_max",
            "entries must be finite and >= damping_std");
  }
}

double getDamping(double /*T_max*/, double T_min, double T_req, double /*T_ava*/, double d_std, double d_max,
                  double T)
{
  if (T >= T_req)
    return d_std;
  if (T <= T_min)
    return d_max;
  const double s = (T - T_min) / (T_req - T_min);  // 0 at T_min, 1 at T_req
  return d_max + s * (d_std - d_max);
}

EnergyTank::EnergyTank(const TankParams& params, std::size_t num_ports)
  : p_(params)
  , desired_(num_ports, Vector6d::Zero())
  , conjugate_(num_ports, Vector6d::Zero())
  , output_(num_ports, Vector6d::Zero())
  , T_(params.T_init)
  , xt_(std::sqrt(2.0 * params.T_init))
{
  p_.validate();
}

void EnergyTank::setDesired(std::size_t port, const Vector6d& a)
{
  if (a.allFinite())
  {
    desired_[port] = a;
  }
  else
  {
    desired_[port].setZero();
    ++rejected_;
  }
}

void EnergyTank::setConjugate(std::size_t port, const Vector6d& m)
{
  if (m.allFinite())
  {
    conjugate_[port] = m;
  }
  else
  {
    conjugate_[port].setZero();
    ++rejected_;
  }
}

double EnergyTank::xtDot(double xt, double sigma, double D, double pin, double pout, double port_power)
{
  return (sigma * D + sigma * pin - pout) / xt - port_power / xt;
}

bool EnergyTank::step(double dt, double pin, double ext_ereq)
{
  if (!(std::isfinite(dt) && dt > 0.0))
    return false;
  if (!std::isfinite(pin) || pin < 0.0)
  {
    if (!std::isfinite(pin))
      ++rejected_;
    pin = 0.0;
  }
  const bool peer_requests = std::isfinite(ext_ereq) && ext_ereq > 0.5;
  const std::size_t n = desired_.size();

  if (p_.bypass)
  {
    double port = 0.0;
    for (std::size_t k = 0; k < n; ++k)
    {
      output_[k] = desired_[k];
      port += output_[k].dot(conjugate_[k]);
    }
    info_ = TankStepInfo();
    info_.port_power = port;
    ledger_.ports += port * dt;  // energy the unrestricted actions put out [J] (T is not updated)
    return true;
  }

  TankStepInfo s;
  s.sigma = (T_ < p_.T_max) ? 1.0 : 0.0;
  s.beta = (T_ > p_.T_ava) ? 1.0 : 0.0;
  s.ereq = (T_ < p_.T_req) ? 1.0 : 0.0;

  Vector6d B;
  for (int i = 0; i < 6; ++i)
    B[i] = getDamping(p_.T_max, p_.T_min, p_.T_req, p_.T_ava, p_.damping_std[i], p_.damping_max[i], T_);

  s.D = 0.0;
  for (std::size_t k = 0; k < n; ++k)
    s.D += (B.array() * conjugate_[k].array().square()).sum();

  s.pin = pin;
  s.pout = (1.0 - s.sigma) * s.D + (peer_requests ? s.beta * p_.P_const : 0.0);
  // Never give away energy below T_min (conservative: a smaller Pout only keeps energy here).
  const double pout_cap = std::max(0.0, (T_ - p_.T_min) / dt);
  s.pout = std::min(s.pout, pout_cap);

  s.KE = s.ereq > 0.5 ? std::min(1.0, std::max(0.0, 1.0 - (T_ - p_.T_min) / (p_.T_req - p_.T_min))) : 0.0;
  const double keep = 1.0 - s.KE;

  double port = 0.0;
  for (std::size_t k = 0; k < n; ++k)
    port += keep * desired_[k].dot(conjugate_[k]);
  const double base = T_ + dt * (s.sigma * s.D + s.sigma * s.pin - s.pout);
  const double deltaE = port * dt;
  s.implemented = (base - deltaE > p_.T_min) || deltaE <= 0.0;
  if (!s.implemented)
    port = 0.0;
  s.port_power = port;

  for (std::size_t k = 0; k < n; ++k)
  {
    const Vector6d damping = -(B.array() * conjugate_[k].array()).matrix();
    output_[k] = s.implemented ? Vector6d(keep * desired_[k] + damping) : damping;
  }

  double T_next = base - port * dt;
  s.clipped = std::max(0.0, T_next - p_.T_max);
  T_next -= s.clipped;

  ledger_.stored_damping += s.sigma * s.D * dt;
  ledger_.received += s.sigma * s.pin * dt;
  ledger_.sent += s.pout * dt;
  ledger_.ports += port * dt;
  ledger_.clipped += s.clipped;

  T_ = T_next;
  xt_ = std::sqrt(2.0 * T_);
  info_ = s;
  return true;
}

}  // namespace saras_teleop

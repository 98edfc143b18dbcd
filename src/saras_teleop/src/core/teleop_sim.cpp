#include "saras_teleop/teleop_sim.h"

#include <algorithm>
#include <cmath>

#include "saras_teleop/twist_estimator.h"

namespace saras_teleop
{
namespace
{
struct MasterMsg
{
  Eigen::Vector3d pos;
  Vector6d twist;
};

/// Receiver side of the energy exchange: each packet carries Pout*dt [J], consumed once.
struct EnergyInbox
{
  double energy = 0.0;
  double ereq = 0.0;
};

struct TankMsg
{
  double energy;  ///< Pout * dt of the sender [J]
  double ereq;
};
}  // namespace

namespace
{
/// One simulated teleoperation loop: the state of runSimulation() and its per-step stages, called
/// in the order of the real chain (master site, transparency, tanks, slave, operator).
class LoopSim
{
public:
  explicit LoopSim(const SimParams& p)
    : p_(p)
    , est_(p.twist_cutoff, 0.1)
    , tr_(p.transparency)
    , tm_(p.master_tank, 1)
    , ts_(p.slave_tank, 1)
    , vi_(p.integrator)
    , fwd_(p.forward)
    , bwd_(p.backward)
    , m2s_(shifted(p.forward, 101))
    , s2m_(shifted(p.backward, 202))
  {
    r_.E0 = p.master_tank.bypass ? 0.0 : p.master_tank.T_init + p.slave_tank.T_init;
    vi_.start(KDL::Frame(KDL::Vector(0, 0, 0)));
    double f_wall = 0.0;
    U0_ = springEnergy(sp_, s_, f_wall);
  }

  SimResult run()
  {
    const double dt = p_.dt;
    const int steps = static_cast<int>(std::lround(p_.duration / dt));
    for (int k = 0; k < steps; ++k)
    {
      const double t = k * dt;
      const Vector6d vhat = masterSite(t);
      Vector6d des_v;
      transparency(t, des_v);
      tanks(t, vhat, des_v);
      const double U = slave();
      operatorAndRecord(k, t, U);
    }
    r_.E_out_final = r_.E_dev + r_.E_slave;
    r_.tracking_rms = steps > 0 ? std::sqrt(sq_ / steps) : 0.0;
    return r_;
  }

private:
  static ChannelParams shifted(ChannelParams c, unsigned seed_offset)
  {
    c.seed += seed_offset;
    return c;
  }

  /// Spring energy of the robot (kr) and the wall (ke) for set-point @p spx; @p s_out is where the
  /// tool settles, @p f_wall the wall's force on it (-x).
  double springEnergy(const Eigen::Vector3d& spx, Eigen::Vector3d& s_out, double& f_wall) const
  {
    const double kr = p_.robot_stiffness, ke = p_.env_stiffness;
    s_out = spx;
    f_wall = 0.0;
    if (spx.x() > p_.wall)
    {
      s_out.x() = (kr * spx.x() + ke * p_.wall) / (kr + ke);
      f_wall = -ke * (s_out.x() - p_.wall);
    }
    const double pen = std::max(0.0, s_out.x() - p_.wall);
    return 0.5 * kr * (spx - s_out).squaredNorm() + 0.5 * ke * pen * pen;
  }

  /// tf_transformer core: the master's twist estimate, sent over the forward channel.
  Vector6d masterSite(double t)
  {
    est_.addSample(t, KDL::Frame(KDL::Vector(xm_.x(), xm_.y(), xm_.z())));
    const Vector6d vhat = est_.twist();
    fwd_.push(MasterMsg{ xm_, vhat }, t);
    return vhat;
  }

  /// Slave site: transparency with what has arrived; its wrench goes back to the master.
  void transparency(double t, Vector6d& des_v)
  {
    fwd_.deliver(t, [&](const MasterMsg& m) {
      tr_.setMasterPosition(m.pos);
      tr_.setMasterTwist(m.twist);
    });
    tr_.setSlavePosition(s_);
    tr_.setContactForce(contact_sample_.head<3>());  // reflected on the master (contact_feedback)
    Vector6d des_w;
    tr_.update(des_w, des_v);
    bwd_.push(des_w, t);
    bwd_.deliver(t, [&](const Vector6d& w) { des_w_master_ = w; });
  }

  /// Both tanks; energy packets are consumed once.
  void tanks(double t, const Vector6d& vhat, const Vector6d& des_v)
  {
    const double dt = p_.dt;
    m2s_.deliver(t, [&](const TankMsg& m) {
      inbox_s_.energy += m.energy;
      inbox_s_.ereq = m.ereq;
    });
    s2m_.deliver(t, [&](const TankMsg& m) {
      inbox_m_.energy += m.energy;
      inbox_m_.ereq = m.ereq;
    });
    tm_.setDesired(0, des_w_master_);
    tm_.setConjugate(0, vhat);
    tm_.step(dt, inbox_m_.energy / dt, inbox_m_.ereq);
    inbox_m_.energy = 0.0;
    if (t >= next_force_sample_)
    {
      double fw;
      Eigen::Vector3d stmp;
      springEnergy(sp_, stmp, fw);
      contact_sample_.setZero();
      contact_sample_[0] = fw;
      next_force_sample_ += 1.0 / p_.force_rate;
    }
    ts_.setDesired(0, des_v);
    ts_.setConjugate(0, p_.contact_force_sign * contact_sample_);
    ts_.step(dt, inbox_s_.energy / dt, inbox_s_.ereq);
    inbox_s_.energy = 0.0;
    m2s_.push(TankMsg{ tm_.pout() * dt, tm_.ereq() }, t);
    s2m_.push(TankMsg{ ts_.pout() * dt, ts_.ereq() }, t);
    f_dev_ = tm_.output(0);
  }

  /// Slave: integrate the set-point and settle against the wall; returns the spring energy [J].
  double slave()
  {
    vi_.step(ts_.output(0), p_.dt, false);
    const KDL::Frame& F = vi_.pose();
    sp_ = Eigen::Vector3d(F.p.x(), F.p.y(), F.p.z());
    double f_wall = 0.0;
    return springEnergy(sp_, s_, f_wall);
  }

  /// Operator + master device (semi-implicit Euler, force held over the step), then the figures.
  void operatorAndRecord(int k, double t, double U)
  {
    const double dt = p_.dt;
    const double xh = p_.hand_amplitude * std::sin(2.0 * M_PI * p_.hand_frequency * t);
    const double vh = p_.hand_amplitude * 2.0 * M_PI * p_.hand_frequency * std::cos(2.0 * M_PI * p_.hand_frequency * t);
    Eigen::Vector3d f_hand = -p_.hand_stiffness * xm_ - p_.hand_damping * vm_;
    f_hand.x() += p_.hand_stiffness * xh + p_.hand_damping * vh;
    const Eigen::Vector3d fd = f_dev_.head<3>();
    vm_ += dt * (f_hand + fd) / p_.master_mass;
    const Eigen::Vector3d dx = dt * vm_;
    xm_ += dx;
    r_.E_dev += fd.dot(dx);
    r_.E_slave = U - U0_;
    const double E_out = r_.E_dev + r_.E_slave;
    r_.E_out_max = std::max(r_.E_out_max, E_out);
    r_.T_master_min = std::min(r_.T_master_min, tm_.energy());
    r_.T_slave_min = std::min(r_.T_slave_min, ts_.energy());
    r_.master_excursion = std::max(r_.master_excursion, xm_.norm());
    r_.slave_excursion = std::max(r_.slave_excursion, s_.norm());
    r_.max_force = std::max(r_.max_force, fd.norm());
    const Eigen::Vector3d e = sp_ - p_.transparency.scale_factor * xm_;
    sq_ += e.squaredNorm();
    if (p_.trace_every > 0 && k % p_.trace_every == 0)
      r_.trace.push_back(SimSample{ t, xm_.x(), s_.x(), sp_.x(), tm_.energy(), ts_.energy(), E_out, fd.x() });
  }

  const SimParams& p_;
  SimResult r_;
  TwistEstimator est_;
  TransparencyChannel tr_;
  EnergyTank tm_, ts_;
  VelocityIntegrator vi_;
  DelayChannel<MasterMsg> fwd_;
  DelayChannel<Vector6d> bwd_;
  DelayChannel<TankMsg> m2s_, s2m_;
  // master and slave start at the origin: excursions and tracking error are measured from it
  Eigen::Vector3d xm_ = Eigen::Vector3d::Zero(), vm_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d sp_ = Eigen::Vector3d::Zero(), s_ = Eigen::Vector3d::Zero();
  Vector6d f_dev_ = Vector6d::Zero();
  Vector6d des_w_master_ = Vector6d::Zero();
  Vector6d contact_sample_ = Vector6d::Zero();  // force of the wall on the tool (sampled)
  EnergyInbox inbox_m_, inbox_s_;
  double next_force_sample_ = 0.0;
  double U0_ = 0.0, sq_ = 0.0;
};
}  // namespace

SimResult runSimulation(const SimParams& p)
{
  return LoopSim(p).run();
}

}  // namespace saras_teleop

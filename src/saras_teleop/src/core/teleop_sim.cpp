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

SimResult runSimulation(const SimParams& p)
{
  SimResult r;
  TwistEstimator est(p.twist_cutoff, 0.1);
  TransparencyChannel tr(p.transparency);
  EnergyTank tm(p.master_tank, 1), ts(p.slave_tank, 1);
  VelocityIntegrator vi(p.integrator);
  DelayChannel<MasterMsg> fwd(p.forward);
  DelayChannel<Vector6d> bwd(p.backward);
  ChannelParams fe = p.forward, be = p.backward;
  fe.seed += 101;
  be.seed += 202;
  DelayChannel<TankMsg> m2s(fe), s2m(be);

  r.E0 = p.master_tank.bypass ? 0.0 : p.master_tank.T_init + p.slave_tank.T_init;
  const double dt = p.dt;
  const int steps = static_cast<int>(std::lround(p.duration / dt));
  const double kr = p.robot_stiffness, ke = p.env_stiffness;

  Eigen::Vector3d xm = Eigen::Vector3d::Zero(), vm = Eigen::Vector3d::Zero();
  const Eigen::Vector3d xm0 = xm;
  vi.start(KDL::Frame(KDL::Vector(0, 0, 0)));
  Eigen::Vector3d sp = Eigen::Vector3d::Zero(), s = sp;
  const Eigen::Vector3d sp0 = sp;
  Vector6d f_dev = Vector6d::Zero();
  Vector6d des_w_master = Vector6d::Zero();
  Vector6d contact_sample = Vector6d::Zero();  // force of the wall on the tool (sampled)
  EnergyInbox inbox_m, inbox_s;
  double next_force_sample = 0.0;
  double U0 = 0.0, sq = 0.0;

  auto springEnergy = [&](const Eigen::Vector3d& spx, Eigen::Vector3d& s_out, double& f_wall) {
    s_out = spx;
    f_wall = 0.0;
    if (spx.x() > p.wall)
    {
      s_out.x() = (kr * spx.x() + ke * p.wall) / (kr + ke);
      f_wall = -ke * (s_out.x() - p.wall);  // on the tool, pushing back (-x)
    }
    const double pen = std::max(0.0, s_out.x() - p.wall);
    return 0.5 * kr * (spx - s_out).squaredNorm() + 0.5 * ke * pen * pen;
  };
  double f_wall = 0.0;
  U0 = springEnergy(sp, s, f_wall);

  for (int k = 0; k < steps; ++k)
  {
    const double t = k * dt;
    // --- master site: tf_transformer core
    est.addSample(t, KDL::Frame(KDL::Vector(xm.x(), xm.y(), xm.z())));
    const Vector6d vhat = est.twist();
    fwd.push(MasterMsg{ xm, vhat }, t);
    // --- slave site: transparency with what has arrived
    fwd.deliver(t, [&](const MasterMsg& m) {
      tr.setMasterPosition(m.pos);
      tr.setMasterTwist(m.twist);
    });
    tr.setSlavePosition(s);
    tr.setContactForce(contact_sample.head<3>());  // reflected on the master (contact_feedback)
    Vector6d des_w, des_v;
    tr.update(des_w, des_v);
    bwd.push(des_w, t);
    bwd.deliver(t, [&](const Vector6d& w) { des_w_master = w; });
    // --- tanks (energy packets consumed once)
    m2s.deliver(t, [&](const TankMsg& m) {
      inbox_s.energy += m.energy;
      inbox_s.ereq = m.ereq;
    });
    s2m.deliver(t, [&](const TankMsg& m) {
      inbox_m.energy += m.energy;
      inbox_m.ereq = m.ereq;
    });
    tm.setDesired(0, des_w_master);
    tm.setConjugate(0, vhat);
    tm.step(dt, inbox_m.energy / dt, inbox_m.ereq);
    inbox_m.energy = 0.0;
    if (t >= next_force_sample)
    {
      double fw;
      Eigen::Vector3d stmp;
      springEnergy(sp, stmp, fw);
      contact_sample.setZero();
      contact_sample[0] = fw;
      next_force_sample += 1.0 / p.force_rate;
    }
    ts.setDesired(0, des_v);
    ts.setConjugate(0, p.contact_force_sign * contact_sample);
    ts.step(dt, inbox_s.energy / dt, inbox_s.ereq);
    inbox_s.energy = 0.0;
    m2s.push(TankMsg{ tm.pout() * dt, tm.ereq() }, t);
    s2m.push(TankMsg{ ts.pout() * dt, ts.ereq() }, t);
    f_dev = tm.output(0);
    // --- slave: integrate and settle against the wall
    vi.step(ts.output(0), dt, false);
    const KDL::Frame& F = vi.pose();
    sp = Eigen::Vector3d(F.p.x(), F.p.y(), F.p.z());
    const double U = springEnergy(sp, s, f_wall);
    // --- operator + master device (semi-implicit Euler, force held over the step)
    const double xh = p.hand_amplitude * std::sin(2.0 * M_PI * p.hand_frequency * t);
    const double vh = p.hand_amplitude * 2.0 * M_PI * p.hand_frequency * std::cos(2.0 * M_PI * p.hand_frequency * t);
    Eigen::Vector3d f_hand = -p.hand_stiffness * xm - p.hand_damping * vm;
    f_hand.x() += p.hand_stiffness * xh + p.hand_damping * vh;
    const Eigen::Vector3d fd = f_dev.head<3>();
    vm += dt * (f_hand + fd) / p.master_mass;
    const Eigen::Vector3d dx = dt * vm;
    xm += dx;
    r.E_dev += fd.dot(dx);
    r.E_slave = U - U0;
    const double E_out = r.E_dev + r.E_slave;
    r.E_out_max = std::max(r.E_out_max, E_out);
    r.T_master_min = std::min(r.T_master_min, tm.energy());
    r.T_slave_min = std::min(r.T_slave_min, ts.energy());
    r.master_excursion = std::max(r.master_excursion, (xm - xm0).norm());
    r.slave_excursion = std::max(r.slave_excursion, (s - sp0).norm());
    r.max_force = std::max(r.max_force, fd.norm());
    const Eigen::Vector3d e = (sp - sp0) - p.transparency.scale_factor * (xm - xm0);
    sq += e.squaredNorm();
    if (p.trace_every > 0 && k % p.trace_every == 0)
      r.trace.push_back(SimSample{ t, xm.x(), s.x(), sp.x(), tm.energy(), ts.energy(), E_out, fd.x() });
  }
  r.E_out_final = r.E_dev + r.E_slave;
  r.tracking_rms = steps > 0 ? std::sqrt(sq / steps) : 0.0;
  return r;
}

}  // namespace saras_teleop

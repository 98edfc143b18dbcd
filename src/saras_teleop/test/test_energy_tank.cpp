// Core tests of the energy tank (no ROS).
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "saras_teleop/energy_tank.h"

using saras_teleop::EnergyTank;
using saras_teleop::TankParams;
using saras_teleop::Vector6d;

namespace
{
Vector6d randomVec(std::mt19937& g, double scale)
{
  std::uniform_real_distribution<double> u(-scale, scale);
  Vector6d v;
  for (int i = 0; i < 6; ++i)
    v[i] = u(g);
  return v;
}
}  // namespace

// dT/dt = sigma D - sum a.m + sigma Pin - Pout integrates exactly: the ledger closes to rounding
// error over random inputs, and T stays in [T_min, T_max].
TEST(EnergyTank, BalanceHoldsOverRandomInputs)
{
  TankParams p;
  EnergyTank tank(p, 2);
  std::mt19937 g(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double T_prev = tank.energy();
  int not_implemented = 0, full = 0, requests = 0;
  for (int k = 0; k < 200000; ++k)
  {
    const double dt = 0.0005 + 0.0015 * u(g);
    // phases: actions that drain the tank (force along the motion), then ones that fill it
    const double c = ((k / 20000) % 2 == 0) ? 30.0 : -30.0;
    for (std::size_t port = 0; port < 2; ++port)
    {
      const Vector6d m = randomVec(g, 0.3);
      // now and then a spike the tank cannot afford (must be cut, not partially applied)
      const double spike = (k % 997 == 0) ? 1e5 : 0.0;
      tank.setDesired(port, Vector6d((c + spike) * m + randomVec(g, 3.0)));
      tank.setConjugate(port, m);
    }
    const double pin = u(g) < 0.3 ? 5.0 * u(g) : 0.0;
    ASSERT_TRUE(tank.step(dt, pin, u(g) < 0.2 ? 1.0 : 0.0));
    const auto& s = tank.info();
    // per-step balance (independent recomputation from the published flows)
    const double expected = T_prev + dt * (s.sigma * s.D - s.port_power + s.sigma * s.pin - s.pout) - s.clipped;
    ASSERT_NEAR(tank.energy(), expected, 1e-12);
    ASSERT_GE(tank.energy(), p.T_min);
    ASSERT_LE(tank.energy(), p.T_max);
    ASSERT_NEAR(0.5 * tank.xt() * tank.xt(), tank.energy(), 1e-12);
    not_implemented += s.implemented ? 0 : 1;
    full += s.sigma < 0.5 ? 1 : 0;
    requests += s.ereq > 0.5 ? 1 : 0;
    T_prev = tank.energy();
  }
  const auto& L = tank.ledger();
  EXPECT_NEAR(tank.energy() - p.T_init, L.stored_damping + L.received - L.sent - L.ports - L.clipped, 1e-8);
  // the random walk visited every regime, so the assertions above covered them
  EXPECT_GT(not_implemented, 0);
  EXPECT_GT(full, 0);
  EXPECT_GT(requests, 0);
}

// xt dynamics: dxt/dt = (sigma D + sigma Pin - Pout)/xt - (a.m)/xt. Integrating it finely with constant
// flows must reproduce T(t) = T0 + P t (the independent closed form); the deliverable's printed form
// (sigma*D not divided by xt) must not.
TEST(EnergyTank, XtDynamicsMatchClosedForm)
{
  const double sigma = 1.0, D = 0.7, pin = 0.4, pout = 0.1, port = 0.25;
  const double P = sigma * D + sigma * pin - pout - port;  // [W]
  const double T0 = 8.0, h = 1e-5, tend = 2.0;
  double xt = std::sqrt(2.0 * T0), xt_seed = xt;
  for (double t = 0.0; t < tend - h / 2; t += h)
  {
    // midpoint (RK2) integration
    const double k1 = EnergyTank::xtDot(xt, sigma, D, pin, pout, port);
    xt += h * EnergyTank::xtDot(xt + 0.5 * h * k1, sigma, D, pin, pout, port);
    xt_seed += h * (sigma * D + (sigma * pin - pout - port) / xt_seed);
  }
  EXPECT_NEAR(0.5 * xt * xt, T0 + P * tend, 1e-8);
  EXPECT_GT(std::fabs(0.5 * xt_seed * xt_seed - (T0 + P * tend)), 1.0);
  // the identity xt * dxt/dt == dT/dt for random values
  std::mt19937 g(3);
  std::uniform_real_distribution<double> u(0.1, 5.0);
  for (int i = 0; i < 1000; ++i)
  {
    const double x = u(g), d = u(g), pi = u(g), po = u(g), pp = u(g) - 2.5;
    EXPECT_NEAR(x * EnergyTank::xtDot(x, 1.0, d, pi, po, pp), d + pi - po - pp, 1e-12);
  }
}

// The tank step agrees with a fine integration of the xt ODE over one control period.
TEST(EnergyTank, StepAgreesWithXtOde)
{
  TankParams p;
  EnergyTank tank(p, 1);
  Vector6d a = Vector6d::Zero(), m = Vector6d::Zero();
  a[0] = 2.0;
  m[0] = 0.05;  // extracts 0.1 W
  m[1] = 0.1;   // damping only
  tank.setDesired(0, a);
  tank.setConjugate(0, m);
  const double xt0 = tank.xt();
  ASSERT_TRUE(tank.step(0.001, 0.3, 0.0));
  const auto& s = tank.info();
  double xt = xt0;
  const int n = 1000;
  for (int i = 0; i < n; ++i)
    xt += (0.001 / n) * EnergyTank::xtDot(xt, s.sigma, s.D, s.pin, s.pout, s.port_power);
  EXPECT_NEAR(tank.xt(), xt, 1e-10);
  // expected flows from the definitions: D = sum B m^2 with B = damping_std at T = 10 J
  EXPECT_NEAR(s.D, 0.5 * (0.05 * 0.05 + 0.1 * 0.1), 1e-15);
  EXPECT_NEAR(s.port_power, 0.1, 1e-15);
  EXPECT_NEAR(tank.output(0)[0], 2.0 - 0.5 * 0.05, 1e-15);
  EXPECT_NEAR(tank.output(0)[1], -0.5 * 0.1, 1e-15);
}

// Draining the tank: T never goes below T_min and at T_min only the damping remains.
TEST(EnergyTank, NeverBelowTminAndZeroActionAtTmin)
{
  TankParams p;
  p.T_init = 3.0;
  p.damping_std.setZero();  // no dissipation refilling the tank: the action drains it
  p.damping_max.setZero();
  EnergyTank tank(p, 1);
  Vector6d a = Vector6d::Zero(), m = Vector6d::Zero();
  a[0] = 3.0;  // force along the motion: the action extracts energy continuously
  m[0] = 0.2;
  tank.setDesired(0, a);
  tank.setConjugate(0, m);
  double prev = tank.energy();
  for (int k = 0; k < 200000; ++k)
  {
    tank.step(0.001, 0.0, 0.0);
    ASSERT_GE(tank.energy(), p.T_min);
    ASSERT_LE(tank.energy(), prev);
    prev = tank.energy();
  }
  // converged to T_min (time constant (T_req - T_min) / 0.6 W = 6.7 s, 200 s run); action is zero
  EXPECT_NEAR(tank.energy(), p.T_min, 1e-9);
  EXPECT_NEAR(tank.output(0)[0], 0.0, 1e-9);
  EXPECT_NEAR(tank.info().KE, 1.0, 1e-9);
  // exactly at the floor the set-point reduction is total
  TankParams q;
  q.T_init = q.T_min + 1e-12;
  EnergyTank at_min(q, 1);
  at_min.setDesired(0, a);
  at_min.setConjugate(0, -m);  // even an action that would give energy back is cut by KE = 1
  at_min.step(0.001, 0.0, 0.0);
  EXPECT_NEAR(at_min.output(0)[0], q.damping_max[0] * 0.2, 1e-9);
  EXPECT_NEAR(at_min.info().KE, 1.0, 1e-9);
}

// An action the tank cannot afford is not implemented at all.
TEST(EnergyTank, UnaffordableActionIsZeroed)
{
  TankParams p;
  p.T_init = 5.0;  // = T_req: KE = 0
  p.damping_std.setZero();
  p.damping_max.setZero();
  EnergyTank tank(p, 1);
  Vector6d a = Vector6d::Zero(), m = Vector6d::Zero();
  a[2] = 1000.0;
  m[2] = 10.0;  // 10 kW for 1 ms = 10 J > T - T_min
  tank.setDesired(0, a);
  tank.setConjugate(0, m);
  tank.step(0.001, 0.0, 0.0);
  EXPECT_FALSE(tank.info().implemented);
  EXPECT_DOUBLE_EQ(tank.output(0).norm(), 0.0);
  EXPECT_DOUBLE_EQ(tank.energy(), 5.0);
}

TEST(EnergyTank, DampingScheduleContinuous)
{
  const TankParams p;
  const double d_std = 0.5, d_max = 5.0;
  const double lip = (d_max - d_std) / (p.T_req - p.T_min);
  double prev = saras_teleop::getDamping(p.T_max, p.T_min, p.T_req, p.T_ava, d_std, d_max, 0.0);
  const double h = 1e-4;
  for (double T = h; T <= 25.0; T += h)
  {
    const double d = saras_teleop::getDamping(p.T_max, p.T_min, p.T_req, p.T_ava, d_std, d_max, T);
    ASSERT_LE(std::fabs(d - prev), lip * h * 1.0001 + 1e-12) << "jump at T = " << T;
    ASSERT_GE(d, d_std);
    ASSERT_LE(d, d_max);
    prev = d;
  }
  EXPECT_DOUBLE_EQ(saras_teleop::getDamping(p.T_max, p.T_min, p.T_req, p.T_ava, d_std, d_max, p.T_min), d_max);
  EXPECT_DOUBLE_EQ(saras_teleop::getDamping(p.T_max, p.T_min, p.T_req, p.T_ava, d_std, d_max, p.T_req), d_std);
  EXPECT_DOUBLE_EQ(saras_teleop::getDamping(p.T_max, p.T_min, p.T_req, p.T_ava, d_std, d_max, 3.0),
                   d_max + 0.5 * (d_std - d_max));
}

// Full tank: dissipated power is passed to the peer (Pout = D), requests are served with P_const.
TEST(EnergyTank, FullTankAndEnergyRequests)
{
  TankParams p;
  p.T_init = p.T_max;
  EnergyTank tank(p, 1);
  Vector6d m = Vector6d::Zero();
  m[0] = 0.4;
  tank.setConjugate(0, m);
  tank.step(0.001, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(tank.info().sigma, 0.0);
  EXPECT_NEAR(tank.pout(), 0.5 * 0.16, 1e-15);
  tank.setConjugate(0, Vector6d::Zero());
  tank.step(0.001, 0.0, 1.0);  // peer asks: beta = 1 since T > T_ava
  EXPECT_NEAR(tank.pout(), p.P_const, 1e-15);

  // two tanks exchanging packets: the low one is refilled, the total never grows
  TankParams low = p;
  low.T_init = 2.0;
  TankParams high = p;
  high.T_init = 15.0;
  EnergyTank a(low, 1), b(high, 1);
  const double dt = 0.001;
  double total0 = a.energy() + b.energy();
  for (int k = 0; k < 20000; ++k)
  {
    const double pa = a.pout(), pb = b.pout(), ea = a.ereq(), eb = b.ereq();
    a.step(dt, pb, eb);
    b.step(dt, pa, ea);
    ASSERT_LE(a.energy() + b.energy(), total0 + 1e-9);
  }
  EXPECT_GE(a.energy(), low.T_req);
  EXPECT_NEAR(a.energy() + b.energy(), total0, 1e-9);  // no damping, no clamp: exchange is lossless
}

TEST(EnergyTank, RejectsNonFiniteInputs)
{
  TankParams p;
  EnergyTank tank(p, 1);
  Vector6d bad = Vector6d::Constant(std::nan(""));
  tank.setDesired(0, bad);
  tank.setConjugate(0, bad);
  EXPECT_TRUE(tank.step(0.001, std::nan(""), std::nan("")));
  EXPECT_EQ(tank.rejectedInputs(), 3u);
  EXPECT_TRUE(std::isfinite(tank.energy()));
  EXPECT_DOUBLE_EQ(tank.output(0).norm(), 0.0);
  EXPECT_FALSE(tank.step(0.0, 0.0, 0.0));
  EXPECT_FALSE(tank.step(std::nan(""), 0.0, 0.0));
  EXPECT_DOUBLE_EQ(tank.energy(), p.T_init);
}

TEST(EnergyTank, ValidationNamesParameter)
{
  TankParams p;
  p.T_req = 0.5;
  try
  {
    p.validate();
    FAIL() << "expected invalid_argument";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("T_req"), std::string::npos);
  }
  TankParams q;
  q.damping_max[3] = 0.1;  // < damping_std
  EXPECT_THROW(q.validate(), std::invalid_argument);
  TankParams r;
  r.T_init = 30.0;
  EXPECT_THROW(EnergyTank(r, 1), std::invalid_argument);
}

TEST(EnergyTank, BypassPassesThrough)
{
  TankParams p;
  p.bypass = true;
  EnergyTank tank(p, 1);
  Vector6d a = Vector6d::Constant(7.0), m = Vector6d::Constant(1.0);
  tank.setDesired(0, a);
  tank.setConjugate(0, m);
  tank.step(0.001, 0.0, 0.0);
  EXPECT_TRUE(tank.output(0).isApprox(a));
  EXPECT_NEAR(tank.ledger().ports, 0.042, 1e-15);
}
